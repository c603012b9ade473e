//! The user's template: names of frames and tools on the controller, speeds, zones, limits. One
//! TOML file (`--program-config`, every key documented in `docs/program.example.toml`) with a
//! `[program]` section common to all formats and one section per vendor. Defaults are slow and
//! conservative; every value is checked against a range and an error names the key.

use crate::program::error::ProgramError;
use serde::Deserialize;

/// Largest number of points a program may hold (any format).
pub const MAX_POINTS_LIMIT: usize = 1_000_000;

/// Coordinates the positions are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Coordinates {
    /// The part frame R_p (KUKA base, ABB work object, Stäubli frame, UR feature): the program
    /// follows the part when the user re-teaches the frame.
    Part,
    /// The robot base frame R0 (the base/work object of the program is the identity).
    Robot,
}

/// How the clearance points above the start and the end of the path are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Clearance {
    /// A clearance plane `clearance_mm` above the highest point of the path (program frame z):
    /// the approach comes straight down onto the first point from it, the retract goes
    /// straight up to it from the last.
    Height,
    /// `clearance_mm` back along the tool axis (the TCP's z axis) from the first and the last
    /// point: for tilted tools.
    ToolAxis,
}

/// Stäubli `mdesc.blend`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum StaubliBlend {
    /// No blending.
    #[serde(rename = "off")]
    Off,
    /// Joint blending.
    #[serde(rename = "joint")]
    Joint,
    /// Cartesian blending.
    #[serde(rename = "Cartesian")]
    Cartesian,
}

impl StaubliBlend {
    /// The VAL3 word.
    pub fn word(self) -> &'static str {
        match self {
            StaubliBlend::Off => "off",
            StaubliBlend::Joint => "joint",
            StaubliBlend::Cartesian => "Cartesian",
        }
    }
}

/// Settings common to every format.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CommonSettings {
    /// Program name; each exporter turns it into a valid name for its language.
    pub name: String,
    /// Frame the positions are written in.
    pub coordinates: Coordinates,
    /// Largest number of points (1 ..= 1 000 000); a longer path is refused, not cut.
    pub max_points: usize,
    /// Most path moves in one program file (10 ..= 100 000); a longer path is split into parts
    /// (`NAME_p01` …) that a main program calls in order (see the crate documentation for the
    /// controllers' limits behind the default).
    pub max_points_per_part: usize,
    /// Largest program file (kB, 16 ..= 100 000); parts are sized to stay below it.
    pub max_part_kb: usize,
    /// Where the approach starts and the retract ends.
    pub clearance: Clearance,
    /// Height of the clearance plane above the path's highest point, or distance along the tool
    /// axis (mm, 1 ..= 2000).
    pub clearance_mm: f64,
    /// TCP speed of the approach onto the first point and of the retract (mm/s, 0.1 ..= 500).
    pub approach_speed_mm_s: f64,
    /// Mass of the tool (kg, 0.001 ..= 500): the load of the programs (KUKA LOAD_DATA
    /// expected, ABB `tooldata`, UR `set_payload`). Absent: the caller's (the twin cell's or the
    /// robot model's payload); RAPID refuses to guess.
    pub tool_mass_kg: Option<f64>,
    /// Centre of gravity of the tool in the flange frame (mm, |·| ≤ 5000), with `tool_mass_kg`.
    pub tool_cog_mm: Option<[f64; 3]>,
    /// Largest TCP speed of a feed move (mm/s, 0.1 ..= 2000): faster path feeds are capped.
    pub max_speed_mm_s: f64,
    /// TCP speed of rapid moves (G0) and of the approach to the first point (mm/s, 0.1 ..= 2000).
    pub rapid_speed_mm_s: f64,
    /// Blending (approximation) distance at each point (mm, 0 ..= 50): KUKA `$APO.CDIS`, ABB
    /// zone radius, Stäubli `leave`/`reach`, UR blend radius. 0 = exact stop at every point.
    pub blend_mm: f64,
    /// Largest reorientation speed (deg/s, 1 ..= 360): KUKA `$VEL.ORI1/2`, ABB `v_ori`,
    /// Stäubli `rmax`.
    pub orientation_speed_deg_s: f64,
}

impl Default for CommonSettings {
    fn default() -> Self {
        CommonSettings {
            name: "deflex_path".into(),
            coordinates: Coordinates::Part,
            max_points: 1_000_000,
            max_points_per_part: 5000,
            max_part_kb: 1024,
            clearance: Clearance::Height,
            clearance_mm: 20.0,
            approach_speed_mm_s: 10.0,
            tool_mass_kg: None,
            tool_cog_mm: None,
            max_speed_mm_s: 50.0,
            rapid_speed_mm_s: 20.0,
            blend_mm: 0.2,
            orientation_speed_deg_s: 30.0,
        }
    }
}

/// KUKA KRL (KR C4 / KSS 8.x).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KukaSettings {
    /// `$TOOL = TOOL_DATA[tool]` (1 ..= 16): the tool calibrated on the controller, which must
    /// be the model's TCP (the program header prints the expected values).
    pub tool: u32,
    /// `$BASE = BASE_DATA[base]` (0 ..= 32, 0 = `$NULLFRAME`, the robot's base with
    /// `coordinates = "robot"`): the part frame taught on the controller.
    pub base: u32,
    /// Axis speed of the first PTP motion (% of maximum, 1 ..= 100), `BAS(#VEL_PTP, …)`.
    pub ptp_speed_percent: f64,
    /// `$ADVANCE` (1 ..= 5): motions planned ahead; C_DIS approximation needs at least 1.
    pub advance: u32,
}

impl Default for KukaSettings {
    fn default() -> Self {
        KukaSettings {
            tool: 1,
            base: 1,
            ptp_speed_percent: 10.0,
            advance: 3,
        }
    }
}

/// ABB RAPID (IRC5 / OmniCore).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AbbSettings {
    /// Name of the `tooldata` used by every move.
    pub tool_name: String,
    /// Declare the `tooldata` in the module with the model's TCP (`true`), or use a tool that
    /// already exists on the controller under `tool_name` (`false`).
    pub declare_tool: bool,
    /// Mass of the tool for the declared `tooldata` (kg, 0.001 ..= 500), when it differs from
    /// `program.tool_mass_kg`.
    pub tool_mass_kg: Option<f64>,
    /// Centre of gravity of the tool in the flange frame for the declared `tooldata` (mm).
    pub tool_cog_mm: Option<[f64; 3]>,
    /// Name of the `wobjdata` (work object) of every move.
    pub wobj_name: String,
    /// Declare the `wobjdata` with the program frame (`true`) or use an existing one (`false`).
    pub declare_wobj: bool,
}

impl Default for AbbSettings {
    fn default() -> Self {
        AbbSettings {
            tool_name: "deflex_tool".into(),
            declare_tool: true,
            tool_mass_kg: None,
            tool_cog_mm: None,
            wobj_name: "deflex_wobj".into(),
            declare_wobj: true,
        }
    }
}

/// Stäubli VAL3 (CS8/CS9, SRS project files).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StaubliSettings {
    /// Name of the `tool` data (declared in the `.dtx` with the model's TCP).
    pub tool_name: String,
    /// Name of the `frame` data the points are expressed in (declared with the program frame).
    pub frame_name: String,
    /// `mdesc.accel`, `vel`, `decel` (% of nominal, 1 ..= 100).
    pub joint_percent: f64,
    /// `mdesc.blend`: `"off"`, `"joint"` or `"Cartesian"`.
    pub blend: StaubliBlend,
}

impl Default for StaubliSettings {
    fn default() -> Self {
        StaubliSettings {
            tool_name: "tTool".into(),
            frame_name: "fPart".into(),
            joint_percent: 20.0,
            blend: StaubliBlend::Cartesian,
        }
    }
}

/// Universal Robots URScript (CB3 / e-Series).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UrSettings {
    /// Tool acceleration of `movel` (m/s², 0.01 ..= 5).
    pub acceleration_m_s2: f64,
    /// Joint speed of the first `movej` (rad/s, 0.01 ..= 3).
    pub approach_joint_speed_rad_s: f64,
    /// Joint acceleration of the first `movej` (rad/s², 0.01 ..= 10).
    pub approach_joint_acceleration_rad_s2: f64,
}

impl Default for UrSettings {
    fn default() -> Self {
        UrSettings {
            acceleration_m_s2: 0.2,
            approach_joint_speed_rad_s: 0.2,
            approach_joint_acceleration_rad_s2: 0.5,
        }
    }
}

/// FANUC TP (R-30iA / R-30iB, the ASCII `.ls` form).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FanucSettings {
    /// `UFRAME_NUM=n` (0 ..= 9, 0 = the world frame, also used with `coordinates = "robot"`):
    /// the user frame taught on the controller as the part frame.
    pub uframe: u32,
    /// `UTOOL_NUM=n` (1 ..= 10): the tool frame, which must hold the model's TCP.
    pub utool: u32,
    /// The payload schedule the user must select (`PAYLOAD[n]`, 1 ..= 10; named in the header,
    /// not written as an instruction).
    pub payload: u32,
    /// Speed of the joint move to the clearance point (`J P[1] n%`, 1 ..= 100).
    pub joint_percent: u32,
    /// Path termination of the inner path points (`CNTn`, 0 ..= 100); the first and the last
    /// point, rapids, the approach and the retract are `FINE`.
    pub cnt: u32,
}

impl Default for FanucSettings {
    fn default() -> Self {
        FanucSettings {
            uframe: 1,
            utool: 1,
            payload: 1,
            joint_percent: 20,
            cnt: 100,
        }
    }
}

/// Yaskawa INFORM `///POSTYPE`: the frame the positions are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InformPostype {
    /// `///POSTYPE USER` with `///USER n`: the part frame taught as user frame `n`.
    User,
    /// `///POSTYPE BASE`: the robot base frame (with `[program] coordinates = "robot"` only).
    Base,
}

/// Yaskawa INFORM (DX100 / DX200 / YRC1000, the `.JBI` job file).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InformSettings {
    /// `///USER n` (1 ..= 63): the user frame taught on the controller as the part frame.
    pub user: u32,
    /// `///TOOL n` (0 ..= 63): the tool file, which must hold the model's TCP and the tool load.
    pub tool: u32,
    /// `///POSTYPE`: `"user"` (the part frame, the default) or `"base"` (the robot base, only
    /// with `coordinates = "robot"`, which always writes `BASE`).
    pub postype: InformPostype,
    /// Speed of the joint move to the clearance point (`MOVJ … VJ=n`, % of the maximum,
    /// 0.01 ..= 100).
    pub joint_percent: f64,
    /// Position level of the inner path points (`PL=n`, 0 ..= 8); the first and the last path
    /// point, rapids, the approach and the retract are `PL=0`.
    pub pl: u32,
}

impl Default for InformSettings {
    fn default() -> Self {
        InformSettings {
            user: 1,
            tool: 1,
            postype: InformPostype::User,
            joint_percent: 10.0,
            pl: 1,
        }
    }
}

/// G-code (the part frame, as `deflex sim isf` and CAM read it).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GcodeSettings {
    /// Decimals of the coordinates in mm (3 ..= 6).
    pub decimals: usize,
    /// Whether the program sets its work offset itself (`G10 L2 P… X… Y… Z…` before the safe
    /// start) instead of asking the operator to enter it; for controllers that allow it
    /// (LinuxCNC, Fanuc-style and most NC controls with G10 L2).
    pub set_work_offset: bool,
}

impl Default for GcodeSettings {
    fn default() -> Self {
        GcodeSettings {
            decimals: 4,
            set_work_offset: false,
        }
    }
}

/// Everything an exporter needs besides the path. `Default` is the documented template.
#[derive(Clone, Debug, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProgramSettings {
    /// Common settings.
    pub program: CommonSettings,
    /// KUKA KRL.
    pub kuka: KukaSettings,
    /// ABB RAPID.
    pub abb: AbbSettings,
    /// Stäubli VAL3.
    pub staubli: StaubliSettings,
    /// Universal Robots.
    pub ur: UrSettings,
    /// G-code.
    pub gcode: GcodeSettings,
    /// FANUC TP.
    pub fanuc: FanucSettings,
    /// Yaskawa INFORM.
    pub inform: InformSettings,
}

impl ProgramSettings {
    /// Parse a TOML template; `source` names the file in errors.
    pub fn from_toml_str(text: &str, source: &str) -> Result<ProgramSettings, ProgramError> {
        let settings: ProgramSettings =
            toml::from_str(text).map_err(|e| ProgramError::Settings {
                source_name: source.to_string(),
                key: "(file)".into(),
                message: e.to_string(),
            })?;
        settings.validate(source)?;
        Ok(settings)
    }

    /// Read a TOML template file.
    pub fn load(path: &std::path::Path) -> Result<ProgramSettings, ProgramError> {
        let source = path.display().to_string();
        // A program template is a few lines: at most 1 MiB, counted while reading.
        let text = deflex_files::read_bounded(path, 1 << 20)
            .map_err(|e| e.reported_as::<ProgramError>("a program template"))?;
        Self::from_toml_str(&text, &source)
    }

    /// Check every range; the error names the key.
    pub fn validate(&self, source: &str) -> Result<(), ProgramError> {
        let check = |key: &str, value: f64, lo: f64, hi: f64| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(ProgramError::Settings {
                    source_name: source.to_string(),
                    key: key.to_string(),
                    message: format!("expected a number within {lo} ..= {hi}, got {value}"),
                })
            }
        };
        let p = &self.program;
        if p.name.trim().is_empty() || p.name.len() > 200 {
            return Err(ProgramError::Settings {
                source_name: source.to_string(),
                key: "program.name".into(),
                message: "expected a non-empty name of at most 200 characters".into(),
            });
        }
        check(
            "program.max_points",
            p.max_points as f64,
            1.0,
            MAX_POINTS_LIMIT as f64,
        )?;
        check("program.max_speed_mm_s", p.max_speed_mm_s, 0.1, 2000.0)?;
        check("program.rapid_speed_mm_s", p.rapid_speed_mm_s, 0.1, 2000.0)?;
        check("program.blend_mm", p.blend_mm, 0.0, 50.0)?;
        check(
            "program.max_points_per_part",
            p.max_points_per_part as f64,
            10.0,
            100_000.0,
        )?;
        check("program.max_part_kb", p.max_part_kb as f64, 16.0, 100_000.0)?;
        check("program.clearance_mm", p.clearance_mm, 1.0, 2000.0)?;
        check(
            "program.approach_speed_mm_s",
            p.approach_speed_mm_s,
            0.1,
            500.0,
        )?;
        for (key, mass) in [
            ("program.tool_mass_kg", p.tool_mass_kg),
            ("abb.tool_mass_kg", self.abb.tool_mass_kg),
        ] {
            if let Some(m) = mass {
                check(key, m, 0.001, 500.0)?;
            }
        }
        for (key, cog) in [
            ("program.tool_cog_mm", p.tool_cog_mm),
            ("abb.tool_cog_mm", self.abb.tool_cog_mm),
        ] {
            for (i, v) in cog.iter().flatten().enumerate() {
                check(&format!("{key}[{i}]"), *v, -5000.0, 5000.0)?;
            }
        }
        check(
            "program.orientation_speed_deg_s",
            p.orientation_speed_deg_s,
            1.0,
            360.0,
        )?;
        let k = &self.kuka;
        check("kuka.tool", f64::from(k.tool), 1.0, 16.0)?;
        check("kuka.base", f64::from(k.base), 0.0, 32.0)?;
        check("kuka.ptp_speed_percent", k.ptp_speed_percent, 1.0, 100.0)?;
        check("kuka.advance", f64::from(k.advance), 1.0, 5.0)?;
        let a = &self.abb;
        for (key, name) in [
            ("abb.tool_name", &a.tool_name),
            ("abb.wobj_name", &a.wobj_name),
        ] {
            crate::program::names::check_identifier(
                name,
                crate::program::names::RAPID,
                key,
                source,
            )?;
        }
        let s = &self.staubli;
        for (key, name) in [
            ("staubli.tool_name", &s.tool_name),
            ("staubli.frame_name", &s.frame_name),
        ] {
            crate::program::names::check_identifier(
                name,
                crate::program::names::VAL3,
                key,
                source,
            )?;
        }
        check("staubli.joint_percent", s.joint_percent, 1.0, 100.0)?;
        let u = &self.ur;
        check("ur.acceleration_m_s2", u.acceleration_m_s2, 0.01, 5.0)?;
        check(
            "ur.approach_joint_speed_rad_s",
            u.approach_joint_speed_rad_s,
            0.01,
            3.0,
        )?;
        check(
            "ur.approach_joint_acceleration_rad_s2",
            u.approach_joint_acceleration_rad_s2,
            0.01,
            10.0,
        )?;
        check("gcode.decimals", self.gcode.decimals as f64, 3.0, 6.0)?;
        let f = &self.fanuc;
        check("fanuc.uframe", f64::from(f.uframe), 0.0, 9.0)?;
        check("fanuc.utool", f64::from(f.utool), 1.0, 10.0)?;
        check("fanuc.payload", f64::from(f.payload), 1.0, 10.0)?;
        check(
            "fanuc.joint_percent",
            f64::from(f.joint_percent),
            1.0,
            100.0,
        )?;
        check("fanuc.cnt", f64::from(f.cnt), 0.0, 100.0)?;
        let y = &self.inform;
        check("inform.user", f64::from(y.user), 1.0, 63.0)?;
        check("inform.tool", f64::from(y.tool), 0.0, 63.0)?;
        check("inform.joint_percent", y.joint_percent, 0.01, 100.0)?;
        check("inform.pl", f64::from(y.pl), 0.0, 8.0)?;
        Ok(())
    }
}

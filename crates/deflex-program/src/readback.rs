//! Readers of the programs this crate writes: the poses and speeds of every motion, back in SI
//! units and as rotation matrices. The round-trip tests compare them with the path; a later
//! tool can use them to learn which compensation a program already contains.
//!
//! The readers accept exactly what the exporters write (one motion per line, the exporters'
//! keywords and data names), not the whole of each language. Inputs are bounded: at most
//! [`MAX_READ_BYTES`] of text, [`MAX_READ_LINE`] characters per line and
//! [`crate::settings::MAX_POINTS_LIMIT`] motions.

use crate::error::ProgramError;
use crate::orientation::{
    rotation_from_abb_quaternion, rotation_from_kuka_abc_deg, rotation_from_staubli_rxryrz_deg,
    rotation_from_ur_rotation_vector,
};
use crate::settings::MAX_POINTS_LIMIT;
use crate::{Format, ProgramFile};
use nalgebra::{Rotation3, Vector3};
use std::collections::HashMap;

/// Largest program text read (bytes).
pub const MAX_READ_BYTES: usize = 512 << 20;
/// Longest line read (characters).
pub const MAX_READ_LINE: usize = 4096;

/// One motion read back from a program.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadPoint {
    /// TCP position in the program frame (m).
    pub position_m: Vector3<f64>,
    /// TCP orientation in the program frame (`None` for G-code).
    pub rotation: Option<Rotation3<f64>>,
    /// Programmed TCP speed of the motion (m/s); `None` for the approach motion (PTP / MoveJ /
    /// movej) and for G-code rapids (`G0`).
    pub speed_m_s: Option<f64>,
}

/// Read the motions of the files `export` produced for `format`, main program and parts in
/// the order the program runs them: the clearance point above the start, the path (its first
/// point is the approach's target), the clearance point above the end. Joint moves (KUKA
/// `PTP $H_POS`, RAPID `MoveAbsJ`, VAL3 `movej(jStart…)`, UR `movej([…])`) are not Cartesian
/// motions and are skipped.
pub fn read_files(format: Format, files: &[ProgramFile]) -> Result<Vec<ReadPoint>, ProgramError> {
    let find = |suffix: &str| {
        files
            .iter()
            .find(|f| f.path.ends_with(suffix))
            .ok_or_else(|| ProgramError::Read {
                file: format!("*{suffix}"),
                line: 0,
                message: format!("no {suffix} file among the {} program files", format.name()),
            })
    };
    let by_name = |name: &str, extension: &str| {
        files
            .iter()
            .find(|f| f.path == format!("{name}.{extension}"))
            .ok_or_else(|| ProgramError::Read {
                file: format!("{name}.{extension}"),
                line: 0,
                message: "the main program calls it, but it is not among the files".into(),
            })
    };
    match format {
        Format::Krl => {
            let main = find(".src")?;
            let mut points = Vec::new();
            let mut speed = None;
            read_krl_into(
                &main.contents,
                &main.path,
                &mut points,
                &mut speed,
                Some(&|name| by_name(name, "src")),
            )?;
            Ok(points)
        }
        Format::Rapid => {
            let main = find(".mod")?;
            let mut points = Vec::new();
            read_rapid_into(
                &main.contents,
                &main.path,
                &mut points,
                &mut HashMap::new(),
                Some(&|name| by_name(name, "mod")),
            )?;
            Ok(points)
        }
        Format::Val3 => {
            let data = find(".dtx")?;
            read_val3_data(&data.contents, &data.path)
        }
        Format::UrScript => {
            let mut points = Vec::new();
            for file in files.iter().filter(|f| f.path.ends_with(".script")) {
                points.extend(read_urscript(&file.contents, &file.path)?);
                if points.len() > MAX_POINTS_LIMIT + 2 {
                    return Err(ProgramError::Read {
                        file: file.path.clone(),
                        line: 0,
                        message: format!("more than {MAX_POINTS_LIMIT} motions"),
                    });
                }
            }
            Ok(points)
        }
        Format::Gcode => {
            let file = find(".gcode")?;
            read_gcode(&file.contents, &file.path)
        }
    }
}

/// A program file by name (a part a main program calls).
type PartLookup<'a> = dyn Fn(&str) -> Result<&'a ProgramFile, ProgramError> + 'a;

struct Lines<'a> {
    file: &'a str,
}

impl Lines<'_> {
    fn error(&self, line: usize, message: impl Into<String>) -> ProgramError {
        ProgramError::Read {
            file: self.file.to_string(),
            line,
            message: message.into(),
        }
    }

    /// Numbered lines after the size checks.
    fn check<'t>(&self, text: &'t str) -> Result<Vec<(usize, &'t str)>, ProgramError> {
        if text.len() > MAX_READ_BYTES {
            return Err(self.error(0, format!("larger than {MAX_READ_BYTES} bytes")));
        }
        text.lines()
            .enumerate()
            .map(|(i, l)| {
                if l.chars().count() > MAX_READ_LINE {
                    Err(self.error(i + 1, format!("longer than {MAX_READ_LINE} characters")))
                } else {
                    Ok((i + 1, l.trim()))
                }
            })
            .collect()
    }

    fn number(&self, line: usize, text: &str, what: &str) -> Result<f64, ProgramError> {
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.error(line, format!("{what}: expected a number, got \"{text}\"")))
    }

    fn push(
        &self,
        points: &mut Vec<ReadPoint>,
        line: usize,
        point: ReadPoint,
    ) -> Result<(), ProgramError> {
        if points.len() >= MAX_POINTS_LIMIT {
            return Err(self.error(line, format!("more than {MAX_POINTS_LIMIT} motions")));
        }
        points.push(point);
        Ok(())
    }
}

/// KUKA `.src`: `PTP {…}` (a Cartesian joint move; `PTP $H_POS` is skipped), `$VEL.CP = v`
/// (m/s) and `LIN {X …, A …}` lines (a single file; [`read_files`] follows the part calls).
pub fn read_krl(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let mut points = Vec::new();
    read_krl_into(text, file, &mut points, &mut None, None)?;
    Ok(points)
}

fn read_krl_into(
    text: &str,
    file: &str,
    points: &mut Vec<ReadPoint>,
    speed: &mut Option<f64>,
    part: Option<&PartLookup>,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    for (n, line) in r.check(text)? {
        let line = line.split(';').next().unwrap_or("").trim();
        if let Some(v) = line.strip_prefix("$VEL.CP =") {
            *speed = Some(r.number(n, v, "$VEL.CP")?);
            continue;
        }
        if let (Some(lookup), Some(name)) = (part, line.strip_suffix("( )"))
            && !name.is_empty()
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            let file = lookup(name)?;
            read_krl_into(&file.contents, &file.path, points, speed, None)?;
            continue;
        }
        let (joint_move, rest) = if let Some(rest) = line.strip_prefix("PTP ") {
            (true, rest)
        } else if let Some(rest) = line.strip_prefix("LIN ") {
            (false, rest)
        } else {
            continue;
        };
        if rest.trim_start().starts_with('$') {
            continue; // PTP $H_POS: HOME, a joint position
        }
        let open = rest
            .find('{')
            .ok_or_else(|| r.error(n, "expected a frame {X …}"))?;
        let close = rest.find('}').ok_or_else(|| r.error(n, "unclosed frame"))?;
        let mut values: HashMap<&str, f64> = HashMap::new();
        for item in rest[open + 1..close].split(',') {
            let mut parts = item.split_whitespace();
            let (Some(key), Some(value), None) = (parts.next(), parts.next(), parts.next()) else {
                return Err(r.error(n, format!("expected `KEY value`, got \"{item}\"")));
            };
            values.insert(key, r.number(n, value, key)?);
        }
        for key in ["S", "T"] {
            if let Some(v) = values.get(key)
                && !(v.fract() == 0.0 && (0.0..64.0).contains(v))
            {
                return Err(r.error(n, format!("{key} {v}: expected a whole number 0 … 63")));
            }
        }
        let get = |key: &str| {
            values
                .get(key)
                .copied()
                .ok_or_else(|| r.error(n, format!("frame without {key}")))
        };
        let point = ReadPoint {
            position_m: Vector3::new(get("X")?, get("Y")?, get("Z")?) * 1e-3,
            rotation: Some(rotation_from_kuka_abc_deg([
                get("A")?,
                get("B")?,
                get("C")?,
            ])),
            speed_m_s: if joint_move {
                None
            } else {
                Some(speed.ok_or_else(|| r.error(n, "LIN before any $VEL.CP"))?)
            },
        };
        r.push(points, n, point)?;
    }
    Ok(())
}

/// Every number in a RAPID aggregate such as `[[1,2,3],[1,0,0,0],…]`.
fn aggregate_numbers(r: &Lines, line: usize, text: &str) -> Result<Vec<f64>, ProgramError> {
    text.split(['[', ']', ','])
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| r.number(line, t, "aggregate value"))
        .collect()
}

/// ABB `.mod`: `CONST speeddata NAME := [v, …];` declarations and `MoveJ`/`MoveL` lines with an
/// inline robtarget (`MoveAbsJ` joint moves are skipped; a single module, [`read_files`] follows
/// the part calls).
pub fn read_rapid(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let mut points = Vec::new();
    read_rapid_into(text, file, &mut points, &mut HashMap::new(), None)?;
    Ok(points)
}

fn read_rapid_into(
    text: &str,
    file: &str,
    points: &mut Vec<ReadPoint>,
    speeds: &mut HashMap<String, f64>,
    part: Option<&PartLookup>,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    for (n, line) in r.check(text)? {
        if let Some(rest) = line.strip_prefix("CONST speeddata ") {
            let (name, value) = rest
                .split_once(":=")
                .ok_or_else(|| r.error(n, "expected NAME := [...]"))?;
            let values = aggregate_numbers(&r, n, value.trim().trim_end_matches(';'))?;
            let v = *values
                .first()
                .ok_or_else(|| r.error(n, "empty speeddata"))?;
            speeds.insert(name.trim().to_string(), v * 1e-3);
            continue;
        }
        if let (Some(lookup), Some(name)) = (part, line.strip_suffix(';'))
            && name.contains("_p")
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            let file = lookup(name)?;
            read_rapid_into(&file.contents, &file.path, points, speeds, None)?;
            continue;
        }
        let (joint_move, rest) = if let Some(rest) = line.strip_prefix("MoveJ ") {
            (true, rest)
        } else if let Some(rest) = line.strip_prefix("MoveL ") {
            (false, rest)
        } else {
            continue;
        };
        let end = rest
            .find("]],")
            .ok_or_else(|| r.error(n, "expected an inline robtarget [[…]]"))?;
        let values = aggregate_numbers(&r, n, &rest[..end + 2])?;
        if values.len() < 11 {
            return Err(r.error(n, "robtarget with fewer than 11 values"));
        }
        if values[7..11]
            .iter()
            .any(|c| c.fract() != 0.0 || c.abs() > 8.0)
        {
            return Err(r.error(n, "robconf values must be whole numbers"));
        }
        let speed_name = rest[end + 3..]
            .split(',')
            .next()
            .map(str::trim)
            .unwrap_or_default();
        let speed = if joint_move {
            None
        } else {
            Some(
                *speeds
                    .get(speed_name)
                    .ok_or_else(|| r.error(n, format!("unknown speeddata \"{speed_name}\"")))?,
            )
        };
        let point = ReadPoint {
            position_m: Vector3::new(values[0], values[1], values[2]) * 1e-3,
            rotation: Some(rotation_from_abb_quaternion([
                values[3], values[4], values[5], values[6],
            ])),
            speed_m_s: speed,
        };
        r.push(points, n, point)?;
    }
    Ok(())
}

/// The value of attribute `name` in an XML element line (`name="value"`).
fn attribute<'t>(line: &'t str, name: &str) -> Option<&'t str> {
    let key = format!(" {name}=\"");
    let start = line.find(&key)? + key.len();
    let len = line[start..].find('"')?;
    Some(&line[start..start + len])
}

/// A pose of a data array: `(key, position, rotation)`.
type KeyedPose = (usize, Vector3<f64>, Rotation3<f64>);

/// Stäubli `.dtx`: `pClear` (the clearance points), the parts' `pPathK` (pointRx) and
/// `nSpeedK` (num) arrays, `mPath` and `mApproach` (mdesc), in the order `start.pgx` runs them:
/// `pClear[0]`, `pPath1[0]` (the approach), the parts' points (their `mPath` speeds),
/// `pClear[1]` (the retract); the clearance points and the approach at `mApproach[1]`.
pub fn read_val3_data(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut block = String::new();
    let mut arrays: HashMap<String, Vec<KeyedPose>> = HashMap::new();
    let mut numbers: HashMap<String, HashMap<usize, usize>> = HashMap::new();
    let mut speeds: HashMap<String, HashMap<usize, f64>> = HashMap::new();
    let mut total = 0usize;
    for (n, line) in r.check(text)? {
        if line.starts_with("<Data ") {
            block = attribute(line, "name").unwrap_or_default().to_string();
            continue;
        }
        if !line.starts_with("<Value ") {
            continue;
        }
        let key: usize = attribute(line, "key")
            .and_then(|k| k.parse().ok())
            .ok_or_else(|| r.error(n, "Value without an integer key"))?;
        let get = |name: &str| {
            attribute(line, name)
                .ok_or_else(|| r.error(n, format!("Value without {name}")))
                .and_then(|v| r.number(n, v, name))
        };
        if block == "pClear" || block.starts_with("pPath") {
            total += 1;
            if total > MAX_POINTS_LIMIT + 2 {
                return Err(r.error(n, format!("more than {MAX_POINTS_LIMIT} points")));
            }
            arrays.entry(block.clone()).or_default().push((
                key,
                Vector3::new(get("x")?, get("y")?, get("z")?) * 1e-3,
                rotation_from_staubli_rxryrz_deg([get("rx")?, get("ry")?, get("rz")?]),
            ));
        } else if block.starts_with("nSpeed") {
            numbers
                .entry(block.clone())
                .or_default()
                .insert(key, get("value")? as usize);
        } else if block == "mPath" || block == "mApproach" {
            speeds
                .entry(block.clone())
                .or_default()
                .insert(key, get("tmax")? * 1e-3);
        }
    }
    let ordered = |name: &str| -> Result<Vec<KeyedPose>, ProgramError> {
        let list = arrays.get(name).cloned().unwrap_or_default();
        for (i, (key, ..)) in list.iter().enumerate() {
            if *key != i {
                return Err(r.error(0, format!("{name} keys out of order at {key}")));
            }
        }
        Ok(list)
    };
    let approach = speeds
        .get("mApproach")
        .and_then(|m| m.get(&1))
        .copied()
        .ok_or_else(|| r.error(0, "no mApproach[1]"))?;
    let clear = ordered("pClear")?;
    if clear.len() != 2 {
        return Err(r.error(0, format!("pClear has {} points, expected 2", clear.len())));
    }
    let point = |(_, position_m, rotation): &KeyedPose, speed: f64| ReadPoint {
        position_m: *position_m,
        rotation: Some(*rotation),
        speed_m_s: Some(speed),
    };
    let mut out = vec![point(&clear[0], approach)];
    for part in 1..=MAX_POINTS_LIMIT {
        let name = format!("pPath{part}");
        if !arrays.contains_key(&name) {
            break;
        }
        let list = ordered(&name)?;
        let indices = numbers.get(&format!("nSpeed{part}"));
        for (i, pose) in list.iter().enumerate() {
            let speed = if part == 1 && i == 0 {
                approach
            } else {
                let k = indices
                    .and_then(|m| m.get(&i))
                    .ok_or_else(|| r.error(0, format!("no nSpeed{part}[{i}]")))?;
                *speeds
                    .get("mPath")
                    .and_then(|m| m.get(k))
                    .ok_or_else(|| r.error(0, format!("no mPath[{k}]")))?
            };
            out.push(point(pose, speed));
        }
    }
    out.push(point(&clear[1], approach));
    Ok(out)
}

/// UR `.script`: `movej(pose_trans(deflex_frame, p[…]), …)` and `movel(…, v=…, …)` lines.
pub fn read_urscript(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut points = Vec::new();
    for (n, line) in r.check(text)? {
        let approach = if line.starts_with("movej([") {
            continue; // a joint move
        } else if line.starts_with("movej(") {
            true
        } else if line.starts_with("movel(") {
            false
        } else {
            continue;
        };
        let start = line
            .find("p[")
            .ok_or_else(|| r.error(n, "expected a pose p[…]"))?
            + 2;
        let len = line[start..]
            .find(']')
            .ok_or_else(|| r.error(n, "unclosed pose"))?;
        let values: Vec<f64> = line[start..start + len]
            .split(',')
            .map(|t| r.number(n, t, "pose value"))
            .collect::<Result<_, _>>()?;
        if values.len() != 6 {
            return Err(r.error(n, format!("pose with {} values, expected 6", values.len())));
        }
        let speed = if approach {
            None
        } else {
            let v = line
                .find("v=")
                .map(|i| &line[i + 2..])
                .and_then(|rest| rest.split([',', ')']).next())
                .ok_or_else(|| r.error(n, "movel without v="))?;
            Some(r.number(n, v, "v")?)
        };
        let point = ReadPoint {
            position_m: Vector3::new(values[0], values[1], values[2]),
            rotation: Some(rotation_from_ur_rotation_vector([
                values[3], values[4], values[5],
            ])),
            speed_m_s: speed,
        };
        r.push(&mut points, n, point)?;
    }
    Ok(points)
}

/// G-code: `G0`/`G1` lines with `X Y Z` and modal `F` (mm/min); comments `( … )` (also after
/// a motion); the safe-start and end lines are not motions.
pub fn read_gcode(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut points = Vec::new();
    let mut feed: Option<f64> = None;
    for (n, line) in r.check(text)? {
        let line = line.split('(').next().unwrap_or("").trim();
        let rapid = if line.starts_with("G0 ") {
            true
        } else if line.starts_with("G1 ") {
            false
        } else {
            continue;
        };
        let mut xyz = [None; 3];
        for word in line.split_whitespace().skip(1) {
            let (letter, value) = word.split_at(1);
            let v = r.number(n, value, letter)?;
            match letter {
                "X" => xyz[0] = Some(v),
                "Y" => xyz[1] = Some(v),
                "Z" => xyz[2] = Some(v),
                "F" => feed = Some(v),
                _ => return Err(r.error(n, format!("unexpected word {word}"))),
            }
        }
        let [Some(x), Some(y), Some(z)] = xyz else {
            return Err(r.error(n, "a motion without all of X, Y and Z"));
        };
        let speed = if rapid {
            None
        } else {
            Some(feed.ok_or_else(|| r.error(n, "G1 before any F"))? / 60.0 * 1e-3)
        };
        r.push(
            &mut points,
            n,
            ReadPoint {
                position_m: Vector3::new(x, y, z) * 1e-3,
                rotation: None,
                speed_m_s: speed,
            },
        )?;
    }
    Ok(points)
}

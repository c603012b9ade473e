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

/// A reader of one program file: `(text, file name)` → motions.
type Reader = fn(&str, &str) -> Result<Vec<ReadPoint>, ProgramError>;

/// Read the motions of the files `export` produced for `format`.
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
    let (file, read): (&ProgramFile, Reader) = match format {
        Format::Krl => (find(".src")?, read_krl),
        Format::Rapid => (find(".mod")?, read_rapid),
        Format::Val3 => (find(".dtx")?, read_val3_data),
        Format::UrScript => (find(".script")?, read_urscript),
        Format::Gcode => (find(".gcode")?, read_gcode),
    };
    read(&file.contents, &file.path)
}

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

/// KUKA `.src`: `PTP {…}` (approach), `$VEL.CP = v` (m/s) and `LIN {X …, A …}` lines.
pub fn read_krl(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut points = Vec::new();
    let mut speed: Option<f64> = None;
    for (n, line) in r.check(text)? {
        if let Some(v) = line.strip_prefix("$VEL.CP =") {
            speed = Some(r.number(n, v, "$VEL.CP")?);
            continue;
        }
        let (approach, rest) = if let Some(rest) = line.strip_prefix("PTP ") {
            (true, rest)
        } else if let Some(rest) = line.strip_prefix("LIN ") {
            (false, rest)
        } else {
            continue;
        };
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
            speed_m_s: if approach {
                None
            } else {
                Some(speed.ok_or_else(|| r.error(n, "LIN before any $VEL.CP"))?)
            },
        };
        r.push(&mut points, n, point)?;
    }
    Ok(points)
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
/// inline robtarget.
pub fn read_rapid(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut points = Vec::new();
    let mut speeds: HashMap<String, f64> = HashMap::new();
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
        let (approach, rest) = if let Some(rest) = line.strip_prefix("MoveJ ") {
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
        if values.len() < 7 {
            return Err(r.error(n, "robtarget with fewer than 7 values"));
        }
        let speed_name = rest[end + 3..]
            .split(',')
            .next()
            .map(str::trim)
            .unwrap_or_default();
        let speed = if approach {
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
        r.push(&mut points, n, point)?;
    }
    Ok(points)
}

/// The value of attribute `name` in an XML element line (`name="value"`).
fn attribute<'t>(line: &'t str, name: &str) -> Option<&'t str> {
    let key = format!(" {name}=\"");
    let start = line.find(&key)? + key.len();
    let len = line[start..].find('"')?;
    Some(&line[start..start + len])
}

/// Stäubli `.dtx`: the `pPath` (pointRx), `nSpeed` (num) and `mPath` (mdesc) arrays.
pub fn read_val3_data(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut block = String::new();
    let mut poses: Vec<(usize, Vector3<f64>, Rotation3<f64>)> = Vec::new();
    let mut speed_index: HashMap<usize, usize> = HashMap::new();
    let mut speeds: HashMap<usize, f64> = HashMap::new();
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
        match block.as_str() {
            "pPath" => {
                if poses.len() >= MAX_POINTS_LIMIT {
                    return Err(r.error(n, format!("more than {MAX_POINTS_LIMIT} points")));
                }
                poses.push((
                    key,
                    Vector3::new(get("x")?, get("y")?, get("z")?) * 1e-3,
                    rotation_from_staubli_rxryrz_deg([get("rx")?, get("ry")?, get("rz")?]),
                ));
            }
            "nSpeed" => {
                speed_index.insert(key, get("value")? as usize);
            }
            "mPath" => {
                speeds.insert(key, get("tmax")? * 1e-3);
            }
            _ => {}
        }
    }
    poses
        .into_iter()
        .enumerate()
        .map(|(i, (key, position_m, rotation))| {
            if key != i {
                return Err(r.error(0, format!("pPath keys out of order at {key}")));
            }
            let speed = if i == 0 {
                None
            } else {
                let k = speed_index
                    .get(&i)
                    .ok_or_else(|| r.error(0, format!("no nSpeed[{i}]")))?;
                Some(
                    *speeds
                        .get(k)
                        .ok_or_else(|| r.error(0, format!("no mPath[{k}]")))?,
                )
            };
            Ok(ReadPoint {
                position_m,
                rotation: Some(rotation),
                speed_m_s: speed,
            })
        })
        .collect()
}

/// UR `.script`: `movej(pose_trans(deflex_frame, p[…]), …)` and `movel(…, v=…, …)` lines.
pub fn read_urscript(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut points = Vec::new();
    for (n, line) in r.check(text)? {
        let approach = if line.starts_with("movej(") {
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

/// G-code: `G0`/`G1` lines with `X Y Z` and modal `F` (mm/min); comments `( … )`.
pub fn read_gcode(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    let r = Lines { file };
    let mut points = Vec::new();
    let mut feed: Option<f64> = None;
    for (n, line) in r.check(text)? {
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

//! Readers of the programs this crate writes: the poses and speeds of every motion, back in SI
//! units and as rotation matrices. The round-trip tests compare them with the path; a later
//! tool can use them to learn which compensation a program already contains.
//!
//! The readers accept exactly what the exporters write (one motion per line, the exporters'
//! keywords and data names), not the whole of each language. Inputs are bounded: at most
//! [`MAX_READ_BYTES`] of text, [`MAX_READ_LINE`] characters per line and
//! [`crate::program::settings::MAX_POINTS_LIMIT`] motions.

use crate::program::error::ProgramError;
use crate::program::settings::MAX_POINTS_LIMIT;
use crate::program::{Format, ProgramFile};
use deflex_files::{FileIoError, FileTooLarge};
use deflex_model::conventions::{
    rotation_from_abb_quaternion, rotation_from_fanuc_wpr_deg, rotation_from_kuka_abc_deg,
    rotation_from_rotation_vector, rotation_from_staubli_rxryrz_deg,
    rotation_from_yaskawa_rxryrz_deg,
};
use nalgebra::{Rotation3, Vector3};
use std::collections::HashMap;
use std::io::{BufRead, Read as _};
use std::path::{Path, PathBuf};

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

/// Where a reader finds a program's files: in memory ([`MemorySource`]) or in a folder
/// ([`DirectorySource`]).
pub trait ProgramSource {
    /// The file at `path` (relative, as the exporter named it), for reading line by line.
    fn open(&self, path: &str) -> Result<Box<dyn BufRead + '_>, ProgramError>;
}

/// Program files in memory (what [`crate::program::export`] returns).
pub struct MemorySource<'a>(pub &'a [ProgramFile]);

impl ProgramSource for MemorySource<'_> {
    fn open(&self, path: &str) -> Result<Box<dyn BufRead + '_>, ProgramError> {
        self.0
            .iter()
            .find(|f| f.path == path)
            .map(|f| Box::new(f.contents.as_bytes()) as Box<dyn BufRead>)
            .ok_or_else(|| ProgramError::Read {
                file: path.to_string(),
                line: 0,
                message: "not among the program files".into(),
            })
    }
}

/// Program files in a folder, read from disk line by line.
pub struct DirectorySource {
    dir: PathBuf,
}

impl DirectorySource {
    /// The files under `dir`.
    pub fn new(dir: &Path) -> DirectorySource {
        DirectorySource {
            dir: dir.to_path_buf(),
        }
    }
}

impl ProgramSource for DirectorySource {
    fn open(&self, path: &str) -> Result<Box<dyn BufRead + '_>, ProgramError> {
        if path.split('/').any(|part| part.is_empty() || part == "..") {
            return Err(ProgramError::Read {
                file: path.to_string(),
                line: 0,
                message: "not a plain relative path".into(),
            });
        }
        let full = self.dir.join(path);
        let file = std::fs::File::open(&full).map_err(|e| FileIoError::new(&full, e))?;
        Ok(Box::new(std::io::BufReader::new(file)))
    }
}

/// What a reader does with each motion it reads.
type Emit<'e> = dyn FnMut(ReadPoint) -> Result<(), ProgramError> + 'e;

/// Read the motions of the files `export` produced for `format`, main program and parts in
/// the order the program runs them: the clearance point above the start, the path (its first
/// point is the approach's target), the clearance point above the end. Joint moves (KUKA
/// `PTP $H_POS`, RAPID `MoveAbsJ`, VAL3 `movej(jStart…)`, UR `movej([…])`) are not Cartesian
/// motions and are skipped.
pub fn read_files(format: Format, files: &[ProgramFile]) -> Result<Vec<ReadPoint>, ProgramError> {
    let paths: Vec<String> = files.iter().map(|f| f.path.clone()).collect();
    let mut points = Vec::new();
    read_program(format, &MemorySource(files), &paths, &mut |p| {
        points.push(p);
        Ok(())
    })?;
    Ok(points)
}

/// [`read_files`] from any [`ProgramSource`], handing each motion to `on_point` as it is read
/// (nothing is held but the line being read and, for VAL3, one part's speed indices): the
/// files are `files` (the paths [`crate::program::export_to`] returned). Returns the motions read.
pub fn read_program(
    format: Format,
    source: &dyn ProgramSource,
    files: &[String],
    on_point: &mut Emit,
) -> Result<usize, ProgramError> {
    let find = |suffix: &str| {
        files
            .iter()
            .find(|f| f.ends_with(suffix))
            .ok_or_else(|| ProgramError::Read {
                file: format!("*{suffix}"),
                line: 0,
                message: format!("no {suffix} file among the {} program files", format.name()),
            })
    };
    let by_name =
        |name: &str, extension: &str| -> Result<(String, Box<dyn BufRead + '_>), ProgramError> {
            let path = format!("{name}.{extension}");
            if !files.contains(&path) {
                return Err(ProgramError::Read {
                    file: path,
                    line: 0,
                    message: "the main program calls it, but it is not among the files".into(),
                });
            }
            let reader = source.open(&path)?;
            Ok((path, reader))
        };
    let mut count = 0usize;
    let mut emit = |p: ReadPoint, file: &str, line: usize| -> Result<(), ProgramError> {
        count += 1;
        if count > MAX_POINTS_LIMIT + 2 {
            return Err(ProgramError::Read {
                file: file.to_string(),
                line,
                message: format!("more than {MAX_POINTS_LIMIT} motions"),
            });
        }
        on_point(p)
    };
    match format {
        Format::Krl => {
            let main = find(".src")?;
            let mut speed = None;
            read_krl_lines(
                &mut source.open(main)?,
                main,
                &mut emit,
                &mut speed,
                Some(&|name| by_name(name, "src")),
            )?;
        }
        Format::Rapid => {
            let main = find(".mod")?;
            read_rapid_lines(
                &mut source.open(main)?,
                main,
                &mut emit,
                &mut HashMap::new(),
                Some(&|name| by_name(name, "mod")),
            )?;
        }
        Format::Val3 => {
            let data = find(".dtx")?;
            read_val3_lines(&mut source.open(data)?, data, &mut emit)?;
        }
        Format::UrScript => {
            for file in files.iter().filter(|f| f.ends_with(".script")) {
                read_urscript_lines(&mut source.open(file)?, file, &mut emit)?;
            }
        }
        Format::Gcode => {
            let file = find(".gcode")?;
            read_gcode_lines(&mut source.open(file)?, file, &mut emit)?;
        }
        Format::Fanuc | Format::Inform => {
            // The main program is the first file (export_to lists it first); it calls its
            // parts by name.
            type TpReader = fn(
                &mut dyn BufRead,
                &str,
                &mut EmitAt,
                Option<&PartLookup>,
            ) -> Result<(), ProgramError>;
            let (extension, read): (&str, TpReader) = if format == Format::Fanuc {
                ("ls", read_fanuc_lines)
            } else {
                ("JBI", read_inform_lines)
            };
            let main = files.first().ok_or_else(|| ProgramError::Read {
                file: format!("*.{extension}"),
                line: 0,
                message: "no program files".into(),
            })?;
            read(
                &mut source.open(main)?,
                main,
                &mut emit,
                Some(&|name| by_name(name, extension)),
            )?;
        }
    }
    Ok(count)
}

/// A part file by name (a part a main program calls): its path and reader.
type PartLookup<'a> = dyn Fn(&str) -> Result<(String, Box<dyn BufRead + 'a>), ProgramError> + 'a;

/// What a line reader does with a motion: the point, its file and line.
type EmitAt<'e> = dyn FnMut(ReadPoint, &str, usize) -> Result<(), ProgramError> + 'e;

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

    /// Each line of `reader`, numbered and trimmed, to `f`; at most [`MAX_READ_BYTES`] of text
    /// and [`MAX_READ_LINE`] characters a line.
    fn each(
        &self,
        reader: &mut dyn BufRead,
        mut f: impl FnMut(usize, &str) -> Result<(), ProgramError>,
    ) -> Result<(), ProgramError> {
        let mut buffer = Vec::with_capacity(256);
        let mut total = 0usize;
        for n in 1.. {
            buffer.clear();
            let read = reader
                .take((MAX_READ_LINE * 4 + 2) as u64)
                .read_until(b'\n', &mut buffer)
                .map_err(|e| self.error(n, e.to_string()))?;
            if read == 0 {
                break;
            }
            total += read;
            if total > MAX_READ_BYTES {
                let (limit, read) = (MAX_READ_BYTES as u64, total as u64);
                return Err(FileTooLarge::new(self.file, "a program file", limit, read).into());
            }
            let text = std::str::from_utf8(&buffer)
                .map_err(|_| self.error(n, "not UTF-8 text"))?
                .trim_end_matches(['\n', '\r']);
            if buffer.last() != Some(&b'\n') && read == MAX_READ_LINE * 4 + 2
                || text.chars().count() > MAX_READ_LINE
            {
                return Err(self.error(n, format!("longer than {MAX_READ_LINE} characters")));
            }
            f(n, text.trim())?;
        }
        Ok(())
    }

    fn number(&self, line: usize, text: &str, what: &str) -> Result<f64, ProgramError> {
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.error(line, format!("{what}: expected a number, got \"{text}\"")))
    }
}

/// Collect a single-file reader's motions.
fn collect(
    read: impl FnOnce(&mut EmitAt) -> Result<(), ProgramError>,
) -> Result<Vec<ReadPoint>, ProgramError> {
    let mut points = Vec::new();
    read(&mut |p, file: &str, line| {
        if points.len() >= MAX_POINTS_LIMIT + 2 {
            return Err(ProgramError::Read {
                file: file.to_string(),
                line,
                message: format!("more than {MAX_POINTS_LIMIT} motions"),
            });
        }
        points.push(p);
        Ok(())
    })?;
    Ok(points)
}

/// KUKA `.src`: `PTP {…}` (a Cartesian joint move; `PTP $H_POS` is skipped), `$VEL.CP = v`
/// (m/s) and `LIN {X …, A …}` lines (a single file; [`read_files`] follows the part calls).
pub fn read_krl(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    collect(|emit| read_krl_lines(&mut text.as_bytes(), file, emit, &mut None, None))
}

fn read_krl_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
    speed: &mut Option<f64>,
    part: Option<&PartLookup>,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    r.each(reader, |n, line| {
        let line = line.split(';').next().unwrap_or("").trim();
        if let Some(v) = line.strip_prefix("$VEL.CP =") {
            *speed = Some(r.number(n, v, "$VEL.CP")?);
            return Ok(());
        }
        if let (Some(lookup), Some(name)) = (part, line.strip_suffix("( )"))
            && !name.is_empty()
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            let (path, mut reader) = lookup(name)?;
            return read_krl_lines(&mut reader, &path, emit, speed, None);
        }
        let (joint_move, rest) = if let Some(rest) = line.strip_prefix("PTP ") {
            (true, rest)
        } else if let Some(rest) = line.strip_prefix("LIN ") {
            (false, rest)
        } else {
            return Ok(());
        };
        if rest.trim_start().starts_with('$') {
            return Ok(()); // PTP $H_POS: HOME, a joint position
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
        emit(point, file, n)
    })
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
    collect(|emit| read_rapid_lines(&mut text.as_bytes(), file, emit, &mut HashMap::new(), None))
}

fn read_rapid_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
    speeds: &mut HashMap<String, f64>,
    part: Option<&PartLookup>,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    r.each(reader, |n, line| {
        if let Some(rest) = line.strip_prefix("CONST speeddata ") {
            let (name, value) = rest
                .split_once(":=")
                .ok_or_else(|| r.error(n, "expected NAME := [...]"))?;
            let values = aggregate_numbers(&r, n, value.trim().trim_end_matches(';'))?;
            let v = *values
                .first()
                .ok_or_else(|| r.error(n, "empty speeddata"))?;
            if speeds.len() >= 1000 {
                return Err(r.error(n, "more than 1000 speeddata"));
            }
            speeds.insert(name.trim().to_string(), v * 1e-3);
            return Ok(());
        }
        if let (Some(lookup), Some(name)) = (part, line.strip_suffix(';'))
            && name.contains("_p")
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            let (path, mut reader) = lookup(name)?;
            return read_rapid_lines(&mut reader, &path, emit, speeds, None);
        }
        let (joint_move, rest) = if let Some(rest) = line.strip_prefix("MoveJ ") {
            (true, rest)
        } else if let Some(rest) = line.strip_prefix("MoveL ") {
            (false, rest)
        } else {
            return Ok(());
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
        emit(point, file, n)
    })
}

/// The value of attribute `name` in an XML element line (`name="value"`).
fn attribute<'t>(line: &'t str, name: &str) -> Option<&'t str> {
    let key = format!(" {name}=\"");
    let start = line.find(&key)? + key.len();
    let len = line[start..].find('"')?;
    Some(&line[start..start + len])
}

/// Stäubli `.dtx`: `pClear` (the clearance points), the parts' `pPathK` (pointRx) and
/// `nSpeedK` (num) arrays, `mPath` and `mApproach` (mdesc), in the order `start.pgx` runs them:
/// `pClear[0]`, `pPath1[0]` (the approach), the parts' points (their `mPath` speeds),
/// `pClear[1]` (the retract); the clearance points and the approach at `mApproach[1]`.
pub fn read_val3_data(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    collect(|emit| read_val3_lines(&mut text.as_bytes(), file, emit))
}

/// The data file as the exporter writes it, in one pass: `mApproach`, `mPath`, `pClear`, then
/// for each part `nSpeedK` followed by `pPathK`, every array's keys in order. Only one part's
/// speed indices are held.
fn read_val3_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    let mut block = String::new();
    let mut approach: HashMap<usize, f64> = HashMap::new();
    let mut path_speeds: HashMap<usize, f64> = HashMap::new();
    let mut clear: Vec<(Vector3<f64>, Rotation3<f64>)> = Vec::new();
    // The part being read (1-based), its speed indices and the next key of its points.
    let mut part = 0usize;
    let mut indices: Vec<usize> = Vec::new();
    let mut next_key = 0usize;
    let mut started = false;
    let mut last_line = 0;
    let point = |position_m: Vector3<f64>, rotation: Rotation3<f64>, speed: f64| ReadPoint {
        position_m,
        rotation: Some(rotation),
        speed_m_s: Some(speed),
    };
    r.each(reader, |n, line| {
        last_line = n;
        if line.starts_with("<Data ") {
            block = attribute(line, "name").unwrap_or_default().to_string();
            if let Some(k) = block.strip_prefix("nSpeed") {
                if k.parse::<usize>().ok() != Some(part + 1) {
                    return Err(r.error(
                        n,
                        format!("{block} out of order: expected nSpeed{}", part + 1),
                    ));
                }
                indices.clear();
            } else if let Some(k) = block.strip_prefix("pPath") {
                if k.parse::<usize>().ok() != Some(part + 1) {
                    return Err(r.error(
                        n,
                        format!("{block} out of order: expected pPath{}", part + 1),
                    ));
                }
                part += 1;
                next_key = 0;
            }
            return Ok(());
        }
        if !line.starts_with("<Value ") {
            return Ok(());
        }
        let key: usize = attribute(line, "key")
            .and_then(|k| k.parse().ok())
            .ok_or_else(|| r.error(n, "Value without an integer key"))?;
        let get = |name: &str| {
            attribute(line, name)
                .ok_or_else(|| r.error(n, format!("Value without {name}")))
                .and_then(|v| r.number(n, v, name))
        };
        let pose = || -> Result<(Vector3<f64>, Rotation3<f64>), ProgramError> {
            Ok((
                Vector3::new(get("x")?, get("y")?, get("z")?) * 1e-3,
                rotation_from_staubli_rxryrz_deg([get("rx")?, get("ry")?, get("rz")?]),
            ))
        };
        let approach_speed = || {
            approach
                .get(&1)
                .copied()
                .ok_or_else(|| r.error(n, "no mApproach[1] before the points"))
        };
        if block == "pClear" {
            if key != clear.len() || key > 1 {
                return Err(r.error(n, format!("pClear keys out of order at {key}")));
            }
            clear.push(pose()?);
        } else if block.starts_with("pPath") {
            if key != next_key {
                return Err(r.error(n, format!("{block} keys out of order at {key}")));
            }
            next_key += 1;
            let (position, rotation) = pose()?;
            let speed = if part == 1 && key == 0 {
                // The clearance point above the start, then the approach onto the first point.
                if clear.len() != 2 {
                    return Err(
                        r.error(n, format!("pClear has {} points, expected 2", clear.len()))
                    );
                }
                let v = approach_speed()?;
                emit(point(clear[0].0, clear[0].1, v), file, n)?;
                started = true;
                v
            } else {
                let k = indices
                    .get(key)
                    .ok_or_else(|| r.error(n, format!("no nSpeed{part}[{key}]")))?;
                *path_speeds
                    .get(k)
                    .ok_or_else(|| r.error(n, format!("no mPath[{k}]")))?
            };
            emit(point(position, rotation, speed), file, n)?;
        } else if block.starts_with("nSpeed") {
            if key != indices.len() {
                return Err(r.error(n, format!("{block} keys out of order at {key}")));
            }
            if indices.len() >= MAX_POINTS_LIMIT {
                return Err(r.error(n, format!("{block}: more than {MAX_POINTS_LIMIT} values")));
            }
            indices.push(get("value")? as usize);
        } else if block == "mPath" || block == "mApproach" {
            let speeds = if block == "mPath" {
                &mut path_speeds
            } else {
                &mut approach
            };
            if speeds.len() >= 1000 {
                return Err(r.error(n, format!("{block}: more than 1000 values")));
            }
            speeds.insert(key, get("tmax")? * 1e-3);
        }
        Ok(())
    })?;
    if !started {
        return Err(r.error(last_line, "no pPath1 points"));
    }
    let v = approach
        .get(&1)
        .copied()
        .ok_or_else(|| r.error(last_line, "no mApproach[1]"))?;
    emit(point(clear[1].0, clear[1].1, v), file, last_line)
}

/// UR `.script`: `movej(pose_trans(deflex_frame, p[…]), …)` and `movel(…, v=…, …)` lines.
pub fn read_urscript(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    collect(|emit| read_urscript_lines(&mut text.as_bytes(), file, emit))
}

fn read_urscript_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    r.each(reader, |n, line| {
        let approach = if line.starts_with("movej([") {
            return Ok(()); // a joint move
        } else if line.starts_with("movej(") {
            true
        } else if line.starts_with("movel(") {
            false
        } else {
            return Ok(());
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
            rotation: Some(rotation_from_rotation_vector([
                values[3], values[4], values[5],
            ])),
            speed_m_s: speed,
        };
        emit(point, file, n)
    })
}

/// G-code, read by [`crate::gcode::LineReader`] (the reader of CAM programs, line by line): the
/// `G0`/`G1` moves with their end and feed (`F` in mm/min, modal) in the order written; the
/// comments, the safe start and the program end are not motions. The coordinate and feed bounds
/// are those of the programs deflex writes ([`crate::gcode::MAX_COORDINATE_BOUND_MM`],
/// [`crate::gcode::MAX_FEED_BOUND_MM_MIN`]); an arc is refused (deflex writes none).
pub fn read_gcode(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    collect(|emit| read_gcode_lines(&mut text.as_bytes(), file, emit))
}

fn read_gcode_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
) -> Result<(), ProgramError> {
    use crate::gcode::{LineReader, MoveKind, ReadOptions};
    let r = Lines { file };
    let gcode_error = |e: crate::gcode::GcodeError| {
        r.error(
            e.line,
            if e.line == 0 {
                e.kind.to_string()
            } else {
                format!("column {}, `{}`: {}", e.column, e.word, e.kind)
            },
        )
    };
    let mut gcode = LineReader::new(&ReadOptions {
        // The start and every motion: the bound on motions below is reached first.
        max_points: MAX_POINTS_LIMIT + 3,
        max_coordinate_mm: crate::gcode::MAX_COORDINATE_BOUND_MM,
        max_feed_mm_min: crate::gcode::MAX_FEED_BOUND_MM_MIN,
        ..ReadOptions::default()
    })
    .map_err(gcode_error)?;
    let mut moved = false;
    r.each(reader, |n, line| {
        // The work offset the program sets itself (`gcode.set_work_offset`), before any motion:
        // a setting, not a motion (the CAM reader refuses G10 in a path it is given).
        if !moved && line.starts_with("G10 L2 P") {
            return Ok(());
        }
        let Some(motion) = gcode.read_line(line).map_err(gcode_error)? else {
            return Ok(());
        };
        let [Some(x), Some(y), Some(z)] = motion.end_mm else {
            return Err(r.error(n, "a motion without all of X, Y and Z"));
        };
        let speed = match motion.kind {
            MoveKind::Rapid => None,
            MoveKind::Linear => motion.feed_mm_s.map(|v| v * 1e-3),
            MoveKind::Arc { .. } => {
                return Err(r.error(n, "an arc (G2/G3): deflex writes straight moves only"));
            }
        };
        moved = true;
        emit(
            ReadPoint {
                position_m: Vector3::new(x, y, z) * 1e-3,
                rotation: None,
                speed_m_s: speed,
            },
            file,
            n,
        )
    })
}

/// A motion or a call in a TP program's `/MN`, resolved once `/POS` is read.
enum TpItem {
    /// `J P[k] …` (speed `None`) or `L P[k] v mm/sec …`, at line `line`.
    Motion {
        index: usize,
        speed_m_s: Option<f64>,
        line: usize,
    },
    /// `CALL NAME ;`
    Call(String),
}

/// FANUC `.ls` (ASCII TP): the `J`/`L` motions of `/MN` with their positions from `/POS`
/// (`UF`, `UT`, `CONFIG` checked for form, X Y Z in mm, W P R in degrees,
/// [`deflex_model::conventions::rotation_from_fanuc_wpr_deg`]); a single file ([`read_files`]
/// follows the `CALL`s to the parts). The motions are held until `/POS` is read (a TP program
/// lists its positions after its instructions), at most one part's.
pub fn read_fanuc(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    collect(|emit| read_fanuc_lines(&mut text.as_bytes(), file, emit, None))
}

/// A TP position record `P[k]{ GP1: UF : u, UT : t, CONFIG : '…', X = … mm, …, R = … deg }`
/// (joined into one line): its number, position (mm) and W P R (deg).
fn tp_position(r: &Lines, n: usize, record: &str) -> Result<(usize, [f64; 6]), ProgramError> {
    let index = record
        .strip_prefix("P[")
        .and_then(|rest| rest.split(']').next())
        .and_then(|k| k.trim().parse::<usize>().ok())
        .ok_or_else(|| r.error(n, "expected a position P[k]{…}"))?;
    let open = record
        .find('{')
        .ok_or_else(|| r.error(n, "position without {"))?;
    let close = record
        .rfind('}')
        .ok_or_else(|| r.error(n, "unclosed position"))?;
    let mut body = record[open + 1..close].trim();
    body = body
        .strip_prefix("GP1:")
        .ok_or_else(|| r.error(n, "position without GP1:"))?;
    // The configuration: 'F U T, t1, t4, t6'.
    let q1 = body
        .find('\'')
        .ok_or_else(|| r.error(n, "position without CONFIG"))?;
    let q2 = body[q1 + 1..]
        .find('\'')
        .ok_or_else(|| r.error(n, "unclosed CONFIG"))?
        + q1
        + 1;
    let config = &body[q1 + 1..q2];
    let mut fields = config.split(',').map(str::trim);
    let letters: Vec<&str> = fields.next().unwrap_or("").split_whitespace().collect();
    let turns: Vec<&str> = fields.collect();
    let valid = letters.len() == 3
        && ["N", "F"].contains(&letters[0])
        && ["U", "D"].contains(&letters[1])
        && ["T", "B"].contains(&letters[2])
        && turns.len() == 3
        && turns
            .iter()
            .all(|t| t.parse::<i32>().is_ok_and(|v| v.abs() <= 8));
    if !valid {
        return Err(r.error(
            n,
            format!("CONFIG '{config}': expected 'N|F U|D T|B, t1, t4, t6'"),
        ));
    }
    let rest = format!("{} {}", &body[..q1], &body[q2 + 1..]);
    let mut values: HashMap<String, f64> = HashMap::new();
    for item in rest.split(',').map(str::trim).filter(|t| !t.is_empty()) {
        let (key, value) = item
            .split_once(['=', ':'])
            .ok_or_else(|| r.error(n, format!("expected `KEY = value`, got \"{item}\"")))?;
        let key = key.trim();
        if key == "CONFIG" {
            continue;
        }
        let mut words = value.split_whitespace();
        let number = r.number(n, words.next().unwrap_or(""), key)?;
        let unit = words.next();
        let want = match key {
            "X" | "Y" | "Z" => Some("mm"),
            "W" | "P" | "R" => Some("deg"),
            "UF" | "UT" => None,
            _ => return Err(r.error(n, format!("unknown position field {key}"))),
        };
        if unit != want || words.next().is_some() {
            return Err(r.error(
                n,
                format!("{key}: expected the unit {want:?}, got {unit:?}"),
            ));
        }
        if matches!(key, "UF" | "UT") && !(number.fract() == 0.0 && (0.0..=10.0).contains(&number))
        {
            return Err(r.error(n, format!("{key} {number}: expected 0 … 10")));
        }
        values.insert(key.to_string(), number);
    }
    let mut out = [0.0; 6];
    for (k, key) in ["X", "Y", "Z", "W", "P", "R"].iter().enumerate() {
        out[k] = *values
            .get(*key)
            .ok_or_else(|| r.error(n, format!("position without {key}")))?;
    }
    for key in ["UF", "UT"] {
        if !values.contains_key(key) {
            return Err(r.error(n, format!("position without {key}")));
        }
    }
    Ok((index, out))
}

fn read_fanuc_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
    part: Option<&PartLookup>,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    let mut section = String::new();
    let mut items: Vec<TpItem> = Vec::new();
    let mut positions: HashMap<usize, [f64; 6]> = HashMap::new();
    let mut record = String::new();
    let mut record_line = 0;
    let mut default_group = false;
    let mut ended = false;
    r.each(reader, |n, line| {
        if ended {
            return Ok(());
        }
        if line.starts_with('/') && record.is_empty() {
            section = line.split_whitespace().next().unwrap_or("").to_string();
            if section == "/END" {
                ended = true;
            }
            return Ok(());
        }
        match section.as_str() {
            "/ATTR" => {
                if let Some(v) = line.strip_prefix("DEFAULT_GROUP") {
                    if !v.trim_start_matches([' ', '\t', '=']).starts_with("1,") {
                        return Err(r.error(n, "DEFAULT_GROUP: expected group 1"));
                    }
                    default_group = true;
                }
            }
            "/MN" => {
                let (_, text) = line
                    .split_once(':')
                    .ok_or_else(|| r.error(n, "expected a numbered line `n:…`"))?;
                let text = text.trim().trim_end_matches(';').trim();
                if let Some(name) = text.strip_prefix("CALL ") {
                    if part.is_some() {
                        items.push(TpItem::Call(name.trim().to_string()));
                        return Ok(());
                    }
                    return Err(r.error(n, "a CALL in a part"));
                }
                let joint = match text.get(..2) {
                    Some("J ") => true,
                    Some("L ") => false,
                    _ => return Ok(()), // comments, frame and tool selection
                };
                let mut words = text[2..].split_whitespace();
                let index = words
                    .next()
                    .and_then(|p| {
                        p.strip_prefix("P[")?
                            .strip_suffix(']')?
                            .parse::<usize>()
                            .ok()
                    })
                    .ok_or_else(|| r.error(n, "expected P[k]"))?;
                let speed = words.next().unwrap_or("");
                let speed_m_s = if joint {
                    let percent = speed
                        .strip_suffix('%')
                        .ok_or_else(|| r.error(n, "J without n%"))?;
                    r.number(n, percent, "joint speed %")?;
                    None
                } else {
                    let v = speed
                        .strip_suffix("mm/sec")
                        .ok_or_else(|| r.error(n, "L without n mm/sec"))?;
                    Some(r.number(n, v, "speed mm/sec")? * 1e-3)
                };
                let termination = words.next().unwrap_or("");
                let valid = termination == "FINE"
                    || termination
                        .strip_prefix("CNT")
                        .and_then(|c| c.parse::<u32>().ok())
                        .is_some_and(|c| c <= 100);
                if !valid || words.next().is_some() {
                    return Err(r.error(n, format!("expected FINE or CNTn, got \"{termination}\"")));
                }
                items.push(TpItem::Motion {
                    index,
                    speed_m_s,
                    line: n,
                });
            }
            "/POS" => {
                if record.is_empty() {
                    record_line = n;
                }
                record.push_str(line);
                record.push(' ');
                if line.ends_with("};") {
                    let (index, values) = tp_position(&r, record_line, record.trim())?;
                    if positions.insert(index, values).is_some() {
                        return Err(r.error(record_line, format!("P[{index}] twice")));
                    }
                    record.clear();
                } else if record.len() > MAX_READ_LINE {
                    return Err(r.error(record_line, "position record too long"));
                }
            }
            _ => {}
        }
        Ok(())
    })?;
    if !ended || !record.is_empty() {
        return Err(r.error(0, "no /END (or an unfinished position)"));
    }
    if !default_group {
        return Err(r.error(0, "no DEFAULT_GROUP in /ATTR"));
    }
    for item in items {
        match item {
            TpItem::Motion {
                index,
                speed_m_s,
                line,
            } => {
                let v = positions
                    .get(&index)
                    .ok_or_else(|| r.error(line, format!("P[{index}] not in /POS")))?;
                let point = ReadPoint {
                    position_m: Vector3::new(v[0], v[1], v[2]) * 1e-3,
                    rotation: Some(rotation_from_fanuc_wpr_deg([v[3], v[4], v[5]])),
                    speed_m_s,
                };
                emit(point, file, line)?;
            }
            TpItem::Call(name) => {
                let lookup = part.expect("calls are only kept with a lookup");
                let (path, mut reader) = lookup(&name)?;
                read_fanuc_lines(&mut reader, &path, emit, None)?;
            }
        }
    }
    Ok(())
}

/// Yaskawa `.JBI` (INFORM job): the `MOVJ` / `MOVL` steps of `//INST` with their positions from
/// `//POS` (`///RECTAN` Cartesian positions, X Y Z in mm, Rx Ry Rz in degrees,
/// [`deflex_model::conventions::rotation_from_yaskawa_rxryrz_deg`]; `///NPOS`, `///POSTYPE`,
/// `///RCONF` and `///GROUP1` checked for form); a single file ([`read_files`] follows the
/// `CALL JOB:`s to the parts).
pub fn read_inform(text: &str, file: &str) -> Result<Vec<ReadPoint>, ProgramError> {
    collect(|emit| read_inform_lines(&mut text.as_bytes(), file, emit, None))
}

fn read_inform_lines(
    reader: &mut dyn BufRead,
    file: &str,
    emit: &mut EmitAt,
    part: Option<&PartLookup>,
) -> Result<(), ProgramError> {
    let r = Lines { file };
    let mut positions: HashMap<usize, [f64; 6]> = HashMap::new();
    let mut npos: Option<usize> = None;
    let mut postype = false;
    let mut rectan = false;
    let mut rconf = false;
    let mut group = false;
    let mut section = "";
    let mut ended = false;
    let mut calls: Vec<(String, usize)> = Vec::new();
    r.each(reader, |n, line| {
        if ended {
            return if line.is_empty() {
                Ok(())
            } else {
                Err(r.error(n, "text after END"))
            };
        }
        if n == 1 {
            return if line == "/JOB" {
                Ok(())
            } else {
                Err(r.error(n, "expected /JOB on the first line"))
            };
        }
        if line.is_empty() {
            return Ok(());
        }
        if line == "//POS" || line == "//INST" {
            section = if line == "//POS" { "pos" } else { "inst" };
            if section == "inst" {
                let count = npos.ok_or_else(|| r.error(n, "//INST before ///NPOS"))?;
                if count != positions.len() {
                    return Err(r.error(
                        n,
                        format!(
                            "///NPOS says {count} positions, //POS holds {}",
                            positions.len()
                        ),
                    ));
                }
                if count > 0 && !(postype && rectan && rconf) {
                    return Err(r.error(n, "positions without ///POSTYPE, ///RECTAN or ///RCONF"));
                }
            }
            return Ok(());
        }
        if let Some(name) = line.strip_prefix("//NAME ") {
            if !crate::program::names::is_valid(name.trim(), &crate::program::names::INFORM) {
                return Err(r.error(n, format!("job name \"{}\"", name.trim())));
            }
            return Ok(());
        }
        match section {
            "pos" => {
                if let Some(v) = line.strip_prefix("///NPOS ") {
                    let c = v.split(',').next().unwrap_or("");
                    npos = Some(
                        c.trim()
                            .parse::<usize>()
                            .map_err(|_| r.error(n, format!("///NPOS \"{v}\"")))?,
                    );
                } else if let Some(v) = line.strip_prefix("///POSTYPE ") {
                    if !matches!(v.trim(), "USER" | "BASE" | "ROBOT") {
                        return Err(
                            r.error(n, format!("///POSTYPE {v}: expected USER, BASE or ROBOT"))
                        );
                    }
                    postype = true;
                } else if line == "///RECTAN" {
                    rectan = true;
                } else if let Some(v) = line.strip_prefix("///RCONF ") {
                    let fields: Vec<&str> = v.split(',').map(str::trim).collect();
                    if !(6..=24).contains(&fields.len())
                        || fields.iter().any(|f| !matches!(*f, "0" | "1"))
                    {
                        return Err(r.error(
                            n,
                            format!("///RCONF {v}: expected 6 to 24 fields of 0 or 1"),
                        ));
                    }
                    rconf = true;
                } else if let Some(v) = line
                    .strip_prefix("///USER ")
                    .or_else(|| line.strip_prefix("///TOOL "))
                {
                    if !v.trim().parse::<u32>().is_ok_and(|k| k <= 63) {
                        return Err(r.error(n, format!("\"{line}\": expected a number 0 … 63")));
                    }
                } else if let Some(rest) = line.strip_prefix('C') {
                    let (k, values) = rest
                        .split_once('=')
                        .ok_or_else(|| r.error(n, "expected Cnnnnn=X,Y,Z,Rx,Ry,Rz"))?;
                    let k = k
                        .parse::<usize>()
                        .ok()
                        .filter(|_| k.len() == 5)
                        .ok_or_else(|| r.error(n, format!("position name C{k}")))?;
                    if !rectan {
                        return Err(r.error(n, "a position before ///RECTAN"));
                    }
                    let fields: Vec<&str> = values.split(',').collect();
                    if fields.len() != 6 {
                        return Err(r.error(
                            n,
                            format!("C{k:05}: expected 6 values, got {}", fields.len()),
                        ));
                    }
                    let mut v = [0.0; 6];
                    for (slot, (text, what)) in v
                        .iter_mut()
                        .zip(fields.iter().zip(["X", "Y", "Z", "Rx", "Ry", "Rz"]))
                    {
                        *slot = r.number(n, text, what)?;
                    }
                    if positions.insert(k, v).is_some() {
                        return Err(r.error(n, format!("C{k:05} twice")));
                    }
                } else {
                    return Err(r.error(n, format!("unexpected line in //POS: \"{line}\"")));
                }
                Ok(())
            }
            "inst" => {
                if line.starts_with("///") {
                    if line == "///GROUP1 RB1" {
                        group = true;
                    }
                    return Ok(());
                }
                if line.starts_with('\'') || line == "NOP" {
                    return Ok(());
                }
                if line == "END" {
                    ended = true;
                    return Ok(());
                }
                if !group {
                    return Err(r.error(n, "an instruction before ///GROUP1 RB1"));
                }
                if let Some(name) = line.strip_prefix("CALL JOB:") {
                    return match part {
                        Some(_) => {
                            calls.push((name.trim().to_string(), n));
                            Ok(())
                        }
                        None => Err(r.error(n, "a CALL in a part")),
                    };
                }
                let mut words = line.split_whitespace();
                let joint = match words.next() {
                    Some("MOVJ") => true,
                    Some("MOVL") => false,
                    _ => return Err(r.error(n, format!("unexpected instruction \"{line}\""))),
                };
                let k = words
                    .next()
                    .and_then(|c| c.strip_prefix('C'))
                    .and_then(|c| c.parse::<usize>().ok())
                    .ok_or_else(|| r.error(n, "expected a position Cnnnnn"))?;
                let v = positions
                    .get(&k)
                    .ok_or_else(|| r.error(n, format!("C{k:05} not in //POS")))?;
                let speed = words.next().unwrap_or("");
                let speed_m_s = if joint {
                    let percent = speed
                        .strip_prefix("VJ=")
                        .ok_or_else(|| r.error(n, "MOVJ without VJ="))?;
                    let percent = r.number(n, percent, "VJ")?;
                    if !(0.0..=100.0).contains(&percent) {
                        return Err(r.error(n, format!("VJ={percent}: expected 0 … 100")));
                    }
                    None
                } else {
                    let v = speed
                        .strip_prefix("V=")
                        .ok_or_else(|| r.error(n, "MOVL without V="))?;
                    Some(r.number(n, v, "V (mm/s)")? * 1e-3)
                };
                if let Some(pl) = words.next() {
                    let valid = pl
                        .strip_prefix("PL=")
                        .and_then(|p| p.parse::<u32>().ok())
                        .is_some_and(|p| p <= 8);
                    if !valid {
                        return Err(r.error(n, format!("expected PL=0 … 8, got \"{pl}\"")));
                    }
                }
                if words.next().is_some() {
                    return Err(r.error(n, format!("unexpected words in \"{line}\"")));
                }
                // Calls come before this motion in the job: read the parts first.
                for (name, _) in calls.drain(..) {
                    let lookup = part.expect("calls are only kept with a lookup");
                    let (path, mut reader) = lookup(&name)?;
                    read_inform_lines(&mut reader, &path, emit, None)?;
                }
                let point = ReadPoint {
                    position_m: Vector3::new(v[0], v[1], v[2]) * 1e-3,
                    rotation: Some(rotation_from_yaskawa_rxryrz_deg([v[3], v[4], v[5]])),
                    speed_m_s,
                };
                emit(point, file, n)
            }
            _ => Err(r.error(n, format!("unexpected line before //POS: \"{line}\""))),
        }
    })?;
    if !ended {
        return Err(r.error(0, "no END"));
    }
    let lookup = part;
    for (name, _) in calls {
        let lookup = lookup.expect("calls are only kept with a lookup");
        let (path, mut reader) = lookup(&name)?;
        read_inform_lines(&mut reader, &path, emit, None)?;
    }
    Ok(())
}

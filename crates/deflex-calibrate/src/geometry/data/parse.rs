//! Parsing absolute measurement CSV text with the crate's one reader
//! ([`crate::measurements::reader`]; the caller reads the file, bounded by
//! [`limits::MAX_FILE_BYTES`]): every value checked once, here, with errors
//! ([`crate::measurements::DataError`]) that name the file, the line, the column and what was
//! expected.

use super::{
    APPROACH, AbsoluteRow, ORIENTATION, PAYLOAD_COM, POSITION, RowOrientation, RowPayload, WRENCH,
    limits,
};
use crate::measurements::reader::{self, Cells, Columns, MeasurementFormat, RowLimit};
use crate::measurements::{
    DataError, HeaderProblem, LabelLength, MAX_COORDINATE_M, MAX_FORCE_N, MAX_JOINT_RAD,
    MAX_MOMENT_NM, MAX_SIGMA_M, MAX_SIGMA_RAD, RowError, RowProblem,
};

/// The absolute format for a robot of `joint_count` joints, as [`reader::read`] reads it.
struct Absolute<'a> {
    joint_count: usize,
    ignored: &'a [String],
}

/// Which optional groups of columns an absolute file's header has.
struct Groups {
    orientation: bool,
    payload_com: bool,
    wrench: bool,
    approach: bool,
}

impl MeasurementFormat for Absolute<'_> {
    type Row = AbsoluteRow;
    type Columns = Groups;
    const ROW_LIMIT: RowLimit = RowLimit::PerFile(limits::MAX_ROWS);
    const RECORD_COLUMN: Option<&'static str> = Some("-");

    fn columns(&self, columns: &Columns) -> Result<Groups, HeaderProblem> {
        let joint_count = self.joint_count;
        let found = columns.joint_count();
        if found != joint_count {
            return Err(HeaderProblem::JointColumns {
                found,
                expected: joint_count,
            });
        }
        let mut required: Vec<&str> = vec!["setup", "target"];
        required.extend(POSITION);
        columns.require(&required)?;
        let strings = |group: &[&str]| group.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let approach: Vec<String> = (1..=joint_count)
            .map(|i| format!("{APPROACH}{i}_rad"))
            .collect();
        let mut known: Vec<String> = ["setup", "target", "config", "sigma_m", "sigma_rad"]
            .iter()
            .chain(&POSITION)
            .chain(&ORIENTATION)
            .chain(&PAYLOAD_COM)
            .chain(&WRENCH)
            .chain(&["payload_kg", "temperature_C", "time_s"])
            .map(|c| c.to_string())
            .collect();
        known.extend((1..=joint_count).map(|i| format!("q{i}_rad")));
        known.extend(approach.iter().cloned());
        columns.check_names(&known, self.ignored, |name| name.starts_with(APPROACH))?;
        Ok(Groups {
            orientation: columns.all_or_none(&strings(&ORIENTATION))?,
            payload_com: columns.all_or_none(&strings(&PAYLOAD_COM))?,
            wrench: columns.all_or_none(&strings(&WRENCH))?,
            approach: columns.all_or_none(&approach)?,
        })
    }

    fn row(&self, groups: &Groups, cells: &Cells<'_>) -> Result<AbsoluteRow, RowError> {
        let joint_count = self.joint_count;
        let q_rad = (1..=joint_count)
            .map(|i| cells.number_in(&format!("q{i}_rad"), MAX_JOINT_RAD, "rad"))
            .collect::<Result<Vec<_>, _>>()?;
        let position_m = triple(cells, POSITION, MAX_COORDINATE_M, "m")?;
        let config = if cells.present("config") {
            Some(label(cells, "config")?)
        } else {
            None
        };
        Ok(AbsoluteRow {
            line: cells.line(),
            setup: label(cells, "setup")?,
            target: label(cells, "target")?,
            config,
            q_rad,
            position_m,
            sigma_m: positive(cells, "sigma_m", MAX_SIGMA_M, "m")?,
            orientation: orientation(cells, groups)?,
            payload: payload(cells, groups)?,
            wrench: wrench(cells, groups)?,
            temperature_c: temperature(cells)?,
            time_s: optional(cells, "time_s", limits::MAX_TIME_S, "s")?,
            approach_rad: approach(cells, groups, joint_count)?,
        })
    }
}

fn label(cells: &Cells<'_>, name: &str) -> Result<String, RowError> {
    cells.label(name, LabelLength::Bytes(limits::MAX_LABEL_BYTES))
}

fn optional(
    cells: &Cells<'_>,
    name: &str,
    limit: f64,
    unit: &'static str,
) -> Result<Option<f64>, RowError> {
    if cells.present(name) {
        cells.number_in(name, limit, unit).map(Some)
    } else {
        Ok(None)
    }
}

fn positive(
    cells: &Cells<'_>,
    name: &str,
    limit: f64,
    unit: &'static str,
) -> Result<Option<f64>, RowError> {
    match optional(cells, name, limit, unit)? {
        Some(v) if v <= 0.0 => Err(RowError::in_column(name, RowProblem::NotPositive(v))),
        other => Ok(other),
    }
}

fn triple(
    cells: &Cells<'_>,
    names: [&str; 3],
    limit: f64,
    unit: &'static str,
) -> Result<[f64; 3], RowError> {
    let mut out = [0.0; 3];
    for (v, name) in out.iter_mut().zip(names) {
        *v = cells.number_in(name, limit, unit)?;
    }
    Ok(out)
}

fn orientation(cells: &Cells<'_>, groups: &Groups) -> Result<Option<RowOrientation>, RowError> {
    if !groups.orientation || !cells.present(ORIENTATION[0]) {
        return Ok(None);
    }
    Ok(Some(RowOrientation {
        rotation_vector_rad: triple(cells, ORIENTATION, limits::MAX_ROTATION_RAD, "rad")?,
        sigma_rad: positive(cells, "sigma_rad", MAX_SIGMA_RAD, "rad")?,
    }))
}

fn payload(cells: &Cells<'_>, groups: &Groups) -> Result<Option<RowPayload>, RowError> {
    let Some(mass_kg) = optional(cells, "payload_kg", limits::MAX_PAYLOAD_KG, "kg")? else {
        return Ok(None);
    };
    if mass_kg < 0.0 {
        return Err(RowError::in_column(
            "payload_kg",
            RowProblem::Negative(mass_kg),
        ));
    }
    let mut com_m = [0.0; 3];
    if groups.payload_com {
        for (v, name) in com_m.iter_mut().zip(PAYLOAD_COM) {
            *v = optional(cells, name, limits::MAX_COM_M, "m")?.unwrap_or(0.0);
        }
    }
    Ok(Some(RowPayload { mass_kg, com_m }))
}

fn wrench(cells: &Cells<'_>, groups: &Groups) -> Result<Option<[f64; 6]>, RowError> {
    if !groups.wrench || !cells.present(WRENCH[0]) {
        return Ok(None);
    }
    let mut w = [0.0; 6];
    for (k, (value, name)) in w.iter_mut().zip(WRENCH).enumerate() {
        let (limit, unit) = if k < 3 {
            (MAX_FORCE_N, "N")
        } else {
            (MAX_MOMENT_NM, "N·m")
        };
        *value = cells.number_in(name, limit, unit)?;
    }
    Ok(Some(w))
}

fn temperature(cells: &Cells<'_>) -> Result<Option<f64>, RowError> {
    let range = limits::TEMPERATURE_RANGE_C;
    match optional(cells, "temperature_C", 1e3, "°C")? {
        Some(value) if !(range[0]..=range[1]).contains(&value) => Err(RowError::in_column(
            "temperature_C",
            RowProblem::Temperature { value, range },
        )),
        other => Ok(other),
    }
}

fn approach(
    cells: &Cells<'_>,
    groups: &Groups,
    joint_count: usize,
) -> Result<Option<Vec<f64>>, RowError> {
    if !groups.approach || !cells.present(&format!("{APPROACH}1_rad")) {
        return Ok(None);
    }
    (1..=joint_count)
        .map(|i| cells.number_in(&format!("{APPROACH}{i}_rad"), 2.0 * MAX_JOINT_RAD, "rad"))
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}

/// Parse absolute measurement CSV text; `origin` names the file in errors. A column the format
/// does not know is an error naming the closest one ([`parse_absolute_ignoring`] skips named
/// columns).
pub fn parse_absolute(
    text: &str,
    origin: &str,
    joint_count: usize,
) -> Result<Vec<AbsoluteRow>, DataError> {
    parse_absolute_ignoring(text, origin, joint_count, &[])
}

/// [`parse_absolute`], skipping the columns named in `ignored` (a user's own columns, kept
/// knowingly; a column the format reads cannot be ignored). A name the file does not have is
/// not an error here: one list serves every file of a command.
pub fn parse_absolute_ignoring(
    text: &str,
    origin: &str,
    joint_count: usize,
    ignored: &[String],
) -> Result<Vec<AbsoluteRow>, DataError> {
    let format = Absolute {
        joint_count,
        ignored,
    };
    Ok(reader::read(&format, text, origin)?.rows)
}

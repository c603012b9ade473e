//! What every exporter shares: checking the input against the settings' bounds, speeds, number
//! formatting, comment text and the line-length check of the result.

use crate::program::error::ProgramError;
use crate::program::settings::ProgramSettings;
use crate::program::{ArmConfiguration, ProgramInput, ProgramPoint};
use nalgebra::Vector3;

/// Longest line any exporter writes (characters). A KRL `LIN` with six values is about 100, a
/// RAPID `MoveL` with an inline robtarget about 170.
pub const MAX_LINE_LEN: usize = 250;

/// Largest |coordinate| accepted (m): no robot cell is 100 m across.
pub const MAX_COORDINATE_M: f64 = 100.0;

/// Longest comment line (characters, after the comment marker).
pub const MAX_COMMENT_LEN: usize = 160;

/// Largest number of header comment lines.
pub const MAX_COMMENT_LINES: usize = 40;

/// A checked point: position in mm, rotation, speed in mm/s (capped), rapid flag.
#[derive(Clone, Debug)]
pub(crate) struct Checked {
    pub position_mm: Vector3<f64>,
    pub rotation: nalgebra::Rotation3<f64>,
    pub speed_mm_s: f64,
    pub rapid: bool,
    /// The arm's configuration, when the caller gave it.
    pub config: Option<ArmConfiguration>,
}

/// Check the point count, the frames and every point (nothing is kept: the exporters convert
/// each point when they write it, [`checked`]).
pub(crate) fn check_input(
    format: &'static str,
    input: &ProgramInput,
    settings: &ProgramSettings,
) -> Result<(), ProgramError> {
    let max = settings.program.max_points;
    if input.points.is_empty() || input.points.len() > max {
        return Err(ProgramError::PointCount {
            format,
            points: input.points.len(),
            max,
        });
    }
    for (which, pose) in [
        ("frame", &input.frame_in_robot),
        ("tool", &input.tool_in_flange),
    ] {
        check_pose(pose).map_err(|(field, value, limit)| ProgramError::BadFrame {
            format,
            which,
            field,
            value,
            limit,
        })?;
    }
    for (index, point) in input.points.iter().enumerate() {
        check_point(format, index, point)?;
    }
    Ok(())
}

/// A pose's bad value as `(field, value, bound)`.
type PoseFault = (&'static str, f64, f64);

fn check_pose(pose: &deflex_model::Pose) -> Result<(), PoseFault> {
    let t = pose.translation.vector;
    for (field, value) in [("x_m", t.x), ("y_m", t.y), ("z_m", t.z)] {
        if !(value.is_finite() && value.abs() <= MAX_COORDINATE_M) {
            return Err((field, value, MAX_COORDINATE_M));
        }
    }
    let m = pose.rotation.matrix();
    let deviation = (m.transpose() * m - nalgebra::Matrix3::identity()).amax();
    if !(deviation < 1e-6 && (m.determinant() - 1.0).abs() < 1e-6) {
        return Err(("rotation (orthonormality error)", deviation, 1e-6));
    }
    Ok(())
}

/// A point as the exporters write it; the point must have passed [`check_input`] (its speed is
/// then valid).
pub(crate) fn checked(point: &ProgramPoint, settings: &ProgramSettings) -> Checked {
    Checked {
        position_mm: point.pose.translation.vector * 1e3,
        rotation: point.pose.rotation,
        speed_mm_s: point
            .speed_m_s
            .map_or(settings.program.rapid_speed_mm_s, |v| {
                (v * 1e3).min(settings.program.max_speed_mm_s)
            }),
        rapid: point.speed_m_s.is_none(),
        config: None,
    }
}

fn check_point(
    format: &'static str,
    index: usize,
    point: &ProgramPoint,
) -> Result<(), ProgramError> {
    check_pose(&point.pose).map_err(|(field, value, limit)| ProgramError::BadValue {
        format,
        index,
        field,
        value,
        limit,
    })?;
    match point.speed_m_s {
        Some(v) if !(v.is_finite() && v > 0.0 && v <= 10.0) => Err(ProgramError::BadValue {
            format,
            index,
            field: "speed_m_s",
            value: v,
            limit: 10.0,
        }),
        _ => Ok(()),
    }
}

/// A speed as the speed tables hold it (mm/s, rounded to 0.01).
pub(crate) fn table_speed(speed_mm_s: f64) -> f64 {
    (speed_mm_s * 100.0).round() / 100.0
}

/// Distinct speeds (mm/s, rounded to 0.01) of `points` in order of first use, at most `max`.
pub(crate) fn speed_table(
    format: &'static str,
    points: impl Iterator<Item = Checked>,
    max: usize,
) -> Result<Vec<f64>, ProgramError> {
    let mut speeds: Vec<f64> = Vec::new();
    for p in points {
        let v = table_speed(p.speed_mm_s);
        if !speeds.contains(&v) {
            speeds.push(v);
            if speeds.len() > max {
                return Err(ProgramError::TooManySpeeds {
                    format,
                    count: speeds.len(),
                    max,
                });
            }
        }
    }
    Ok(speeds)
}

/// The index of a point's speed in a table from [`speed_table`] over it.
pub(crate) fn speed_index(speeds: &[f64], p: &Checked) -> usize {
    let v = table_speed(p.speed_mm_s);
    speeds.iter().position(|s| *s == v).unwrap_or(0)
}

/// `value` with `decimals` decimals, never `-0.000`.
pub(crate) fn num(value: f64, decimals: usize) -> String {
    let s = format!("{value:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// Comment text safe for every controller: printable ASCII only (a few common symbols are
/// spelled out, anything else becomes `?`), without the characters in `forbidden` (brackets
/// become `[ ]`, `&` `+`, `-` `_`), at most
/// [`MAX_COMMENT_LEN`] characters.
pub(crate) fn comment_text(text: &str, forbidden: &[char]) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        let replacement: &str = match c {
            'ä' | 'à' | 'â' => "a",
            'é' | 'è' | 'ê' | 'ë' => "e",
            'ö' | 'ô' => "o",
            'ü' | 'ù' | 'û' => "u",
            'Ä' => "A",
            'Ö' => "O",
            'Ü' => "U",
            'µ' | 'μ' => "u",
            '°' => " deg",
            '×' | '·' => "x",
            '—' | '–' | '−' => "-",
            '≤' => "<=",
            '≥' => ">=",
            '±' => "+/-",
            'δ' => "d",
            'Δ' => "D",
            'Ø' => "D",
            c if (' '..='~').contains(&c) && !forbidden.contains(&c) => {
                out.push(c);
                continue;
            }
            '(' | '<' => "[",
            ')' | '>' => "]",
            '&' => "+",
            '-' => "_",
            _ => "?",
        };
        out.push_str(replacement);
    }
    out.chars().take(MAX_COMMENT_LEN).collect()
}

/// The header comment lines: the caller's description (bounded) plus the standard notice, each
/// wrapped at word boundaries to [`COMMENT_WIDTH`] characters (never cut mid-word; a single
/// word longer than that is split).
pub(crate) fn header_lines(input: &ProgramInput) -> Vec<String> {
    header_texts(input)
        .iter()
        .flat_map(|l| wrap(l, COMMENT_WIDTH))
        .collect()
}

/// The header comment texts of [`header_lines`], one per paragraph, not wrapped (for a writer
/// that wraps to its own width).
pub(crate) fn header_texts(input: &ProgramInput) -> Vec<String> {
    let mut lines: Vec<String> = input
        .description
        .iter()
        .take(MAX_COMMENT_LINES)
        .cloned()
        .collect();
    if let Some(load) = &input.tool_load_in_flange {
        let centre = load.centre_of_mass_m;
        lines.push(format!(
            "tool load ({}): {:.3} kg at ({:.4}, {:.4}, {:.4}) mm in the flange frame",
            input.tool_load_source,
            load.mass_kg,
            centre[0] * 1e3,
            centre[1] * 1e3,
            centre[2] * 1e3
        ));
    }
    lines.push(
        "Generated by deflex. Not yet run on a real controller: check it in the vendor's \
         simulator, then on the robot at reduced speed, before production."
            .into(),
    );
    lines
}

/// Width of a header comment line (characters, before the comment marker).
pub const COMMENT_WIDTH: usize = 90;

/// `text` in lines of at most `width` characters, broken at spaces (a word longer than `width`
/// is cut into pieces of `width`); always at least one line, empty for an empty text.
pub fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let mut word: Vec<char> = word.chars().collect();
        while word.len() > width {
            if !line.is_empty() {
                out.push(std::mem::take(&mut line));
            }
            out.push(word.drain(..width).collect());
        }
        let word: String = word.into_iter().collect();
        let needed = line.chars().count() + usize::from(!line.is_empty()) + word.chars().count();
        if needed > width && !line.is_empty() {
            out.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(&word);
    }
    if !line.is_empty() || out.is_empty() {
        out.push(line);
    }
    out
}

/// Check every line of a produced file against [`MAX_LINE_LEN`].
pub(crate) fn check_lines(format: &'static str, text: &str) -> Result<(), ProgramError> {
    for (i, line) in text.lines().enumerate() {
        let length = line.chars().count();
        if length > MAX_LINE_LEN {
            return Err(ProgramError::LineTooLong {
                format,
                line: i + 1,
                length,
                max: MAX_LINE_LEN,
            });
        }
    }
    Ok(())
}

/// Blend (approximation) radius at point `i` of `n` (mm), `position(k)` the points' positions:
/// `blend_mm`, at most 45 % of the shorter of the two segments meeting there (two neighbouring
/// blends must not overlap), 0 at the last point (the program ends exactly there).
pub(crate) fn blend_radius(
    i: usize,
    n: usize,
    position: impl Fn(usize) -> Vector3<f64>,
    blend_mm: f64,
) -> f64 {
    if i + 1 >= n || blend_mm <= 0.0 {
        return 0.0;
    }
    let next = (position(i + 1) - position(i)).norm();
    let prev = if i > 0 {
        (position(i) - position(i - 1)).norm()
    } else {
        next
    };
    blend_mm.min(0.45 * prev.min(next))
}

//! CAM G-code import. Supported, and nothing else (anything else is an error naming the line):
//!
//! * `G0` (rapid) and `G1` (linear feed) with `X Y Z` targets and `F` feed (units per minute),
//!   modal as usual; `G90`/`G91` absolute/relative; `G20`/`G21` inch/mm;
//! * `N` line numbers (ignored), comments in `( … )` or after `;`, `%` tape markers, blank lines;
//! * `M2`/`M30` end the program (the rest of the file is ignored).
//!
//! Coordinates are the TCP (the centre of the ball tip) in the part frame R_p, z up, in the unit
//! in force; the program starts at R_p's origin.
//!
//! Bounds (each an error naming the line): a file of at most [`MAX_GCODE_BYTES`], at most
//! [`MAX_WAYPOINTS`] moves, coordinates within ±[`MAX_COORDINATE_MM`] of R_p's origin, feeds
//! from [`MIN_FEED_MM_MIN`] to [`MAX_FEED_MM_MIN`] mm/min (in the unit in force). A run of the
//! program is further bounded in time by the cell (`deflex_sim::cell_config::MAX_RUN_S`).

use crate::error::SimError;
use crate::toolpath::{ToolPath, Waypoint};

/// Largest G-code file read (bytes).
pub const MAX_GCODE_BYTES: u64 = 64 << 20;
/// Most moves in a program.
pub const MAX_WAYPOINTS: usize = 1_000_000;
/// Largest |coordinate| of a move (mm, after units).
pub const MAX_COORDINATE_MM: f64 = 10_000.0;
/// Slowest feed (mm/min): 0.01 mm/s.
pub const MIN_FEED_MM_MIN: f64 = 0.6;
/// Fastest feed (mm/min): 1 m/s.
pub const MAX_FEED_MM_MIN: f64 = 60_000.0;

/// Read a G-code file into a [`ToolPath`].
pub fn read_gcode(path: &std::path::Path) -> Result<ToolPath, SimError> {
    let size = std::fs::metadata(path)
        .map_err(|e| SimError::Path(format!("{}: {e}", path.display())))?
        .len();
    if size > MAX_GCODE_BYTES {
        return Err(SimError::Path(format!(
            "{}: {size} bytes; G-code files of at most {MAX_GCODE_BYTES} bytes are read",
            path.display()
        )));
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| SimError::Path(format!("{}: {e}", path.display())))?;
    // Errors name the whole path; the tool path is named after the file.
    let mut toolpath = parse_gcode(&text, &path.display().to_string())?;
    if let Some(name) = path.file_name() {
        toolpath.name = name.to_string_lossy().into_owned();
    }
    Ok(toolpath)
}

/// Parse G-code text; `file` names the source in errors and becomes the path name.
pub fn parse_gcode(text: &str, file: &str) -> Result<ToolPath, SimError> {
    let mut position = [0.0f64; 3];
    let mut absolute = true;
    let mut scale = 1.0; // mm per unit
    let mut motion: Option<u32> = None;
    let mut feed_mm_s: Option<f64> = None;
    let mut waypoints = vec![Waypoint {
        p_mm: position,
        feed_mm_s: None,
    }];
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let err = |message: String| SimError::Gcode {
            file: file.to_string(),
            line,
            message,
        };
        let code = strip_comments(raw).map_err(&err)?;
        let code = code.trim();
        if code.is_empty() || code == "%" {
            continue;
        }
        let words = split_words(code).map_err(&err)?;
        let mut target: [Option<f64>; 3] = [None; 3];
        let mut line_motion: Option<u32> = None;
        let mut line_feed: Option<f64> = None;
        let mut line_units: Option<f64> = None;
        let mut line_mode: Option<bool> = None;
        let mut end = false;
        for (letter, value, text) in &words {
            match letter {
                'N' => {}
                'G' => {
                    let g = integer_code(*value).ok_or_else(|| {
                        err(format!(
                            "unsupported G-code G{text}: only G0, G1, G20, G21, G90, G91"
                        ))
                    })?;
                    match g {
                        0 | 1 => {
                            if line_motion.replace(g).is_some() {
                                return Err(err("two motion codes on one line".into()));
                            }
                        }
                        20 => line_units = Some(25.4),
                        21 => line_units = Some(1.0),
                        90 => line_mode = Some(true),
                        91 => line_mode = Some(false),
                        _ => {
                            return Err(err(format!(
                                "unsupported G-code G{text}: only G0, G1, G20, G21, G90, G91"
                            )));
                        }
                    }
                }
                'M' => match integer_code(*value) {
                    Some(2) | Some(30) => end = true,
                    _ => {
                        return Err(err(format!(
                            "unsupported M-code M{text}: only M2/M30 (program end)"
                        )));
                    }
                },
                'X' | 'Y' | 'Z' => {
                    let axis = (*letter as u8 - b'X') as usize;
                    if target[axis].replace(*value).is_some() {
                        return Err(err(format!("{letter} given twice")));
                    }
                }
                'F' => {
                    line_feed = Some(*value);
                }
                other => {
                    return Err(err(format!(
                        "unsupported word {other}{text}: only G0/G1, G20/G21, G90/G91, X, Y, Z, F, N, M2/M30"
                    )));
                }
            }
        }
        if let Some(u) = line_units {
            scale = u;
        }
        if let Some(m) = line_mode {
            absolute = m;
        }
        if let Some(f) = line_feed {
            let per_min = f * scale;
            if !(MIN_FEED_MM_MIN..=MAX_FEED_MM_MIN).contains(&per_min) {
                return Err(err(format!(
                    "feed F{f} is {per_min} mm/min; feeds from {MIN_FEED_MM_MIN} to \
                     {MAX_FEED_MM_MIN} mm/min are accepted"
                )));
            }
            feed_mm_s = Some(per_min / 60.0);
        }
        if let Some(m) = line_motion {
            motion = Some(m);
        }
        if target.iter().any(Option::is_some) {
            let Some(m) = motion else {
                return Err(err(
                    "coordinates without a motion mode: give G0 or G1 first".into(),
                ));
            };
            let mut next = position;
            for axis in 0..3 {
                if let Some(v) = target[axis] {
                    next[axis] = if absolute {
                        v * scale
                    } else {
                        position[axis] + v * scale
                    };
                }
            }
            let feed = if m == 0 {
                None
            } else {
                Some(
                    feed_mm_s
                        .ok_or_else(|| err("G1 move without a feed rate: set F first".into()))?,
                )
            };
            if let Some(axis) = (0..3).find(|&a| next[a].abs() > MAX_COORDINATE_MM) {
                return Err(err(format!(
                    "{} = {} mm is beyond ±{MAX_COORDINATE_MM} mm of the part origin",
                    ['X', 'Y', 'Z'][axis],
                    next[axis]
                )));
            }
            let moved = (0..3).any(|a| (next[a] - position[a]).abs() > 1e-12);
            if moved {
                if waypoints.len() >= MAX_WAYPOINTS {
                    return Err(err(format!("more than {MAX_WAYPOINTS} moves")));
                }
                waypoints.push(Waypoint {
                    p_mm: next,
                    feed_mm_s: feed,
                });
            }
            position = next;
        }
        if end {
            break;
        }
    }
    if waypoints.len() < 2 {
        return Err(SimError::Gcode {
            file: file.to_string(),
            line: text.lines().count().max(1),
            message: "no move in the program".into(),
        });
    }
    Ok(ToolPath {
        name: file.to_string(),
        waypoints,
        step_down_mm: None,
        wall_angle_deg: None,
    })
}

fn integer_code(value: f64) -> Option<u32> {
    (value >= 0.0 && value.fract() == 0.0 && value < 1000.0).then_some(value as u32)
}

fn strip_comments(line: &str) -> Result<String, String> {
    let mut out = String::with_capacity(line.len());
    let mut depth = 0;
    for c in line.chars() {
        match c {
            ';' if depth == 0 => break,
            '(' => depth += 1,
            ')' => {
                if depth == 0 {
                    return Err("')' without '('".into());
                }
                depth -= 1;
            }
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    if depth != 0 {
        return Err("unclosed comment '('".into());
    }
    Ok(out)
}

fn split_words(code: &str) -> Result<Vec<(char, f64, String)>, String> {
    let chars: Vec<char> = code.chars().filter(|c| !c.is_whitespace()).collect();
    let mut words = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let letter = chars[i].to_ascii_uppercase();
        if !letter.is_ascii_alphabetic() {
            return Err(format!("expected a letter, found '{}'", chars[i]));
        }
        i += 1;
        let start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || matches!(chars[i], '.' | '-' | '+'))
        {
            i += 1;
        }
        let text: String = chars[start..i].iter().collect();
        let value: f64 = text
            .parse()
            .map_err(|_| format!("{letter}: expected a number, found \"{text}\""))?;
        if !value.is_finite() {
            return Err(format!("{letter}{text}: not a finite number"));
        }
        words.push((letter, value, text));
    }
    Ok(words)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absolute_relative_units_feeds_and_comments() {
        let text = "%\n(square test) ; header\nN10 G21 G90\nG0 X10 Y0 Z5\nG1 Z0 F600 (plunge)\n\
                    G91\nX-5 Y5\nG20 G1 X1 F60\nM30\nG1 X1000\n";
        let path = parse_gcode(text, "t.nc").unwrap();
        let p: Vec<[f64; 3]> = path.waypoints.iter().map(|w| w.p_mm).collect();
        assert_eq!(p[0], [0.0, 0.0, 0.0]);
        assert_eq!(p[1], [10.0, 0.0, 5.0]);
        assert_eq!(path.waypoints[1].feed_mm_s, None);
        assert_eq!(p[2], [10.0, 0.0, 0.0]);
        assert!((path.waypoints[2].feed_mm_s.unwrap() - 10.0).abs() < 1e-12);
        assert_eq!(p[3], [5.0, 5.0, 0.0]);
        assert!((p[4][0] - 30.4).abs() < 1e-12);
        // F60 in/min = 25.4 mm/s.
        assert!((path.waypoints[4].feed_mm_s.unwrap() - 25.4).abs() < 1e-12);
        assert_eq!(p.len(), 5, "M30 ends the program");
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            ("G1 X1\n", 1, "feed"),
            ("G0 X1\nG2 X1 Y1 I1\n", 2, "G2"),
            ("G0 X1\n\nS1000\n", 3, "unsupported word S"),
            ("X5\n", 1, "motion mode"),
            ("G0 X1 (open\n", 1, "unclosed"),
            ("G0 Xabc\n", 1, "expected a number"),
            ("G0 X1 X2\n", 1, "twice"),
            ("M3\n", 1, "M-code"),
            ("(nothing)\n", 1, "no move"),
            // Issue 12: a feed that would take forever, and absurd magnitudes.
            ("G1 X1 F1e-42\n", 1, "unsupported word E"),
            (
                "G1 X1 F0.000000000000000000000000000000000000000001\n",
                1,
                "feeds from",
            ),
            ("G0 X1\nG1 X2 F0\n", 2, "feeds from"),
            ("G0 X1\nG1 X2 F-5\n", 2, "feeds from"),
            ("G0 X20000\n", 1, "beyond"),
            ("G0 X1\nG91\nG0 X9999\nG0 X9999\n", 4, "beyond"),
            ("G20 G1 X1 F100000\n", 1, "feeds from"),
        ];
        for (text, line, needle) in cases {
            let e = parse_gcode(text, "p.nc").unwrap_err().to_string();
            assert!(e.starts_with(&format!("p.nc:{line}:")), "{e}");
            assert!(e.contains(needle), "{e} should mention {needle}");
        }
    }
}

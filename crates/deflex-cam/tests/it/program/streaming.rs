//! Programs written part by part to a folder ([`DirectorySink`]) and read back from it line by
//! line ([`DirectorySource`]) are the programs [`export`] builds in memory, motion for motion;
//! the VAL3 data file, read in one pass, refuses arrays out of the exporter's order.

use deflex_cam::program::readback::{DirectorySource, read_files, read_program, read_val3_data};
use deflex_cam::program::settings::ProgramSettings;
use deflex_cam::program::{DirectorySink, Format, ProgramInput, ProgramPoint, export, export_to};
use deflex_model::Pose;
use nalgebra::{Rotation3, Translation3, Vector3};

/// A descending spiral of `n` points, tool down, one rapid in the middle.
fn spiral(n: usize) -> ProgramInput {
    let down = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
    let points = (0..n)
        .map(|i| {
            let a = 0.01 * i as f64;
            ProgramPoint {
                pose: Pose::from_parts(
                    Translation3::new(0.02 * a.cos(), 0.02 * a.sin(), -1e-5 * i as f64),
                    Rotation3::from_scaled_axis(Vector3::new(1e-3 * a.sin(), 0.0, 0.0)) * down,
                ),
                speed_m_s: if i == 0 || i == n / 2 {
                    None
                } else {
                    Some(0.01)
                },
            }
        })
        .collect();
    let mut input = ProgramInput::new(points);
    input.tool_load_in_flange = Some(deflex_model::ToolLoad {
        mass_kg: 2.0,
        centre_of_mass_m: Vector3::new(0.0, 0.0, 0.1),
    });
    input.tool_load_source = "test".into();
    input
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("deflex-program-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn programs_streamed_to_a_folder_are_the_ones_built_in_memory() {
    let settings = ProgramSettings {
        program: deflex_cam::program::settings::CommonSettings {
            max_points_per_part: 700,
            ..Default::default()
        },
        ..Default::default()
    };
    let input = spiral(3000);
    for format in Format::ALL {
        let dir = scratch(format.name());
        let memory = export(format, &input, &settings).unwrap();
        let mut sink = DirectorySink::new(&dir);
        let files = export_to(format, &input, &settings, &mut sink).unwrap();
        assert_eq!(
            files,
            memory.iter().map(|f| f.path.clone()).collect::<Vec<_>>(),
            "{format:?}: the same files, the main program first"
        );
        let mut bytes = 0;
        for file in &memory {
            let on_disk = std::fs::read_to_string(dir.join(&file.path)).unwrap();
            assert_eq!(on_disk, file.contents, "{format:?} {}", file.path);
            bytes += on_disk.len() as u64;
        }
        assert_eq!(sink.bytes, bytes);
        if format != Format::Gcode {
            assert!(files.len() > 2, "{format:?} is split: {files:?}");
        }
        let expected = read_files(format, &memory).unwrap();
        let mut read = Vec::new();
        let count = read_program(format, &DirectorySource::new(&dir), &files, &mut |p| {
            read.push(p);
            Ok(())
        })
        .unwrap();
        assert_eq!(count, 3002, "{format:?}: clearance, path, clearance");
        assert_eq!(read, expected, "{format:?}");
        // A part missing from the folder is named.
        if format == Format::Krl {
            std::fs::remove_file(dir.join(&files[3])).unwrap();
            let e = read_program(format, &DirectorySource::new(&dir), &files, &mut |_| Ok(()))
                .unwrap_err();
            assert!(e.to_string().contains(&files[3]), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn the_val3_data_file_is_read_in_the_exporters_order() {
    let settings = ProgramSettings {
        program: deflex_cam::program::settings::CommonSettings {
            max_points_per_part: 40,
            ..Default::default()
        },
        ..Default::default()
    };
    let files = export(Format::Val3, &spiral(100), &settings).unwrap();
    let data = files.iter().find(|f| f.path.ends_with(".dtx")).unwrap();
    assert_eq!(read_val3_data(&data.contents, "d.dtx").unwrap().len(), 102);
    // The second part's arrays before the first's.
    let swapped = data
        .contents
        .replace("name=\"pPath1\"", "name=\"pPathX\"")
        .replace("name=\"pPath2\"", "name=\"pPath1\"")
        .replace("name=\"pPathX\"", "name=\"pPath2\"");
    let e = read_val3_data(&swapped, "d.dtx").unwrap_err();
    assert!(e.to_string().contains("out of order"), "{e}");
    // A point key skipped.
    let skipped = data
        .contents
        .replacen("<Value key=\"3\" x=", "<Value key=\"4\" x=", 1);
    let e = read_val3_data(&skipped, "d.dtx").unwrap_err();
    assert!(e.to_string().contains("keys out of order at 4"), "{e}");
}

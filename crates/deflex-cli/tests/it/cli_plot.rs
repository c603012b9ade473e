//! `deflex plot` through the real binary: two recordings on one overlaid page, a foreign file
//! named with the earlier output left whole, the run names checked.

use deflex_record::synthetic::SyntheticCell;
use std::path::Path;
use std::process::{Command, Output};

fn deflex(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deflex"))
        .args(args)
        .output()
        .unwrap()
}

/// A SIMULATED recording of `seconds` of the synthetic cell at 100 Hz.
fn recording(path: &Path, seed: u64, seconds: usize) {
    let mut cell = SyntheticCell::new(0.01, seed, true);
    let info = cell.session_info();
    let mut sink = deflex_record::McapSink::new(
        Vec::new(),
        "mem",
        &info,
        deflex_record::RecordOptions::default(),
    )
    .unwrap();
    for _ in 0..seconds * 100 {
        sink.write(&cell.next_sample()).unwrap();
    }
    std::fs::write(path, sink.finish().unwrap().0).unwrap();
}

#[test]
fn two_recordings_make_one_overlaid_page_and_a_foreign_file_is_named() {
    let dir = std::env::temp_dir().join(format!("deflex-plot-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b) = (dir.join("a.mcap"), dir.join("b.mcap"));
    recording(&a, 1, 4);
    recording(&b, 2, 3);
    let out = dir.join("plots");
    let (a, b, out_s) = (
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let run = deflex(&[
        "--json",
        "plot",
        a,
        b,
        "--out",
        out_s,
        "--labels",
        "first,second",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("first vs second") && html.contains("SIMULATED"));
    for f in [
        "forces.png",
        "correction.png",
        "deflection.png",
        "path_error.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // A foreign file: the error names it, and the earlier output stays whole.
    let foreign = dir.join("notes.txt");
    std::fs::write(&foreign, "hello,world\n1,2\n").unwrap();
    let run = deflex(&["plot", foreign.to_str().unwrap(), "--out", out_s]);
    assert!(!run.status.success());
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(
        e.contains("notes.txt") && e.contains("not a deflex log"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("index.html")).unwrap(),
        html
    );
    let run = deflex(&["plot", a, "--out", out_s, "--labels", "x,y"]);
    assert!(!run.status.success());
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("--labels"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}

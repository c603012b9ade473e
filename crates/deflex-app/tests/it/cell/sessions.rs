//! The two sessions both front ends drive from one `CELL.toml`: `deflex run`
//! (`deflex_app::cell::run_session`, its summary in `run_summary`) and `deflex cell --sim`
//! (`deflex_app::cell::sim_cell`) — what they refuse before any link opens, the file names they
//! derive, and both together over loopback with their logs, recordings and summaries.

use crate::example_cell::{example_cell_file, free_udp_port};
use deflex_app::cell::run_session::{RunEvent, RunOptions, RunPlan, mcap_beside};
use deflex_app::cell::run_summary::OutletLines;
use deflex_app::cell::sim_cell::{SimCellPath, SimCellPlan, sim_cell_log_path};
use deflex_sim::twin::cell_server::ServeOptions;
use deflex_sim::{CellConfig, ConeParams, ToolPath};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("deflex-app-sessions-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A minimal `CELL.toml` in `dir` with `extra` sections.
fn minimal_cell_file(dir: &Path, sensor: &str, extra: &str) -> PathBuf {
    let path = dir.join("cell.toml");
    std::fs::write(
        &path,
        format!(
            "[robot]\nkind = \"simple-udp\"\nbind = \"127.0.0.1:{}\"\n{sensor}\n\
             [model]\nfile = \"tx200\"\n{extra}",
            free_udp_port()
        ),
    )
    .unwrap();
    path
}

const NETFT: &str = "[sensor]\nkind = \"netft\"\naddress = \"127.0.0.1:49152\"";

#[test]
fn the_recording_is_named_beside_the_log_and_never_replaces_it() {
    assert_eq!(
        mcap_beside(Path::new("/x/deflex-run.csv"), "log.path").unwrap(),
        Path::new("/x/deflex-run.mcap")
    );
    assert_eq!(
        mcap_beside(Path::new("/x/run"), "--log").unwrap(),
        Path::new("/x/run.mcap")
    );
    let refused = mcap_beside(Path::new("/x/run.mcap"), "--log")
        .unwrap_err()
        .to_string();
    assert_eq!(
        refused,
        "--log: expected a log name other than NAME.mcap (the MCAP recording is written beside \
         the CSV log with the extension .mcap; give the log another extension, .csv), got \
         /x/run.mcap"
    );
}

#[test]
fn the_twin_s_log_is_named_after_the_run_s() {
    let dir = scratch("log-names");
    let with_log = SimCellPlan::load(&minimal_cell_file(
        &dir,
        NETFT,
        "[log]\npath = \"logs/deflex-run.csv\"\n",
    ))
    .unwrap();
    assert_eq!(
        sim_cell_log_path(&with_log.cell, None),
        dir.join("logs/deflex-run.sim-cell.csv")
    );
    assert_eq!(
        sim_cell_log_path(&with_log.cell, Some(Path::new("/t/twin.csv"))),
        Path::new("/t/twin.csv")
    );
    let without = SimCellPlan::load(&minimal_cell_file(&dir, NETFT, "")).unwrap();
    assert_eq!(
        sim_cell_log_path(&without.cell, None),
        dir.join("deflex-run.sim-cell.csv")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_twin_s_paths_by_name() {
    for path in SimCellPath::ALL {
        assert_eq!(SimCellPath::from_name(path.name()), Some(path));
    }
    assert_eq!(SimCellPath::from_name("spiral"), None);
    assert_eq!(
        SimCellPath::Cone.tool_path(None).unwrap(),
        ToolPath::paper_cone()
    );
    let helical = ToolPath::cone(&ConeParams {
        helical: true,
        ..ConeParams::default()
    })
    .unwrap();
    assert_eq!(SimCellPath::Helical.tool_path(None).unwrap(), helical);
    assert_eq!(
        SimCellPath::Helical.tool_path(Some(30.0)).unwrap(),
        helical.truncated(30.0)
    );
}

/// Refused before any link opens, naming the file and the field: a log path that is a folder,
/// a recording that would be the log itself, a ROS 2 sensor for the simulated cell.
#[test]
fn sessions_refuse_their_files_before_any_link_opens() {
    let dir = scratch("refusals");
    std::fs::create_dir_all(dir.join("a-folder")).unwrap();
    let config = minimal_cell_file(&dir, NETFT, "[log]\npath = \"a-folder\"\n");
    let error = RunPlan::load(&config).err().unwrap().to_string();
    assert!(
        error.starts_with(&config.display().to_string()) && error.contains("[log] path"),
        "{error}"
    );
    let config = minimal_cell_file(&dir, NETFT, "[log]\npath = \"run.mcap\"\n");
    let error = RunPlan::load(&config).err().unwrap().to_string();
    assert!(
        error.starts_with("log.path: expected a log name other than NAME.mcap"),
        "{error}"
    );
    let ros2 = "[sensor]\nkind = \"ros2\"\ntopic = \"/ati/wrench\"\n[ros2]\n";
    let config = minimal_cell_file(&dir, "", ros2);
    let error = SimCellPlan::load(&config).err().unwrap().to_string();
    assert!(
        error.starts_with(&format!(
            "{}: sensor.kind = \"ros2\": the simulated cell plays the robot and an ATI Net F/T",
            config.display()
        )),
        "{error}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `deflex cell --sim` and `deflex run` in-process from one CELL.toml, over loopback (SIMULATED):
/// the run's CSV log and its MCAP recording are committed with every cycle, the twin's
/// ground-truth log and its recording beside the run's log; both summaries say so, in text and
/// JSON, with the front end's outlet lines in their places.
#[test]
fn run_and_the_simulated_cell_together() {
    let _turn = crate::twin::session_turn();
    let dir = scratch("together");
    let config = example_cell_file(&dir);
    let twin = SimCellPlan::load(&config)
        .unwrap()
        .start(
            ServeOptions {
                twin: CellConfig::default(),
                // 30 mm: 3.1 s of forming.
                path: SimCellPath::Cone.tool_path(Some(30.0)).unwrap(),
                seed: 1,
                speed: 1.0,
                wait_s: 60.0,
                dwell_s: 0.5,
                pose_jump: None,
            },
            None,
        )
        .unwrap();
    let cell_thread = std::thread::spawn(move || {
        let stop = AtomicBool::new(false);
        twin.serve(&stop, &mut |_| {})
    });
    let plan = RunPlan::load(&config).unwrap();
    assert_eq!(
        plan.mcap_path.as_deref(),
        Some(dir.join("run.mcap").as_path())
    );
    let options = RunOptions {
        startup_timeout_s: 60.0,
        idle_exit_s: 0.5,
        duration_s: None,
    };
    let session = plan
        .start(&options, None, &mut |_| {})
        .unwrap()
        .record()
        .unwrap();
    let (mut statuses, mut log_failures) = (0, 0);
    session.wait(&AtomicBool::new(false), &mut |event| match event {
        RunEvent::Status { rate_hz, .. } => {
            assert!(rate_hz.is_finite());
            statuses += 1;
        }
        RunEvent::LogFailed { .. } => log_failures += 1,
    });
    assert!(
        statuses > 0 && log_failures == 0,
        "{statuses} {log_failures}"
    );
    let run = session.finish().unwrap();
    let cell = cell_thread.join().unwrap().unwrap();

    // The run: its log and recording, every cycle.
    let s = &run.session.summary;
    assert!(s.error.is_none(), "{:?}", s.error);
    assert!(run.session.log_committed && run.session.log_rows > 100);
    let recording = run.recording.as_ref().unwrap();
    assert_eq!(recording.path, dir.join("run.mcap"));
    let recorded = recording.result.as_ref().unwrap();
    assert_eq!(
        (recorded.stats.recorded, recorded.lost),
        (run.session.log_rows, 0)
    );
    let outlets = OutletLines {
        links: vec!["  outlet link".into()],
        view: Some("the view".into()),
    };
    let text = run.summary_text(&outlets);
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[0].starts_with("deflex run: ") && text.ends_with('\n'),
        "{text}"
    );
    let at = |prefix: &str| lines.iter().position(|l| l.starts_with(prefix)).unwrap();
    assert_eq!(at("  outlet link"), at("  sensor: ") + 1, "{text}");
    assert_eq!(
        at("  live view: the view"),
        at("  recording: ") + 1,
        "{text}"
    );
    assert!(
        lines[at("  recording: ")].contains("run.mcap (MCAP, "),
        "{text}"
    );
    let json = run.summary_json();
    assert_eq!(json["mcap"]["committed"], true, "{json}");
    assert_eq!(json["mcap"]["cycles"], json["log_rows"], "{json}");
    assert_eq!(json["robot_protocol"], "KUKA RSI", "{json}");
    assert!(
        json.get("exit_code").is_none() && json.get("view").is_none(),
        "{json}"
    );

    // The twin: its ground-truth log and recording beside the run's log.
    assert_eq!(cell.log_path, dir.join("run.sim-cell.csv"));
    let log = std::fs::read_to_string(&cell.log_path).unwrap();
    assert!(log.starts_with("# SIMULATED"));
    assert_eq!(
        log.lines().filter(|l| !l.starts_with('#')).count() - 1,
        cell.log_rows
    );
    assert_eq!(cell.recording.path, dir.join("run.sim-cell.mcap"));
    assert!(cell.recording.result.is_ok());
    let text = cell.summary_text();
    assert!(
        text.starts_with("deflex cell (SIMULATED ")
            && text.contains("phase: ended (robot program finished)")
            && text.contains("run.sim-cell.csv"),
        "{text}"
    );
    let json = cell.summary_json();
    assert_eq!(
        (
            &json["simulated"],
            &json["phase"],
            &json["mcap"]["committed"]
        ),
        (&true.into(), &"ended".into(), &true.into()),
        "{json}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

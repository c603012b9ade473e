//! The run log's one definition: its columns and units, its two notations (`deflex run`'s and
//! the study's twin controller log, character for character), and the one log reader (a log
//! written is read back; every error names the file, the line and the column).

use deflex_control::CycleOutput;
use deflex_record::log_reader::{LogReadError, LogReader};
use deflex_record::run_log::{
    RUN_LOG_SKIP_FLAGS, RunLogBlock, RunLogColumn, RunLogFormat, cycle_sample, joint_columns,
};
use deflex_telemetry::{CycleSample, Flags};

fn output() -> CycleOutput {
    let mut out = CycleOutput {
        time_s: 1.5,
        wrench_sensor: [0.5; 6],
        wrench_tcp: [-1.25, 0.0, 900.0, 0.0, 0.0, 0.125],
        delta_s_hat: [1e-4, 0.0, -2.5e-4, 0.0, 0.0, 1e-6],
        xi: [-1e-4, 0.0, 2.5e-4, 0.0, 0.0, -1e-6],
        epsilon: [3e-9, 0.0, 0.0, 0.0, 0.0, 0.0],
        loop_gain: 0.25,
        path_s_m: 0.0125,
        ..CycleOutput::default()
    };
    out.flags.set(Flags::ACTIVE | Flags::RAMPING);
    out
}

#[test]
fn columns_carry_their_units() {
    let cell = RunLogFormat::cell(6);
    assert_eq!(cell.columns().len(), 1 + 6 + 7 * 6 + 5);
    assert_eq!(RunLogColumn::Joint(0).name(), "q1_rad");
    assert_eq!(
        RunLogColumn::Block(RunLogBlock::TcpWrench, 5).name(),
        "w_mz_nm"
    );
    assert_eq!(
        RunLogColumn::Block(RunLogBlock::Correction, 3).name(),
        "xi_rx_rad"
    );
    assert_eq!(RunLogColumn::Block(RunLogBlock::TcpWrench, 4).unit(), "N·m");
    assert_eq!(RunLogColumn::Block(RunLogBlock::Deflection, 2).unit(), "m");
    assert_eq!(
        RunLogColumn::Block(RunLogBlock::FeedForward, 5).unit(),
        "rad"
    );
    assert_eq!(RunLogColumn::CycleTime.unit(), "µs");
    // Every column's name ends in its unit (the ratio, flags and status have none).
    for column in cell.columns() {
        let name = column.name();
        let suffix = match column.unit() {
            "N" => "_n",
            "N·m" => "_nm",
            "µs" => "_us",
            "" => "",
            unit => &format!("_{unit}"),
        };
        assert!(name.ends_with(suffix), "{name}: {}", column.unit());
    }
    // The skipped rows: the fault bits, latched, taring, stale; not an active correction.
    assert_eq!(
        RUN_LOG_SKIP_FLAGS,
        0x7FF | (1 << 16) | (1 << 21) | (1 << 22)
    );
    assert_eq!(RUN_LOG_SKIP_FLAGS & Flags::ACTIVE, 0);
}

/// The study's controller log of the twin (`forming_closed/controller_log.csv`), character for
/// character: time with 4 decimals, the TCP wrench with 3, δŝ, ξ, ε with 6 significant digits,
/// the loop gain with 4 (empty when unknown), the flags as an integer and by name.
#[test]
fn the_twin_notation_is_the_study_controller_log() {
    let twin = RunLogFormat::twin();
    assert_eq!(
        twin.header(),
        "time_s,w_fx_n,w_fy_n,w_fz_n,w_mx_nm,w_my_nm,w_mz_nm,ds_x_m,ds_y_m,ds_z_m,ds_rx_rad,\
         ds_ry_rad,ds_rz_rad,xi_x_m,xi_y_m,xi_z_m,xi_rx_rad,xi_ry_rad,xi_rz_rad,eps_x_m,eps_y_m,\
         eps_z_m,eps_rx_rad,eps_ry_rad,eps_rz_rad,loop_gain,flags,status"
    );
    let mut out = output();
    let mut sample = CycleSample::default();
    deflex_control::RecordCycle::record_output(&mut sample, &out);
    assert_eq!(
        twin.row(&sample),
        "1.5000,-1.250,0.000,900.000,0.000,0.000,0.125,\
         1.00000e-4,0.00000e0,-2.50000e-4,0.00000e0,0.00000e0,1.00000e-6,\
         -1.00000e-4,0.00000e0,2.50000e-4,0.00000e0,0.00000e0,-1.00000e-6,\
         3.00000e-9,0.00000e0,0.00000e0,0.00000e0,0.00000e0,0.00000e0,\
         0.2500,1572864,ramping|active"
    );
    out.loop_gain = f64::NAN;
    deflex_control::RecordCycle::record_output(&mut sample, &out);
    assert!(
        twin.row(&sample)
            .ends_with(",0.00000e0,,1572864,ramping|active")
    );
}

/// A `deflex run` log written with the format is read back by the one reader: every column
/// found by its name, the values to their printed precision, the empty arc length unknown.
#[test]
fn a_written_log_reads_back() {
    let format = RunLogFormat::cell(3);
    let mut text = String::from("# a comment\n");
    text.push_str(&format.header());
    text.push('\n');
    let mut samples = Vec::new();
    for k in 0..4 {
        let mut out = output();
        out.time_s = 0.004 * k as f64;
        out.path_s_m = if k == 0 { f64::NAN } else { 0.001 * k as f64 };
        let sample = cycle_sample(&[0.1, -0.2, 0.3 + 0.01 * k as f64], &[1.0; 6], &out, 12.5);
        format.write_row(&sample, &mut text);
        text.push('\n');
        samples.push(sample);
    }
    let mut log = LogReader::new(&text, "run.csv").unwrap();
    assert!(!log.simulated());
    assert_eq!(log.header_line(), 2);
    assert_eq!(joint_columns(&log), [1, 2, 3]);
    let columns: Vec<usize> = format
        .columns()
        .iter()
        .map(|c| c.find(&log).unwrap())
        .collect();
    assert_eq!(columns, (0..format.columns().len()).collect::<Vec<_>>());
    let q3 = RunLogColumn::Joint(2).find(&log).unwrap();
    let fz = RunLogColumn::Block(RunLogBlock::TcpWrench, 2)
        .find(&log)
        .unwrap();
    let path = RunLogColumn::PathPosition.find(&log).unwrap();
    let flags = RunLogColumn::Flags.find(&log).unwrap();
    let mut k = 0;
    while let Some(row) = log.next_row().unwrap() {
        let sample = &samples[k];
        assert_eq!(row.line(), 3 + k);
        assert!((row.finite(q3).unwrap() - sample.q_rad[2]).abs() < 1e-9);
        assert_eq!(row.finite(fz).unwrap(), 900.0);
        assert_eq!(row.unsigned(flags).unwrap(), sample.flags);
        let s = row.number(path).unwrap();
        if k == 0 {
            assert!(s.is_nan());
            // Empty is unknown, not a finite number.
            assert!(row.finite(path).is_err());
        } else {
            assert!((s - sample.path_s_m).abs() < 1e-6);
        }
        k += 1;
    }
    assert_eq!(k, 4);
    // Several columns at once.
    let found =
        RunLogColumn::find_all(&[RunLogColumn::Time, RunLogColumn::LoopGain], &log).unwrap();
    assert_eq!(found, [0, columns[columns.len() - 4]]);
}

#[test]
fn reader_errors_name_the_file_line_and_column() {
    let text = "# SIMULATED twin\ntime_s,q1_rad,flags\n0.0,0.1,0\n0.1,abc,0\n0.2,nan,4.5\n";
    let mut log = LogReader::new(text, "x.csv").unwrap();
    assert!(log.simulated());
    let q = log.column("q1_rad").unwrap();
    let flags = log.column("flags").unwrap();
    assert_eq!(
        log.columns_of(&["time_s", "w_fx_n", "flags", "xi_x_m"]),
        Err(vec!["w_fx_n".to_string(), "xi_x_m".to_string()])
    );
    let row = log.next_row().unwrap().unwrap();
    assert_eq!(row.finite(q).unwrap(), 0.1);
    let row = log.next_row().unwrap().unwrap();
    assert_eq!(
        row.number(q).unwrap_err().to_string(),
        "x.csv:4: column `q1_rad`: expected a number, got \"abc\""
    );
    let row = log.next_row().unwrap().unwrap();
    assert!(row.number(q).unwrap().is_nan());
    assert_eq!(
        row.finite(q).unwrap_err(),
        LogReadError::BadValue {
            file: "x.csv".into(),
            line: 5,
            column: "q1_rad".into(),
            value: "nan".into()
        }
    );
    assert_eq!(
        row.unsigned(flags).unwrap_err().to_string(),
        "x.csv:5: column `flags`: expected a number, got \"4.5\""
    );
    assert!(log.next_row().unwrap().is_none());
    // A row with another number of cells than the header.
    let mut log = LogReader::new("a,b\n1,2\n1,2,3\n", "y.csv").unwrap();
    assert!(log.next_row().unwrap().is_some());
    match log.next_row() {
        Err(e @ LogReadError::Csv { line: 3, .. }) => {
            assert!(e.to_string().starts_with("y.csv:3: "), "{e}")
        }
        other => panic!("{other:?}"),
    }
}

/// The row format `deflex run` writes, character for character (the columns and precisions of
/// the log before it became a sink of the stream): seconds with 6 decimals, joints with 9,
/// wrenches with 4, displacements with 9, the arc length empty when unknown, the loop gain with
/// 4, the cycle time in µs with 2, the flags as an integer and by name.
#[test]
fn the_row_format_is_unchanged() {
    // The arc length unknown: its column empty.
    let mut out = output();
    out.path_s_m = f64::NAN;
    let row = RunLogFormat::cell(2).row(&cycle_sample(
        &[0.1, -0.2],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        &out,
        12.5,
    ));
    let expected = "1.500000,0.100000000,-0.200000000,\
        1.0000,2.0000,3.0000,4.0000,5.0000,6.0000,\
        0.5000,0.5000,0.5000,0.5000,0.5000,0.5000,\
        -1.2500,0.0000,900.0000,0.0000,0.0000,0.1250,\
        0.000100000,0.000000000,-0.000250000,0.000000000,0.000000000,0.000001000,\
        -0.000100000,0.000000000,0.000250000,0.000000000,0.000000000,-0.000001000,\
        0.000000003,0.000000000,0.000000000,0.000000000,0.000000000,0.000000000,\
        0.000000000,0.000000000,0.000000000,0.000000000,0.000000000,0.000000000,\
        ,0.2500,12.50,1572864,ramping|active";
    assert_eq!(row, expected);
    assert_eq!(
        RunLogFormat::cell(2).header(),
        "time_s,q1_rad,q2_rad,raw_fx_n,raw_fy_n,raw_fz_n,raw_mx_nm,raw_my_nm,raw_mz_nm,\
         ws_fx_n,ws_fy_n,ws_fz_n,ws_mx_nm,ws_my_nm,ws_mz_nm,w_fx_n,w_fy_n,w_fz_n,w_mx_nm,\
         w_my_nm,w_mz_nm,ds_x_m,ds_y_m,ds_z_m,ds_rx_rad,ds_ry_rad,ds_rz_rad,xi_x_m,xi_y_m,\
         xi_z_m,xi_rx_rad,xi_ry_rad,xi_rz_rad,eps_x_m,eps_y_m,eps_z_m,eps_rx_rad,eps_ry_rad,\
         eps_rz_rad,ff_x_m,ff_y_m,ff_z_m,ff_rx_rad,ff_ry_rad,ff_rz_rad,path_s_m,loop_gain,\
         cycle_us,flags,status"
    );
}

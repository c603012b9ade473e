//! `deflex`: the command-line front end. Thin: it parses arguments and calls the crates.

mod args;
mod cell_server;
mod cmd_calib;
mod cmd_compensate;
mod cmd_control;
mod cmd_demo;
mod cmd_egcal;
mod cmd_export;
mod cmd_model;
mod cmd_plan;
mod cmd_plot;
mod cmd_register;
mod cmd_sim;
mod error;
mod live;
mod ros2_parts;

use clap::{Parser, Subcommand};
use deflex_files::OutputKind;
use error::CliError;
use std::path::Path;
use std::process::ExitCode;

/// `deflex --version`: the version and whether this build has the ROS 2 bridge (the `ros2`
/// cargo feature, see [`ros2_parts`]).
#[cfg(feature = "ros2")]
const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), " (with ROS 2)");
#[cfg(not(feature = "ros2"))]
const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (without ROS 2: ",
    ros2_parts::ros2_build_command!(),
    ")"
);

/// deflex: make industrial robots accurate under load (elasto-geometrical model, calibration,
/// force-feedback correction, digital twin). SI units in files; human output in mm, degrees.
#[derive(Parser)]
#[command(name = "deflex", version = VERSION, about, long_about = None)]
struct Cli {
    /// Machine-readable JSON on stdout instead of human-readable text.
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Inspect a robot model.
    Model {
        #[command(subcommand)]
        command: cmd_model::ModelCommand,
    },
    /// TCP pose for given joint values.
    Pose(cmd_model::PoseArgs),
    /// TCP deflection under a wrench (eq. 15).
    Deflect(cmd_model::DeflectArgs),
    /// Joint values for a TCP pose.
    Ik(cmd_model::IkArgs),
    /// Deflection over a grid of TCP positions, tool pointing down (paper Fig. 10 set-up).
    Map(cmd_model::MapArgs),
    /// Identify stiffnesses (and the model structure) from measurements.
    Calibrate(cmd_calib::CalibrateArgs),
    /// Elasto-geometric calibration from absolute tracker readings: geometry, set-ups,
    /// targets, gravity sag and stiffness together.
    CalibrateGeometry(cmd_egcal::CalibrateGeometryArgs),
    /// Predict absolute readings (each row's target in its set-up's tracker frame).
    Predict(cmd_egcal::PredictArgs),
    /// Register a new measuring session (tracker set-up) and, optionally, a new target from a
    /// few readings, the calibrated robot frozen.
    Register(cmd_register::RegisterArgs),
    /// Convert a public data set into deflex's absolute measurement format.
    Import {
        #[command(subcommand)]
        command: cmd_egcal::ImportCommand,
    },
    /// Prediction errors of a model against measurements, with plots.
    Validate(cmd_calib::ValidateArgs),
    /// Propose a measurement campaign for identification.
    Plan(cmd_plan::PlanArgs),
    /// The digital twin of the robotised ISF cell (SIMULATED).
    Sim {
        #[command(subcommand)]
        command: cmd_sim::SimCommand,
    },
    /// Compensate a tool path offline and write robot programs (no real-time option needed).
    Compensate(cmd_compensate::CompensateArgs),
    /// Write a calibrated robot as a URDF, a UR calibration file or a DH-corrections table.
    Export(cmd_export::ExportArgs),
    /// Run the real-time correction controller against a robot and a force sensor.
    Run(cmd_control::RunArgs),
    /// Serve the simulated cell over the robot and sensor protocols on loopback.
    Cell(cell_server::CellArgs),
    /// The paper's whole study on the built-in SIMULATED cell, with an HTML report.
    Demo(cmd_demo::DemoArgs),
    /// Figures of a run's log (deflex run CSV, sim isf log.csv or MCAP), or two overlaid.
    Plot(cmd_plot::PlotArgs),
}

impl Command {
    /// Every output the command writes, with the flag that names it: checked before the
    /// command runs ([`deflex_files::check_output_flag`]: no device, FIFO, socket, dangling
    /// link or foreign folder is ever replaced). Outputs named in files (`[log] path`) are
    /// checked by their command once the file is read.
    fn outputs(&self) -> Vec<(&'static str, &Path, OutputKind)> {
        use OutputKind::{File, Folder};
        let mut outputs = Vec::new();
        match self {
            Command::Map(a) => outputs.push(("--out", a.out.as_path(), Folder)),
            Command::Calibrate(a) => {
                outputs.push(("--out", a.out.as_path(), File));
                if let Some(r) = &a.report {
                    outputs.push(("--report", r.as_path(), Folder));
                }
            }
            Command::CalibrateGeometry(a) => {
                outputs.push(("--out", a.out.as_path(), File));
                if let Some(r) = &a.report {
                    outputs.push(("--report", r.as_path(), Folder));
                }
            }
            Command::Predict(a) => outputs.push(("--out", a.out.as_path(), File)),
            Command::Register(a) => outputs.push(("--out", a.out.as_path(), File)),
            Command::Import {
                command: cmd_egcal::ImportCommand::Ur10Tracker(a),
            } => outputs.push(("--out", a.out.as_path(), File)),
            Command::Validate(a) => {
                if let Some(o) = &a.out {
                    outputs.push(("--out", o.as_path(), Folder));
                }
            }
            Command::Plan(a) => outputs.push(("--out", a.out.as_path(), File)),
            Command::Sim { command } => match command {
                cmd_sim::SimCommand::Campaign(a) => outputs.push(("--out", a.out.as_path(), File)),
                cmd_sim::SimCommand::Isf(a) => outputs.push(("--out", a.out.as_path(), Folder)),
                cmd_sim::SimCommand::Sensitivity(a) => {
                    outputs.push(("--out", a.out.as_path(), Folder))
                }
                cmd_sim::SimCommand::Robot(a) => outputs.push(("--out", a.out.as_path(), File)),
            },
            Command::Compensate(a) => outputs.push(("--out", a.out.as_path(), Folder)),
            Command::Export(a) => outputs.push(("--out", a.out.as_path(), File)),
            Command::Demo(a) => outputs.push(("--out", a.out.as_path(), Folder)),
            Command::Plot(a) => outputs.push(("--out", a.out.as_path(), Folder)),
            Command::Model { .. }
            | Command::Pose(_)
            | Command::Deflect(_)
            | Command::Ik(_)
            | Command::Run(_)
            | Command::Cell(_) => {}
        }
        outputs
    }
}

/// Refuse, before the command runs, an output that is not a file or folder deflex may replace.
fn check_outputs(command: &Command) -> Result<(), CliError> {
    for (flag, path, kind) in command.outputs() {
        deflex_files::check_output_flag(flag, path, kind)?;
    }
    Ok(())
}

fn main() -> ExitCode {
    restore_default_sigpipe();
    // Every file a command reads is remembered, so that no output replaces one of them.
    deflex_files::track_inputs();
    let cli = Cli::parse();
    if let Err(error) = check_outputs(&cli.command) {
        eprintln!("error: {}", deflex_files::shown_text(&error.to_string()));
        return ExitCode::from(error.exit_code());
    }
    let result = match cli.command {
        Command::Model { command } => cmd_model::model(command, cli.json),
        Command::Pose(args) => cmd_model::pose(args, cli.json),
        Command::Deflect(args) => cmd_model::deflect(args, cli.json),
        Command::Ik(args) => cmd_model::ik(args, cli.json),
        Command::Map(args) => cmd_model::map(args, cli.json),
        Command::Calibrate(args) => cmd_calib::calibrate(args, cli.json),
        Command::CalibrateGeometry(args) => cmd_egcal::calibrate_geometry(args, cli.json),
        Command::Predict(args) => cmd_egcal::predict(args, cli.json),
        Command::Register(args) => cmd_register::register(args, cli.json),
        Command::Import { command } => cmd_egcal::import(command, cli.json),
        Command::Validate(args) => cmd_calib::validate(args, cli.json),
        Command::Plan(args) => cmd_plan::plan(args, cli.json),
        Command::Sim { command } => cmd_sim::sim(command, cli.json),
        Command::Compensate(args) => cmd_compensate::compensate_command(args, cli.json),
        Command::Export(args) => cmd_export::export(args, cli.json),
        Command::Run(args) => cmd_control::run(args, cli.json),
        Command::Cell(args) => cell_server::cell(args, cli.json),
        Command::Demo(args) => cmd_demo::demo(args, cli.json),
        Command::Plot(args) => cmd_plot::plot(args, cli.json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // The one place a command's error becomes text.
            eprintln!("error: {}", deflex_files::shown_text(&error.to_string()));
            ExitCode::from(error.exit_code())
        }
    }
}

/// `deflex ... | head` should end quietly like other Unix tools instead of panicking on a
/// broken pipe: restore the default SIGPIPE action that the Rust runtime replaces.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal disposition to SIG_DFL at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

//! `deflex register`: a new measuring session (where the tracker stands) and, optionally, a new
//! target (probe) registered from a handful of readings with the calibrated robot frozen
//! (maths in `deflex_calibrate::geometry::register`).

use crate::args::{check_flag, print_json};
use crate::cmd_egcal::{load_model, read_absolute, read_bounded, terms_path};
use crate::error::{CliError, CommandResult, UsageError};
use clap::Args;
use deflex_app::report::absolute_report::registration;
use deflex_calibrate::geometry::campaign::Campaign;
use deflex_calibrate::geometry::data::DEFAULT_ORIENTATION_SIGMA_RAD;
use deflex_calibrate::geometry::register::{RegisterOptions, register as register_session};
use deflex_calibrate::geometry::solve::Loss;
use std::path::PathBuf;

/// Readings that do not say which set-up or target to register.
#[derive(Debug, thiserror::Error)]
pub enum RegisterInputError {
    /// Several set-ups and no `--setup`.
    #[error("{}: the data names set-ups {setups}: choose one with --setup", .data.display())]
    WhichSetup {
        /// The data file.
        data: PathBuf,
        /// The set-ups it names.
        setups: String,
    },
    /// No reading of the set-up asked for.
    #[error("{}: no reading of set-up `{setup}`", .data.display())]
    NoSetupReadings {
        /// The data file.
        data: PathBuf,
        /// The set-up.
        setup: String,
    },
    /// A reading of a target the robot file does not know, and not the one to register.
    #[error("{}:{line}: target `{target}` is not in the robot file: register it with --target {target}", .data.display())]
    UnknownTarget {
        /// The data file.
        data: PathBuf,
        /// Its line.
        line: u64,
        /// The target.
        target: String,
    },
    /// `--target` names a target no reading has.
    #[error("{}: no reading of target `{target}`", .data.display())]
    NoTargetReadings {
        /// The data file.
        data: PathBuf,
        /// The target.
        target: String,
    },
}

#[derive(Args)]
pub struct RegisterArgs {
    /// Calibrated robot file (from calibrate-geometry; its NAME.terms.json is used when present).
    #[arg(long)]
    pub robot: String,
    /// A few absolute readings of the new session (30 recommended, spread over the workspace
    /// and the wrist orientations).
    #[arg(long)]
    pub data: PathBuf,
    /// Set-up to register (default: the one set-up the data names). A new name is registered
    /// from scratch; a known one is re-registered (same tracker place, new session).
    #[arg(long)]
    pub setup: Option<String>,
    /// Target whose offset on the flange is fitted too (a new probe, or one remounted): 3
    /// parameters, 6 with --orientations.
    #[arg(long)]
    pub target: Option<String>,
    /// Fit the measured orientations (rx_rad…) too.
    #[arg(long)]
    pub orientations: bool,
    /// Standard deviation of an orientation component for rows without sigma_rad (rad).
    #[arg(long, default_value_t = DEFAULT_ORIENTATION_SIGMA_RAD)]
    pub sigma_rad: f64,
    /// Residual RMS (mm) above which the robot is deemed changed (default: 1.5 × the
    /// calibration's held-out RMS from the terms file).
    #[arg(long)]
    pub recalibrate_above_mm: Option<f64>,
    /// Updated robot file (the new set-up and target added; everything else as it was).
    #[arg(long)]
    pub out: PathBuf,
    /// A column of the measurement file(s) that deflex does not read, kept knowingly
    /// (repeatable). Without it an unknown column is an error naming the closest known one.
    #[arg(long = "ignore-column", value_name = "NAME")]
    pub ignore_column: Vec<String>,
}

/// Runs `deflex register`.
pub fn register(args: RegisterArgs, json_output: bool) -> CommandResult {
    check_flag(
        "--sigma-rad",
        args.sigma_rad,
        1e-9,
        deflex_calibrate::measurements::MAX_SIGMA_RAD,
        "rad",
    )?;
    if let Some(mm) = args.recalibrate_above_mm {
        check_flag("--recalibrate-above-mm", mm, 1e-3, 1e3, "mm")?;
    }
    let (mut model, terms) = load_model(&args.robot)?;
    let rows = read_absolute(&args.data, model.robot.joint_count(), &args.ignore_column)?;
    let setup_name = match &args.setup {
        Some(s) => s.clone(),
        None => {
            let mut names: Vec<&str> = rows.iter().map(|r| r.setup.as_str()).collect();
            names.sort_unstable();
            names.dedup();
            match names.as_slice() {
                [one] => one.to_string(),
                _ => {
                    return Err(RegisterInputError::WhichSetup {
                        data: args.data.clone(),
                        setups: names.join(", "),
                    }
                    .into());
                }
            }
        }
    };
    let rows: Vec<_> = rows.into_iter().filter(|r| r.setup == setup_name).collect();
    if rows.is_empty() {
        return Err(RegisterInputError::NoSetupReadings {
            data: args.data.clone(),
            setup: setup_name,
        }
        .into());
    }
    for row in &rows {
        let known = model.target_index(&row.target).is_some();
        if !known && args.target.as_deref() != Some(row.target.as_str()) {
            return Err(RegisterInputError::UnknownTarget {
                data: args.data.clone(),
                line: row.line,
                target: row.target.clone(),
            }
            .into());
        }
    }
    let new_setup = model.setup_index(&setup_name).is_none();
    if let Some(t) = args
        .target
        .as_deref()
        .and_then(|name| model.target_index(name))
    {
        // A remounted or replaced probe: found from scratch.
        model.targets[t].position = nalgebra::Vector3::zeros();
        model.targets[t].rotation = None;
    }
    let mut campaign = Campaign::new(&mut model, rows, Vec::new())?;
    if args.orientations {
        campaign.use_orientations(args.sigma_rad);
        if campaign.orientation_rows.is_empty() {
            return Err(UsageError::Missing {
                what: "--orientations",
                give: "no reading has rx_rad, ry_rad, rz_rad",
            }
            .into());
        }
    }
    let setup =
        model
            .setup_index(&setup_name)
            .ok_or_else(|| RegisterInputError::NoSetupReadings {
                data: args.data.clone(),
                setup: setup_name.clone(),
            })?;
    let target =
        match &args.target {
            Some(name) => Some(model.target_index(name).ok_or_else(|| {
                RegisterInputError::NoTargetReadings {
                    data: args.data.clone(),
                    target: name.clone(),
                }
            })?),
            None => None,
        };
    let options = RegisterOptions {
        setup,
        target,
        loss: Loss::HUBER_DEFAULT,
        recalibrate_above_m: args
            .recalibrate_above_mm
            .map(|mm| mm * 1e-3)
            .or_else(|| terms.as_ref().and_then(|t| t.recalibrate_above_m())),
        restart_setup: new_setup,
    };
    let all = vec![1.0; campaign.len()];
    let result = register_session(&mut model, &campaign, &all, &options)?;
    // Orientations measured but not fitted: the new target's frame in closed form, so that
    // `predict` can report orientation errors.
    if let Some(t) = target.filter(|&t| model.targets[t].rotation.is_none()) {
        deflex_calibrate::geometry::register::start::initialise_target_rotations(
            &mut model,
            &campaign,
            &[t],
            &all,
        );
    }
    let robot_out = model.to_robot();
    let toml = deflex_app::load::robot_to_toml_for(&robot_out, &args.out);
    if terms.is_some() {
        let from = terms_path(std::path::Path::new(&args.robot));
        let text = read_bounded(&from, 64 << 20)?;
        let to = terms_path(&args.out);
        deflex_files::write_atomic(&to, text).map_err(CliError::write(&to))?;
    }
    deflex_files::write_atomic(&args.out, toml).map_err(CliError::write(&args.out))?;
    if json_output {
        print_json(&registration::json(
            &result,
            &setup_name,
            args.target.as_deref(),
            &args.out,
        ));
    } else {
        print!(
            "{}",
            registration::text(&result, &setup_name, args.target.as_deref())
        );
        println!("updated robot written to {}", args.out.display());
    }
    Ok(())
}

//! Progress of a long job: one message for every long computation of deflex (the structure
//! search of a stiffness calibration, the compensation of a tool path, the whole study of
//! `deflex demo`), so that a front end has one display for all of them (the command line's
//! progress bars, a Python callback).
//!
//! A job is a sequence of **stages** (the study's ten, the search's steps, the compensation's
//! passes and iterations). It reports, in this order, for each stage:
//!
//! 1. [`Progress::Stage`] once, when the stage starts: its number and name;
//! 2. [`Progress::Work`] as the stage advances: `done` of `total` units (candidate structures,
//!    path points, or per mille of a simulated run, [`Progress::per_mille`]); `done` never
//!    decreases within a stage;
//! 3. [`Progress::Done`] when the stage has a one-line result to show (optional: the search and
//!    the compensation report their results in their return values).
//!
//! A job that runs another one inside a stage (the study's identification runs the structure
//! search) passes the inner job's [`Progress::Work`] on as its own stage's and keeps the inner
//! stages to itself.
//!
//! Receivers are `FnMut(Progress<'_>)` closures ([`OnProgress`]); a caller without a display
//! passes `&mut |_| {}`.
//!
//! ```
//! use deflex_telemetry::Progress;
//! let mut shown = Vec::new();
//! let mut on_progress = |p: Progress<'_>| shown.push(p.to_string());
//! on_progress(Progress::Stage { index: 1, count: Some(2), name: "plan" });
//! on_progress(Progress::Work { done: 3, total: 4 });
//! on_progress(Progress::Done { note: "40 load cases" });
//! assert_eq!(shown, ["stage 1/2: plan", "3/4", "done: 40 load cases"]);
//! ```

/// One report of a long job's progress (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress<'a> {
    /// A stage starts.
    Stage {
        /// Its number, from 1.
        index: usize,
        /// How many stages the job has, when it knows that in advance (the study's ten);
        /// `None` when it depends on the work (the search's steps, the compensation's
        /// iterations).
        count: Option<usize>,
        /// What the stage does, as shown to the user (`step 2`, `IK of the path`).
        name: &'a str,
    },
    /// Work done in the current stage: `done` of `total` units.
    Work {
        /// Units done (never decreasing within a stage).
        done: usize,
        /// Units of the stage (`0` when unknown).
        total: usize,
    },
    /// The current stage is done.
    Done {
        /// Its result in one line (may be empty).
        note: &'a str,
    },
}

/// Where a job sends its progress.
pub type OnProgress<'a> = &'a mut dyn FnMut(Progress<'_>);

/// The units of [`Progress::per_mille`].
pub const PER_MILLE: usize = 1000;

impl Progress<'static> {
    /// Work measured as a fraction of the stage (a simulated run's time): `fraction` (clamped
    /// to 0 … 1; NaN counts as 0) in per mille, `Work { done, total: 1000 }`.
    pub fn per_mille(fraction: f64) -> Progress<'static> {
        Progress::Work {
            done: (fraction.clamp(0.0, 1.0) * PER_MILLE as f64) as usize,
            total: PER_MILLE,
        }
    }
}

impl Progress<'_> {
    /// The fraction of the stage done, for a [`Progress::Work`] of known total (clamped to
    /// 0 … 1); `None` for the other reports.
    pub fn fraction(&self) -> Option<f64> {
        match *self {
            Progress::Work { done, total } if total > 0 => {
                Some((done as f64 / total as f64).clamp(0.0, 1.0))
            }
            _ => None,
        }
    }
}

impl std::fmt::Display for Progress<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Progress::Stage {
                index,
                count: Some(count),
                name,
            } => write!(f, "stage {index}/{count}: {name}"),
            Progress::Stage {
                index,
                count: None,
                name,
            } => write!(f, "stage {index}: {name}"),
            Progress::Work { done, total } => write!(f, "{done}/{total}"),
            Progress::Done { note } => write!(f, "done: {note}"),
        }
    }
}

//! The correction law in-process against the twin (SIMULATED): the paper's Table 1 model (the
//! paper's cone with a model identified from the twin's campaign and a model read from a file
//! are in deflex-app's tests, which identify and read it).

use deflex_model::Robot;
use deflex_sim::twin::{ClosedLoopRun, controller_config_for, run_closed_loop};
use deflex_sim::{CellConfig, FormingRun, ToolPath};

struct Comparison {
    open: FormingRun,
    closed: ClosedLoopRun,
}

fn compare(path: ToolPath, model: Robot, seed: u64) -> Comparison {
    let cell = CellConfig::default();
    let open = deflex_sim::run_forming(&cell, path.clone(), seed, None).unwrap();
    let config = controller_config_for(&cell);
    let closed = run_closed_loop(&cell, path, seed, model, config, true, &mut |_| {}).unwrap();
    Comparison { open, closed }
}

/// With the paper's Table 1 model (stiffer than the twin's robot) the loop still helps.
#[test]
fn table1_model_still_improves_a_short_run() {
    let model = deflex_model::builtin("tx200").unwrap();
    let c = compare(ToolPath::paper_cone().truncated(600.0), model, 2);
    let (o, k) = (&c.open.summary, &c.closed.forming.summary);
    assert!(k.max_error_norm_mm < 0.9 * o.max_error_norm_mm);
    assert!(c.closed.fault.is_none());
}

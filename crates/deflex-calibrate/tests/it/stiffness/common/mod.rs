//! Shared test fixtures: a second 6-axis geometry and campaign helpers.
#![allow(dead_code)]

use deflex_calibrate::measurements::MeasurementRow;
use deflex_calibrate::stiffness::plan::{BasePoint, PlanOptions, plan_experiments};
use deflex_calibrate::stiffness::synthetic::random_campaign;
use deflex_model::{Robot, robot_from_toml_str};
use rand::{Rng, SeedableRng};

/// A KUKA KR210-like arm in modified DH (shoulder offset, long upper arm, forearm offset),
/// with a 0.1 m tool. Truth: z on joints 1–5, a y-eDoF on joint 3 with its centre shifted
/// −0.3 m along z3, and a base tilt about x0.
pub const KR_LIKE: &str = r#"
name = "KR210-like test arm"
[base]
stiffness = { x = 9.0e6 }
[[joint]]
alpha = 0.0
a = 0.0
d = 0.0
theta_offset = 0.0
limits = [-3.2, 3.2]
stiffness = { z = 3.5e6 }
[[joint]]
alpha = -1.5707963267948966
a = 0.35
d = 0.0
theta_offset = -1.5707963267948966
limits = [-2.4, 0.6]
stiffness = { z = 2.8e6 }
[[joint]]
alpha = 0.0
a = 1.15
d = 0.0
theta_offset = 0.0
limits = [-2.0, 2.6]
center_shift = -0.3
stiffness = { y = 1.3e6, z = 1.9e6 }
[[joint]]
alpha = -1.5707963267948966
a = -0.041
d = 1.0
theta_offset = 0.0
limits = [-6.0, 6.0]
stiffness = { z = 0.25e6 }
[[joint]]
alpha = 1.5707963267948966
a = 0.0
d = 0.0
theta_offset = 0.0
limits = [-2.1, 2.1]
stiffness = { z = 0.12e6 }
[[joint]]
alpha = -1.5707963267948966
a = 0.0
d = 0.215
theta_offset = 0.0
limits = [-6.0, 6.0]
[tool]
xyz = [0.0, 0.0, 0.1]
"#;

pub fn kr_like() -> Robot {
    robot_from_toml_str(KR_LIKE, "kr-like", None).unwrap()
}

/// The TX200 of the paper (Table 1, δr3 = 0.4 m) plus a base tilt about y0 (the paper's
/// Section 3.1 observation at M1).
pub fn tx200_truth() -> Robot {
    let mut r = deflex_model::builtin("tx200").unwrap();
    r.set_stiffness(
        deflex_model::EdofSite::Base,
        deflex_model::Axis::Y,
        Some(6.0e6),
    );
    r
}

/// Identification campaign: the planner's full-family plan (axis-by-axis + D-optimal) with load
/// magnitudes redrawn in 600–1400 N, plus random load cases.
pub fn campaign(
    robot: &Robot,
    plan_cases: usize,
    random_cases: usize,
    seed: u64,
) -> Vec<MeasurementRow> {
    let plan = plan_experiments(
        robot,
        &PlanOptions {
            max_force_n: 1400.0,
            load_cases: plan_cases,
            configurations: 300,
            full_family: true,
            seed,
            // The recovery fixtures measure the TCP and the mid-arm points only.
            base_point: BasePoint::Off,
            ..PlanOptions::default()
        },
    )
    .unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x55);
    let mut rows = plan.rows;
    let mut last = String::new();
    let mut scale = 1.0;
    for r in &mut rows {
        if r.load_case != last {
            last = r.load_case.clone();
            scale = rng.gen_range(600.0..=1400.0) / 1400.0;
        }
        for v in &mut r.wrench {
            *v *= scale;
        }
    }
    rows.extend(random_campaign(
        robot,
        random_cases,
        (600.0, 1400.0),
        seed + 1000,
    ));
    rows
}

//! Integration tests of `deflex-model`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file. That the hot path allocates nothing and
//! that the robot readers never panic are checked in the facade's test binary
//! (`no_alloc::model`, `fuzz::model`).

mod conventions;
mod files;
mod fixtures;
mod robots;
mod wrench_transport;

/// One DH `[[joint]]` stating `extra` and, for each of the four required DH keys (`alpha`, `a`,
/// `d`, `theta_offset`) `extra` does not state, 0.0.
pub fn dh_joint(extra: &str) -> String {
    let mut joint = String::from("[[joint]]\n");
    for key in ["alpha", "a", "d", "theta_offset"] {
        let stated = extra
            .lines()
            .any(|l| l.split('=').next().map(str::trim) == Some(key));
        if !stated {
            joint += &format!("{key} = 0.0\n");
        }
    }
    joint + extra
}

//! Integration tests of `deflex-model`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

// Counts only the calling thread's allocations (see `deflex-alloc-count`), so the
// no-allocation tests are undisturbed by the other tests of this binary running in parallel.
#[global_allocator]
static GLOBAL: deflex_alloc_count::CountingAllocator = deflex_alloc_count::CountingAllocator;

mod files;
mod fixtures;
mod fuzz;
mod no_alloc;
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

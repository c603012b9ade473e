//! The promises that span the layers, checked through the facade in one test binary:
//!
//! * [`no_alloc`]: no per-cycle path allocates (the model's kinematics and deflection, the
//!   control law's cycle, the protocols' receive and send, the telemetry publish, the
//!   runtime's control thread, and what a live page or the ROS 2 bridge costs it), counted per
//!   thread by the counting global allocator of this binary;
//! * [`fuzz`]: no parser panics, whatever its input (robot files and URDF, measurement files,
//!   wire protocols, `CELL.toml`, the twin's settings), with a small deterministic mutation
//!   fuzzer ([`fuzz::engine`]);
//! * [`layers`]: every package depends only on packages of lower layers.

/// Counts every allocation per thread (`densa_alloc::thread_stats`), so a test counts only its
/// own thread's.
#[global_allocator]
static ALLOCATOR: densa_alloc::CountingAllocator = densa_alloc::CountingAllocator::system();

mod fuzz;
mod layers;
mod no_alloc;

//! The tests of `deflex-telemetry`, through its public API: one test binary (modules below), so
//! the library is compiled once (`[lib] test = false`). The ring and the sequence cell under
//! concurrent readers, the progress message of a long job, and the ROS 2 messages' CDR encodings and definitions. That publishing
//! allocates nothing is checked in the facade's test binary (`no_alloc::telemetry`), under its
//! counting allocator.

mod progress;
mod ring;
mod ros;

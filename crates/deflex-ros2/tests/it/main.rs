//! Integration tests of `deflex-ros2`: one test binary, through the public API. `loopback`: the
//! bridge and the sensor link talking to themselves over loopback DDS (its helpers in `dds`);
//! `handover`: the bounded queue between the DDS reader and the sensor thread. The independent
//! check of the bytes is the Python cyclonedds test in tests/python; what the ROS 2 parts cost
//! the control thread of a real session is measured above the runtime, in the facade's
//! `no_alloc::ros2` (crates/deflex/tests/it).

mod dds;
mod handover;
mod loopback;

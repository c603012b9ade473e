//! Integration tests of `deflex-record`: one test binary, through the public API. `recording`
//! writes MCAP recordings and reads them back (values, ROS 2 schemas, the size cap, a full disk,
//! the recorder thread, foreign and damaged files); `csv_log` writes the CSV log from the
//! telemetry stream; `run_log` is the run log's one definition and the one log reader; `trace`
//! reads every kind of run log as plot columns.

mod csv_log;
mod recording;
mod run_log;
mod trace;

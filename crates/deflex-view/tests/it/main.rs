//! Integration tests of `deflex-view`: one test binary. `server` talks to the server over
//! loopback sockets; `browser` (ignored by default, run with `cargo test -p deflex-view --
//! --ignored`) drives Debian's headless Chromium over the DevTools protocol; `frame` checks the
//! decimation, the p99 and the wire format against separately written computations.
//!
//! What an open page costs the control loop of a session against the twin is measured above
//! the twin and the runtime, in the facade's `no_alloc::view` (crates/deflex/tests/it).

mod browser;
mod cdp;
mod frame;
mod server;
mod support;

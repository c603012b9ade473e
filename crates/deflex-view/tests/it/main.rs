//! Integration tests of `deflex-view`: one test binary. `server` talks to the server over
//! loopback sockets; `browser` (ignored by default, run with `cargo test -p deflex-view --
//! --ignored`) drives Debian's headless Chromium over the DevTools protocol.

mod browser;
mod cdp;
mod server;
mod support;

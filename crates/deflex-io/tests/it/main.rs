//! The tests of `deflex-io`, through its public API: one test binary (modules below), so a fresh
//! clone links one executable for this crate instead of one per file, and compiles the library
//! once (it has no test build of its own). A module per protocol or piece (`egm`, `rsi`, …) and
//! per concern across them (`peers`, `replays`, …). That the hot path allocates nothing and that
//! no parser panics are checked in the facade's test binary (`no_alloc::io`, `fuzz::io`).

mod egm;
mod fanuc_stream;
mod guard;
mod link;
mod netft;
mod peer;
mod peer_policy;
mod peers;
mod replays;
mod rsi;
mod rtde;
mod rtde_python;
mod simple_tcp;
mod simple_udp;
mod staubli;
mod tcp_abuse;
mod udp;
mod xml;

//! Integration tests of `deflex-compensate`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file. That the per-point work allocates nothing
//! is checked in the facade's test binary (`no_alloc::compensate`).

mod compensate;
mod compensated_line;
mod logged;
mod path;
mod table;

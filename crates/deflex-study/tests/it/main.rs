//! Integration tests of `deflex-study`: one test binary (modules below), so a fresh clone links one
//! executable for this crate instead of one per file.

mod quick_demo;
mod stiff_contact;

//! The tests of `deflex_cam::export` (the old `deflex-export`).

mod round_trip;

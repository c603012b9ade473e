//! deflex-sim

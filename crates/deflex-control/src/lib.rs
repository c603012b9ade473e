//! deflex-control

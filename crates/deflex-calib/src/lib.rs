//! deflex-calib

//! deflex-report

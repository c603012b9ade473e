//! deflex-io

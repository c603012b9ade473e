//! deflex-model

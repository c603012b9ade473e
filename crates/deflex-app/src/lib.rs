//! # deflex-app
//!
//! deflex's workflows, the one layer under the command-line tool and the Python package.

#![warn(missing_docs)]

pub mod calibrate;
pub mod calibrate_geometry;
pub mod cell;
pub mod compensate;
pub mod error;
pub mod export;
pub mod load;
pub mod option_names;
pub mod report;
pub mod robot;
pub mod study;
pub mod table;
pub mod twin;

pub use error::{Error, ErrorKind, Result};

//! # deflex-app
//!
//! deflex's workflows, the one layer under the command-line tool and the Python package.

#![warn(missing_docs)]

pub mod cell;
pub mod load;
pub mod report;
pub mod study;
pub mod twin;

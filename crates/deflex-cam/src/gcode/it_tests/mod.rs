//! Tests of the public API, written as a user of the crate would call it (they were an
//! integration-test binary; as unit tests they share the crate's test binary, so the workspace
//! links fewer executables).

mod corpus;
mod refusals;

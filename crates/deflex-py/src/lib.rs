//! # deflex-py
//!
//! deflex for Python (`import deflex`): the elasto-geometrical model with batched pose,
//! Jacobian, compliance (eq. 15's `C = J K_θ⁻¹ Jᵀ`), deflection and inverse kinematics;
//! stiffness identification and elasto-geometric calibration; offline compensation and the five
//! robot program formats; the digital twin's forming runs and deflex's logs — numpy in, numpy
//! out, the GIL released and the batches spread over the cores (rayon).
//!
//! Two layers:
//!
//! * the **engine** ([`model`], [`calibration`], [`geometry`], [`compensation`], [`twin`],
//!   [`table`]): plain Rust on slices and deflex types, one module per domain, the only code that
//!   calls the other deflex crates (so a restructuring re-points these modules and nothing
//!   else), with typed errors ([`error::Error`]) carrying the CLI's text, and panics caught
//!   ([`error::guard`]);
//! * the **bindings** (`py`, behind the `python` feature that maturin turns on): argument
//!   conversion and checks (shapes, NaN, types), the GIL released around every engine call,
//!   numpy arrays out, errors raised as `deflex.InputError`, `deflex.ModelError`, ….
//!
//! Without the `python` feature the crate builds and tests with no Python at all.

#![warn(missing_docs)]

#[cfg(feature = "python")]
mod py;

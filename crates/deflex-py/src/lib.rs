//! # deflex-py
//!
//! deflex for Python (`import deflex`): the elasto-geometrical model with batched pose,
//! Jacobian, compliance (eq. 15's `C = J K_θ⁻¹ Jᵀ`), deflection and inverse kinematics;
//! stiffness identification and elasto-geometric calibration; offline compensation and the five
//! robot program formats; the digital twin's forming runs and deflex's logs — numpy in, numpy
//! out, the GIL released and the batches spread over the cores (rayon).
//!
//! The crate is the Python front end only: argument checks naming the Python keywords, numpy
//! conversion (shapes, NaN, types), the GIL released around every call, numpy arrays and
//! dictionaries out, errors raised as `deflex.InputError`, `deflex.ModelError`, … (from
//! `deflex_app::ErrorKind`). Every workflow — reading files, calibrating, compensating, running
//! the twin, writing outputs — is `deflex-app`'s, the same code the `deflex` command runs. The
//! bindings are behind the `python` feature that maturin turns on; without it the crate is
//! empty and builds with no Python at all.

#![warn(missing_docs)]

#[cfg(feature = "python")]
mod py;

//! The Python module `deflex._deflex` (PyO3): classes and entry points over the engine layer.
//! The public API is `deflex` (python/deflex), which re-exports the classes and wraps the
//! `_`-prefixed functions with argument handling (paths, DataFrames) and documentation.

mod calib;
mod comp;
mod convert;
mod geometry;
mod robot;
mod twin;

use pyo3::prelude::*;

/// deflex's Rust engine (see the ``deflex`` package for the documented API).
#[pymodule]
fn _deflex(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<robot::PyRobot>()?;
    m.add_class::<calib::PyStiffnessCalibration>()?;
    m.add_class::<calib::PyValidation>()?;
    m.add_class::<geometry::PyGeometryCalibration>()?;
    m.add_class::<geometry::PyPrediction>()?;
    m.add_class::<geometry::PyRegistration>()?;
    m.add_class::<comp::PyCompensation>()?;
    m.add_class::<twin::PyTwinRun>()?;
    m.add_function(wrap_pyfunction!(calib::_calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_validate, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_predict_displacements, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::_calibrate_geometry, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::_predict, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::_register, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::_import_ur10_tracker, m)?)?;
    m.add_function(wrap_pyfunction!(comp::_compensate, m)?)?;
    m.add_function(wrap_pyfunction!(twin::_form, m)?)?;
    m.add_function(wrap_pyfunction!(twin::_cell_robot, m)?)?;
    m.add_function(wrap_pyfunction!(twin::_read_table, m)?)?;
    m.add_function(wrap_pyfunction!(twin::_parse_table, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

//! The Python module `deflex._deflex` (PyO3): classes and entry points over the engine layer.
//! The public API is `deflex` (python/deflex), which re-exports the classes and wraps the
//! `_`-prefixed functions with argument handling (paths, DataFrames) and documentation.

mod calib;
mod comp;
mod convert;
mod robot;

use pyo3::prelude::*;

/// deflex's Rust engine (see the ``deflex`` package for the documented API).
#[pymodule]
fn _deflex(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<robot::PyRobot>()?;
    m.add_class::<calib::PyStiffnessCalibration>()?;
    m.add_class::<calib::PyValidation>()?;
    m.add_class::<calib::PyGeometryCalibration>()?;
    m.add_class::<calib::PyPrediction>()?;
    m.add_class::<comp::PyCompensation>()?;
    m.add_class::<comp::PyTwinRun>()?;
    m.add_function(wrap_pyfunction!(calib::_calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_validate, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_predict_displacements, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_calibrate_geometry, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_predict, m)?)?;
    m.add_function(wrap_pyfunction!(calib::_import_ur10_tracker, m)?)?;
    m.add_function(wrap_pyfunction!(comp::_compensate, m)?)?;
    m.add_function(wrap_pyfunction!(comp::_form, m)?)?;
    m.add_function(wrap_pyfunction!(comp::_cell_robot, m)?)?;
    m.add_function(wrap_pyfunction!(comp::_read_table, m)?)?;
    m.add_function(wrap_pyfunction!(comp::_parse_table, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

//! Conversions at the boundary: numpy/sequence arguments to checked `f64` slices, engine
//! results to numpy arrays and Python objects, engine errors to `deflex` exceptions, and the
//! GIL released (with panics caught) around every engine call.

use deflex_app::error::{Error, ErrorKind, guard};
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::prelude::*;
use numpy::{PyArrayDyn, PyReadonlyArrayDyn};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

/// The exception class of an error kind, from `deflex._errors` (pure Python, imported once).
fn exception_class(py: Python<'_>, kind: ErrorKind) -> PyResult<Bound<'_, PyAny>> {
    static MODULE: PyOnceLock<Py<PyModule>> = PyOnceLock::new();
    let module = MODULE.get_or_try_init(py, || py.import("deflex._errors").map(|m| m.unbind()))?;
    let name = match kind {
        ErrorKind::Input => "InputError",
        ErrorKind::Model => "ModelError",
        ErrorKind::Data => "DataError",
        ErrorKind::Calibration => "CalibrationError",
        ErrorKind::Compensation => "CompensationError",
        ErrorKind::Program => "ProgramError",
        ErrorKind::Simulation => "SimulationError",
        ErrorKind::Io => "DeflexIOError",
        ErrorKind::Internal => "InternalError",
    };
    module.bind(py).getattr(name)
}

/// An exception of class `name` of `deflex._errors` with `message`.
pub fn raise_named(py: Python<'_>, name: &str, message: String) -> PyErr {
    match py
        .import("deflex._errors")
        .and_then(|m| m.getattr(name))
        .and_then(|cls| cls.call1((message.clone(),)))
    {
        Ok(instance) => PyErr::from_value(instance),
        Err(_) => PyRuntimeError::new_err(message),
    }
}

/// The engine error as its `deflex` exception, carrying the CLI's text.
pub fn to_py(py: Python<'_>, error: Error) -> PyErr {
    let message = error.to_string();
    match exception_class(py, error.kind()).and_then(|cls| cls.call1((message.clone(),))) {
        Ok(instance) => PyErr::from_value(instance),
        Err(_) => PyRuntimeError::new_err(message),
    }
}

/// Run engine work with the GIL released and panics caught; errors become `deflex` exceptions.
pub fn run<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> deflex_app::error::Result<T> + Send,
) -> PyResult<T> {
    py.detach(|| guard(f)).map_err(|e| to_py(py, e))
}

/// A wrong argument type (`deflex.InputTypeError`, a `TypeError`).
pub fn type_error(py: Python<'_>, name: &str, expected: &str, got: &Bound<'_, PyAny>) -> PyErr {
    let type_name = got
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    raise_named(
        py,
        "InputTypeError",
        format!("{name}: expected {expected}, got {type_name}"),
    )
}

/// A checked float array argument: its shape and its values in C order, copied while the GIL
/// is held (so that no Python thread can change them while the engine reads them with the GIL
/// released; the copy costs about 1 % of a batched deflection).
pub struct FloatArray<'py> {
    /// Shape.
    pub shape: Vec<usize>,
    values: Vec<f64>,
    _py: std::marker::PhantomData<Python<'py>>,
}

impl FloatArray<'_> {
    /// The values, C order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The values as an owned vector.
    pub fn into_vec(self) -> Vec<f64> {
        self.values
    }
}

/// Read `obj` (a numpy array of any numeric dtype, a list, a tuple, a scalar) as float64
/// values: wrong types raise `deflex.InputTypeError`; NaN and infinities raise
/// `deflex.InputError` naming the index. `expected` describes the shape in messages.
pub fn float_array<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    name: &'static str,
    expected: &str,
) -> PyResult<FloatArray<'py>> {
    let what = format!("an array of numbers of shape {expected}");
    if obj.is_none() || obj.is_instance_of::<PyString>() {
        return Err(type_error(py, name, &what, obj));
    }
    let array: Bound<'py, PyArrayDyn<f64>> = match obj.cast::<PyArrayDyn<f64>>() {
        Ok(a) => a.clone(),
        Err(_) => {
            let numpy = py.import("numpy")?;
            let kwargs = PyDict::new(py);
            kwargs.set_item("dtype", "float64")?;
            let converted = numpy
                .getattr("asarray")?
                .call((obj,), Some(&kwargs))
                .map_err(|_| type_error(py, name, &what, obj))?;
            converted
                .cast_into::<PyArrayDyn<f64>>()
                .map_err(|_| type_error(py, name, &what, obj))?
        }
    };
    let readonly: PyReadonlyArrayDyn<'py, f64> = array.try_readonly().map_err(|e| {
        to_py(
            py,
            Error::invalid(name, format!("the array cannot be read: {e}")),
        )
    })?;
    let shape = readonly.shape().to_vec();
    // `as_slice` also succeeds on Fortran-ordered arrays (memory order): only a C-ordered
    // array's memory is row-major.
    let values = match readonly.as_slice() {
        Ok(slice) if array.is_c_contiguous() => slice.to_vec(),
        _ => readonly.as_array().iter().copied().collect(),
    };
    let array = FloatArray {
        shape,
        values,
        _py: std::marker::PhantomData,
    };
    let cols = if array.shape.len() >= 2 {
        Some(array.shape[1..].iter().product())
    } else {
        None
    };
    deflex_app::robot::check_finite(name, array.values(), cols).map_err(|e| to_py(py, e))?;
    Ok(array)
}

/// Python's way of writing a shape: `(6,)`, `(3, 6)`.
pub fn shape_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A shape error.
pub fn shape_error(py: Python<'_>, name: &'static str, expected: String, got: &[usize]) -> PyErr {
    to_py(
        py,
        Error::Shape {
            name,
            expected,
            got: shape_text(got),
        },
    )
}

/// Rows of a `(cols,)` or `(N, cols)` argument: `(rows, batched)`.
pub fn rows_of(
    py: Python<'_>,
    array: &FloatArray<'_>,
    name: &'static str,
    cols: usize,
    what: &str,
) -> PyResult<(usize, bool)> {
    match array.shape.as_slice() {
        [c] if *c == cols => Ok((1, false)),
        [r, c] if *c == cols && *r > 0 => Ok((*r, true)),
        other => Err(shape_error(
            py,
            name,
            format!("({cols},) or (N, {cols}) with N ≥ 1 ({what})"),
            other,
        )),
    }
}

/// A numpy array of `shape` owning `values` (no copy).
pub fn to_numpy<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let array = ArrayD::from_shape_vec(IxDyn(shape), values)
        .map_err(|e| PyRuntimeError::new_err(format!("internal shape error: {e}")))?;
    Ok(array.into_pyarray(py).into_any())
}

/// Rows of fixed width as a `(rows, N)` numpy array.
pub fn rows_to_numpy<'py, const N: usize>(
    py: Python<'py>,
    rows: &[[f64; N]],
) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<f64> = rows.iter().flatten().copied().collect();
    to_numpy(py, values, &[rows.len(), N])
}

/// A JSON value (from the engine's summaries) as Python objects, through `json.loads`.
pub fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.getattr("loads")?.call1((text,))
}

/// A `deflex.Log` of named columns (numpy arrays or lists of text), comment lines and the
/// SIMULATED flag.
pub fn make_log<'py>(
    py: Python<'py>,
    table: deflex_app::table::CsvTable,
) -> PyResult<Bound<'py, PyAny>> {
    let columns = PyDict::new(py);
    let simulated = table.simulated();
    let rows = table.rows;
    for (name, column) in table.columns {
        match column {
            deflex_app::table::TableColumn::Number(values) => {
                columns.set_item(name, to_numpy(py, values, &[rows])?)?
            }
            deflex_app::table::TableColumn::Text(values) => {
                columns.set_item(name, PyList::new(py, values)?)?
            }
        }
    }
    let comments = PyList::new(py, table.comments)?;
    py.import("deflex.log")?.getattr("Log")?.call1(PyTuple::new(
        py,
        [
            columns.into_any(),
            comments.into_any(),
            simulated.into_pyobject(py)?.to_owned().into_any(),
        ],
    )?)
}

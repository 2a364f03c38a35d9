//! NumPy arrays in and out through NumPy's own functions (`ascontiguousarray`, `tobytes`,
//! `frombuffer`): one copy each way, and the stable ABI (abi3) throughout.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

/// `obj` as a C-contiguous float64 array of shape `(n, cols)`: its values row by row.
pub fn points<const D: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; D]>> {
    let (shape, values) = f64_array(obj)?;
    if shape.len() != 2 || shape[1] != D {
        return Err(PyValueError::new_err(format!(
            "{what}: an array of shape (n, {D}) expected, got {shape:?}"
        )));
    }
    Ok(values
        .chunks_exact(D)
        .map(|c| std::array::from_fn(|d| c[d]))
        .collect())
}

/// `obj` as integer indices of shape `(n, cols)`.
pub fn indices<const K: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[usize; K]>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (obj, "int64"))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != K {
        return Err(PyValueError::new_err(format!(
            "{what}: an integer array of shape (n, {K}) expected, got {shape:?}"
        )));
    }
    let bytes = a.call_method0("tobytes")?;
    let v: Vec<i64> = bytes
        .cast::<PyBytes>()?
        .as_bytes()
        .chunks_exact(8)
        .map(|c| i64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect();
    if let Some(x) = v.iter().find(|x| **x < 0) {
        return Err(PyValueError::new_err(format!("{what}: negative index {x}")));
    }
    Ok(v.chunks_exact(K)
        .map(|c| std::array::from_fn(|k| c[k] as usize))
        .collect())
}

/// `obj` as the rows of an integer array of shape `(n, k)`, concatenated.
pub fn flat_indices(obj: &Bound<'_, PyAny>, k: usize, what: &str) -> PyResult<Vec<usize>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,))?;
    let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind != "i" && kind != "u" {
        return Err(PyValueError::new_err(format!(
            "{what}: an integer array expected, got dtype kind {kind:?}"
        )));
    }
    let a = np.call_method1("ascontiguousarray", (a, "int64"))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != k {
        return Err(PyValueError::new_err(format!(
            "{what}: an integer array of shape (n, {k}) expected, got {shape:?}"
        )));
    }
    let bytes = a.call_method0("tobytes")?;
    bytes
        .cast::<PyBytes>()?
        .as_bytes()
        .chunks_exact(8)
        .map(|c| {
            let v = i64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
            usize::try_from(v)
                .map_err(|_| PyValueError::new_err(format!("{what}: negative index {v}")))
        })
        .collect()
}

/// `obj` as a flat float64 vector.
pub fn vector(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let (shape, values) = f64_array(obj)?;
    if shape.len() > 1 {
        return Err(PyValueError::new_err(format!(
            "{what}: a 1-D array expected, got shape {shape:?}"
        )));
    }
    Ok(values)
}

fn f64_array(obj: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (obj, "float64"))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let bytes = a.call_method0("tobytes")?;
    let bytes = bytes.cast::<PyBytes>()?.as_bytes();
    Ok((
        shape,
        bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect(),
    ))
}

/// A float64 NumPy array of `shape` from `values` (row-major), writable.
pub fn to_f64<'py>(
    py: Python<'py>,
    values: impl IntoIterator<Item = f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let bytes: Vec<u8> = values.into_iter().flat_map(|v| v.to_le_bytes()).collect();
    array(py, &bytes, "<f8", shape)
}

/// An int64 NumPy array of `shape` from `values` (row-major), writable.
pub fn to_i64<'py>(
    py: Python<'py>,
    values: impl IntoIterator<Item = usize>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let bytes: Vec<u8> = values
        .into_iter()
        .flat_map(|v| (v as i64).to_le_bytes())
        .collect();
    array(py, &bytes, "<i8", shape)
}

fn array<'py>(
    py: Python<'py>,
    bytes: &[u8],
    dtype: &str,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let np = py.import("numpy")?;
    let flat = np.call_method1("frombuffer", (PyBytes::new(py, bytes), dtype))?;
    let shape = PyTuple::new(py, shape)?;
    flat.call_method1("reshape", (shape,))?.call_method0("copy")
}

/// Points `[f64; D]` as an `(n, D)` array.
pub fn of_points<'py, const D: usize>(
    py: Python<'py>,
    pts: &[[f64; D]],
) -> PyResult<Bound<'py, PyAny>> {
    to_f64(py, pts.iter().flatten().copied(), &[pts.len(), D])
}

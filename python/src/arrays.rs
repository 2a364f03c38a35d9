//! NumPy arrays in and out through NumPy's own functions (`ascontiguousarray`, `tobytes`,
//! `frombuffer`): one copy each way, and the stable ABI (abi3) throughout.

use crate::errors::BadInputError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

/// The most rows an input array may have: the command line's limit on an input's points
/// (`ATLASMESH_MAX_POINTS`, 4 million by default) times `per_point` (2 for triangles, about
/// twice the vertices of a closed surface). Checked on the array's shape before any copy, so a
/// zero-copy view of a billion rows costs nothing to refuse.
fn max_rows(per_point: usize) -> usize {
    atlasmesh::formats::max_points().saturating_mul(per_point)
}

/// `obj` as a NumPy array (no copy when it already is one, a view included) and its row
/// count, its shape checked as `(n, cols)` (or 1-D when `cols` is `None`) and its dtype kind
/// one of `kinds`. Everything refused is a [`BadInputError`] naming `what`.
fn checked<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    cols: Option<usize>,
    kinds: &str,
) -> PyResult<(Bound<'py, PyAny>, usize)> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,)).map_err(|e| {
        BadInputError::new_err(format!(
            "{what}: not an array of numbers ({})",
            e.value(obj.py())
        ))
    })?;
    let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let expected = match cols {
        Some(c) => format!("(n, {c})"),
        None => "(n,)".to_string(),
    };
    let fits = match cols {
        Some(c) => shape.len() == 2 && shape[1] == c,
        None => shape.len() <= 1,
    };
    if !fits {
        return Err(BadInputError::new_err(format!(
            "{what}: an array of shape {expected} expected, got {shape:?}"
        )));
    }
    if !kinds.contains(kind.as_str()) {
        let dtype: String = a.getattr("dtype")?.str()?.extract()?;
        return Err(BadInputError::new_err(if kinds.contains('f') {
            format!("{what}: numbers expected, got dtype {dtype}")
        } else {
            format!(
                "{what}: an integer array expected, got dtype {dtype} (indices are whole numbers; \
                 cast with .astype(int) if they are)"
            )
        }));
    }
    Ok((a, shape.first().copied().unwrap_or(1)))
}

/// Refuses `rows` beyond [`max_rows`]`(per_point)` before anything is copied.
fn check_rows(rows: usize, per_point: usize, what: &str) -> PyResult<()> {
    let max = max_rows(per_point);
    if rows > max {
        return Err(BadInputError::new_err(format!(
            "{what}: {rows} rows, beyond the limit of {max} (set ATLASMESH_MAX_POINTS to \
             raise it; a fit takes about 1 kB per point), or decimate the surface"
        )));
    }
    Ok(())
}

/// The bytes of `a` converted to the little-endian `dtype` (`<f8`, `<i8`), C-contiguous.
fn bytes_as(a: &Bound<'_, PyAny>, dtype: &str) -> PyResult<Vec<u8>> {
    let np = a.py().import("numpy")?;
    let c = np.call_method1("ascontiguousarray", (a, dtype))?;
    let b = c.call_method0("tobytes")?;
    Ok(b.cast::<PyBytes>()?.as_bytes().to_vec())
}

fn f64s(bytes: &[u8]) -> impl Iterator<Item = f64> + '_ {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
}

/// Integer values as indices; a negative one is refused naming `what`.
fn usizes(bytes: &[u8], what: &str) -> PyResult<Vec<usize>> {
    bytes
        .chunks_exact(8)
        .map(|c| {
            let v = i64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
            usize::try_from(v)
                .map_err(|_| BadInputError::new_err(format!("{what}: negative index {v}")))
        })
        .collect()
}

/// `obj` (any array-like of numbers, shape `(n, D)`) as points.
pub fn points<const D: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; D]>> {
    let (a, rows) = checked(obj, what, Some(D), "biuf")?;
    check_rows(rows, 1, what)?;
    let bytes = bytes_as(&a, "<f8")?;
    let v: Vec<f64> = f64s(&bytes).collect();
    Ok(v.chunks_exact(D)
        .map(|c| std::array::from_fn(|d| c[d]))
        .collect())
}

/// `obj` as integer indices of shape `(n, K)` (facets: `n` up to twice the point limit).
/// Floats are refused, never truncated.
pub fn indices<const K: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[usize; K]>> {
    let v = flat_indices(obj, K, what)?;
    Ok(v.chunks_exact(K)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect())
}

/// `obj` as the rows of an integer array of shape `(n, k)`, concatenated.
pub fn flat_indices(obj: &Bound<'_, PyAny>, k: usize, what: &str) -> PyResult<Vec<usize>> {
    let (a, rows) = checked(obj, what, Some(k), "iu")?;
    check_rows(rows, 2, what)?;
    usizes(&bytes_as(&a, "<i8")?, what)
}

/// `obj` as a flat float64 vector of at most `max` values.
pub fn vector(obj: &Bound<'_, PyAny>, what: &str, max: usize) -> PyResult<Vec<f64>> {
    let (a, n) = checked(obj, what, None, "biuf")?;
    if n > max {
        return Err(BadInputError::new_err(format!(
            "{what}: {n} values, at most {max} expected"
        )));
    }
    Ok(f64s(&bytes_as(&a, "<f8")?).collect())
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

/// `a` made read-only: what a getter returns is the object's own data, and a write to it
/// (`mesh.nodes[0] = ...`) raises NumPy's "assignment destination is read-only" instead of
/// being lost on a copy.
fn frozen<'py>(a: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    a.getattr("flags")?.setattr("writeable", false)?;
    Ok(a)
}

/// [`to_f64`], read-only (for getters).
pub fn frozen_f64<'py>(
    py: Python<'py>,
    values: impl IntoIterator<Item = f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    frozen(to_f64(py, values, shape)?)
}

/// [`to_i64`], read-only (for getters).
pub fn frozen_i64<'py>(
    py: Python<'py>,
    values: impl IntoIterator<Item = usize>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    frozen(to_i64(py, values, shape)?)
}

/// [`of_points`], read-only (for getters).
pub fn frozen_points<'py, const D: usize>(
    py: Python<'py>,
    pts: &[[f64; D]],
) -> PyResult<Bound<'py, PyAny>> {
    frozen(of_points(py, pts)?)
}

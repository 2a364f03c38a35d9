//! Numeric arguments read from any Python number (`int`, `float`, NumPy scalars) with the
//! argument's name in the message, so that a wrong value is an `atlasmesh.BadInputError`
//! (never an `OverflowError` or a `TypeError` from the binding) and a huge one is refused
//! before it sizes anything.

use crate::errors::BadInputError;
use pyo3::prelude::*;

/// The value as Python shows it, cut to 60 characters (a 10⁶-digit integer is not echoed).
fn shown(obj: &Bound<'_, PyAny>) -> String {
    let r = obj
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into());
    if r.chars().count() > 60 {
        format!("{}...", r.chars().take(57).collect::<String>())
    } else {
        r
    }
}

/// `obj` as a whole number in `min..=max` (an `int` or anything with `__index__`; not a
/// `bool`, not a `float`).
pub fn count(obj: &Bound<'_, PyAny>, name: &str, min: u64, max: u64) -> PyResult<u64> {
    let bad = || {
        BadInputError::new_err(format!(
            "{name}={}: a whole number from {min} to {max} expected",
            shown(obj)
        ))
    };
    if obj.is_instance_of::<pyo3::types::PyBool>() {
        return Err(bad());
    }
    let v: i128 = obj
        .call_method0("__index__")
        .and_then(|i| i.extract())
        .map_err(|_| bad())?;
    u64::try_from(v)
        .ok()
        .filter(|v| (min..=max).contains(v))
        .ok_or_else(bad)
}

/// [`count`] as a `usize`.
pub fn size(obj: &Bound<'_, PyAny>, name: &str, min: usize, max: usize) -> PyResult<usize> {
    count(obj, name, min as u64, max as u64).map(|v| v as usize)
}

/// `obj` as a finite real number (an `int`, a `float`, a NumPy scalar; not a `bool`).
pub fn real(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<f64> {
    let bad = || BadInputError::new_err(format!("{name}={}: a finite number expected", shown(obj)));
    if obj.is_instance_of::<pyo3::types::PyBool>() {
        return Err(bad());
    }
    obj.extract::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(bad)
}

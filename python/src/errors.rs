//! atlasmesh's errors as Python exceptions of one family, by the class the command line
//! exits with: every one an `atlasmesh.Error`, and each also the built-in exception a Python
//! user catches for its kind (`ValueError` for bad input and invalid meshes, `OSError` for
//! files, `RuntimeError` for a fit that did not converge).

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

/// The family: name, built-in base (beside `Error`), docstring.
const FAMILY: [(&str, &str, &str); 5] = [
    (
        "Error",
        "Exception",
        "Any atlasmesh error; the message names the file and the problem.",
    ),
    (
        "BadInputError",
        "ValueError",
        "Malformed, degenerate or inconsistent input, or a parameter out of range (exit code 2); \
         also a ValueError.",
    ),
    (
        "IoError",
        "OSError",
        "A file could not be read or written (exit code 3); also an OSError.",
    ),
    (
        "InvalidMeshError",
        "ValueError",
        "A mesh that no solver could use (exit code 4); also a ValueError.",
    ),
    (
        "NotConvergedError",
        "RuntimeError",
        "A fit that did not converge, or a numerical failure on degenerate data (exit code 5); \
         also a RuntimeError.",
    ),
];

static CLASSES: PyOnceLock<Vec<Py<PyType>>> = PyOnceLock::new();

/// The family's classes, made once: `Error(Exception)`, then each `Name(Error, Builtin)`.
fn classes(py: Python<'_>) -> PyResult<&Vec<Py<PyType>>> {
    CLASSES.get_or_try_init(py, || {
        let builtins = py.import("builtins")?;
        let make = builtins.getattr("type")?;
        let mut out: Vec<Py<PyType>> = Vec::with_capacity(FAMILY.len());
        for (name, builtin, doc) in FAMILY {
            let dict = PyDict::new(py);
            dict.set_item("__doc__", doc)?;
            dict.set_item("__module__", "atlasmesh")?;
            let builtin = builtins.getattr(builtin)?;
            let bases = match out.first() {
                Some(error) => PyTuple::new(py, [error.bind(py).clone().into_any(), builtin])?,
                None => PyTuple::new(py, [builtin])?,
            };
            let class = make.call1((name, bases, dict))?;
            out.push(class.cast_into::<PyType>()?.unbind());
        }
        Ok(out)
    })
}

/// An exception of the family's class `k` (an index into [`FAMILY`]) with `message`.
fn raise(k: usize, message: String) -> PyErr {
    Python::attach(|py| match classes(py) {
        Ok(c) => PyErr::from_type(c[k].bind(py).clone(), message),
        Err(e) => e,
    })
}

macro_rules! family_member {
    ($name:ident, $k:expr) => {
        #[doc = concat!("`atlasmesh.", stringify!($name), "`: see the module.")]
        pub struct $name;
        impl $name {
            /// The exception with `message`.
            pub fn new_err(message: impl Into<String>) -> PyErr {
                raise($k, message.into())
            }
        }
    };
}

family_member!(Error, 0);
family_member!(BadInputError, 1);
family_member!(IoError, 2);
family_member!(InvalidMeshError, 3);
family_member!(NotConvergedError, 4);

/// The Python exception of an atlasmesh error.
pub fn to_py(e: atlasmesh::Error) -> PyErr {
    let m = e.to_string();
    match e.exit_code() {
        2 => BadInputError::new_err(m),
        3 => IoError::new_err(m),
        4 => InvalidMeshError::new_err(m),
        5 => NotConvergedError::new_err(m),
        _ => Error::new_err(m),
    }
}

/// Adds the exceptions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for ((name, _, _), class) in FAMILY.iter().zip(classes(m.py())?) {
        m.add(*name, class.bind(m.py()))?;
    }
    Ok(())
}

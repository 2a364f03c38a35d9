//! atlasmesh's errors as Python exceptions of one family, by the class the command line
//! exits with.

use pyo3::prelude::*;

pyo3::create_exception!(
    atlasmesh,
    Error,
    pyo3::exceptions::PyException,
    "Any atlasmesh error; the message names the file and the problem."
);
pyo3::create_exception!(
    atlasmesh,
    BadInputError,
    Error,
    "Malformed, degenerate or inconsistent input, or a parameter out of range (exit code 2)."
);
pyo3::create_exception!(
    atlasmesh,
    IoError,
    Error,
    "A file could not be read or written (exit code 3)."
);
pyo3::create_exception!(
    atlasmesh,
    InvalidMeshError,
    Error,
    "A mesh that no solver could use (exit code 4)."
);
pyo3::create_exception!(
    atlasmesh,
    NotConvergedError,
    Error,
    "A fit that did not converge, or a numerical failure (exit code 5)."
);

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
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("BadInputError", py.get_type::<BadInputError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    m.add("InvalidMeshError", py.get_type::<InvalidMeshError>())?;
    m.add("NotConvergedError", py.get_type::<NotConvergedError>())?;
    Ok(())
}

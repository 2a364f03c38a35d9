//! `atlasmesh` for Python: the library's engine over NumPy arrays (pyo3, the stable ABI).
//! Atlases are built, loaded and saved, their shape model sampled and projected, and subjects
//! fitted (Algorithm 1, eq. 5-8) with the mean mesh morphed onto them (eq. 9), repaired and
//! checked, the GIL released while the work runs. Shapes and meshes come in and out in the
//! data's frame and unit (mm for mm data).

#![warn(clippy::too_many_lines)]

mod args;
mod arrays;
mod errors;
mod leave_one_out;
mod materials;
mod model;
mod population;
mod read;
mod result;

use pyo3::prelude::*;

/// The extension module `atlasmesh._atlasmesh` (re-exported by the `atlasmesh` package).
#[pymodule]
fn _atlasmesh(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<model::Atlas>()?;
    m.add_class::<result::Mesh>()?;
    m.add_class::<result::FitResult>()?;
    m.add_function(wrap_pyfunction!(read::read_shapes, m)?)?;
    m.add_function(wrap_pyfunction!(read::read_label_surface, m)?)?;
    m.add_function(wrap_pyfunction!(materials::map_materials, m)?)?;
    m.add_function(wrap_pyfunction!(leave_one_out::leave_one_out, m)?)?;
    m.add_class::<read::LabelMap>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

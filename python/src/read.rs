//! Shape files read as arrays: `atlasmesh.read_shapes`.

use crate::arrays;
use crate::errors::to_py;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::path::PathBuf;

/// The shapes of a file as `(name, points, facets)` tuples: a 3D surface (PLY, STL, OBJ, VTP,
/// VTK; checked and oriented outwards), or the 2D outlines of a CSV (`shape,point,x,y`), text
/// or VTK file, `closed` or open, with `resample` every outline resampled to that many
/// points along a smooth curve through its points (in correspondence when all have the same
/// point count).
#[pyfunction]
#[pyo3(signature = (path, closed=true, resample=None))]
pub fn read_shapes<'py>(
    py: Python<'py>,
    path: PathBuf,
    closed: bool,
    resample: Option<usize>,
) -> PyResult<Vec<Bound<'py, PyTuple>>> {
    if atlasmesh::study::is_surface_file(&path).map_err(to_py)? {
        let s = atlasmesh::formats::read_surface(&path).map_err(to_py)?;
        let t = (
            s.name.clone(),
            arrays::of_points::<3>(py, &s.points)?,
            arrays::to_i64(py, s.facets.iter().flatten().copied(), &[s.facets.len(), 3])?,
        );
        return Ok(vec![PyTuple::new(
            py,
            [t.0.into_pyobject(py)?.into_any(), t.1, t.2],
        )?]);
    }
    let opts = atlasmesh::study::PopulationOptions {
        closed,
        resample,
        ..Default::default()
    };
    let shapes = atlasmesh::study::load_population(&[path], &opts).map_err(to_py)?;
    shapes
        .iter()
        .map(|s| {
            PyTuple::new(
                py,
                [
                    s.name.clone().into_pyobject(py)?.into_any(),
                    arrays::of_points::<2>(py, &s.points)?,
                    arrays::to_i64(py, s.facets.iter().flatten().copied(), &[s.facets.len(), 2])?,
                ],
            )
        })
        .collect()
}

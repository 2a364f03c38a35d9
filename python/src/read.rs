//! Shape files read as arrays: `atlasmesh.read_shapes`, `atlasmesh.read_label_surface`; a
//! label map as a subject (`atlasmesh.LabelMap`).

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
    resample: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<Bound<'py, PyTuple>>> {
    let resample = resample
        .map(|r| crate::args::size(r, "resample", 0, usize::MAX))
        .transpose()?;
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

/// A label map's label as a shape, accepted wherever a shape file is (`Atlas.fit`,
/// `Atlas.fit_many`, `Atlas.build`): the image `path` (NIfTI, NRRD, MetaImage), the `label`
/// (a number, several as `"1,7"`, or a name of `label_table`, a CSV of `label,name` rows, or
/// of a `.seg.nrrd`'s segments).
#[pyclass(frozen, module = "atlasmesh")]
pub struct LabelMap {
    pub(crate) path: PathBuf,
    label: String,
    label_table: Option<PathBuf>,
}

impl LabelMap {
    /// The library's label reading.
    pub(crate) fn reading(&self) -> PyResult<atlasmesh::study::LabelReading> {
        let choice: atlasmesh::image::LabelChoice = self.label.parse().map_err(to_py)?;
        atlasmesh::study::LabelReading::new(Some(choice), self.label_table.as_deref())
            .map_err(to_py)
    }
}

#[pymethods]
impl LabelMap {
    #[new]
    #[pyo3(signature = (path, label, label_table=None))]
    fn new(
        path: PathBuf,
        label: &Bound<'_, PyAny>,
        label_table: Option<PathBuf>,
    ) -> PyResult<Self> {
        let label = match label.extract::<i64>() {
            Ok(n) => n.to_string(),
            Err(_) => label.extract::<String>().map_err(|_| {
                crate::errors::BadInputError::new_err("label: a number, \"1,7\" or a name")
            })?,
        };
        let map = LabelMap {
            path,
            label,
            label_table,
        };
        map.reading()?;
        Ok(map)
    }

    fn __repr__(&self) -> String {
        format!(
            "LabelMap({:?}, label={:?})",
            self.path.display().to_string(),
            self.label
        )
    }
}

/// The surface of a label map's label as `(name, points, facets)` (world RAS, mm; see
/// `LabelMap` for `label` and `label_table`); what a user should know (islands dropped,
/// cavities filled, cut by the image's border) as Python warnings.
#[pyfunction]
#[pyo3(signature = (path, label, label_table=None))]
pub fn read_label_surface<'py>(
    py: Python<'py>,
    path: PathBuf,
    label: &Bound<'py, PyAny>,
    label_table: Option<PathBuf>,
) -> PyResult<Bound<'py, PyTuple>> {
    let map = LabelMap::new(path, label, label_table)?;
    let reading = map.reading()?;
    let s = py
        .detach(|| atlasmesh::study::read_label_surface(&map.path, &reading))
        .map_err(to_py)?;
    let warnings = py.import("warnings")?;
    for w in &s.warnings {
        warnings.call_method1("warn", (format!("{}: {w}", map.path.display()),))?;
    }
    PyTuple::new(
        py,
        [
            s.shape.name.clone().into_pyobject(py)?.into_any(),
            arrays::of_points::<3>(py, &s.shape.points)?,
            arrays::to_i64(
                py,
                s.shape.facets.iter().flatten().copied(),
                &[s.shape.facets.len(), 3],
            )?,
        ],
    )
}

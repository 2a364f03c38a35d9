//! What a fit gives back to Python: the morphed FE mesh and the fit's figures.

use crate::arrays;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// An FE mesh: nodes, elements, kind, sets and each element's smallest scaled Jacobian.
#[pyclass(frozen, module = "atlasmesh")]
pub struct Mesh {
    dim: usize,
    nodes: Vec<f64>,
    kind: atlasmesh::mesh::ElementKind,
    connectivity: Vec<usize>,
    sets: atlasmesh::mesh::MeshSets,
    scaled_jacobian: Vec<f64>,
}

impl Mesh {
    /// The Python mesh of `mesh` with its elements' quality.
    pub fn of<const D: usize>(
        mesh: &atlasmesh::mesh::FeMesh<D>,
        quality: &[atlasmesh::mesh::ElementQuality],
    ) -> Self {
        Mesh {
            dim: D,
            nodes: mesh.nodes.iter().flatten().copied().collect(),
            kind: mesh.kind,
            connectivity: mesh.connectivity.clone(),
            sets: mesh.sets.clone(),
            scaled_jacobian: quality.iter().map(|q| q.scaled_jacobian_min).collect(),
        }
    }

    /// The mesh with 3D node coordinates (z = 0 for a 2D mesh).
    pub(crate) fn fe_mesh_3d(&self) -> atlasmesh::mesh::FeMesh<3> {
        atlasmesh::mesh::FeMesh {
            nodes: self
                .nodes
                .chunks_exact(self.dim)
                .map(|c| std::array::from_fn(|d| c.get(d).copied().unwrap_or(0.0)))
                .collect(),
            kind: self.kind,
            connectivity: self.connectivity.clone(),
            sets: self.sets.clone(),
        }
    }

    fn fe_mesh<const D: usize>(&self) -> atlasmesh::mesh::FeMesh<D> {
        atlasmesh::mesh::FeMesh {
            nodes: self
                .nodes
                .chunks_exact(D)
                .map(|c| std::array::from_fn(|d| c[d]))
                .collect(),
            kind: self.kind,
            connectivity: self.connectivity.clone(),
            sets: self.sets.clone(),
        }
    }
}

#[pymethods]
impl Mesh {
    /// Node coordinates, `(N, D)` float64 (data's frame and unit).
    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_f64(
            py,
            self.nodes.iter().copied(),
            &[self.nodes.len() / self.dim, self.dim],
        )
    }

    /// Element connectivity, `(E, k)` int64 (VTK node order).
    #[getter]
    fn elements<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let k = self.kind.nodes();
        arrays::frozen_i64(
            py,
            self.connectivity.iter().copied(),
            &[self.connectivity.len() / k, k],
        )
    }

    /// The element kind: `quad4`, `hex8`, `tri3`, `tet4`, `hex20` or `tet10`.
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind.name()
    }

    /// The VTK cell type number of the elements.
    #[getter]
    fn vtk_type(&self) -> u8 {
        self.kind.vtk_type()
    }

    /// Each element's smallest corner scaled Jacobian (1 is a perfect element), `(E,)`.
    #[getter]
    fn scaled_jacobian<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_f64(
            py,
            self.scaled_jacobian.iter().copied(),
            &[self.scaled_jacobian.len()],
        )
    }

    /// The sets: `{"nodes": {name: indices}, "elements": {name: indices}, "surfaces": {name:
    /// (element, face) pairs}}`.
    #[getter]
    fn sets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        let nodes = PyDict::new(py);
        for (n, v) in &self.sets.node_sets {
            nodes.set_item(n, arrays::frozen_i64(py, v.iter().copied(), &[v.len()])?)?;
        }
        let elements = PyDict::new(py);
        for (n, v) in &self.sets.element_sets {
            elements.set_item(n, arrays::frozen_i64(py, v.iter().copied(), &[v.len()])?)?;
        }
        let surfaces = PyDict::new(py);
        for (n, v) in &self.sets.surfaces {
            surfaces.set_item(
                n,
                arrays::frozen_i64(
                    py,
                    v.iter().flat_map(|&(e, f)| [e, usize::from(f)]),
                    &[v.len(), 2],
                )?,
            )?;
        }
        out.set_item("nodes", nodes)?;
        out.set_item("elements", elements)?;
        out.set_item("surfaces", surfaces)?;
        Ok(out)
    }

    /// Writes the mesh with its sets; the format from the extension: `.vtu`, `.vtk`, `.inp`
    /// (Abaqus/CalculiX), `.msh` (Gmsh 4.1), `.feb` (FEBio, 3D).
    fn write(&self, path: std::path::PathBuf) -> PyResult<()> {
        fn go<const D: usize>(m: &Mesh, path: &std::path::Path) -> atlasmesh::Result<()> {
            let mesh = m.fe_mesh::<D>();
            let q = atlasmesh::mesh::quality::mesh_quality(&mesh);
            atlasmesh::formats::write_mesh(path, &mesh, None, &q)
        }
        if self.dim == 3 {
            go::<3>(self, &path)
        } else {
            go::<2>(self, &path)
        }
        .map_err(crate::errors::to_py)
    }

    fn __repr__(&self) -> String {
        format!(
            "Mesh({} nodes, {} {} elements)",
            self.nodes.len() / self.dim,
            self.connectivity.len() / self.kind.nodes(),
            self.kind.name()
        )
    }
}

/// A subject fitted (Algorithm 1) with its morphed mesh and its measures.
#[pyclass(frozen, module = "atlasmesh")]
pub struct FitResult {
    pub(crate) dim: usize,
    /// The fit's weights in standard deviations of each mode.
    pub(crate) sd: Vec<f64>,
    pub(crate) scale: f64,
    pub(crate) rotation: Vec<f64>,
    pub(crate) translation: Vec<f64>,
    pub(crate) surface: Vec<f64>,
    pub(crate) facets: Vec<usize>,
    pub(crate) mesh: Option<Py<Mesh>>,
    /// The measures of `report.json`, a dict parsed once.
    pub(crate) measures: Py<PyAny>,
    /// Measures left to compute on first use (a fit alone: its two-way RMS distance).
    pub(crate) pending: std::sync::Mutex<Option<Pending>>,
}

/// Measures of a fit computed when first asked for: `(name, value)` pairs.
pub(crate) type Pending = Box<dyn FnOnce() -> Vec<(&'static str, f64)> + Send>;

impl FitResult {
    /// The measure `name` of the dict, None when the fit has none.
    fn measure<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let dict = self.measures_dict(py)?;
        Ok(dict.get_item(name).ok().filter(|v| !v.is_none()))
    }

    /// The number `name` of the measures, NaN when the fit has none (or JSON's null).
    fn number(&self, py: Python<'_>, name: &str) -> PyResult<f64> {
        self.measure(py, name)?
            .map_or(Ok(f64::NAN), |v| v.extract())
    }

    /// The list of strings `name` of the measures, empty when the fit has none.
    fn list(&self, py: Python<'_>, name: &str) -> PyResult<Vec<String>> {
        self.measure(py, name)?
            .map_or(Ok(Vec::new()), |v| v.extract())
    }

    /// The measures dict, with the pending measures computed into it (once, the GIL released).
    fn measures_dict<'py>(&self, py: Python<'py>) -> PyResult<&Bound<'py, PyAny>> {
        let job = self
            .pending
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .take();
        let dict = self.measures.bind(py);
        if let Some(job) = job {
            for (k, v) in py.detach(job) {
                dict.set_item(k, v)?;
            }
        }
        Ok(dict)
    }
}

#[pymethods]
impl FitResult {
    /// The fitted instance's weights, in standard deviations of each mode.
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_f64(py, self.sd.iter().copied(), &[self.sd.len()])
    }

    /// The pose `t_{R,T,s}` (reference frame → subject): `{"scale", "rotation" (D×D),
    /// "translation" (D,)}`.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("scale", self.scale)?;
        d.set_item(
            "rotation",
            arrays::frozen_f64(py, self.rotation.iter().copied(), &[self.dim, self.dim])?,
        )?;
        d.set_item(
            "translation",
            arrays::frozen_f64(py, self.translation.iter().copied(), &[self.dim])?,
        )?;
        Ok(d)
    }

    /// The fitted surface (or outline) projected onto the subject, `(N, D)`: point `i` of every
    /// subject corresponds.
    #[getter]
    fn surface<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_f64(
            py,
            self.surface.iter().copied(),
            &[self.surface.len() / self.dim, self.dim],
        )
    }

    /// The facets of `surface` (triangles, or outline segments), `(F, D)` int64.
    #[getter]
    fn facets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_i64(
            py,
            self.facets.iter().copied(),
            &[self.facets.len() / self.dim, self.dim],
        )
    }

    /// The subject's FE mesh: the mean mesh morphed onto it (eq. 9), repaired, checked
    /// (None for a fit made with `mesh=False`).
    #[getter]
    fn mesh(&self, py: Python<'_>) -> Option<Py<Mesh>> {
        self.mesh.as_ref().map(|m| m.clone_ref(py))
    }

    /// The measures of `report.json` for this subject, as a dict (a copy).
    #[getter]
    fn measures<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.measures_dict(py)?.call_method0("copy")
    }

    /// Every measure's name beside the result's own attributes (`dir(r)`, completion).
    fn __dir__(slf: &Bound<'_, Self>) -> PyResult<Vec<String>> {
        let mut names: Vec<String> = slf.get_type().dir()?.extract()?;
        let py = slf.py();
        let keys = slf.get().measures_dict(py)?.call_method0("keys")?;
        for k in keys.try_iter()? {
            names.push(k?.extract()?);
        }
        names.sort();
        names.dedup();
        Ok(names)
    }

    /// Whether every check passed (`failed_checks` empty); None for a fit made with
    /// `mesh=False`, which has no mesh to check.
    #[getter]
    fn success(&self, py: Python<'_>) -> PyResult<Option<bool>> {
        if self.mesh.is_none() {
            return Ok(None);
        }
        self.measure(py, "success")?
            .map(|v| v.extract())
            .transpose()
    }

    /// What a user should know about this subject, one sentence each (empty when nothing).
    #[getter]
    fn warnings(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.list(py, "warnings")
    }

    /// The checks of `success` that failed (`fit`, `mesh_distance`, `mesh_quality`; empty
    /// when all passed or without a mesh).
    #[getter]
    fn failed_checks(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.list(py, "failed_checks")
    }

    /// The fitted instance's two-way RMS distance to the subject (eq. 6 both ways; the
    /// subject's unit).
    #[getter]
    fn rms_distance(&self, py: Python<'_>) -> PyResult<f64> {
        self.number(py, "rms_distance")
    }

    /// `rms_distance` over the subject's bounding-box diagonal.
    #[getter]
    fn rms_distance_relative(&self, py: Python<'_>) -> PyResult<f64> {
        self.number(py, "rms_distance_relative")
    }

    /// The smallest corner scaled Jacobian of the mesh (NaN without a mesh).
    #[getter]
    fn scaled_jacobian_min(&self, py: Python<'_>) -> PyResult<f64> {
        self.number(py, "scaled_jacobian_min")
    }

    /// The delivered mesh's two-way RMS distance to the subject (the subject's unit; NaN
    /// without a mesh).
    #[getter]
    fn mesh_rms_distance(&self, py: Python<'_>) -> PyResult<f64> {
        self.number(py, "mesh_rms_distance")
    }

    /// The delivered mesh's 95th-percentile distance to the subject (NaN without a mesh).
    #[getter]
    fn mesh_p95_distance(&self, py: Python<'_>) -> PyResult<f64> {
        self.number(py, "mesh_p95_distance")
    }

    /// The delivered mesh's element size: the median edge of its boundary (NaN without a
    /// mesh).
    #[getter]
    fn element_size(&self, py: Python<'_>) -> PyResult<f64> {
        self.number(py, "element_size")
    }

    /// A measure of `report.json` by name (`rms_distance`, `success`, `scaled_jacobian_min`,
    /// ...).
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.measures_dict(py)?.get_item(name).map_err(|_| {
            pyo3::exceptions::PyAttributeError::new_err(format!(
                "FitResult has no attribute {name:?}"
            ))
        })
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let v = |k: &str| {
            self.__getattr__(py, k)
                .map(|x| x.to_string())
                .unwrap_or_default()
        };
        format!(
            "FitResult(rms_distance={}, success={}, scaled_jacobian_min={})",
            v("rms_distance"),
            v("success"),
            v("scaled_jacobian_min")
        )
    }
}

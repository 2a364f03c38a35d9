//! What a fit gives back to Python: the morphed FE mesh and the fit's figures.

use crate::arrays;
use crate::errors::BadInputError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A `DeprecationWarning` for a former name, pointing at the caller's line.
fn deprecated(py: Python<'_>, message: &std::ffi::CStr) -> PyResult<()> {
    PyErr::warn(
        py,
        &py.get_type::<pyo3::exceptions::PyDeprecationWarning>(),
        message,
        1,
    )
}

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

/// The element kind of `k`-node elements in `dim` dimensions.
fn kind_of(dim: usize, k: usize) -> Option<atlasmesh::mesh::ElementKind> {
    use atlasmesh::mesh::ElementKind as K;
    match (dim, k) {
        (2, 4) => Some(K::Quad4),
        (2, 3) => Some(K::Tri3),
        (3, 8) => Some(K::Hex8),
        (3, 4) => Some(K::Tet4),
        (3, 20) => Some(K::Hex20),
        (3, 10) => Some(K::Tet10),
        _ => None,
    }
}

/// `obj` as a 1-D array of indices, named `what` in errors.
fn index_list(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<usize>> {
    let np = obj.py().import("numpy")?;
    let column = np
        .call_method1("reshape", (obj, (-1i64, 1i64)))
        .map_err(|e| {
            BadInputError::new_err(format!(
                "{what}: not a list of indices ({})",
                e.value(obj.py())
            ))
        })?;
    arrays::flat_indices(&column, 1, what)
}

/// The sets of a `sets` dictionary as [`Mesh::sets`] gives them (`"nodes"`, `"elements"`:
/// name to indices; `"surfaces"`: name to `(n, 2)` element and face).
fn sets_of(sets: &Bound<'_, PyDict>) -> PyResult<atlasmesh::mesh::MeshSets> {
    let mut out = atlasmesh::mesh::MeshSets::default();
    for (key, value) in sets.iter() {
        let key: String = key.extract().map_err(|_| {
            BadInputError::new_err("sets: the keys are \"nodes\", \"elements\" and \"surfaces\"")
        })?;
        let named = value.cast::<PyDict>().map_err(|_| {
            BadInputError::new_err(format!(
                "sets[{key:?}]: a dictionary of name to indices expected"
            ))
        })?;
        for (name, members) in named.iter() {
            let name: String = name
                .extract()
                .map_err(|_| BadInputError::new_err(format!("sets[{key:?}]: names are strings")))?;
            let what = format!("sets[{key:?}][{name:?}]");
            match key.as_str() {
                "nodes" => {
                    out.node_sets.insert(name, index_list(&members, &what)?);
                }
                "elements" => {
                    out.element_sets.insert(name, index_list(&members, &what)?);
                }
                "surfaces" => {
                    let pairs = arrays::flat_indices(&members, 2, &what)?;
                    let faces = pairs
                        .chunks_exact(2)
                        .map(|c| {
                            u8::try_from(c[1]).map(|f| (c[0], f)).map_err(|_| {
                                BadInputError::new_err(format!(
                                    "{what}: face {} does not exist",
                                    c[1]
                                ))
                            })
                        })
                        .collect::<PyResult<Vec<_>>>()?;
                    out.surfaces.insert(name, faces);
                }
                _ => {
                    return Err(BadInputError::new_err(format!(
                        "sets: {key:?} is not a kind of set (\"nodes\", \"elements\", \"surfaces\")"
                    )));
                }
            }
        }
    }
    Ok(out)
}

#[pymethods]
impl Mesh {
    /// A mesh from arrays: `nodes` `(N, 2)` or `(N, 3)` in the data's frame and unit,
    /// `elements` `(E, k)` node indices in VTK's node order, `kind` (`quad4`, `tri3`, `hex8`,
    /// `tet4`, `hex20`, `tet10`; by default the kind of `k` nodes in the nodes' dimension) and
    /// `sets` as the `sets` property gives them. Each element's quality is computed; nothing
    /// is repaired. What cannot make a mesh (an index beyond the nodes, a coordinate that is
    /// not finite, a kind of another dimension, a bad set name) raises `BadInputError`.
    #[new]
    #[pyo3(signature = (nodes, elements, kind=None, sets=None))]
    fn new(
        nodes: &Bound<'_, PyAny>,
        elements: &Bound<'_, PyAny>,
        kind: Option<&Bound<'_, PyAny>>,
        sets: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let kind: Option<String> = kind
            .filter(|k| !k.is_none())
            .map(|k| {
                k.extract().map_err(|_| {
                    BadInputError::new_err(
                        "kind: a name expected (quad4, tri3, hex8, tet4, hex20, tet10)",
                    )
                })
            })
            .transpose()?;
        let sets = sets
            .filter(|s| !s.is_none())
            .map(|s| {
                s.cast::<PyDict>().map_err(|_| {
                    BadInputError::new_err(
                        "sets: a dictionary expected ({\"nodes\": {name: indices}, ...})",
                    )
                })
            })
            .transpose()?;
        let np = nodes.py().import("numpy")?;
        let shape: Vec<usize> = np
            .call_method1("shape", (nodes,))
            .and_then(|s| s.extract())
            .map_err(|e| {
                BadInputError::new_err(format!("nodes: not an array ({})", e.value(nodes.py())))
            })?;
        let dim = match shape.as_slice() {
            [_, d @ (2 | 3)] => *d,
            _ => {
                return Err(BadInputError::new_err(format!(
                    "nodes: an array of shape (n, 2) or (n, 3) expected, got {shape:?}"
                )));
            }
        };
        let k: usize = np
            .call_method1("shape", (elements,))
            .and_then(|s| s.extract::<Vec<usize>>())
            .ok()
            .filter(|s| s.len() == 2)
            .map(|s| s[1])
            .ok_or_else(|| BadInputError::new_err("elements: an array of shape (n, k) expected"))?;
        let kind = match kind.as_deref() {
            Some(name) => atlasmesh::mesh::ElementKind::from_name(name).ok_or_else(|| {
                BadInputError::new_err(format!(
                    "kind {name:?}: one of quad4, tri3, hex8, tet4, hex20, tet10 expected"
                ))
            })?,
            None => kind_of(dim, k).ok_or_else(|| {
                BadInputError::new_err(format!(
                    "elements of {k} nodes in {dim}D: no element kind has them (quad4, tri3 in 2D; hex8, tet4, hex20, tet10 in 3D)"
                ))
            })?,
        };
        if kind.dimension() != dim || kind.nodes() != k {
            return Err(BadInputError::new_err(format!(
                "kind {}: elements of {} nodes in {}D, got {k} nodes in {dim}D",
                kind.name(),
                kind.nodes(),
                kind.dimension()
            )));
        }
        let sets = match sets {
            Some(s) => sets_of(s)?,
            None => atlasmesh::mesh::MeshSets::default(),
        };
        let connectivity = arrays::flat_indices(elements, k, "elements")?;
        fn make<const D: usize>(
            nodes: &Bound<'_, PyAny>,
            kind: atlasmesh::mesh::ElementKind,
            connectivity: Vec<usize>,
            sets: atlasmesh::mesh::MeshSets,
        ) -> PyResult<Mesh> {
            let nodes = arrays::points::<D>(nodes, "nodes")?;
            if let Some(i) = nodes.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
                return Err(BadInputError::new_err(format!(
                    "nodes: node {i} has a coordinate that is not a finite number"
                )));
            }
            let mesh = atlasmesh::mesh::FeMesh {
                nodes,
                kind,
                connectivity,
                sets,
            };
            mesh.check_connectivity()
                .map_err(|m| BadInputError::new_err(format!("elements: {m}")))?;
            mesh.sets
                .check(kind, mesh.nodes.len(), mesh.num_elements())
                .map_err(|m| BadInputError::new_err(format!("sets: {m}")))?;
            Ok(Mesh::of(
                &mesh,
                &atlasmesh::mesh::quality::mesh_quality(&mesh),
            ))
        }
        if dim == 3 {
            make::<3>(nodes, kind, connectivity, sets)
        } else {
            make::<2>(nodes, kind, connectivity, sets)
        }
    }

    /// Pickling: the arguments of the constructor that makes this mesh again.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let m = slf.get();
        let args = (m.nodes(py)?, m.elements(py)?, m.kind(), m.sets(py)?).into_pyobject(py)?;
        Ok((slf.get_type().into_any(), args.into_any()))
    }

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

    /// Each element's smallest corner scaled Jacobian (1 is a perfect element), `(E,)`: the
    /// cell data `scaled_jacobian_min` of the mesh files.
    #[getter]
    fn scaled_jacobian_min<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_f64(
            py,
            self.scaled_jacobian.iter().copied(),
            &[self.scaled_jacobian.len()],
        )
    }

    /// The former name of `scaled_jacobian_min` (a `DeprecationWarning`).
    #[getter]
    fn scaled_jacobian<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        deprecated(
            py,
            c"Mesh.scaled_jacobian is Mesh.scaled_jacobian_min (as the mesh files name it)",
        )?;
        self.scaled_jacobian_min(py)
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

    /// Writes a solver deck built around the atlas's mean mesh with this mesh's node
    /// coordinates (the command line's `--deck`): `deck` is an Abaqus/CalculiX `.inp` or an
    /// FEBio `.feb` started from `atlasmesh convert ATLAS mean.inp` (or `mean.feb`), its
    /// materials, sets and steps added; everything but the nodes' coordinates is copied.
    /// `path` takes the deck's extension. The deck's elements must be this mesh's (a fitted
    /// mesh has those of the mean mesh).
    fn write_deck(&self, deck: std::path::PathBuf, path: std::path::PathBuf) -> PyResult<()> {
        use crate::errors::{BadInputError, to_py};
        let d = atlasmesh::formats::Deck::read(&deck).map_err(to_py)?;
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if ext.as_deref() != Some(d.extension()) {
            return Err(BadInputError::new_err(format!(
                "{}: a .{} deck is written to a .{} file",
                path.display(),
                d.extension(),
                d.extension()
            )));
        }
        fn go<const D: usize>(
            m: &Mesh,
            d: &atlasmesh::formats::Deck,
            deck: &std::path::Path,
            path: &std::path::Path,
        ) -> atlasmesh::Result<()> {
            let mesh = m.fe_mesh::<D>();
            atlasmesh::study::check_deck_mesh(&mesh, "this mesh", d, deck)?;
            atlasmesh::formats::write_atomic(path, d.with_nodes(&mesh.nodes)?.as_bytes())
        }
        if self.dim == 3 {
            go::<3>(self, &d, &deck, &path)
        } else {
            go::<2>(self, &d, &deck, &path)
        }
        .map_err(to_py)
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
    /// The fitted instance's weights, in standard deviations of each mode (`report.json`'s
    /// `sd`, `scores.csv`'s `mode_1..m`; `Atlas.instance(sd)` makes the shape back).
    #[getter]
    fn sd<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::frozen_f64(py, self.sd.iter().copied(), &[self.sd.len()])
    }

    /// The former name of `sd` (a `DeprecationWarning`).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        deprecated(
            py,
            c"FitResult.weights is FitResult.sd (as report.json names it)",
        )?;
        self.sd(py)
    }

    /// The pose `t_{R,T,s}` (reference frame → subject, `x_subject = s R x + T`): `{"scale",
    /// "rotation" (D×D), "translation" (D,), "matrix"}`, the matrix `[[s R, T], [0, 1]]`
    /// ((D+1)×(D+1)) as PyVista's `transform` and VTK apply it.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        /// The report's pose of the similarity (its homogeneous matrix made there).
        fn pose_of<const D: usize>(r: &FitResult) -> atlasmesh::report::Pose {
            atlasmesh::report::Pose::of(&atlasmesh::geometry::Similarity::<D> {
                s: r.scale,
                r: std::array::from_fn(|i| std::array::from_fn(|j| r.rotation[i * D + j])),
                t: std::array::from_fn(|i| r.translation[i]),
            })
        }
        let pose = if self.dim == 3 {
            pose_of::<3>(self)
        } else {
            pose_of::<2>(self)
        };
        let d = PyDict::new(py);
        let n = self.dim + 1;
        d.set_item(
            "matrix",
            arrays::frozen_f64(py, pose.matrix.into_iter().flatten(), &[n, n])?,
        )?;
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

    /// The checks of `success` that failed (`fit`, `mesh_distance`, `mesh_farther_than_fit`,
    /// `mesh_quality`; empty when all passed or without a mesh).
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

    /// Pickling: the result's arrays, its mesh (a `Mesh` pickles) and its measures, made
    /// again by `_from_state`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let r = slf.get();
        let measures = r.measures_dict(py)?.call_method0("copy")?;
        let state = (
            r.dim,
            r.sd.clone(),
            (r.scale, r.rotation.clone(), r.translation.clone()),
            (r.surface.clone(), r.facets.clone()),
            r.mesh.as_ref().map(|m| m.clone_ref(py)),
            measures,
        );
        Ok((
            slf.get_type().getattr("_from_state")?,
            state.into_pyobject(py)?.into_any(),
        ))
    }

    /// The result of `__reduce__`'s state: what unpickling a result calls.
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    fn _from_state(
        dim: usize,
        sd: Vec<f64>,
        pose: (f64, Vec<f64>, Vec<f64>),
        shape: (Vec<f64>, Vec<usize>),
        mesh: Option<Py<Mesh>>,
        measures: Bound<'_, PyDict>,
    ) -> PyResult<Self> {
        let (scale, rotation, translation) = pose;
        let (surface, facets) = shape;
        let fits = (dim == 2 || dim == 3)
            && rotation.len() == dim * dim
            && translation.len() == dim
            && surface.len() % dim == 0
            && facets.len() % dim == 0
            && facets.iter().all(|&f| f < surface.len() / dim);
        if !fits {
            return Err(BadInputError::new_err(
                "a pickled FitResult whose arrays do not fit together",
            ));
        }
        Ok(FitResult {
            dim,
            sd,
            scale,
            rotation,
            translation,
            surface,
            facets,
            mesh,
            measures: measures.copy()?.into_any().unbind(),
            pending: std::sync::Mutex::new(None),
        })
    }

    /// The three figures a user looks at first, `None` where the fit has none (a fit made
    /// with `mesh=False` has no verdict and no mesh quality).
    fn __repr__(slf: &Bound<'_, Self>) -> String {
        let v = |k: &str| {
            slf.getattr(k)
                .and_then(|x| x.repr())
                .map_or_else(|_| "None".to_string(), |r| r.to_string())
        };
        format!(
            "FitResult(rms_distance={}, success={}, scaled_jacobian_min={})",
            v("rms_distance"),
            v("success"),
            v("scaled_jacobian_min")
        )
    }
}

//! `atlasmesh.Atlas`: an atlas of 2D outlines or 3D surfaces, its shape model and its fits.

use crate::errors::to_py;
use crate::result::{FitResult, Mesh};
use crate::{args, arrays};
use atlasmesh::geometry::{Point, Shape};
use atlasmesh::model::Atlas as RustAtlas;
use atlasmesh::study::{RunContext, RunParams, Subject};
use pyo3::prelude::*;
use pyo3::types::PyList;
use rayon::prelude::*;
use std::path::PathBuf;

/// An atlas of either dimension, held as the run engine holds it (the dimension is chosen
/// once, where the atlas is loaded or built).
enum Inner {
    Two(RunContext<2>),
    Three(RunContext<3>),
}

/// Runs `$body` with `$a` the `RunContext<D>` of either dimension and `D` its dimension.
macro_rules! each {
    ($inner:expr, $a:ident, $d:ident => $body:expr) => {
        match $inner {
            Inner::Two($a) => {
                #[allow(dead_code)]
                const $d: usize = 2;
                $body
            }
            Inner::Three($a) => {
                #[allow(dead_code)]
                const $d: usize = 3;
                $body
            }
        }
    };
}

/// The run of `atlas` from Python: the library's defaults without pictures (a call writes
/// no files).
fn context<const D: usize>(atlas: RustAtlas<D>) -> PyResult<RunContext<D>> {
    let params = RunParams {
        plots: false,
        ..RunParams::default()
    };
    RunContext::new(atlas, params, Default::default()).map_err(to_py)
}

/// The sets of a `sets` argument: a sets TOML file's path or a dict of its tables (checked
/// as the file is).
fn sets_config(obj: &Bound<'_, PyAny>) -> PyResult<atlasmesh::mesh::SetsConfig> {
    if let Ok(d) = obj.cast::<pyo3::types::PyDict>() {
        let json: String = obj
            .py()
            .import("json")?
            .call_method1("dumps", (d,))
            .map_err(|e| {
                crate::errors::BadInputError::new_err(format!(
                    "sets: not a dict of TOML tables ({})",
                    e.value(obj.py())
                ))
            })?
            .extract()?;
        return atlasmesh::mesh::SetsConfig::from_json(std::path::Path::new("sets"), &json)
            .map_err(to_py);
    }
    let path: PathBuf = obj.extract().map_err(|_| {
        crate::errors::BadInputError::new_err("sets: a TOML file's path or a dict expected")
    })?;
    atlasmesh::mesh::SetsConfig::read(&path).map_err(to_py)
}

/// The run of a copy of `ctx`'s atlas with `sets` on its mean mesh.
fn with_sets<const D: usize>(
    ctx: &RunContext<D>,
    sets: atlasmesh::mesh::SetsConfig,
) -> PyResult<RunContext<D>> {
    let params = RunParams {
        sets: Some(sets),
        ..ctx.params.clone()
    };
    RunContext::new((*ctx.atlas).clone(), params, Default::default()).map_err(to_py)
}

/// The most float64 values one returned array holds (512 MiB).
const MAX_ARRAY_VALUES: usize = 1 << 26;

/// A statistical atlas (sections 2.2-2.4): the shape model of a population (mean, modes,
/// variances, eq. 4) and the FE mesh of its mean, in the population's unit.
#[pyclass(frozen, module = "atlasmesh")]
pub struct Atlas {
    inner: Inner,
}

/// What `__reduce__` gives pickle: the function that makes the object again and its
/// arguments (an atlas's dimension and bytes).
type Reduced<'py> = (Bound<'py, PyAny>, (usize, Bound<'py, pyo3::types::PyBytes>));

/// A subject from `(points, facets)` arrays or a file path, read and cleaned as the command
/// line reads it ([`atlasmesh::study::read_subjects`], [`atlasmesh::study::prepare_subject`]);
/// a surface given as arrays is checked and oriented as a surface file is.
pub(crate) fn subject_of<const D: usize>(obj: &Bound<'_, PyAny>, k: usize) -> PyResult<Subject<D>> {
    if let Ok(map) = obj.extract::<PyRef<'_, crate::read::LabelMap>>() {
        let reading = atlasmesh::study::SubjectReading {
            labels: map.reading()?,
            ..Default::default()
        };
        let mut v = atlasmesh::study::read_subjects::<D>(&map.path, &reading).map_err(to_py)?;
        return Ok(v.remove(0));
    }
    if let Ok(path) = obj.extract::<PathBuf>() {
        let mut v =
            atlasmesh::study::read_subjects::<D>(&path, &Default::default()).map_err(to_py)?;
        if v.len() != 1 {
            return Err(crate::errors::BadInputError::new_err(format!(
                "{}: {} outlines; give one per file, or arrays",
                path.display(),
                v.len()
            )));
        }
        return Ok(v.remove(0));
    }
    let (points, facets): (Bound<'_, PyAny>, Bound<'_, PyAny>) = obj.extract().map_err(|_| {
        crate::errors::BadInputError::new_err(format!(
            "shape {k}: a (points, facets) pair of arrays or a file path expected"
        ))
    })?;
    let shape = Shape::<D> {
        name: format!("shape{k}"),
        points: arrays::points::<D>(&points, &format!("shape {k}: points"))?,
        facets: arrays::indices::<D>(&facets, &format!("shape {k}: facets"))?,
        landmarks: Vec::new(),
    };
    let shape = if D == 3 {
        atlasmesh::geometry::prepare_surface(shape.into_dim::<3>())
            .map_err(to_py)?
            .into_dim::<D>()
    } else {
        shape
    };
    atlasmesh::study::prepare_subject(shape, std::path::Path::new(&format!("shape {k}")))
        .map_err(to_py)
}

/// The dimension of `(points, facets)` or a file.
pub(crate) fn dimension_of(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    if obj.extract::<PyRef<'_, crate::read::LabelMap>>().is_ok() {
        return Ok(3);
    }
    if let Ok(path) = obj.extract::<PathBuf>() {
        return Ok(
            if atlasmesh::study::is_surface_file(&path).map_err(to_py)? {
                3
            } else {
                2
            },
        );
    }
    let (points, _): (Bound<'_, PyAny>, Bound<'_, PyAny>) = obj.extract().map_err(|_| {
        crate::errors::BadInputError::new_err(
            "a shape is a (points, facets) pair of arrays or a file path",
        )
    })?;
    let np = obj.py().import("numpy")?;
    let shape: Vec<usize> = np
        .call_method1("shape", (points,))
        .and_then(|s| s.extract())
        .map_err(|e| {
            crate::errors::BadInputError::new_err(format!(
                "points: not an array of numbers ({})",
                e.value(obj.py())
            ))
        })?;
    match shape.as_slice() {
        [_, 2] => Ok(2),
        [_, 3] => Ok(3),
        s => Err(crate::errors::BadInputError::new_err(format!(
            "points of shape {s:?}: (n, 2) or (n, 3) expected"
        ))),
    }
}

/// `grid` and `alpha` of a fit call (20 control points per axis, smoothing 50 when absent);
/// their ranges are checked with the run's parameters ([`call_params`]).
fn morph_args(
    grid: Option<&Bound<'_, PyAny>>,
    alpha: Option<&Bound<'_, PyAny>>,
) -> PyResult<(usize, f64)> {
    Ok((
        grid.map(|g| args::size(g, "grid", 0, usize::MAX))
            .transpose()?
            .unwrap_or(20),
        alpha
            .map(|a| args::real(a, "alpha"))
            .transpose()?
            .unwrap_or(50.0),
    ))
}

/// The run's parameters with a call's options, checked as the command line's are
/// ([`RunParams::validate`]).
fn call_params<const D: usize>(
    ctx: &RunContext<D>,
    partial: bool,
    grid: usize,
    alpha: f64,
) -> PyResult<RunParams> {
    let mut p = ctx.params.clone();
    p.fit.partial = partial;
    p.morph.grid = grid;
    p.morph.alpha = alpha;
    p.validate(D).map_err(to_py)?;
    Ok(p)
}

/// A pool of `jobs` threads (an argument from Python; None or 0: every core).
fn thread_pool(jobs: Option<&Bound<'_, PyAny>>) -> PyResult<rayon::ThreadPool> {
    let jobs = jobs
        .map(|j| args::size(j, "jobs", 0, 1024))
        .transpose()?
        .unwrap_or(0);
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| crate::errors::Error::new_err(format!("thread pool: {e}")))
}

/// The fit of one subject (Algorithm 1, eq. 9, repair), with its report as JSON.
fn fit_one<const D: usize>(
    ctx: &RunContext<D>,
    subject: &Subject<D>,
    params: &RunParams,
) -> atlasmesh::Result<(atlasmesh::study::SubjectOutcome<D>, String)> {
    let o = ctx.fit(subject, params)?;
    let report = serde_json::to_string(&o.report)
        .map_err(|e| atlasmesh::Error::Numerical(format!("report: {e}")))?;
    Ok((o, report))
}

/// The Python result of a fit `fit` of `atlas`, with its mesh and measures (JSON, parsed
/// here once into a dict).
fn fit_result<const D: usize>(
    py: Python<'_>,
    atlas: &RustAtlas<D>,
    fit: &atlasmesh::fit::FitResult<D>,
    mesh: Option<Py<Mesh>>,
    report: String,
) -> PyResult<FitResult> {
    let measures = py
        .import("json")?
        .call_method1("loads", (report,))?
        .unbind();
    let t = fit.similarity;
    Ok(FitResult {
        dim: D,
        sd: atlas.in_sd(&fit.weights),
        scale: t.s,
        rotation: t.r.iter().flatten().copied().collect(),
        translation: t.t.to_vec(),
        surface: fit.projected.iter().flat_map(|p| p.point).collect(),
        facets: atlas.facets.iter().flatten().copied().collect(),
        mesh,
        measures,
        pending: std::sync::Mutex::new(None),
    })
}

fn result<const D: usize>(
    py: Python<'_>,
    ctx: &RunContext<D>,
    o: atlasmesh::study::SubjectOutcome<D>,
    report: String,
) -> PyResult<FitResult> {
    let mesh = Py::new(py, Mesh::of(&o.mesh, &o.quality))?;
    fit_result(py, &ctx.atlas, &o.fit, Some(mesh), report)
}

/// A subject's fit alone (Algorithm 1, eq. 5-8, projected onto the subject; no morph): the
/// subject, the fit, its seconds and the subject's closest-point index (kept for the two-way
/// distance asked later).
type FitAlone<const D: usize> = (
    Shape<D>,
    atlasmesh::fit::FitResult<D>,
    f64,
    atlasmesh::geometry::ClosestPointIndex<D>,
);

/// The fit of `subject` alone (Algorithm 1; see [`FitAlone`]).
fn fit_alone<const D: usize>(
    ctx: &RunContext<D>,
    subject: &Subject<D>,
    params: &RunParams,
) -> atlasmesh::Result<FitAlone<D>> {
    let shape = subject.shape.clone();
    let index = atlasmesh::geometry::ClosestPointIndex::from_shape(&shape);
    let start = std::time::Instant::now();
    let fit = ctx.fitter()?.fit(&shape, &index, &params.fit)?;
    Ok((shape, fit, start.elapsed().as_secs_f64(), index))
}

/// The Python result of a fit alone: its weights, pose and surface, and its measures (`e_d`,
/// `iterations`, `converged`, `fit_seconds`; `rms_distance` and `rms_distance_relative`
/// computed when first read).
fn fit_alone_result<const D: usize>(
    py: Python<'_>,
    ctx: &RunContext<D>,
    (shape, fit, seconds, index): FitAlone<D>,
) -> PyResult<FitResult> {
    let report = serde_json::json!({
        "name": shape.name,
        "e_d": fit.e_d_history.last().copied().unwrap_or(f64::NAN),
        "iterations": fit.iterations,
        "converged": fit.converged,
        "fit_seconds": seconds,
    })
    .to_string();
    let r = fit_result(py, &ctx.atlas, &fit, None, report)?;
    // The two-way RMS distance (a second index, of the instance, and a query per subject
    // vertex: a third of the fit's time) when first asked for.
    let (instance, facets, subject) = (fit.instance, ctx.atlas.facets.clone(), shape);
    let job: crate::result::Pending = Box::new(move || {
        let rms = atlasmesh::eval::two_way_rms(&instance, &facets, &subject, &index);
        vec![
            ("rms_distance", rms),
            ("rms_distance_relative", rms / subject.bbox_diagonal()),
        ]
    });
    *r.pending
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(job);
    Ok(r)
}

#[pymethods]
impl Atlas {
    /// Loads an atlas written by `atlasmesh build` or `Atlas.save`.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        // The file and its checksum kept: a study's report names them, as `fit`'s does.
        let file = path.display().to_string();
        let crc = atlasmesh::study::batch::file_crc32(&path).map_err(to_py)?;
        let inner = match atlasmesh::formats::atlas_dimension(&path).map_err(to_py)? {
            3 => {
                let mut ctx = context(RustAtlas::load(&path).map_err(to_py)?)?;
                (ctx.atlas_file, ctx.atlas_crc) = (file, crc);
                Inner::Three(ctx)
            }
            _ => {
                let mut ctx = context(RustAtlas::load(&path).map_err(to_py)?)?;
                (ctx.atlas_file, ctx.atlas_crc) = (file, crc);
                Inner::Two(ctx)
            }
        };
        Ok(Atlas { inner })
    }

    /// Builds an atlas from shapes in point correspondence (same point count and facets):
    /// `(points, facets)` pairs of arrays (points `(N, 2)` or `(N, 3)`, facets `(F, 2)`
    /// segments or `(F, 3)` triangles) or file paths. GPA with tangent projection (eq. 3),
    /// PCA (eq. 4), `modes` modes or the fewest explaining `variance`, and the automatic
    /// quadrilateral or hexahedral mesh of the mean at `element_size` (a length in the
    /// shapes' unit, a share such as `"2%"`, or `"auto"`); `mesh=False` keeps the shape model
    /// alone. `register=True` brings raw shapes into correspondence first (FFD registration
    /// of a template, eq. 1-2). `cut`: surfaces put on a common cut as the command line's
    /// `--cut` (`"auto"`, `"S:60"`, `"none"`; by default when a shape is open where a plane
    /// cut it). `closed=False`: outlines in CSV and text files are open (`--open`).
    /// `landmarks`: landmark files (one CSV for all shapes, or one file per shape in their
    /// order: Scalismo JSON, Slicer markups, `.pts`, CSV), which guide the registration and
    /// the fit; `template`: the registration's template, a shape's name or a surface file
    /// outside the population, with its `template_landmarks`; `template_mesh`: 3D, your own
    /// volume mesh of the first shape (or one per shape) instead of the automatic mesh. Files
    /// are read as `atlasmesh build` reads them; what it says on stderr (an island dropped,
    /// the cut) comes as Python warnings.
    #[staticmethod]
    #[pyo3(signature = (shapes, modes=None, variance=None, element_size=None, register=false, mesh=true, cut=None, closed=true, landmarks=None, template=None, template_landmarks=None, template_mesh=None))]
    #[allow(clippy::too_many_arguments)]
    fn build(
        py: Python<'_>,
        shapes: &Bound<'_, PyList>,
        modes: Option<&Bound<'_, PyAny>>,
        variance: Option<&Bound<'_, PyAny>>,
        element_size: Option<&Bound<'_, PyAny>>,
        register: bool,
        mesh: bool,
        cut: Option<&str>,
        closed: bool,
        landmarks: Option<&Bound<'_, PyAny>>,
        template: Option<&Bound<'_, PyAny>>,
        template_landmarks: Option<&Bound<'_, PyAny>>,
        template_mesh: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        if shapes.is_empty() {
            return Err(crate::errors::BadInputError::new_err("no shape given"));
        }
        let dim = dimension_of(&shapes.get_item(0)?)?;
        let params = crate::population::run_params(modes, variance, element_size)?;
        let with = crate::population::Correspondence {
            landmarks,
            template,
            template_landmarks,
            template_mesh,
        };
        let spec = crate::population::spec(register, cut, closed, !mesh, &with)?;
        fn go<const D: usize>(
            py: Python<'_>,
            list: &Bound<'_, PyList>,
            params: &RunParams,
            spec: &atlasmesh::study::PopulationSpec,
            mesh: bool,
        ) -> PyResult<RustAtlas<D>> {
            let loaded = crate::population::loaded::<D>(list, spec)?;
            let (atlas, warnings) = py
                .detach(|| {
                    let mut population = atlasmesh::study::Population::new(loaded, spec)?;
                    let c = population.corresponded(spec, 0, &atlasmesh::study::Silent)?;
                    let atlas = population.atlas(&c.shapes, params, mesh)?;
                    let mut warnings: Vec<String> = population
                        .warnings()
                        .map(|(n, w)| format!("{n}: {w}"))
                        .collect();
                    warnings.extend(population.notes.iter().cloned());
                    Ok((atlas, warnings))
                })
                .map_err(to_py)?;
            crate::population::warn_all(py, warnings)?;
            Ok(atlas)
        }
        let inner = if dim == 3 {
            Inner::Three(context(go::<3>(py, shapes, &params, &spec, mesh)?)?)
        } else {
            Inner::Two(context(go::<2>(py, shapes, &params, &spec, mesh)?)?)
        };
        Ok(Atlas { inner })
    }

    /// The atlas of a cohort of 3D surfaces in correspondence too large to hold (the command
    /// line's `build --stream`): `shapes` are paths (files, folders, `.list` files), read
    /// from their files on each pass, `batch` at a time; GPA in passes and the leading modes
    /// by a randomized PCA (`modes`, or up to `max_modes`, 100 by default, with a share of
    /// `variance`); `batch` 256 by default.
    #[staticmethod]
    #[pyo3(signature = (shapes, modes=None, variance=None, element_size=None, mesh=true, batch=None, max_modes=None))]
    #[allow(clippy::too_many_arguments)]
    fn build_streamed(
        py: Python<'_>,
        shapes: &Bound<'_, PyList>,
        modes: Option<&Bound<'_, PyAny>>,
        variance: Option<&Bound<'_, PyAny>>,
        element_size: Option<&Bound<'_, PyAny>>,
        mesh: bool,
        batch: Option<&Bound<'_, PyAny>>,
        max_modes: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let paths: Vec<PathBuf> = shapes
            .iter()
            .map(|o| {
                o.extract::<PathBuf>().map_err(|_| {
                    crate::errors::BadInputError::new_err(
                        "build_streamed: shapes are paths (surface files, folders, .list files)",
                    )
                })
            })
            .collect::<PyResult<_>>()?;
        if paths.is_empty() {
            return Err(crate::errors::BadInputError::new_err("no shape given"));
        }
        let params = crate::population::run_params(modes, variance, element_size)?;
        let mut stream = atlasmesh::model::StreamParams::default();
        if let Some(b) = batch {
            stream.batch = crate::args::size(b, "batch", 1, 1_000_000)?;
        }
        if let Some(m) = max_modes {
            stream.max_modes = crate::args::size(m, "max_modes", 1, 10_000)?;
        }
        let atlas = py
            .detach(|| {
                let files = atlasmesh::study::batch::subject_files(&paths)?;
                let files = atlasmesh::study::SurfaceFiles::new(files)?;
                atlasmesh::study::streamed_atlas(&files, &params, &stream, !mesh)
            })
            .map_err(to_py)?;
        Ok(Atlas {
            inner: Inner::Three(context(atlas)?),
        })
    }

    /// This atlas with named node sets, element sets and surfaces on its mean mesh, carried
    /// to every fitted mesh and written with it (the command line's `--sets`): `sets` is a
    /// sets TOML file's path or a dict of its tables (`{"node_set": [{"name": "DISTAL",
    /// "half_space": {"axis": "longest", "below": 0.1}}]}`), checked as the file is. A set
    /// of a name the mesh has is replaced. The atlas's `save` and pickling keep them.
    fn with_sets(&self, sets: &Bound<'_, PyAny>) -> PyResult<Atlas> {
        let config = sets_config(sets)?;
        if !each!(&self.inner, a, D => a.atlas.has_mesh()) {
            return Err(crate::errors::BadInputError::new_err(
                "sets: the atlas has no mean mesh (built with mesh=False)",
            ));
        }
        let inner = match &self.inner {
            Inner::Two(a) => Inner::Two(with_sets(a, config)?),
            Inner::Three(a) => Inner::Three(with_sets(a, config)?),
        };
        Ok(Atlas { inner })
    }

    /// Writes the atlas (safetensors; `atlasmesh` reads it back).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        each!(&self.inner, a, D => a.atlas.save(&path)).map_err(to_py)
    }

    /// Pickling: the atlas as `save` writes it (safetensors bytes) and its dimension, made
    /// again by `_from_bytes`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Reduced<'py>> {
        let py = slf.py();
        let (dimension, bytes) = each!(&slf.get().inner, a, D => (D, a.atlas.to_bytes()));
        let bytes = bytes.map_err(to_py)?;
        Ok((
            slf.get_type().getattr("_from_bytes")?,
            (dimension, pyo3::types::PyBytes::new(py, &bytes)),
        ))
    }

    /// The atlas of `data`, the bytes of an atlas file of `dimension` (2 or 3): what
    /// unpickling an atlas calls.
    #[staticmethod]
    fn _from_bytes(dimension: usize, data: &[u8]) -> PyResult<Self> {
        let path = std::path::Path::new("<pickled atlas>");
        let inner = match dimension {
            3 => Inner::Three(context(RustAtlas::from_bytes(path, data).map_err(to_py)?)?),
            2 => Inner::Two(context(RustAtlas::from_bytes(path, data).map_err(to_py)?)?),
            d => {
                return Err(crate::errors::BadInputError::new_err(format!(
                    "a pickled atlas of dimension {d}: 2 or 3 expected"
                )));
            }
        };
        Ok(Atlas { inner })
    }

    /// 2 or 3.
    #[getter]
    fn dimension(&self) -> usize {
        each!(&self.inner, _a, D => D)
    }

    /// The mean shape `S_bar`, `(N, D)`, in the data's frame and unit.
    #[getter]
    fn mean<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&self.inner, a, D => arrays::frozen_points::<D>(py, &a.atlas.to_data_frame(&a.atlas.mean)))
    }

    /// The facets of the shapes (triangles or segments), `(F, D)` int64.
    #[getter]
    fn facets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&self.inner, a, D => arrays::frozen_i64(py, a.atlas.facets.iter().flatten().copied(), &[a.atlas.facets.len(), D]))
    }

    /// The modes `Psi`, `(m, N, D)`: orthonormal directions of the shape space (the
    /// reference frame's axes, which the data's frame rotates).
    #[getter]
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&self.inner, a, D => {
            let (n, m) = (a.atlas.mean.len(), a.atlas.num_modes());
            arrays::frozen_f64(
                py,
                (0..m).flat_map(|k| (0..n * D).map(move |r| (k, r))).map(|(k, r)| a.atlas.modes[(r, k)]),
                &[m, n, D],
            )
        })
    }

    /// The variances of the modes `lambda_k` in the data's unit squared (mm² for mm data).
    #[getter]
    fn variances<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&self.inner, a, D => {
            let s = a.atlas.data_frame.map_or(1.0, |t| t.s);
            arrays::frozen_f64(py, a.atlas.eigenvalues.iter().map(|l| l * s * s), &[a.atlas.num_modes()])
        })
    }

    /// The cumulative share of the variance of the first 1, 2, ... modes (of all the
    /// training PCA's modes).
    #[getter]
    fn cumulative_variance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&self.inner, a, D => arrays::frozen_f64(py, a.atlas.cumulative_variance.iter().copied(), &[a.atlas.cumulative_variance.len()]))
    }

    /// The atlas's FE mesh of the mean (data's frame and unit), or None (`mesh=False`).
    #[getter]
    fn mean_mesh(&self, py: Python<'_>) -> PyResult<Option<Py<Mesh>>> {
        each!(&self.inner, a, D => {
            if !a.atlas.has_mesh() {
                return Ok(None);
            }
            let m = a.atlas.mesh.with_nodes(a.atlas.to_data_frame(&a.atlas.mesh.nodes));
            let q = atlasmesh::mesh::quality::mesh_quality(&m);
            Ok(Some(Py::new(py, Mesh::of(&m, &q))?))
        })
    }

    /// The instance of weights `sd` (standard deviations of each mode; fewer: the rest 0):
    /// `S_bar + Psi w` (eq. 4), `(N, D)` in the data's frame and unit.
    fn instance<'py>(
        &self,
        py: Python<'py>,
        sd: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        // A single number would be mode 1 alone: refused, as it is most likely a mistake.
        let number = sd.is_instance_of::<pyo3::types::PyFloat>()
            || sd.is_instance_of::<pyo3::types::PyInt>()
            || sd
                .getattr("ndim")
                .and_then(|n| n.extract::<usize>())
                .is_ok_and(|n| n == 0);
        if number {
            return Err(crate::errors::BadInputError::new_err(
                "sd: a sequence of weights expected (standard deviations, one per mode from the first; fewer: the rest 0), got a single number; [x] is mode 1 alone",
            ));
        }
        each!(&self.inner, a, D => {
            let m = a.atlas.num_modes();
            // The count is checked below, with the model's modes named.
            let sd = arrays::vector(sd, "sd", 1 << 20)?;
            if sd.len() > m || sd.iter().any(|v| !v.is_finite()) {
                return Err(crate::errors::BadInputError::new_err(format!(
                    "{} weights for a model of {m} modes (finite numbers of standard deviations)",
                    sd.len()
                )));
            }
            let w: Vec<f64> = (0..m).map(|k| sd.get(k).copied().unwrap_or(0.0) * a.atlas.eigenvalues[k].sqrt()).collect();
            let shape = a.atlas.to_data_frame(&a.atlas.instance(&w));
            if shape.iter().flatten().any(|v| !v.is_finite()) {
                return Err(crate::errors::BadInputError::new_err(
                    "instance: the weights are so large that the shape is not finite",
                ));
            }
            arrays::of_points::<D>(py, &shape)
        })
    }

    /// The model's closest shape to `points` (`(N, D)`, in correspondence with the model's
    /// points, any pose and size): `points` aligned to the mean by a similarity, projected
    /// onto the model's span (`S_bar + Psi Psi^T (x - S_bar)`), and put back in their pose.
    /// Returns the projection `(N, D)` and its weights in standard deviations.
    fn project<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        each!(&self.inner, a, D => {
            let x = arrays::points::<D>(points, "points")?;
            if x.iter().flatten().any(|v| !v.is_finite()) {
                return Err(crate::errors::BadInputError::new_err(
                    "project: points have NaN or infinite coordinates",
                ));
            }
            if x.len() != a.atlas.mean.len() {
                return Err(crate::errors::BadInputError::new_err(format!(
                    "{} points for a model of {}",
                    x.len(),
                    a.atlas.mean.len()
                )));
            }
            let t = atlasmesh::model::fit_similarity(&a.atlas.mean, &x, None);
            let inside: Vec<Point<D>> = x.iter().map(|p| t.apply_inverse(p)).collect();
            let w = a.atlas.coefficients(&inside);
            let p: Vec<Point<D>> = a.atlas.instance(&w).iter().map(|q| t.apply(q)).collect();
            let sd = a.atlas.in_sd(&w);
            Ok((arrays::of_points::<D>(py, &p)?, arrays::to_f64(py, sd.iter().copied(), &[sd.len()])?))
        })
    }

    /// `n` random shapes of the model (weights ~ N(0, Lambda), each within `max_sd`
    /// standard deviations when given), seeded: `(shapes (n, N, D), weights (n, m) in
    /// standard deviations)`, shapes in the data's frame and unit.
    #[pyo3(signature = (n, seed=None, max_sd=None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        n: &Bound<'py, PyAny>,
        seed: Option<&Bound<'py, PyAny>>,
        max_sd: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let n = args::size(n, "n", 0, usize::MAX)?;
        let seed = seed
            .map(|s| args::count(s, "seed", 0, u64::MAX))
            .transpose()?
            .unwrap_or(1);
        let max_sd = max_sd.map(|m| args::real(m, "max_sd")).transpose()?;
        each!(&self.inner, a, D => {
            let values = n.saturating_mul(a.atlas.mean.len()).saturating_mul(D);
            if values > MAX_ARRAY_VALUES {
                return Err(crate::errors::BadInputError::new_err(format!(
                    "sample({n}): {n} shapes of {} points would take {} MB; draw at most {} at a time",
                    a.atlas.mean.len(),
                    values.saturating_mul(8) >> 20,
                    MAX_ARRAY_VALUES / (a.atlas.mean.len() * D).max(1)
                )));
            }
            let specs = atlasmesh::study::sample_specs(&a.atlas, n, seed, max_sd).map_err(to_py)?;
            let m = a.atlas.num_modes();
            let mut pts = Vec::with_capacity(n * a.atlas.mean.len() * D);
            for s in &specs {
                let w: Vec<f64> = (0..m).map(|k| s.sd[k] * a.atlas.eigenvalues[k].sqrt()).collect();
                pts.extend(a.atlas.to_data_frame(&a.atlas.instance(&w)).iter().flatten().copied());
            }
            Ok((
                arrays::to_f64(py, pts, &[n, a.atlas.mean.len(), D])?,
                arrays::to_f64(py, specs.iter().flat_map(|s| s.sd.clone()), &[n, m])?,
            ))
        })
    }

    /// Fits a subject, `(points, facets)` arrays or a file path, in its own frame and unit:
    /// the model instance that matches it (Algorithm 1, eq. 5-8), projected onto it, and the
    /// mean mesh morphed onto it by the B-spline FFD of eq. 9 (`grid` control points per
    /// axis, smoothing `alpha`), repaired and checked. `partial=True` for a subject that
    /// misses parts; `mesh=False` for the fit alone (no morph: `mesh` is None). The GIL is
    /// released while it runs.
    #[pyo3(signature = (subject, facets=None, partial=false, grid=None, alpha=None, mesh=true))]
    fn fit(
        &self,
        subject: &Bound<'_, PyAny>,
        facets: Option<&Bound<'_, PyAny>>,
        partial: bool,
        grid: Option<&Bound<'_, PyAny>>,
        alpha: Option<&Bound<'_, PyAny>>,
        mesh: bool,
    ) -> PyResult<FitResult> {
        let py = subject.py();
        let (grid, alpha) = morph_args(grid, alpha)?;
        each!(&self.inner, a, D => {
            let params = call_params(a, partial, grid, alpha)?;
            let subject = match facets {
                Some(f) => subject_of::<D>(&pyo3::types::PyTuple::new(py, [subject, f])?.into_any(), 0)?,
                None => subject_of::<D>(subject, 0)?,
            };
            if !mesh {
                let alone = py.detach(|| fit_alone(a, &subject, &params)).map_err(to_py)?;
                return fit_alone_result(py, a, alone);
            }
            let (o, report) = py.detach(|| fit_one(a, &subject, &params)).map_err(to_py)?;
            result(py, a, o, report)
        })
    }

    /// Fits every subject of `subjects` (as `fit` takes them) in parallel on `jobs` threads
    /// (0: every core), the GIL released: a list with a `FitResult` or the exception (an
    /// `atlasmesh.Error`) of each, in order. `mesh=False`: the fits alone, as `fit` makes
    /// them.
    #[pyo3(signature = (subjects, partial=false, grid=None, alpha=None, jobs=None, mesh=true))]
    #[allow(clippy::too_many_arguments)]
    fn fit_many(
        &self,
        py: Python<'_>,
        subjects: &Bound<'_, PyList>,
        partial: bool,
        grid: Option<&Bound<'_, PyAny>>,
        alpha: Option<&Bound<'_, PyAny>>,
        jobs: Option<&Bound<'_, PyAny>>,
        mesh: bool,
    ) -> PyResult<Vec<Py<PyAny>>> {
        let (grid, alpha) = morph_args(grid, alpha)?;
        let pool = thread_pool(jobs)?;
        each!(&self.inner, a, D => {
            let params = call_params(a, partial, grid, alpha)?;
            let shapes: Vec<PyResult<Subject<D>>> = subjects
                .iter()
                .enumerate()
                .map(|(k, o)| subject_of::<D>(&o, k))
                .collect();
            // (A fit with its mesh, or alone.)
            type Outcome<const D: usize> = Result<
                (atlasmesh::study::SubjectOutcome<D>, String),
                FitAlone<D>,
            >;
            let outcomes: Vec<atlasmesh::Result<Outcome<D>>> = py.detach(|| {
                pool.install(|| {
                    shapes
                        .par_iter()
                        .map(|s| match s {
                            Ok(s) if mesh => fit_one(a, s, &params).map(Ok),
                            Ok(s) => fit_alone(a, s, &params).map(Err),
                            Err(_) => Err(atlasmesh::Error::Parameter(String::new())),
                        })
                        .collect()
                })
            });
            shapes
                .into_iter()
                .zip(outcomes)
                .map(|(s, o)| -> PyResult<Py<PyAny>> {
                    Ok(match (s, o) {
                        (Err(e), _) => e.into_value(py).into_any(),
                        (Ok(_), Err(e)) => to_py(e).into_value(py).into_any(),
                        (Ok(_), Ok(Ok((o, report)))) => {
                            Py::new(py, result(py, a, o, report)?)?.into_any()
                        }
                        (Ok(_), Ok(Err(alone))) => {
                            Py::new(py, fit_alone_result(py, a, alone)?)?.into_any()
                        }
                    })
                })
                .collect()
        })
    }

    /// Fits `subjects` and writes what `atlasmesh fit` writes into `out`: each subject's mesh,
    /// fitted surface, pictures and page (`plots=False`: no pictures and pages), `report.json`,
    /// `scores.csv` and the overview `report.html`; returns the report (`report.json` as a
    /// dict; a subject that failed is in its `failed` list with the reason). Subjects given
    /// as paths (files, folders, `.list` files) get a folder each, `out/NAME/`, as on the
    /// command line, and a subject already complete there is skipped (`resume=False` fits it
    /// again); subjects given as arrays or shapes are written flat into `out`. `jobs` threads
    /// (0 or None: every core); the GIL is released while it runs.
    #[pyo3(signature = (subjects, out, partial=false, grid=None, alpha=None, jobs=None, plots=true, resume=true))]
    #[allow(clippy::too_many_arguments)]
    fn fit_study(
        &self,
        py: Python<'_>,
        subjects: &Bound<'_, PyList>,
        out: PathBuf,
        partial: bool,
        grid: Option<&Bound<'_, PyAny>>,
        alpha: Option<&Bound<'_, PyAny>>,
        jobs: Option<&Bound<'_, PyAny>>,
        plots: bool,
        resume: bool,
    ) -> PyResult<Py<PyAny>> {
        let (grid, alpha) = morph_args(grid, alpha)?;
        if subjects.is_empty() {
            return Err(crate::errors::BadInputError::new_err("no subject given"));
        }
        let pool = thread_pool(jobs)?;
        // Paths only (not label maps, which carry their label): the command line's batch.
        let paths: Option<Vec<PathBuf>> = subjects
            .iter()
            .map(|o| {
                if o.extract::<PyRef<'_, crate::read::LabelMap>>().is_ok() {
                    None
                } else {
                    o.extract::<PathBuf>().ok()
                }
            })
            .collect();
        let json = each!(&self.inner, a, D => {
            let mut params = call_params(a, partial, grid, alpha)?;
            params.plots = plots;
            let place = atlasmesh::study::RunPlace { out, resume, shard: None };
            let ctx = a.with_place(params, place).map_err(to_py)?;
            let silent = &atlasmesh::study::Silent;
            let report = match &paths {
                Some(paths) => {
                    let files = atlasmesh::study::batch::subject_files(paths).map_err(to_py)?;
                    atlasmesh::study::batch::check_folder_names(&files).map_err(to_py)?;
                    let name = atlasmesh::study::dataset_name(&files);
                    py.detach(|| {
                        pool.install(|| {
                            atlasmesh::study::fit_batch(&ctx, &files, &Default::default(), &name, silent)
                        })
                    })
                }
                None => {
                    let shapes = subjects
                        .iter()
                        .enumerate()
                        .map(|(k, o)| subject_of::<D>(&o, k))
                        .collect::<PyResult<Vec<Subject<D>>>>()?;
                    py.detach(|| {
                        pool.install(|| atlasmesh::study::fit_shapes(&ctx, &shapes, "arrays", silent))
                    })
                }
            }
            .map_err(to_py)?;
            serde_json::to_string(&report)
                .map_err(|e| crate::errors::Error::new_err(format!("the report as JSON: {e}")))?
        });
        Ok(py.import("json")?.call_method1("loads", (json,))?.unbind())
    }

    fn __repr__(&self) -> String {
        each!(&self.inner, a, D => format!(
            "Atlas({D}D, {} points, {} modes, {})",
            a.atlas.mean.len(),
            a.atlas.num_modes(),
            if a.atlas.has_mesh() {
                format!("mean mesh of {} {} elements", a.atlas.mesh.num_elements(), a.atlas.mesh.kind.name())
            } else {
                "no mesh".to_string()
            }
        ))
    }
}

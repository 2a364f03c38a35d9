//! `atlasmesh.leave_one_out`: the paper's leave-one-out experiment (section 6.1) from Python,
//! the same run as the command line's `loo`, its report returned as `report.json` holds it.

use crate::errors::{BadInputError, to_py};
use crate::model::dimension_of;
use crate::population::{Correspondence, loaded, run_params, spec, warn_all};
use atlasmesh::study::{self, PopulationSpec, RunParams};
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::path::{Path, PathBuf};

/// The leave-one-out of `shapes` (files, `(points, facets)` arrays, label maps, PyVista or
/// meshio shapes, read as `Atlas.build` reads them): for each shape the atlas of the others,
/// its fit, the morphed and repaired mesh and the measures, written into `out` as
/// `atlasmesh loo` writes them (pictures with `plots=True`). Returns the report (`report.json`
/// as a dict); what the command line says on stderr comes as `UserWarning`s. `landmarks`,
/// `template`, `template_landmarks` and `template_mesh` as `Atlas.build` takes them. With
/// `folds=K`, a k-fold cross-validation as `atlasmesh loo --folds K` runs it: the shapes in K
/// consecutive groups, each fitted with the atlas of the others.
#[pyfunction]
#[pyo3(signature = (shapes, out, modes=None, variance=None, element_size=None, register=false, cut=None, closed=true, plots=false, jobs=None, landmarks=None, template=None, template_landmarks=None, template_mesh=None, folds=None))]
#[allow(clippy::too_many_arguments)]
pub fn leave_one_out(
    py: Python<'_>,
    shapes: &Bound<'_, PyList>,
    out: PathBuf,
    modes: Option<&Bound<'_, PyAny>>,
    variance: Option<&Bound<'_, PyAny>>,
    element_size: Option<&Bound<'_, PyAny>>,
    register: bool,
    cut: Option<&str>,
    closed: bool,
    plots: bool,
    jobs: Option<&Bound<'_, PyAny>>,
    landmarks: Option<&Bound<'_, PyAny>>,
    template: Option<&Bound<'_, PyAny>>,
    template_landmarks: Option<&Bound<'_, PyAny>>,
    template_mesh: Option<&Bound<'_, PyAny>>,
    folds: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    if shapes.is_empty() {
        return Err(BadInputError::new_err("no shape given"));
    }
    let jobs = jobs.map_or(Ok(0), |j| crate::args::size(j, "jobs", 0, 1024))?;
    let folds = folds
        .map(|k| crate::args::size(k, "folds", 2, 1_000_000))
        .transpose()?;
    let dim = dimension_of(&shapes.get_item(0)?)?;
    let mut params = run_params(modes, variance, element_size)?;
    params.plots = plots;
    let with = Correspondence {
        landmarks,
        template,
        template_landmarks,
        template_mesh,
    };
    let spec = spec(register, cut, closed, false, &with)?;
    let (json, warnings) = if dim == 3 {
        run::<3>(py, shapes, &params, &spec, &out, jobs, folds)?
    } else {
        run::<2>(py, shapes, &params, &spec, &out, jobs, folds)?
    };
    warn_all(py, warnings)?;
    Ok(py.import("json")?.call_method1("loads", (json,))?.unbind())
}

/// The leave-one-out (with `folds`, the k-fold cross-validation) in dimension `D`: the report
/// as JSON, and the population's warnings.
fn run<const D: usize>(
    py: Python<'_>,
    list: &Bound<'_, PyList>,
    params: &RunParams,
    spec: &PopulationSpec,
    out: &Path,
    jobs: usize,
    folds: Option<usize>,
) -> PyResult<(String, Vec<String>)> {
    let loaded = loaded::<D>(list, spec)?;
    py.detach(|| -> atlasmesh::Result<(String, Vec<String>)> {
        let mut population = study::Population::new(loaded, spec)?;
        let c = population.corresponded(spec, jobs, &study::Silent)?;
        let mut warnings: Vec<String> = population
            .warnings()
            .map(|(n, w)| format!("{n}: {w}"))
            .collect();
        warnings.extend(population.notes.iter().cloned());
        let facts = study::PopulationFacts {
            inputs: population.inputs.clone(),
            template: c.template.clone(),
        };
        let each = study::Folds {
            corresponded: &c.shapes,
            // Shapes put on a common cut are fitted as read, as `loo` fits them.
            subjects: population.as_read.as_deref().unwrap_or(&population.shapes),
            meshes: population.meshes.as_deref(),
            population: &facts,
        };
        let (dataset, silent) = ("leave-one-out", &study::Silent);
        let report = match folds {
            Some(k) => study::cross_validation(each, k, dataset, params, out, jobs, silent)?,
            None => study::leave_one_out_of(each, dataset, params, out, jobs, silent)?,
        };
        let json = serde_json::to_string(&report)
            .map_err(|e| atlasmesh::Error::Numerical(format!("the report as JSON: {e}")))?;
        Ok((json, warnings))
    })
    .map_err(to_py)
}

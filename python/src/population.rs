//! A population from Python (files, arrays, label maps) as the command line reads `--shapes`:
//! the library's [`atlasmesh::study::PopulationSpec`], for `Atlas.build` and `leave_one_out`.

use crate::args;
use crate::errors::{BadInputError, to_py};
use crate::model::subject_of;
use atlasmesh::geometry::Shape;
use atlasmesh::study::{CutChoice, PopulationOptions, PopulationSpec, RunParams};
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::path::PathBuf;

/// The run's parameters from Python's `modes`, `variance` and `element_size` (a string such as
/// `"auto"`, `"2"`, `"1.5%"`, or a length as a number); no pictures.
pub(crate) fn run_params(
    modes: Option<&Bound<'_, PyAny>>,
    variance: Option<&Bound<'_, PyAny>>,
    element_size: Option<&Bound<'_, PyAny>>,
) -> PyResult<RunParams> {
    let mut params = RunParams {
        plots: false,
        ..RunParams::default()
    };
    params.atlas.modes = match (modes, variance) {
        (Some(m), _) => atlasmesh::model::ModeSelection::Count(args::size(m, "modes", 1, 100_000)?),
        (None, Some(v)) => atlasmesh::model::ModeSelection::Variance(args::real(v, "variance")?),
        (None, None) => atlasmesh::model::ModeSelection::Variance(0.985),
    };
    params.element_size = match element_size {
        None => atlasmesh::mesh::ElementSize::Auto,
        Some(e) => match e.extract::<String>() {
            Ok(t) => t.parse(),
            Err(_) => args::real(e, "element_size")?.to_string().parse(),
        }
        .map_err(|m: String| BadInputError::new_err(format!("element_size: {m}")))?,
    };
    Ok(params)
}

/// The population's spec from Python's `register`, `cut` (as `--cut`), `closed` and
/// `point_sets` (a model without a mesh).
pub(crate) fn spec(
    register: bool,
    cut: Option<&str>,
    closed: bool,
    point_sets: bool,
) -> PyResult<PopulationSpec> {
    let cut: CutChoice = match cut {
        None => CutChoice::WhenOpen,
        Some(c) => c
            .parse()
            .map_err(|e: atlasmesh::Error| BadInputError::new_err(format!("cut: {e}")))?,
    };
    Ok(PopulationSpec {
        outlines: PopulationOptions {
            closed,
            ..Default::default()
        },
        point_sets,
        cut,
        registration: register.then(Default::default),
        ..Default::default()
    })
}

/// The shapes of `list`, each with what its reading noted: a file as `build` reads it (a CSV
/// holds one shape or several), arrays and label maps as `fit` takes them.
pub(crate) fn loaded<const D: usize>(
    list: &Bound<'_, PyList>,
    spec: &PopulationSpec,
) -> PyResult<Vec<(Shape<D>, Vec<String>)>> {
    let mut loaded: Vec<(Shape<D>, Vec<String>)> = Vec::new();
    for (k, o) in list.iter().enumerate() {
        let file = o
            .extract::<PathBuf>()
            .ok()
            .filter(|_| o.extract::<PyRef<'_, crate::read::LabelMap>>().is_err());
        match file {
            Some(p) => loaded.extend(
                PopulationSpec {
                    shapes: vec![p],
                    ..spec.clone()
                }
                .load::<D>()
                .map_err(to_py)?,
            ),
            None => {
                let s = subject_of::<D>(&o, k)?;
                loaded.push((s.shape, s.warnings));
            }
        }
    }
    Ok(loaded)
}

/// What the command line says on stderr (an island dropped, the cut made), as Python's
/// `UserWarning`s.
pub(crate) fn warn_all(py: Python<'_>, warnings: Vec<String>) -> PyResult<()> {
    for w in warnings {
        let text = std::ffi::CString::new(w.replace('\0', " ")).unwrap_or_default();
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &text,
            1,
        )?;
    }
    Ok(())
}

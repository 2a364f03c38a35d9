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

/// The files that bring shapes into correspondence, as Python gives them (each a path, or a
/// list of paths where several are taken): the command line's `--landmarks`, `--template`,
/// `--template-landmarks` and `--template-mesh`.
pub(crate) struct Correspondence<'a, 'py> {
    /// Landmark files: one CSV for all shapes, or one file per shape in their order.
    pub landmarks: Option<&'a Bound<'py, PyAny>>,
    /// The registration's template: a shape's name or a shape file outside the population.
    pub template: Option<&'a Bound<'py, PyAny>>,
    /// The landmarks of a template file.
    pub template_landmarks: Option<&'a Bound<'py, PyAny>>,
    /// 3D: template volume meshes, one per shape (or one for the first).
    pub template_mesh: Option<&'a Bound<'py, PyAny>>,
}

/// `obj` as paths: one path (`str`, `os.PathLike`) or a list or tuple of them; `name` is the
/// argument's name in the error.
fn paths(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<PathBuf>> {
    if let Ok(p) = obj.extract::<PathBuf>() {
        return Ok(vec![p]);
    }
    let bad = || {
        BadInputError::new_err(format!(
            "{name}: a path or a list of paths, not a {}",
            obj.get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        ))
    };
    // (A `str` is one path above: it is never taken as a list of characters.)
    let items = obj.try_iter().map_err(|_| bad())?;
    items
        .map(|i| i.and_then(|i| i.extract::<PathBuf>()).map_err(|_| bad()))
        .collect()
}

/// The population's spec from Python's `register`, `cut` (as `--cut`), `closed`,
/// `point_sets` (a model without a mesh) and the files that bring shapes into correspondence;
/// a template without `register` is refused as the command line refuses it.
pub(crate) fn spec(
    register: bool,
    cut: Option<&str>,
    closed: bool,
    point_sets: bool,
    with: &Correspondence<'_, '_>,
) -> PyResult<PopulationSpec> {
    let cut: CutChoice = match cut {
        None => CutChoice::WhenOpen,
        Some(c) => c
            .parse()
            .map_err(|e: atlasmesh::Error| BadInputError::new_err(format!("cut: {e}")))?,
    };
    let template = with
        .template
        .map(|t| match paths(t, "template")?.as_slice() {
            [one] => Ok(one.to_string_lossy().into_owned()),
            _ => Err(BadInputError::new_err(
                "template: one shape's name or one shape file",
            )),
        })
        .transpose()?;
    let template_landmarks = with
        .template_landmarks
        .map(|t| match paths(t, "template_landmarks")?.as_slice() {
            [one] => Ok(one.clone()),
            _ => Err(BadInputError::new_err("template_landmarks: one file")),
        })
        .transpose()?;
    if !register && template.is_some() {
        return Err(BadInputError::new_err(
            "template= chooses the registration's template: it needs register=True",
        ));
    }
    if template.is_none() && template_landmarks.is_some() {
        return Err(BadInputError::new_err(
            "template_landmarks= are the landmarks of a template file: it needs template=",
        ));
    }
    let list = |o: Option<&Bound<'_, PyAny>>, name| o.map_or(Ok(Vec::new()), |o| paths(o, name));
    Ok(PopulationSpec {
        landmarks: list(with.landmarks, "landmarks")?,
        template_meshes: list(with.template_mesh, "template_mesh")?,
        outlines: PopulationOptions {
            closed,
            ..Default::default()
        },
        point_sets,
        cut,
        registration: register.then(|| atlasmesh::study::RegistrationSpec {
            template,
            template_landmarks,
            ..Default::default()
        }),
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

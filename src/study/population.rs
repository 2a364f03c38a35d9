//! Loading a population: outlines and surfaces, landmarks, registration to a template.

use super::Progress;
use crate::error::{Error, Result};
use crate::geometry::{ClosestPointIndex, Point, Shape};
use crate::register::{resample_corresponding, resample_uniform};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// How to read a population of outlines.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct PopulationOptions {
    /// Outlines are closed (CSV and text inputs; VTK files carry their own topology).
    pub closed: bool,
    /// Resample every outline to this many points.
    pub resample: Option<usize>,
}

/// Reads outlines that need not correspond (any point counts), each resampled evenly by arc
/// length to `resample` points when given.
pub fn load_outlines_raw(paths: &[PathBuf], opts: &PopulationOptions) -> Result<Vec<Shape<2>>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    let mut shapes = Vec::new();
    for p in paths {
        for s in crate::formats::read_outlines(p, opts.closed)? {
            s.validate()
                .map_err(|e| Error::parse(p, 0, e.to_string()))?;
            let closed = s.is_closed();
            shapes.push(match opts.resample {
                Some(n) => resample_uniform(&s, n, closed)?,
                None => s,
            });
        }
    }
    Ok(shapes)
}

/// Gives every shape its landmarks from `files`: one CSV for the whole population (rows by
/// shape name), or one Scalismo JSON / `.pts` file per shape, in the shapes' order.
pub fn attach_landmarks<const D: usize>(shapes: &mut [Shape<D>], files: &[PathBuf]) -> Result<()> {
    use crate::formats::landmarks::{attach, read_landmarks, read_landmarks_csv};
    if files.is_empty() {
        return Ok(());
    }
    let csv = files.len() == 1
        && files[0]
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if csv {
        let map = read_landmarks_csv::<D>(&files[0])?;
        if let Some(name) = map.keys().find(|k| !shapes.iter().any(|s| &s.name == *k)) {
            return Err(Error::parse(
                &files[0],
                0,
                format!("landmarks for shape '{name}', which is not in the population"),
            ));
        }
        for s in shapes.iter_mut() {
            let l = map.get(&s.name).ok_or_else(|| {
                Error::parse(&files[0], 0, format!("no landmarks for shape '{}'", s.name))
            })?;
            attach(s, l, &files[0])?;
        }
    } else {
        if files.len() != shapes.len() {
            return Err(Error::Population(format!(
                "{} landmark files for {} shapes; give one per shape, in the same order, or one CSV",
                files.len(),
                shapes.len()
            )));
        }
        for (s, f) in shapes.iter_mut().zip(files) {
            let l = read_landmarks::<D>(f)?;
            attach(s, &l, f)?;
        }
    }
    let n0 = shapes[0].landmarks.len();
    if let Some((s, f)) = shapes
        .iter()
        .zip(files.iter().cycle())
        .find(|(s, _)| s.landmarks.len() != n0)
    {
        return Err(Error::parse(
            f,
            0,
            format!(
                "shape '{}' has {} landmarks but '{}' has {n0}; every shape needs the same landmarks",
                s.name,
                s.landmarks.len(),
                shapes[0].name
            ),
        ));
    }
    Ok(())
}

/// Brings shapes that are not in correspondence into correspondence (section 2.1): the
/// template (`template` names it; by default the shape nearest to the others after
/// alignment) is registered to every other shape ([`crate::register::register`]) and each is
/// resampled at the template's points. Returns the corresponded shapes (same order; the
/// template as it is) and the template's index. `jobs` threads (0 = all cores).
pub fn register_population<const D: usize>(
    shapes: &[Shape<D>],
    template: Option<&str>,
    params: &crate::register::RegisterParams,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<(Vec<Shape<D>>, usize)> {
    if shapes.len() < 2 {
        return Err(Error::Population(format!(
            "registration needs at least 2 shapes, got {}",
            shapes.len()
        )));
    }
    let t = match template {
        Some(name) => shapes.iter().position(|s| s.name == name).ok_or_else(|| {
            Error::Population(format!("--template {name}: no shape of that name"))
        })?,
        None => nearest_to_others(shapes, params)?,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::Parameter(format!("--jobs: {e}")))?;
    let label = "registration";
    progress.items_started(label, shapes.len());
    let out: Vec<Result<Shape<D>>> = pool.install(|| {
        shapes
            .par_iter()
            .enumerate()
            .map(|(k, s)| {
                let r = if k == t {
                    Ok(s.clone())
                } else {
                    let index = ClosestPointIndex::from_shape(s);
                    crate::register::register(&shapes[t], s, &index, params)
                        .map(|r| r.resampled(&shapes[t], s))
                };
                progress.item_done(label, &s.name);
                r
            })
            .collect()
    });
    progress.items_finished(label);
    Ok((out.into_iter().collect::<Result<Vec<_>>>()?, t))
}

/// The shape nearest to the others: every shape pre-aligned to the first, then the one of
/// least mean two-way distance to the rest (on up to 200 points of each).
fn nearest_to_others<const D: usize>(
    shapes: &[Shape<D>],
    params: &crate::register::RegisterParams,
) -> Result<usize> {
    let first = ClosestPointIndex::from_shape(&shapes[0]);
    let aligned: Vec<Shape<D>> = shapes
        .par_iter()
        .map(|s| {
            let sim = crate::register::pre_align(s, &shapes[0], &first, params.starts)?;
            Ok(Shape {
                points: s.points.iter().map(|p| sim.apply(p)).collect(),
                ..s.clone()
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let indexes: Vec<ClosestPointIndex<D>> =
        aligned.iter().map(ClosestPointIndex::from_shape).collect();
    let sample = |s: &Shape<D>| -> Vec<Point<D>> {
        let step = (s.points.len() / 200).max(1);
        s.points.iter().step_by(step).copied().collect()
    };
    let samples: Vec<Vec<Point<D>>> = aligned.iter().map(sample).collect();
    let ms = |a: usize, b: usize| -> f64 {
        samples[a]
            .iter()
            .map(|p| indexes[b].closest(p).dist2)
            .sum::<f64>()
            / samples[a].len() as f64
    };
    let n = shapes.len();
    let score: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| {
            (0..n)
                .filter(|&j| j != i)
                .map(|j| ms(i, j) + ms(j, i))
                .sum()
        })
        .collect();
    Ok((0..n)
        .min_by(|&a, &b| score[a].total_cmp(&score[b]))
        .unwrap_or(0))
}

/// Reads the triangle surfaces in `paths` (PLY, STL, OBJ), in the order given. Shapes in
/// correspondence must share their vertex count and facets (checked when the atlas is built).
pub fn load_surfaces(paths: &[PathBuf]) -> Result<Vec<Shape<3>>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    paths
        .par_iter()
        .map(|p| crate::formats::read_surface(p))
        .collect()
}

/// Whether `path` names a 3D surface file: by its extension (`.ply`, `.stl`, `.obj`), and
/// for legacy `.vtk` files by their content (POLYGONS make a surface, LINES an outline).
pub fn is_surface_file(path: &Path) -> bool {
    match path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .as_deref()
    {
        Some("ply" | "stl" | "obj" | "vtp") => true,
        Some("vtk") => {
            crate::formats::read_vtk_polydata(path).is_ok_and(|v| !v.polygons.is_empty())
        }
        _ => false,
    }
}

/// Reads the outlines in `paths` and, with `resample`, resamples them: in correspondence when
/// all have the same point count (the points are then taken as corresponding landmarks),
/// evenly by arc length otherwise. Without `resample` all shapes must have equal counts.
pub fn load_population(paths: &[PathBuf], opts: &PopulationOptions) -> Result<Vec<Shape<2>>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    let mut shapes = Vec::new();
    let mut origin: Vec<PathBuf> = Vec::new();
    for p in paths {
        let s = crate::formats::read_outlines(p, opts.closed)?;
        origin.extend(std::iter::repeat_n(p.clone(), s.len()));
        shapes.extend(s);
    }
    for (s, p) in shapes.iter().zip(&origin) {
        s.validate()
            .map_err(|e| Error::parse(p, 0, e.to_string()))?;
    }
    let n0 = shapes[0].points.len();
    let same = shapes.iter().all(|s| s.points.len() == n0);
    let closed = shapes[0].is_closed();
    if shapes.iter().any(|s| s.is_closed() != closed) {
        return Err(Error::Population(
            "some outlines are open and others closed".into(),
        ));
    }
    match opts.resample {
        Some(n) if same => Ok(resample_corresponding(&shapes, n, closed)?.0),
        Some(n) => shapes
            .iter()
            .map(|s| resample_uniform(s, n, closed))
            .collect(),
        None if same => Ok(shapes),
        None => {
            let (k, s) = shapes
                .iter()
                .enumerate()
                .find(|(_, s)| s.points.len() != n0)
                .ok_or_else(|| Error::Population("counts differ".into()))?;
            Err(Error::Population(format!(
                "{}: shape {} has {} points but {}: shape {} has {n0}; shapes without correspondence need --resample N",
                origin[k].display(),
                s.name,
                s.points.len(),
                origin[0].display(),
                shapes[0].name
            )))
        }
    }
}

/// Whether the inputs are 3D surfaces (all of them, `true`) or 2D outlines (none, `false`).
///
/// # Errors
/// [`Error::Population`] when surfaces and outlines are mixed.
pub fn inputs_are_surfaces(paths: &[PathBuf]) -> Result<bool> {
    let n = paths.iter().filter(|p| is_surface_file(p)).count();
    if n > 0 && n < paths.len() {
        let odd = paths
            .iter()
            .find(|p| !is_surface_file(p))
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        return Err(Error::Population(format!(
            "2D and 3D shapes mixed: {odd} is an outline, other inputs are surfaces (.ply/.stl/.obj)"
        )));
    }
    Ok(n > 0)
}

/// The template volume meshes of `paths` (3D), read in order.
pub fn read_template_meshes(paths: &[PathBuf]) -> Result<Vec<crate::mesh::FeMesh<3>>> {
    paths
        .iter()
        .map(|p| crate::formats::read_fe_mesh::<3>(p))
        .collect()
}

/// The shapes in correspondence: with `register`, every shape registered to a template
/// (by name, or the one nearest to the others) with `params`
/// ([`register_population`]); else the shapes as given. Returns them and the template's
/// index (`None` without registration).
pub fn correspond<const D: usize>(
    shapes: &[Shape<D>],
    register: Option<(&crate::register::RegisterParams, Option<&str>)>,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<(Vec<Shape<D>>, Option<usize>)> {
    match register {
        None => Ok((shapes.to_vec(), None)),
        Some((params, template)) => {
            let (c, t) = register_population(shapes, template, params, jobs, progress)?;
            Ok((c, Some(t)))
        }
    }
}

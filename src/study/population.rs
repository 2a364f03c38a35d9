//! Loading a population: outlines and surfaces, landmarks, registration to a template.

use super::Progress;
use crate::error::{Error, Result};
use crate::formats::CsvColumns;
use crate::geometry::{ClosestPointIndex, Point, Shape};
use crate::register::RegistrationResiduals;
use crate::register::{resample_corresponding, resample_uniform};
use crate::report::InputReport;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// How to read a population of outlines.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PopulationOptions {
    /// Outlines are closed (CSV and text inputs; VTK files carry their own topology).
    pub closed: bool,
    /// Resample every outline to this many points.
    pub resample: Option<usize>,
    /// The columns of CSV inputs, where their names are not the usual ones.
    pub columns: crate::formats::CsvColumns,
}

/// Reads outlines that need not correspond (any point counts), each resampled evenly by arc
/// length to `resample` points when given.
pub fn load_outlines_raw(paths: &[PathBuf], opts: &PopulationOptions) -> Result<Vec<Shape<2>>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    let mut shapes = Vec::new();
    for p in paths {
        for s in crate::formats::read_outlines_with(p, opts.closed, &opts.columns)? {
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

/// How [`attach_landmarks`] paired the landmarks of a population.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LandmarkPairing {
    /// The ids of the landmarks given to every shape, in their order ([`by_id`]).
    ///
    /// [`by_id`]: crate::formats::landmarks::by_id
    pub ids: Vec<String>,
    /// `(shape, warning)`: a shape's ids that are not in every shape, and not used.
    pub warnings: Vec<(String, String)>,
}

/// Gives every shape its landmarks from `files`: one CSV for the whole population (rows by
/// shape name), or one Scalismo JSON / `.pts` file per shape, in the shapes' order.
/// Landmarks are paired between shapes by id, not by their order in the files: the ids that
/// every shape has are used (in id order); an id missing from some shape (a typo in one
/// file, say) is not used, with a warning naming the shapes that have it.
///
/// # Errors
/// A file that cannot be read or parsed (an id given twice among them); no id common to
/// every shape while some have landmarks; a landmark out of range or far from its shape; two
/// landmarks on one point.
pub fn attach_landmarks<const D: usize>(
    shapes: &mut [Shape<D>],
    files: &[PathBuf],
) -> Result<LandmarkPairing> {
    use crate::formats::landmarks::{read_landmarks, read_landmarks_csv};
    if files.is_empty() {
        return Ok(LandmarkPairing::default());
    }
    let csv = files.len() == 1
        && files[0]
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let mut lists = Vec::with_capacity(shapes.len());
    if csv {
        let mut map = read_landmarks_csv::<D>(&files[0])?;
        if let Some(name) = map.keys().find(|k| !shapes.iter().any(|s| &s.name == *k)) {
            return Err(Error::parse(
                &files[0],
                0,
                format!("landmarks for shape '{name}', which is not in the population"),
            ));
        }
        for s in shapes.iter() {
            let l = map.remove(&s.name).ok_or_else(|| {
                Error::parse(&files[0], 0, format!("no landmarks for shape '{}'", s.name))
            })?;
            lists.push((l, files[0].clone()));
        }
    } else {
        if files.len() != shapes.len() {
            return Err(Error::Population(format!(
                "{} landmark files for {} shapes; give one per shape, in the same order, or one CSV",
                files.len(),
                shapes.len()
            )));
        }
        for f in files {
            lists.push((read_landmarks::<D>(f)?, f.clone()));
        }
    }
    pair_by_id(shapes, lists)
}

/// Attaches the landmarks of each shape's list (`(landmarks, file)`, in id order) that every
/// list has: see [`attach_landmarks`].
fn pair_by_id<const D: usize>(
    shapes: &mut [Shape<D>],
    lists: Vec<(Vec<crate::formats::landmarks::NamedLandmark<D>>, PathBuf)>,
) -> Result<LandmarkPairing> {
    use crate::formats::landmarks::attach;
    let has =
        |l: &[crate::formats::landmarks::NamedLandmark<D>], id: &str| l.iter().any(|x| x.0 == id);
    let ids: Vec<String> = lists[0]
        .0
        .iter()
        .map(|x| x.0.clone())
        .filter(|id| lists.iter().all(|(l, _)| has(l, id)))
        .collect();
    if ids.is_empty() && lists.iter().any(|(l, _)| !l.is_empty()) {
        let (k, (l, f)) = (lists.iter().enumerate())
            .find(|(_, (l, _))| !l.is_empty())
            .unwrap_or((0, &lists[0]));
        let other = if k == 0 { 1.min(lists.len() - 1) } else { 0 };
        return Err(Error::parse(
            f,
            0,
            format!(
                "no landmark id is in every shape ('{}' has [{}], '{}' has [{}]); landmarks are paired by id",
                shapes[k].name,
                id_list(l.iter().map(|x| &x.0)),
                shapes[other].name,
                id_list(lists[other].0.iter().map(|x| &x.0)),
            ),
        ));
    }
    let mut warnings = Vec::new();
    for ((l, f), s) in lists.into_iter().zip(shapes.iter_mut()) {
        let (kept, dropped): (Vec<_>, Vec<_>) = l.into_iter().partition(|x| ids.contains(&x.0));
        if !dropped.is_empty() {
            warnings.push((
                s.name.clone(),
                format!(
                    "landmark(s) [{}] of {} are not in every shape and are not used (landmarks are paired by id)",
                    id_list(dropped.iter().map(|x| &x.0)),
                    f.display()
                ),
            ));
        }
        attach(s, &kept, &f)?;
    }
    Ok(LandmarkPairing { ids, warnings })
}

/// Gives `shape` (a registration template outside the population) the landmarks of `file`
/// whose ids are `ids` (a population's [`LandmarkPairing::ids`]), in that order.
///
/// # Errors
/// The file's errors; an id of `ids` the file lacks.
pub fn attach_landmarks_paired<const D: usize>(
    shape: &mut Shape<D>,
    file: &Path,
    ids: &[String],
) -> Result<Vec<String>> {
    let mut l = crate::formats::landmarks::read_landmarks::<D>(file)?;
    if let Some(id) = ids.iter().find(|id| !l.iter().any(|x| &x.0 == *id)) {
        return Err(Error::parse(
            file,
            0,
            format!("the template has no landmark '{id}', which every shape of the population has"),
        ));
    }
    let unused: Vec<String> = l
        .iter()
        .filter(|x| !ids.contains(&x.0))
        .map(|x| x.0.clone())
        .collect();
    l.retain(|x| ids.contains(&x.0));
    crate::formats::landmarks::attach(shape, &l, file)?;
    Ok(unused)
}

/// The first ids of a list, for messages.
fn id_list<'a>(ids: impl Iterator<Item = &'a String>) -> String {
    let v: Vec<&String> = ids.collect();
    let mut s = v
        .iter()
        .take(8)
        .map(|x| x.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    if v.len() > 8 {
        s.push_str(", ...");
    }
    s
}

/// A floating component under this share of a surface's area (an outline's length) is
/// dropped, with a warning in the report.
pub const ISLAND_SHARE: f64 = 0.01;

/// Records each shape's registration residuals in its input report, with a warning where
/// the registered template did not reach it (95th percentile beyond
/// [`crate::register::REGISTRATION_WARNING_P95`] of its diagonal). Returns the warnings
/// added, `(shape, warning)`.
pub fn record_registration(
    inputs: &mut [InputReport],
    residuals: &[Option<RegistrationResiduals>],
) -> Vec<(String, String)> {
    let mut added = Vec::new();
    for (i, res) in inputs.iter_mut().zip(residuals) {
        i.registration = *res;
        if let Some(x) = res
            && x.p95_relative > crate::register::REGISTRATION_WARNING_P95
        {
            let w = format!(
                "the registered template is up to {:.3} (95th percentile, {:.1} % of the \
                 diagonal; two-way RMS {:.3}) from it: check its registration",
                x.p95,
                100.0 * x.p95_relative,
                x.rms
            );
            i.warnings.push(w.clone());
            added.push((i.name.clone(), w));
        }
    }
    added
}

/// A population's shapes cleaned as every front end cleans them ([`clean_shapes`] with
/// [`ISLAND_SHARE`]), the landmark pairing's warnings added to their shapes'; with
/// `refuse_islands`, a shape with a floating component is an error instead.
///
/// # Errors
/// [`Error::InvalidShape`] naming the first shape with islands, with `refuse_islands`.
pub fn clean_population<const D: usize>(
    shapes: &mut [Shape<D>],
    pairing: &LandmarkPairing,
    refuse_islands: bool,
) -> Result<Vec<InputReport>> {
    let mut inputs = clean_shapes(shapes, ISLAND_SHARE);
    for (name, w) in &pairing.warnings {
        if let Some(i) = inputs.iter_mut().find(|i| &i.name == name) {
            i.warnings.push(w.clone());
        }
    }
    if let Some(i) = inputs
        .iter()
        .find(|i| refuse_islands && i.dropped_components > 0)
    {
        return Err(Error::shape(
            &i.name,
            format!(
                "has {} floating component(s) under {:.0} % of its area (--refuse-islands)",
                i.dropped_components,
                100.0 * ISLAND_SHARE
            ),
        ));
    }
    Ok(inputs)
}

/// Drops from every shape the floating components under `min_share` of its area (length),
/// and describes each shape's topology (components, genus) and what was dropped; a point set
/// without facets is left as it is (0 components).
pub fn clean_shapes<const D: usize>(shapes: &mut [Shape<D>], min_share: f64) -> Vec<InputReport> {
    shapes
        .iter_mut()
        .map(|s| {
            if s.facets.is_empty() {
                // A point set (`build --no-mesh`): no topology to clean.
                return InputReport {
                    name: s.name.clone(),
                    vertices: s.points.len(),
                    components: 0,
                    genus: None,
                    dropped_components: 0,
                    dropped_share: 0.0,
                    registration: None,
                    cut: None,
                    warnings: Vec::new(),
                };
            }
            let parts = crate::geometry::components(s);
            let (clean, dropped) = crate::geometry::drop_small_components(s, min_share);
            let dropped_share: f64 = dropped.iter().map(|d| d.1).sum();
            let mut warnings = Vec::new();
            if !dropped.is_empty() {
                warnings.push(format!(
                    "{} floating component(s) of {} vertices ({:.2} % of the {}) dropped",
                    dropped.len(),
                    dropped.iter().map(|d| d.0).sum::<usize>(),
                    100.0 * dropped_share,
                    if D == 2 { "length" } else { "area" }
                ));
            }
            if parts.len() - dropped.len() > 1 {
                warnings.push(format!(
                    "{} components remain (each above {:.1} % of the {})",
                    parts.len() - dropped.len(),
                    100.0 * min_share,
                    if D == 2 { "length" } else { "area" }
                ));
            }
            *s = clean;
            InputReport {
                name: s.name.clone(),
                vertices: s.points.len(),
                components: parts.len(),
                genus: parts.first().and_then(|c| c.genus),
                dropped_components: dropped.len(),
                dropped_share,
                registration: None,
                cut: None,
                warnings,
            }
        })
        .collect()
}

/// The template of a registration of a population.
#[derive(Clone, Copy, Debug)]
pub enum Template<'a, const D: usize> {
    /// The member nearest to the others, among those of one component and the population's
    /// most common genus.
    Nearest,
    /// The member of that name.
    Member(&'a str),
    /// A shape outside the population (a reference surface), used only as the template.
    External(&'a Shape<D>),
}

/// A population brought into correspondence by registration.
#[derive(Clone, Debug)]
pub struct Registered<const D: usize> {
    /// The shapes resampled at the template's points (same order; a member template as it
    /// is).
    pub shapes: Vec<Shape<D>>,
    /// The template's name.
    pub template: String,
    /// The template's index in the population (`None` for an external template).
    pub template_index: Option<usize>,
    /// The residuals of every registration (`None` for the member template).
    pub residuals: Vec<Option<RegistrationResiduals>>,
}

/// Brings shapes that are not in correspondence into correspondence (section 2.1): the
/// template (see [`Template`]) is registered to every other shape
/// ([`crate::register::register`]) and each is resampled at the template's points; with the
/// residuals of every registration, both ways. `jobs` threads (0 = all cores).
pub fn register_population<const D: usize>(
    shapes: &[Shape<D>],
    template: Template<'_, D>,
    params: &crate::register::RegisterParams,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Registered<D>> {
    super::build::refuse_point_sets(shapes, "a registration")?;
    if shapes.len() < 2 {
        return Err(Error::Population(format!(
            "registration needs at least 2 shapes, got {}",
            shapes.len()
        )));
    }
    let member = match template {
        Template::Member(name) => {
            Some(shapes.iter().position(|s| s.name == name).ok_or_else(|| {
                Error::Population(format!(
                    "--template {name}: no shape of that name, and no such file"
                ))
            })?)
        }
        Template::Nearest => Some(nearest_to_others(shapes, params)?),
        Template::External(t) => {
            t.validate()?;
            if shapes
                .iter()
                .any(|s| s.landmarks.len() != t.landmarks.len())
            {
                return Err(Error::Population(format!(
                    "the template {} has {} landmarks but the shapes have {}: give the \
                     template's landmarks (--template-landmarks)",
                    t.name,
                    t.landmarks.len(),
                    shapes[0].landmarks.len()
                )));
            }
            None
        }
    };
    let t: &Shape<D> = match (template, member) {
        (Template::External(t), _) => t,
        (_, Some(i)) => &shapes[i],
        _ => unreachable!("a member template has an index"),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::Parameter(format!("--jobs: {e}")))?;
    let label = "registration";
    progress.items_started(label, shapes.len());
    let out: Vec<Result<(Shape<D>, Option<RegistrationResiduals>)>> = pool.install(|| {
        shapes
            .par_iter()
            .enumerate()
            .map(|(k, s)| {
                let r = if Some(k) == member {
                    Ok((s.clone(), None))
                } else {
                    let index = ClosestPointIndex::from_shape(s);
                    crate::register::register(t, s, &index, params)
                        .map(|r| (r.resampled(t, s), Some(r.residuals(t, s, &index))))
                };
                progress.item_done(label, &s.name);
                r
            })
            .collect()
    });
    progress.items_finished(label);
    let (shapes_out, residuals) = out
        .into_iter()
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    Ok(Registered {
        shapes: shapes_out,
        template: t.name.clone(),
        template_index: member,
        residuals,
    })
}

/// The shape nearest to the others: every shape pre-aligned to the first, then the one of
/// least mean two-way distance to the rest (on up to 200 points of each), among the shapes
/// of one component and the population's most common genus (a surface with islands or odd
/// topology is never the template unless all are).
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
    let clean = clean_candidates(shapes);
    Ok((0..n)
        .filter(|&i| clean[i])
        .min_by(|&a, &b| score[a].total_cmp(&score[b]))
        .unwrap_or(0))
}

/// Which shapes may be the automatic template: one component and the most common genus; all
/// when none qualifies.
fn clean_candidates<const D: usize>(shapes: &[Shape<D>]) -> Vec<bool> {
    let parts: Vec<Vec<crate::geometry::Component>> =
        shapes.par_iter().map(crate::geometry::components).collect();
    let mut genus_count: std::collections::HashMap<Option<usize>, usize> = Default::default();
    for p in &parts {
        *genus_count
            .entry(p.first().and_then(|c| c.genus))
            .or_default() += 1;
    }
    let common = genus_count
        .iter()
        .max_by_key(|(g, c)| (**c, std::cmp::Reverse(**g)))
        .and_then(|(g, _)| *g);
    let ok: Vec<bool> = parts
        .iter()
        .map(|p| p.len() == 1 && p[0].genus == common)
        .collect();
    if ok.iter().any(|&b| b) {
        ok
    } else {
        vec![true; shapes.len()]
    }
}

/// Reads the 3D point sets in `paths` ([`crate::formats::read_point_set`]: files with or
/// without faces; CSV files by [`crate::formats::read_point_sets_csv`], a long table of
/// several shapes or one shape of `x,y,z` rows), in the order given.
pub fn load_point_sets(paths: &[PathBuf], columns: &CsvColumns) -> Result<Vec<Shape<3>>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    let per_file: Vec<Vec<Shape<3>>> = paths
        .par_iter()
        .map(|p| {
            if is_csv(p) {
                crate::formats::read_point_sets_csv(p, columns)
            } else {
                crate::formats::read_point_set(p).map(|s| vec![s])
            }
        })
        .collect::<Result<_>>()?;
    Ok(per_file.into_iter().flatten().collect())
}

/// Whether `path` is named as a CSV file.
fn is_csv(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
}

/// Reads the triangle surfaces in `paths` (PLY, STL, OBJ, VTP, VTK, or a label map's label
/// by `labels`), in the order given. Shapes in correspondence must share their vertex count
/// and facets (checked when the atlas is built).
pub fn load_surfaces(paths: &[PathBuf], labels: &super::LabelReading) -> Result<Vec<Shape<3>>> {
    Ok(load_surfaces_noted(paths, labels)?
        .into_iter()
        .map(|(s, _)| s)
        .collect())
}

/// [`load_surfaces`] with what a user should know about each (a label map's islands dropped,
/// cavities filled, cut by the image's border).
pub fn load_surfaces_noted(
    paths: &[PathBuf],
    labels: &super::LabelReading,
) -> Result<Vec<(Shape<3>, Vec<String>)>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    paths
        .par_iter()
        .map(|p| {
            if crate::formats::is_image_file(p) {
                let s = super::read_label_surface(p, labels)?;
                Ok((s.shape, s.warnings))
            } else {
                Ok((read_surface_file(p)?, Vec::new()))
            }
        })
        .collect()
}

/// The triangle surface in `path` ([`crate::formats::read_surface`]); a CSV of 3D points is
/// refused with what it can make instead.
pub(crate) fn read_surface_file(path: &Path) -> Result<Shape<3>> {
    if is_csv(path) {
        return Err(Error::parse(
            path,
            0,
            "3D points without facets: they make a shape model alone (build --no-mesh); a mesh, a registration or a fit needs surfaces (PLY, STL, OBJ, VTP, VTK)",
        ));
    }
    crate::formats::read_surface(path)
}

/// Whether `path` names a 3D surface file: by its extension (`.ply`, `.stl`, `.obj`), and
/// for VTK files (`.vtk`, `.vtp`) by what they hold once parsed (polygons make a surface,
/// lines an outline).
///
/// # Errors
/// A VTK file that does not parse, or holds neither polygons nor lines.
pub fn is_surface_file(path: &Path) -> Result<bool> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if crate::formats::is_image_file(path) {
        return Ok(true);
    }
    match ext.as_str() {
        "ply" | "stl" | "obj" => Ok(true),
        "csv" => crate::formats::csv_holds_3d_points(path),
        "vtk" | "vtp" => match crate::formats::read_polydata(path)? {
            Some(v) => polydata_is_surface(path, &v),
            None => Ok(false),
        },
        _ => Ok(false),
    }
}

/// Whether VTK polydata read from `path` is a surface (polygons, or points alone: a 3D point
/// set for `build --no-mesh`) rather than an outline (lines).
///
/// # Errors
/// Polydata with neither polygons nor lines nor points.
pub(crate) fn polydata_is_surface(path: &Path, v: &crate::formats::VtkPolyData) -> Result<bool> {
    if v.polygons.is_empty() && v.lines.is_empty() && v.points.is_empty() {
        return Err(Error::parse(
            path,
            0,
            "neither polygons (a surface) nor lines (an outline) nor points",
        ));
    }
    Ok(v.lines.is_empty())
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
        let s = crate::formats::read_outlines_with(p, opts.closed, &opts.columns)?;
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
    let surface = paths
        .iter()
        .map(|p| is_surface_file(p))
        .collect::<Result<Vec<bool>>>()?;
    let n = surface.iter().filter(|&&s| s).count();
    if n > 0 && n < paths.len() {
        let odd = paths
            .iter()
            .zip(&surface)
            .find(|(_, s)| !**s)
            .map(|(p, _)| p.display().to_string())
            .unwrap_or_default();
        return Err(Error::Population(format!(
            "2D and 3D shapes mixed: {odd} is a 2D outline, other inputs are 3D (surfaces or x,y,z points)"
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
/// ([`register_population`]); else the shapes as given (no template, no residuals).
pub fn correspond<const D: usize>(
    shapes: &[Shape<D>],
    register: Option<(&crate::register::RegisterParams, Template<'_, D>)>,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Option<Registered<D>>> {
    match register {
        None => Ok(None),
        Some((params, template)) => {
            register_population(shapes, template, params, jobs, progress).map(Some)
        }
    }
}

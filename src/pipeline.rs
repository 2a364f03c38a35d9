//! The stages strung together for the command-line tool: loading a population, building an
//! atlas, fitting and meshing subjects, the leave-one-out experiment (section 6.1), and the
//! built-in demo.

use crate::error::{Error, Result};
use crate::eval::{e_d, normal_correlation, normals_at, two_way_rms};
use crate::export::{write_mesh, write_vtp, write_vtu};
use crate::fe::FeMesh;
use crate::fe::quality::{mesh_quality, summarize};
use crate::ffd::FfdParams;
use crate::fit::{FitParams, Fitter};
use crate::geometry::{ClosestPointIndex, Point, Shape, Similarity};
use crate::model::{Atlas, AtlasParams, same_dim};
use crate::morph::Morpher;
use crate::report::{
    JACOBIAN_BINS, MeanMeshReport, Report, SubjectReport, Summary, jacobian_histogram,
    plot_cumulative_variance, plot_e_d, plot_jacobian_histogram, plot_subject,
};
use crate::resample::{resample_corresponding, resample_uniform};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to read a population of outlines.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct PopulationOptions {
    /// Outlines are closed (CSV and text inputs; VTK files carry their own topology).
    pub closed: bool,
    /// Resample every outline to this many points.
    pub resample: Option<usize>,
}

/// All parameters of a run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunParams {
    pub atlas: AtlasParams,
    pub fit: FitParams,
    pub morph: FfdParams,
    /// Write PNG plots.
    pub plots: bool,
    /// Also measure the paper's baselines (fig. 12/20): the normal correlation of the
    /// correspondence by a similarity ICP and by an FFD registration of the mean to the
    /// subject.
    pub baselines: bool,
    /// Formats of every subject's FE mesh (`NAME_mesh.EXT`).
    pub formats: Vec<crate::export::MeshFormat>,
    /// Sets defined on the mean mesh (added to those the atlas carries).
    #[serde(skip)]
    pub sets: Option<crate::fe::sets::SetsConfig>,
    /// A whole Abaqus/CalculiX deck around the atlas's mean mesh: every subject gets a copy
    /// with its node coordinates (`NAME_deck.inp`).
    #[serde(skip)]
    pub deck: Option<std::sync::Arc<crate::io::femesh::InpDeck>>,
    /// Repair of every morphed mesh (untangling and quality; `None`: off).
    pub repair: Option<crate::repair::RepairParams>,
    /// A fit whose two-way RMS distance to its subject (eq. 6 both ways) exceeds this share
    /// of the subject's bounding-box diagonal did not converge: the subject is refused
    /// ([`Error::NotConverged`]) and no mesh is written for it. A good fit is below 0.01. With
    /// `fit.partial` the distance is the subject's to the instance only.
    #[serde(default = "default_max_misfit")]
    pub max_misfit: f64,
}

fn default_max_misfit() -> f64 {
    0.05
}

impl Default for RunParams {
    fn default() -> Self {
        RunParams {
            baselines: false,
            formats: vec![crate::export::MeshFormat::Vtu],
            sets: None,
            deck: None,
            repair: Some(crate::repair::RepairParams::default()),
            max_misfit: default_max_misfit(),
            atlas: AtlasParams::default(),
            fit: FitParams::default(),
            morph: FfdParams::default(),
            plots: true,
        }
    }
}

/// Reads outlines that need not correspond (any point counts), each resampled evenly by arc
/// length to `resample` points when given.
pub fn load_outlines_raw(paths: &[PathBuf], opts: &PopulationOptions) -> Result<Vec<Shape<2>>> {
    if paths.is_empty() {
        return Err(Error::Population("no input file given".into()));
    }
    let mut shapes = Vec::new();
    for p in paths {
        for s in crate::io::read_outlines(p, opts.closed)? {
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
    use crate::io::landmarks::{attach, read_landmarks, read_landmarks_csv};
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
    quiet: bool,
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
    let progress = Progress::new("registration", shapes.len(), quiet);
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
                progress.tick(&s.name);
                r
            })
            .collect()
    });
    progress.finish();
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
        .map(|p| crate::io::surface::read_surface(p))
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
        Some("vtk") => crate::io::read_vtk_polydata(path).is_ok_and(|v| !v.polygons.is_empty()),
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
        let s = crate::io::read_outlines(p, opts.closed)?;
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

pub(crate) fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Fits `subject` with the atlas, morphs the mean mesh, measures, and writes the subject's
/// mesh (VTU), its fitted outline (VTP) and its plot into `out`.
pub fn process_subject<const D: usize>(
    atlas: &Atlas<D>,
    fitter: &Fitter<D>,
    morpher: &Morpher<D>,
    subject: &Shape<D>,
    out: &Path,
    params: &RunParams,
) -> Result<SubjectReport> {
    let index = ClosestPointIndex::from_shape(subject);
    let t0 = Instant::now();
    let fit = fitter.fit(subject, &index, &params.fit)?;
    let fit_seconds = t0.elapsed().as_secs_f64();
    let rms = two_way_rms(&fit.instance, &atlas.facets, subject, &index);
    let rel = rms / subject.bbox_diagonal();
    // A partial subject (`--partial`) misses parts of the model: only its own points' distance
    // to the instance can tell whether the fit converged.
    let misfit = if params.fit.partial {
        let on_instance = ClosestPointIndex::new(&fit.instance, &atlas.facets);
        let ms = subject
            .points
            .iter()
            .map(|p| on_instance.closest(p).dist2)
            .sum::<f64>()
            / subject.points.len().max(1) as f64;
        ms.sqrt() / subject.bbox_diagonal()
    } else {
        rel
    };
    if misfit.is_nan() || misfit > params.max_misfit {
        return Err(Error::NotConverged {
            name: subject.name.clone(),
            message: format!(
                "the fitted model instance stays {:.4} (RMS distance; {:.1} % of the subject's \
                 bounding-box diagonal) from the subject, above the bound of {:.1} % \
                 (--max-misfit): the subject lies outside what the model can represent",
                misfit * subject.bbox_diagonal(),
                100.0 * misfit,
                100.0 * params.max_misfit
            ),
        });
    }
    let morph = morpher.morph(&fit)?;
    let mut mesh = morph.mesh;
    let mut per_element = morph.quality;
    let unrepaired = summarize(&per_element);
    let mut repair = None;
    if let Some(rp) = &params.repair {
        let (r, q) = crate::repair::repair_with_quality(&mut mesh, Some(&index), rp, &per_element)?;
        per_element = q;
        repair = Some(r);
    }
    let surface_distance_change = repair.map_or(0.0, |r| r.surface_distance_change);
    let q = summarize(&per_element);
    let dist = crate::fe::quality::distribution(&mesh, &per_element);
    let mean_normals = atlas.mean_shape().vertex_normals();
    let nc = normal_correlation(&mean_normals, &normals_at(subject, &fit.projected));
    let baselines = if params.baselines {
        Some(baseline_correlations(
            atlas,
            subject,
            &index,
            &mean_normals,
        )?)
    } else {
        None
    };
    let base = file_name(&subject.name);
    let mut files = Vec::new();
    let mean_in_subject = atlas.mesh.with_nodes(
        atlas
            .mesh
            .nodes
            .iter()
            .map(|p| fit.similarity.apply(p))
            .collect(),
    );
    for f in &params.formats {
        let mesh_file = format!("{base}_mesh.{}", f.extension());
        write_mesh(
            &out.join(&mesh_file),
            &mesh,
            Some(&mean_in_subject),
            &per_element,
        )?;
        files.push(mesh_file);
    }
    if let Some(deck) = &params.deck {
        let deck_file = format!("{base}_deck.inp");
        crate::io::write_atomic(
            &out.join(&deck_file),
            deck.with_nodes(&mesh.nodes)?.as_bytes(),
        )?;
        files.push(deck_file);
    }
    let fitted = Shape {
        name: subject.name.clone(),
        points: fit.projected.iter().map(|p| p.point).collect(),
        facets: atlas.facets.clone(),
        landmarks: atlas.landmarks.clone(),
    };
    let outline_file = format!("{base}_fit.vtp");
    write_vtp(&out.join(&outline_file), &fitted)?;
    files.push(outline_file);
    if params.plots && D == 3 {
        // Figs. 23 and 27: the fitted surface coloured by its distance to the subject, and the
        // morphed mesh's surface coloured by scaled Jacobian, seen alike.
        use crate::report::render;
        let to3 = |v: &[Point<D>]| -> Vec<Point<3>> { v.iter().map(same_dim::<D, 3>).collect() };
        let instance = to3(&fit.instance);
        let distance: Vec<f64> = fit
            .instance
            .iter()
            .map(|p| index.closest(p).dist2.sqrt())
            .collect();
        let tris: Vec<[usize; 3]> = atlas
            .facets
            .iter()
            .map(|f| std::array::from_fn(|k| f[k.min(D - 1)]))
            .collect();
        let view = render::View::fitting(&to3(&subject.points));
        let far = 0.01 * subject.bbox_diagonal();
        let by_distance = render::distance_color(far);
        let mesh3 = FeMesh {
            nodes: to3(&mesh.nodes),
            kind: mesh.kind,
            connectivity: mesh.connectivity.clone(),
            sets: Default::default(),
        };
        let sj: Vec<f64> = per_element.iter().map(|e| e.scaled_jacobian_min).collect();
        let (btris, bvals) = render::boundary_triangles(&mesh3, &sj);
        type Picture<'a> = (
            &'a str,
            &'a [Point<3>],
            &'a [[usize; 3]],
            Option<&'a [f64]>,
            Option<&'a [f64]>,
            render::Legend<'a>,
        );
        let pictures: [Picture; 2] = [
            (
                "distance",
                &instance,
                &tris,
                Some(&distance),
                None,
                render::Legend {
                    color: &by_distance,
                    lo: 0.0,
                    hi: far,
                    lo_label: "0".into(),
                    hi_label: format!("{far:.3} (1 % diag.)"),
                },
            ),
            (
                "quality",
                &mesh3.nodes,
                &btris,
                None,
                Some(&bvals),
                render::Legend {
                    color: &render::jacobian_color,
                    lo: 0.0,
                    hi: 1.0,
                    lo_label: "≤ 0".into(),
                    hi_label: "1".into(),
                },
            ),
        ];
        for (what, points, facets, vertex, face, legend) in pictures {
            let img = render::render(points, facets, vertex, face, legend.color, &view, 480, 360);
            let title = match what {
                "distance" => format!("{}: fit, distance to the subject", subject.name),
                _ => format!("{}: morphed mesh, scaled Jacobian", subject.name),
            };
            let img = render::annotated(&img, &title, Some(&legend));
            let name = format!("{base}_{what}.png");
            crate::io::write_atomic(&out.join(&name), &img.png()?)?;
            files.push(name);
        }
    }
    if params.plots && D == 2 {
        let png = format!("{base}.png");
        let to2 = |v: &[Point<D>]| -> Vec<Point<2>> { v.iter().map(same_dim::<D, 2>).collect() };
        let mean_pts: Vec<Point<2>> = atlas
            .mean
            .iter()
            .map(|p| same_dim::<D, 2>(&fit.similarity.apply(p)))
            .collect();
        let closed = subject.facets.len() == subject.points.len();
        let locus: Vec<Vec<Point<2>>> = fit.locus.iter().map(|l| to2(l)).collect();
        let mesh2 = FeMesh {
            nodes: to2(&mesh.nodes),
            kind: mesh.kind,
            connectivity: mesh.connectivity.clone(),
            sets: Default::default(),
        };
        plot_subject(
            &out.join(&png),
            &subject.name,
            &mean_pts,
            &to2(&subject.points),
            &locus,
            &mesh2,
            closed,
        )?;
        files.push(png);
    }
    Ok(SubjectReport {
        name: subject.name.clone(),
        iterations: fit.iterations,
        fit_seconds,
        e_d: e_d(&fit.instance, &index),
        rms_distance: rms,
        rms_distance_relative: rel,
        normal_correlation: nc,
        normal_correlation_icp: baselines.map(|b| b.0),
        normal_correlation_ffd: baselines.map(|b| b.1),
        jacobian_min: q.jacobian_min,
        scaled_jacobian_min: q.scaled_jacobian_min,
        inverted_elements: q.inverted_elements,
        inverted_before_repair: unrepaired.inverted_elements,
        scaled_jacobian_min_before_repair: unrepaired.scaled_jacobian_min,
        surface_distance_change,
        surface_distance_change_edges: repair.map_or(0.0, |r| {
            r.surface_distance_change / r.median_edge.max(f64::MIN_POSITIVE)
        }),
        repair_bound: repair.map_or(0.0, |r| r.bound),
        repaired: repair.is_some_and(|r| r.below_bound_before > 0),
        morph_alpha: morph.alpha,
        scaled_jacobian_histogram: jacobian_histogram(
            per_element.iter().map(|e| e.scaled_jacobian_min),
        ),
        scaled_jacobian_p01: dist.scaled_jacobian_p01,
        scaled_jacobian_p05: dist.scaled_jacobian_p05,
        edge_ratio_max: dist.edge_ratio_max,
        elements_below_bound: dist.elements_below_bound,
        success: rel < 0.01 && q.inverted_elements == 0,
        converged: fit.converged,
        e_d_history: fit.e_d_history,
        files,
    })
}

/// The baselines of the paper's fig. 12/20 for one subject: the normal correlation (eq. 13)
/// between the mean and the subject at the correspondence found (a) by a similarity ICP of
/// the mean to the subject (the closest points of the aligned mean) and (b) by the FFD
/// registration of the mean to the subject (eq. 2, with landmarks when both have them).
pub fn baseline_correlations<const D: usize>(
    atlas: &Atlas<D>,
    subject: &Shape<D>,
    index: &ClosestPointIndex<D>,
    mean_normals: &[Point<D>],
) -> Result<(f64, f64)> {
    let params = crate::register::RegisterParams::for_dimension(D);
    let mut mean = atlas.mean_shape();
    if mean.landmarks.len() != subject.landmarks.len() {
        mean.landmarks.clear();
    }
    // The ICP baseline uses no landmarks (with them pre_align would pair the landmarks).
    let unmarked = Shape {
        landmarks: Vec::new(),
        ..mean.clone()
    };
    let sim = crate::register::pre_align(&unmarked, subject, index, params.starts)?;
    let icp: Vec<_> = mean
        .points
        .iter()
        .map(|p| index.closest(&sim.apply(p)))
        .collect();
    let nc_icp = normal_correlation(mean_normals, &normals_at(subject, &icp));
    let reg = crate::register::register(&mean, subject, index, &params)?;
    let nc_ffd = normal_correlation(mean_normals, &normals_at(subject, &reg.correspondence));
    Ok((nc_icp, nc_ffd))
}

pub(crate) fn mean_mesh_report<const D: usize>(atlas: &Atlas<D>) -> MeanMeshReport {
    let q = summarize(&mesh_quality(&atlas.mesh));
    MeanMeshReport {
        nodes: atlas.mesh.nodes.len(),
        elements: atlas.mesh.num_elements(),
        element_kind: atlas.mesh.kind.name().into(),
        scaled_jacobian_min: q.scaled_jacobian_min,
        jacobian_min: q.jacobian_min,
        edge_ratio_max: crate::fe::quality::edge_ratio_max(&atlas.mesh),
    }
}

fn create_dir(out: &Path) -> Result<()> {
    crate::io::create_dir(out)
}

/// A progress bar on a terminal, plain log lines otherwise.
pub struct Progress {
    bar: indicatif::ProgressBar,
    tty: bool,
    label: String,
    total: u64,
    done: std::sync::atomic::AtomicU64,
}

impl Progress {
    pub fn new(label: &str, total: usize, quiet: bool) -> Self {
        use std::io::IsTerminal;
        let tty = std::io::stderr().is_terminal() && !quiet;
        let bar = if tty {
            indicatif::ProgressBar::new(total as u64)
        } else {
            indicatif::ProgressBar::hidden()
        };
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{msg} [{bar:30}] {pos}/{len} {per_sec} eta {eta}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(label.to_string());
        Progress {
            bar,
            tty,
            label: if quiet {
                String::new()
            } else {
                label.to_string()
            },
            total: total as u64,
            done: 0.into(),
        }
    }
    pub fn tick(&self, what: &str) {
        let d = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if self.tty {
            self.bar.inc(1);
        } else if !self.label.is_empty() {
            eprintln!("{}: {d}/{} {what}", self.label, self.total);
        }
    }
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// A step of unknown length (building an atlas, meshing the mean, a repair): a spinner with
/// the elapsed time on a terminal, a line at its start and its end otherwise.
pub struct Spinner {
    bar: Option<indicatif::ProgressBar>,
    label: String,
    start: Instant,
}

impl Spinner {
    pub fn new(label: &str, quiet: bool) -> Self {
        use std::io::IsTerminal;
        let bar = if quiet {
            None
        } else if std::io::stderr().is_terminal() {
            let b = indicatif::ProgressBar::new_spinner();
            if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            {
                b.set_style(style);
            }
            b.set_message(label.to_string());
            b.enable_steady_tick(std::time::Duration::from_millis(120));
            Some(b)
        } else {
            eprintln!("{label} ...");
            None
        };
        Spinner {
            bar,
            label: if quiet { String::new() } else { label.into() },
            start: Instant::now(),
        }
    }

    pub fn finish(self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        if !self.label.is_empty() {
            eprintln!(
                "{}: done in {:.1} s",
                self.label,
                self.start.elapsed().as_secs_f64()
            );
        }
    }
}

/// Writes the population-level plots and the report.
pub(crate) fn finish_report<const D: usize>(
    out: &Path,
    dataset: &str,
    atlas_for_variance: &Atlas<D>,
    subjects: Vec<SubjectReport>,
    params: &RunParams,
    mean_mesh: Option<MeanMeshReport>,
    batch: crate::batch::BatchFacts,
) -> Result<Report> {
    let crate::batch::BatchFacts {
        failed,
        shard,
        resumed,
        measures,
    } = batch;
    let m = atlas_for_variance.num_modes();
    if params.plots {
        plot_cumulative_variance(
            &out.join("cumulative_variance.png"),
            &atlas_for_variance.cumulative_variance,
            m,
        )?;
        let hist: Vec<(String, Vec<f64>)> = subjects
            .iter()
            .map(|s| (s.name.clone(), s.e_d_history.clone()))
            .collect();
        plot_e_d(&out.join("e_d.png"), &hist)?;
        let mut counts = vec![0u32; JACOBIAN_BINS];
        for s in &subjects {
            for (c, v) in counts.iter_mut().zip(&s.scaled_jacobian_histogram) {
                *c += v;
            }
        }
        plot_jacobian_histogram(&out.join("scaled_jacobians.png"), &counts)?;
    }
    let report = Report {
        dataset: dataset.to_string(),
        dimension: D,
        modes: m,
        variance_explained: atlas_for_variance.cumulative_variance[..m].to_vec(),
        parameters: serde_json::to_value(params).unwrap_or_default(),
        mean_mesh,
        summary: Summary {
            resumed,
            ..Summary::of(&subjects, failed.len())
        },
        failed,
        shard,
        subjects,
        atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
    };
    report.write(&out.join("report.json"))?;
    if params.plots {
        let mut pictures = crate::report::html::Pictures::default();
        if let Some(m) = &measures {
            crate::report::plot_shape_model_measures(&out.join("measures.png"), m, "")?;
            pictures.measures = Some("measures.png".into());
        }
        if report
            .subjects
            .iter()
            .any(|s| s.normal_correlation_icp.is_some())
        {
            crate::report::plot_baselines(&out.join("baselines.png"), &report.subjects)?;
        }
        if atlas_for_variance.num_modes() > 0 {
            crate::report::plot_modes(&out.join("modes.png"), atlas_for_variance)?;
            pictures.modes = Some("modes.png".into());
        }
        crate::report::html::write(&out.join("report.html"), &report, out, &pictures)?;
    }
    Ok(report)
}

/// The paper's leave-one-out experiment (section 6.1): for every shape, the atlas from the
/// others, a fit of the held-out shape (its known correspondence unused: it is fitted as an
/// outline), the morphed mesh and the measures. Writes `out/report.json`, each subject's VTU,
/// VTP and plot, and the population plots. `jobs` threads (0 = all cores).
pub fn leave_one_out<const D: usize>(
    shapes: &[Shape<D>],
    dataset: &str,
    params: &RunParams,
    out: &Path,
    jobs: usize,
    quiet: bool,
) -> Result<Report> {
    leave_one_out_of(shapes, shapes, None, dataset, params, out, jobs, quiet)
}

/// The atlas of `shapes`: with `meshes` (one template volume mesh per shape, or one for the
/// first) their mean as the FE mesh (`Atlas::build_with_meshes`), else the automatic mesh.
fn atlas_of<const D: usize>(
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
) -> Result<Atlas<D>> {
    let mut atlas = match meshes {
        Some(m) => Atlas::build_with_meshes(shapes, &params.atlas, m)?,
        None => Atlas::build(shapes, &params.atlas)?,
    };
    if let Some(c) = &params.sets {
        apply_sets(&mut atlas, c)?;
    }
    Ok(atlas)
}

/// Adds the sets of `config` (evaluated on the mean mesh, with the atlas's landmarks) to the
/// atlas's mesh; a set of the same name is replaced.
pub fn apply_sets<const D: usize>(
    atlas: &mut Atlas<D>,
    config: &crate::fe::sets::SetsConfig,
) -> Result<()> {
    let landmarks: Vec<Point<D>> = atlas.landmarks.iter().map(|&i| atlas.mean[i]).collect();
    let s = config.evaluate(&atlas.mesh, &landmarks)?;
    atlas.mesh.sets.merge(s);
    Ok(())
}

/// Checks that a deck's mesh is the atlas's mean mesh (same elements and node count).
pub fn check_deck<const D: usize>(
    atlas: &Atlas<D>,
    deck: &crate::io::femesh::InpDeck,
    path: &Path,
) -> Result<()> {
    if deck.mesh.nodes.len() != atlas.mesh.nodes.len()
        || deck.mesh.kind != atlas.mesh.kind
        || deck.mesh.connectivity != atlas.mesh.connectivity
    {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the deck's mesh ({} nodes, {} {} elements) is not the atlas's mean mesh ({} nodes, {} {} elements); start the deck from `atlasmesh convert ATLAS mean.inp`",
                deck.mesh.nodes.len(),
                deck.mesh.num_elements(),
                deck.mesh.kind.name(),
                atlas.mesh.nodes.len(),
                atlas.mesh.num_elements(),
                atlas.mesh.kind.name()
            ),
        ));
    }
    Ok(())
}

/// Leave-one-out where the atlas of fold `k` is built from `corresponded` without entry `k`
/// (with `meshes`, one template volume mesh per shape, the mean of the training ones as its
/// FE mesh), and `subjects[k]` (the same shape as given, before registration) is the one
/// fitted.
#[allow(clippy::too_many_arguments)]
pub fn leave_one_out_of<const D: usize>(
    corresponded: &[Shape<D>],
    subjects: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    dataset: &str,
    params: &RunParams,
    out: &Path,
    jobs: usize,
    quiet: bool,
) -> Result<Report> {
    let shapes = corresponded;
    if subjects.len() != shapes.len() {
        return Err(Error::Population(format!(
            "{} subjects for {} corresponded shapes",
            subjects.len(),
            shapes.len()
        )));
    }
    if let Some(m) = meshes
        && m.len() != shapes.len()
    {
        return Err(Error::Population(format!(
            "leave-one-out with template meshes needs one per shape: {} meshes, {} shapes",
            m.len(),
            shapes.len()
        )));
    }
    if shapes.len() < 4 {
        return Err(Error::Population(format!(
            "leave-one-out needs at least 4 shapes, got {}",
            shapes.len()
        )));
    }
    create_dir(out)?;
    // The full atlas, for the variance figures and to check the population once.
    let spin = Spinner::new("atlas of all shapes (GPA, PCA, mesh of the mean)", quiet);
    let full = atlas_of(shapes, meshes, params)?;
    spin.finish();
    let progress = Progress::new("leave-one-out", shapes.len(), quiet);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::Parameter(format!("--jobs: {e}")))?;
    let results: Vec<Result<SubjectReport>> = pool.install(|| {
        (0..shapes.len())
            .into_par_iter()
            .map(|k| {
                let training: Vec<Shape<D>> = shapes
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != k)
                    .map(|(_, s)| s.clone())
                    .collect();
                let training_meshes: Option<Vec<FeMesh<D>>> = meshes.map(|m| {
                    m.iter()
                        .enumerate()
                        .filter(|(i, _)| *i != k)
                        .map(|(_, x)| x.clone())
                        .collect()
                });
                let atlas = atlas_of(&training, training_meshes.as_deref(), params)?;
                let fitter = Fitter::new(&atlas);
                let morpher = Morpher::new(&atlas, &params.morph)?;
                let r = process_subject(&atlas, &fitter, &morpher, &subjects[k], out, params);
                progress.tick(&subjects[k].name);
                r
            })
            .collect()
    });
    progress.finish();
    let subjects = results.into_iter().collect::<Result<Vec<_>>>()?;
    // Compactness, generalization and specificity of the population's model, for the HTML
    // report (up to 10 modes, 200 random instances).
    let measures = if params.plots {
        crate::eval::shape_model_measures(shapes, 10, 200, 0).ok()
    } else {
        None
    };
    finish_report(
        out,
        dataset,
        &full,
        subjects,
        params,
        Some(mean_mesh_report(&full)),
        crate::batch::BatchFacts {
            measures,
            ..Default::default()
        },
    )
}

/// Builds an atlas from a population and writes it, with the mean mesh as VTU and the mean
/// outline as VTP beside it.
pub fn build<const D: usize>(
    shapes: &[Shape<D>],
    params: &RunParams,
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    build_with_meshes(shapes, None, params, atlas_path)
}

/// [`build`] with template volume meshes (one per shape, or one for the first shape).
pub fn build_with_meshes<const D: usize>(
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    let atlas = atlas_of(shapes, meshes, params)?;
    if let Some(dir) = atlas_path.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_dir(dir)?;
    }
    atlas.save(atlas_path)?;
    let stem = atlas_path.with_extension("");
    write_vtu(
        &PathBuf::from(format!("{}_mean_mesh.vtu", stem.display())),
        &atlas.mesh,
        None,
    )?;
    write_vtp(
        &PathBuf::from(format!("{}_mean.vtp", stem.display())),
        &atlas.mean_shape(),
    )?;
    Ok(atlas)
}

/// Fits subjects with a saved atlas; writes their meshes and `out/report.json`.
pub fn fit_subjects<const D: usize>(
    atlas: &Atlas<D>,
    subjects: &[Shape<D>],
    dataset: &str,
    params: &RunParams,
    out: &Path,
    quiet: bool,
) -> Result<Report> {
    create_dir(out)?;
    let fitter = Fitter::new(atlas);
    let morpher = Morpher::new(atlas, &params.morph)?;
    let progress = Progress::new("fit", subjects.len(), quiet);
    let reports = subjects
        .par_iter()
        .map(|s| {
            let r = process_subject(atlas, &fitter, &morpher, s, out, params);
            progress.tick(&s.name);
            r
        })
        .collect::<Result<Vec<_>>>()?;
    progress.finish();
    finish_report(
        out,
        dataset,
        atlas,
        reports,
        params,
        Some(mean_mesh_report(atlas)),
        Default::default(),
    )
}

/// The demo's synthetic population: `n` closed outlines of an asymmetric bone-like section
/// with four independent modes of variation (elongation, a lobe, a bend, a notch), each in a
/// random similarity pose. Points correspond (same parameter values on every shape).
pub fn demo_population(n: usize, points: usize, seed: u64) -> Vec<Shape<2>> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let c: [f64; 4] = std::array::from_fn(|_| crate::eval::standard_normal(&mut rng));
            let mut pose = Similarity::<2>::planar_rotation(rng.random_range(-0.6..0.6));
            pose.s = rng.random_range(20.0..60.0);
            pose.t = [
                rng.random_range(-100.0..100.0),
                rng.random_range(-100.0..100.0),
            ];
            let pts = (0..points)
                .map(|i| {
                    let t = i as f64 / points as f64 * std::f64::consts::TAU;
                    let lobe = 0.18 * (-((t - 1.2) / 0.45).powi(2)).exp();
                    let notch = -0.1 * (-((t - 4.0) / 0.3).powi(2)).exp();
                    let r = 1.0
                        + 0.3 * t.cos()
                        + lobe * (1.0 + 0.35 * c[1])
                        + notch * (1.0 + 0.4 * c[3]);
                    let x = r * t.cos() * (1.0 + 0.08 * c[0]);
                    let y = r * t.sin() * 0.7 + 0.06 * c[2] * x * x;
                    pose.apply(&[x, y])
                })
                .collect();
            Shape::polyline(format!("demo-{k:02}"), pts, true)
        })
        .collect()
}

/// The 3D demo's synthetic population: `n` closed surfaces (a triangulated sphere of
/// `rings × 2 rings` vertices, deformed) with four independent modes of variation (length,
/// a condyle-like lobe, a bend, a flattening), each in a random similarity pose. Vertices
/// correspond (same parameters on every shape).
pub fn demo_population_3d(n: usize, rings: usize, seed: u64) -> Result<Vec<Shape<3>>> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let nu = 2 * rings;
    let nv = rings;
    (0..n)
        .map(|k| {
            let c: [f64; 4] = std::array::from_fn(|_| crate::eval::standard_normal(&mut rng));
            let axis = crate::geometry::normalize([
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ]);
            let angle: f64 = rng.random_range(-0.5..0.5);
            let mut pose = Similarity::<3>::identity();
            pose.r = crate::geometry::rotation_exp::<3>(&crate::geometry::scale(axis, angle));
            pose.s = rng.random_range(10.0..40.0);
            pose.t = std::array::from_fn(|_| rng.random_range(-50.0..50.0));
            let shape_at = |th: f64, ph: f64| -> Point<3> {
                // Unit sphere direction.
                let d = [th.cos() * ph.cos(), th.cos() * ph.sin(), th.sin()];
                let lobe = 0.25
                    * (1.0 + 0.4 * c[1])
                    * (-((d[0] - 0.7).powi(2) + (d[1] + 0.3).powi(2) + (d[2] - 0.5).powi(2))
                        / 0.15)
                        .exp();
                let r = 1.0 + lobe;
                let x = r * d[0] * (1.6 + 0.15 * c[0]);
                let y = r * d[1] * (0.8 + 0.06 * c[3]);
                let z = r * d[2] + 0.12 * c[2] * (x * x - 1.0);
                pose.apply(&[x, y, z])
            };
            let (points, facets) = crate::geometry::uv_sphere(nu, nv, shape_at);
            crate::io::surface::prepare_surface(Shape {
                name: format!("demo3d-{k:02}"),
                points,
                facets,
                landmarks: Vec::new(),
            })
        })
        .collect()
}

/// The built-in 3D demo: a seeded synthetic population of closed surfaces, an atlas from 24
/// with an automatic hexahedral mesh of the mean, fits and morphs of the 6 held-out ones; all
/// outputs in `out`.
pub fn demo_3d(out: &Path, quiet: bool) -> Result<Report> {
    create_dir(out)?;
    let shapes = demo_population_3d(30, 24, 20261122)?;
    let (train, test) = shapes.split_at(24);
    let mut params = RunParams::default();
    params.atlas.element_size = 0.05;
    params.atlas.modes = crate::model::ModeSelection::Variance(0.99);
    build(train, &params, &out.join("atlas.safetensors"))?;
    let loaded = Atlas::<3>::load(&out.join("atlas.safetensors"))?;
    fit_subjects(
        &loaded,
        test,
        "demo 3D (synthetic, seed 20261122)",
        &params,
        out,
        quiet,
    )
}

/// The built-in demo: a seeded synthetic population, an atlas from 24 shapes, fits and morphs
/// of the 6 held-out shapes, all outputs in `out`.
pub fn demo(out: &Path, quiet: bool) -> Result<Report> {
    create_dir(out)?;
    let population = demo_population(30, 180, 20261122);
    let (shapes, _) = resample_corresponding(&population, 400, true)?;
    let (train, test) = shapes.split_at(24);
    let mut params = RunParams::default();
    params.atlas.element_size = 0.03;
    build(train, &params, &out.join("atlas.safetensors"))?;
    let loaded = Atlas::<2>::load(&out.join("atlas.safetensors"))?;
    fit_subjects(
        &loaded,
        test,
        "demo (synthetic, seed 20261122)",
        &params,
        out,
        quiet,
    )
}

//! Shapes the model allows, as FE models: an instance of the model for given weights (eq. 4),
//! carried to the data's frame and unit ([`Atlas::data_frame`]), the mean mesh morphed onto it
//! (eq. 9), repaired, checked and written like a fitted subject's, with its sets and deck.
//! `atlasmesh instance` asks for the weights, `atlasmesh sample` draws them from the model's
//! prior ([`sample_specs`]).
//!
//! Like a batch of subjects ([`super::batch`]), the instances are made in parallel, each into
//! its own folder `OUT/NAME/` whose record `instance.json` is written last: a re-run skips
//! the complete ones (same atlas, parameters and weights), and a shard takes every `N`-th
//! instance of the list.

use super::params::RunParams;
use super::progress::Progress;
use super::subject::{check_valid, delivered_distances};
use super::write_subject::{file_name, quality_picture};
use crate::error::{Error, Result};
use crate::formats::{write_atomic, write_mesh, write_shape};
use crate::geometry::{ClosestPointIndex, Point, Shape, Similarity, same_dim};
use crate::mesh::quality::summarize;
use crate::mesh::{Correspondence, Morpher, repair_with_quality};
use crate::model::Atlas;
use crate::report::{FailedSubject, InstanceReport, InstancesReport, InstancesSummary, Sampling};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// File name of an instance's record in its folder.
pub const INSTANCE_RECORD: &str = "instance.json";

/// One instance asked for: its name and its weights in standard deviations of each mode
/// (`w_k = sd_k sqrt(lambda_k)`; modes not given are 0).
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceSpec {
    /// The instance's name (its files' and folder's).
    pub name: String,
    /// Weights in standard deviations, one per mode from the first (shorter: the rest 0).
    pub sd: Vec<f64>,
}

/// How a run of instances goes.
#[derive(Clone, Debug, Default)]
pub struct InstanceRun {
    /// Skip instances whose outputs are complete.
    pub resume: bool,
    /// The shard `(i, n)`: only the instances `k` with `k mod n == i`.
    pub shard: Option<(usize, usize)>,
    /// How the weights were drawn (`sample`).
    pub sampling: Option<Sampling>,
    /// The atlas file (for the report).
    pub atlas_file: String,
    /// CRC-32 of the atlas file (part of an instance's completeness).
    pub atlas_crc: u32,
}

/// An instance's record `NAME/instance.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct InstanceRecord {
    /// CRC-32 of the atlas, the parameters and the weights.
    run_crc32: u32,
    /// The instance's report (files relative to the output folder).
    report: InstanceReport,
}

/// `n` instances of weights drawn from the model's prior (eq. 4, `w ~ N(0, Lambda)`, each
/// standard normal redrawn beyond `max_sd`) by one ChaCha8 stream from `seed`, named
/// `sample-001`, ... (as many digits as `n` needs). The list depends on `seed`, `n` and the
/// number of modes only, so every shard of a sampled population draws the same.
///
/// # Errors
/// [`Error::Parameter`] for `n` = 0 or a bound [`Atlas::sample_weights`] refuses.
pub fn sample_specs<const D: usize>(
    atlas: &Atlas<D>,
    n: usize,
    seed: u64,
    max_sd: Option<f64>,
) -> Result<Vec<InstanceSpec>> {
    use rand::SeedableRng;
    if n == 0 {
        return Err(Error::Parameter("sample: --n must be at least 1".into()));
    }
    let digits = n.to_string().len().max(3);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let w = atlas.sample_weights(&mut rng, max_sd)?;
            Ok(InstanceSpec {
                name: format!("sample-{:0digits$}", k + 1),
                sd: w
                    .iter()
                    .zip(&atlas.eigenvalues)
                    .map(|(w, l)| w / l.sqrt())
                    .collect(),
            })
        })
        .collect()
}

/// Makes and writes the instances of `specs` (those of the shard of `run`) into `out/NAME/`
/// (without a `morpher`, for an atlas without a mesh, their surfaces alone):
/// the surface (`NAME.EXT` in every `params.surface_formats`), the FE mesh (`NAME_mesh.EXT`
/// in every `params.formats`, with the displacement from the mean mesh as point data), the
/// deck (`NAME_deck.inp|feb`) and, with `params.plots`, a picture (`NAME.png`), in the data's
/// frame and unit (the reference frame for an atlas of format version 2), with the atlas's
/// sets; then `out/instances.json` over all of them. An instance that fails (its mesh stays
/// invalid) is in the report's `failed`, the others go on.
///
/// # Errors
/// [`Error::Parameter`] for more weights than modes, a weight that is not finite or two
/// instances of one folder name; the errors of the output folder and of the report.
pub fn write_instances<const D: usize>(
    atlas: &Atlas<D>,
    morpher: Option<&Morpher<D>>,
    specs: &[InstanceSpec],
    params: &RunParams,
    out: &Path,
    run: &InstanceRun,
    progress: &dyn Progress,
) -> Result<InstancesReport> {
    let m = atlas.num_modes();
    if let Some(spec) = specs
        .iter()
        .find(|s| s.sd.len() > m || s.sd.iter().any(|v| !v.is_finite()))
    {
        return Err(Error::Parameter(format!(
            "instance {}: {} weights for a model of {m} modes (finite numbers of standard deviations)",
            spec.name,
            spec.sd.len()
        )));
    }
    let mut folders: Vec<String> = specs.iter().map(|s| file_name(&s.name)).collect();
    folders.sort();
    if let Some(w) = folders.windows(2).find(|w| w[0] == w[1]) {
        return Err(Error::Parameter(format!(
            "two instances would share the folder {}/",
            w[0]
        )));
    }
    let shard_label = run.shard.map(|(i, n)| format!("{i}/{n}"));
    crate::formats::create_dir(out)?;
    let _lock = crate::formats::lock_dir(out)?;
    super::batch::check_report_shard(&out.join("instances.json"), shard_label.as_deref())?;
    let mine: Vec<&InstanceSpec> = specs
        .iter()
        .enumerate()
        .filter(|(k, _)| run.shard.is_none_or(|(i, n)| k % n == i))
        .map(|(_, s)| s)
        .collect();
    let parameters = serde_json::to_value(params).unwrap_or_default();
    // The same view of every instance (3D pictures): the mean in the data's frame, widened.
    let view = (D == 3 && morpher.is_some()).then(|| {
        let mean: Vec<Point<3>> = atlas
            .to_data_frame(&atlas.mean)
            .iter()
            .map(same_dim::<D, 3>)
            .collect();
        crate::report::render::View::fitting(&widened(&mean, 1.15))
    });
    let label = "instance";
    progress.items_started(label, mine.len());
    let resumed = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<std::result::Result<InstanceReport, FailedSubject>> = mine
        .par_iter()
        .map(|spec| {
            let crc = run_crc(run.atlas_crc, &parameters, spec);
            let folder = file_name(&spec.name);
            let r = if let Some(r) = run.resume.then(|| complete(out, &folder, crc)).flatten() {
                resumed.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                Ok(r)
            } else {
                write_instance(atlas, morpher, spec, params, view.as_ref(), out, crc)
                    .map_err(|e| FailedSubject::new(&spec.name, "", &e))
            };
            progress.item_done(label, &spec.name);
            r
        })
        .collect();
    progress.items_finished(label);
    let mut instances = Vec::new();
    let mut failed = Vec::new();
    for r in results {
        match r {
            Ok(r) => instances.push(r),
            Err(f) => failed.push(f),
        }
    }
    let mut summary = InstancesSummary::of(&instances, failed.len());
    summary.resumed = resumed.into_inner();
    let report = InstancesReport {
        atlas: run.atlas_file.clone(),
        dimension: D,
        modes: m,
        eigenvalues: atlas.eigenvalues.clone(),
        data_unit: atlas.data_frame.is_some(),
        sampling: run.sampling.clone(),
        shard: shard_label,
        parameters,
        summary,
        failed,
        instances,
        atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
    };
    report.write(&out.join("instances.json"))?;
    if params.plots {
        crate::report::html::write_instances(&out.join("instances.html"), &report, out)?;
    }
    Ok(report)
}

/// `points` scaled by `k` about their bounding box's centre.
fn widened(points: &[Point<3>], k: f64) -> Vec<Point<3>> {
    let (lo, hi) = crate::geometry::bounding_box(points);
    let c: Point<3> = std::array::from_fn(|d| 0.5 * (lo[d] + hi[d]));
    points
        .iter()
        .map(|p| std::array::from_fn(|d| c[d] + k * (p[d] - c[d])))
        .collect()
}

/// CRC-32 of what an instance is made from: the atlas, the parameters and its weights.
fn run_crc(atlas_crc: u32, parameters: &serde_json::Value, spec: &InstanceSpec) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&atlas_crc.to_le_bytes());
    h.update(parameters.to_string().as_bytes());
    for v in &spec.sd {
        h.update(&v.to_le_bytes());
    }
    h.finalize()
}

/// The report of a complete instance in `out/folder`: its record made from the same run,
/// with every file it lists present.
fn complete(out: &Path, folder: &str, crc: u32) -> Option<InstanceReport> {
    let text = std::fs::read(out.join(folder).join(INSTANCE_RECORD)).ok()?;
    let rec: InstanceRecord = serde_json::from_slice(&text).ok()?;
    (rec.run_crc32 == crc && rec.report.files.iter().all(|f| out.join(f).is_file()))
        .then_some(rec.report)
}

/// The FE mesh of one instance: the mean mesh morphed onto it, repaired, checked, measured.
struct InstanceMesh<const D: usize> {
    mesh: crate::mesh::FeMesh<D>,
    quality: Vec<crate::mesh::ElementQuality>,
    before: crate::mesh::quality::QualitySummary,
    after: crate::mesh::quality::QualitySummary,
    repair_bound: f64,
    elements_below_bound: usize,
    delivered: super::subject::Delivered,
    node_distances: Vec<f64>,
}

/// The mean mesh morphed onto `surface` (data's frame) by eq. 9, repaired and checked.
fn instance_mesh<const D: usize>(
    morpher: &Morpher<D>,
    surface: &Shape<D>,
    frame: Similarity<D>,
    params: &RunParams,
) -> Result<InstanceMesh<D>> {
    let morph = morpher.morph(&Correspondence {
        targets: surface.points.clone(),
        partnered: Vec::new(),
        frame,
    })?;
    let mut mesh = morph.mesh;
    let before = summarize(&morph.quality);
    let mut quality = morph.quality;
    let index = ClosestPointIndex::from_shape(surface);
    let mut repair_bound = 0.0;
    if let Some(rp) = &params.repair {
        let (r, q) = repair_with_quality(&mut mesh, Some(&index), rp, &quality)?;
        (repair_bound, quality) = (r.bound, q);
    }
    let after = summarize(&quality);
    check_valid(surface, &mesh, &after, params)?;
    let delivered = delivered_distances(&mesh, surface, &index, params);
    let elements_below_bound =
        crate::mesh::quality::distribution(&mesh, &quality).elements_below_bound;
    let node_distances = crate::mesh::boundary_surface(&mesh)
        .points
        .iter()
        .map(|p| index.closest(p).dist2.sqrt())
        .collect();
    Ok(InstanceMesh {
        mesh,
        quality,
        before,
        after,
        repair_bound,
        elements_below_bound,
        delivered,
        node_distances,
    })
}

/// One instance of [`write_instances`], written into `out/NAME/` with its record last; the
/// surface alone without a `morpher` (an atlas without a mesh).
#[allow(clippy::too_many_arguments)]
fn write_instance<const D: usize>(
    atlas: &Atlas<D>,
    morpher: Option<&Morpher<D>>,
    spec: &InstanceSpec,
    params: &RunParams,
    view: Option<&crate::report::render::View>,
    out: &Path,
    crc: u32,
) -> Result<InstanceReport> {
    let m = atlas.num_modes();
    let w: Vec<f64> = (0..m)
        .map(|k| spec.sd.get(k).copied().unwrap_or(0.0) * atlas.eigenvalues[k].sqrt())
        .collect();
    let frame = atlas.data_frame.unwrap_or_else(Similarity::identity);
    let surface = Shape {
        name: spec.name.clone(),
        points: atlas.to_data_frame(&atlas.instance(&w)),
        facets: atlas.facets.clone(),
        landmarks: atlas.landmarks.clone(),
    };
    let made = morpher
        .map(|m| instance_mesh(m, &surface, frame, params))
        .transpose()?;
    let base = file_name(&spec.name);
    let dir = out.join(&base);
    crate::formats::create_dir(&dir)?;
    let _ = std::fs::remove_file(dir.join(INSTANCE_RECORD));
    let mut files = Vec::new();
    if let Some(im) = &made {
        let mean_mesh = atlas
            .mesh
            .with_nodes(atlas.to_data_frame(&atlas.mesh.nodes));
        for f in &params.formats {
            let name = format!("{base}_mesh.{}", f.extension());
            write_mesh(&dir.join(&name), &im.mesh, Some(&mean_mesh), &im.quality)?;
            files.push(format!("{base}/{name}"));
        }
        if let Some(deck) = &params.deck {
            let name = format!("{base}_deck.{}", deck.extension());
            write_atomic(
                &dir.join(&name),
                deck.with_nodes(&im.mesh.nodes)?.as_bytes(),
            )?;
            files.push(format!("{base}/{name}"));
        }
    }
    // A point set (no facets) is written as VTP points only.
    let surface_formats: &[crate::formats::ShapeFormat] = if surface.facets.is_empty() {
        &[crate::formats::ShapeFormat::Vtp]
    } else {
        &params.surface_formats
    };
    for &f in surface_formats {
        let name = format!("{base}.{}", f.extension());
        write_shape(&dir.join(&name), &surface, f)?;
        files.push(format!("{base}/{name}"));
    }
    if let (true, Some(im)) = (params.plots, &made) {
        let name = format!("{base}.png");
        if let Some(view) = view {
            let title = format!("{}: mesh, scaled Jacobian", spec.name);
            write_atomic(
                &dir.join(&name),
                &quality_picture(&im.mesh, &im.quality, view, &title)?,
            )?;
        } else {
            let to2 =
                |v: &[Point<D>]| -> Vec<Point<2>> { v.iter().map(same_dim::<D, 2>).collect() };
            let mesh2 = crate::mesh::FeMesh {
                nodes: to2(&im.mesh.nodes),
                kind: im.mesh.kind,
                connectivity: im.mesh.connectivity.clone(),
                sets: Default::default(),
            };
            crate::report::plot_subject(
                &dir.join(&name),
                &spec.name,
                &to2(&atlas.to_data_frame(&atlas.mean)),
                &to2(&surface.points),
                &[],
                &mesh2,
                atlas.facets.len() == atlas.mean.len(),
            )?;
        }
        files.push(format!("{base}/{name}"));
        // The thumbnail `instances.html` shows.
        let bytes = std::fs::read(dir.join(&name)).map_err(|e| Error::io(dir.join(&name), e))?;
        let thumb = format!("{base}_thumb.png");
        write_atomic(
            &dir.join(&thumb),
            &crate::report::render::thumbnail(&bytes, 200)?,
        )?;
        files.push(format!("{base}/{thumb}"));
    }
    let nan = f64::NAN;
    let rms = |v: &[f64]| (v.iter().map(|d| d * d).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let report = InstanceReport {
        name: spec.name.clone(),
        sd: spec.sd.clone(),
        mahalanobis: spec.sd.iter().map(|v| v * v).sum::<f64>().sqrt(),
        elements: made.as_ref().map_or(0, |im| im.mesh.num_elements()),
        scaled_jacobian_min: made.as_ref().map_or(nan, |im| im.after.scaled_jacobian_min),
        scaled_jacobian_min_before_repair: made
            .as_ref()
            .map_or(nan, |im| im.before.scaled_jacobian_min),
        inverted_elements: made.as_ref().map_or(0, |im| im.after.inverted_elements),
        repair_bound: made.as_ref().map_or(0.0, |im| im.repair_bound),
        elements_below_repair_bound: made.as_ref().map_or(0, |im| {
            im.quality
                .iter()
                .filter(|e| e.scaled_jacobian_min < im.repair_bound)
                .count()
        }),
        elements_below_bound: made.as_ref().map_or(0, |im| im.elements_below_bound),
        mesh_rms_distance: made.as_ref().map_or(nan, |im| im.delivered.distances.rms),
        mesh_p95_distance: made.as_ref().map_or(nan, |im| im.delivered.distances.p95),
        mesh_max_distance: made.as_ref().map_or(nan, |im| im.delivered.distances.max),
        boundary_node_rms_distance: made.as_ref().map_or(nan, |im| rms(&im.node_distances)),
        boundary_node_max_distance: made.as_ref().map_or(nan, |im| {
            im.node_distances.iter().fold(0.0, |a, &d| a.max(d))
        }),
        element_size: made.as_ref().map_or(nan, |im| im.delivered.element_size),
        files,
    };
    let rec = InstanceRecord {
        run_crc32: crc,
        report,
    };
    let text = serde_json::to_vec_pretty(&rec)
        .map_err(|e| Error::Numerical(format!("instance record: {e}")))?;
    write_atomic(&dir.join(INSTANCE_RECORD), &text)?;
    Ok(rec.report)
}

/// Joins the `instances.json` of several shards of one sampled population (or runs of one
/// atlas and parameters) into one report: instances and failures concatenated (sorted by
/// name), summary recomputed. Refuses reports of another atlas, sampling or parameters, and
/// an instance that is in two of them.
///
/// # Errors
/// [`Error::Parse`] for a file that is not an instances report; [`Error::Population`] for
/// reports that do not belong together.
pub fn merge_instances(paths: &[std::path::PathBuf]) -> Result<InstancesReport> {
    let mut merged: Option<InstancesReport> = None;
    for p in paths {
        let text = crate::formats::read_input(p)?;
        let r: InstancesReport = serde_json::from_slice(&text).map_err(|e| {
            Error::parse(
                p,
                e.line(),
                format!("not an atlasmesh instances report: {e}"),
            )
        })?;
        match &mut merged {
            None => merged = Some(r),
            Some(m) => {
                if m.dimension != r.dimension
                    || m.eigenvalues != r.eigenvalues
                    || m.parameters != r.parameters
                    || m.sampling != r.sampling
                {
                    return Err(Error::Population(format!(
                        "{}: made with another atlas, sampling or parameters than {}",
                        p.display(),
                        paths[0].display()
                    )));
                }
                m.summary.resumed += r.summary.resumed;
                m.instances.extend(r.instances);
                m.failed.extend(r.failed);
            }
        }
    }
    let mut m = merged.ok_or_else(|| Error::Population("no report to merge".into()))?;
    m.instances.sort_by(|a, b| a.name.cmp(&b.name));
    if let Some(w) = m.instances.windows(2).find(|w| w[0].name == w[1].name) {
        return Err(Error::Population(format!(
            "instance {} is in two of the reports (overlapping shards?)",
            w[0].name
        )));
    }
    m.failed.sort_by(|a, b| a.name.cmp(&b.name));
    let resumed = m.summary.resumed;
    m.summary = InstancesSummary::of(&m.instances, m.failed.len());
    m.summary.resumed = resumed;
    m.shard = None;
    Ok(m)
}

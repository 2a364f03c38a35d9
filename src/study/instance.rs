//! Shapes the model allows, as FE models: an instance of the model for given weights (eq. 4),
//! carried to the data's frame and unit ([`Atlas::data_frame`]), the mean mesh morphed onto it
//! (eq. 9), repaired, checked and written like a fitted subject's, with its sets and deck.
//! `atlasmesh instance` asks for the weights, `atlasmesh sample` draws them from the model's
//! prior ([`sample_specs`]).
//!
//! Like a batch of subjects ([`super::batch`]), the instances are a [`Job`] of the run
//! engine: made in parallel, each into its own folder `OUT/NAME/` whose record
//! `instance.json` is written last; a re-run skips the complete ones (same atlas, parameters
//! and weights), and a shard takes every `N`-th instance of the list.

use super::params::RunParams;
use super::progress::Progress;
use super::run::{Job, Origin, RunContext, RunOutcome, Units, check_folders, run_items};
use super::subject::{check_valid, delivered_distances};
use super::write_subject::{file_name, quality_picture};
use crate::error::{Error, Result};
use crate::formats::{write_atomic, write_mesh, write_shape};
use crate::geometry::{ClosestPointIndex, Point, Shape, Similarity, same_dim};
use crate::mesh::quality::summarize;
use crate::mesh::{Correspondence, Morpher, repair_with_quality};
use crate::model::Atlas;
use crate::report::{FailedSubject, InstanceReport, InstancesReport, InstancesSummary, Sampling};
use std::path::Path;
use std::sync::Arc;

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

impl super::run::UnitReport for InstanceReport {
    fn files(&self) -> &[String] {
        &self.files
    }
    fn files_mut(&mut self) -> &mut Vec<String> {
        &mut self.files
    }
}

/// The most shapes one `sample` draws (the command line's bound, and Python's).
pub const MAX_SAMPLES: usize = 1_000_000;

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
    if n == 0 || n > MAX_SAMPLES {
        return Err(Error::Parameter(format!(
            "sample: --n {n} must be from 1 to {MAX_SAMPLES}"
        )));
    }
    let digits = n.to_string().len().max(3);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let w = atlas.sample_weights(&mut rng, max_sd)?;
            Ok(InstanceSpec {
                name: format!("sample-{:0digits$}", k + 1),
                sd: atlas.in_sd(&w),
            })
        })
        .collect()
}

/// Makes and writes the instances of `specs` (those of the run's shard) with the atlas of
/// `ctx` into `OUT/NAME/` (without a mean mesh, their surfaces alone): the surface
/// (`NAME.EXT` in every `params.surface_formats`), the FE mesh (`NAME_mesh.EXT` in every
/// `params.formats`, with the displacement from the mean mesh as point data), the deck
/// (`NAME_deck.inp|feb`) and, with `params.plots`, a picture (`NAME.png`), in the data's
/// frame and unit (the reference frame for an atlas of format version 2), with the atlas's
/// sets; then `OUT/instances.json` over all of them (`sampling`: how the weights were
/// drawn). An instance that fails (its mesh stays invalid) is in the report's `failed`, the
/// others go on.
///
/// # Errors
/// [`Error::Parameter`] for more weights than modes or a weight that is not finite;
/// [`Error::Population`] for two instances of one folder name; the errors of the output
/// folder and of the report.
pub fn write_instances<const D: usize>(
    ctx: &RunContext<D>,
    specs: &[InstanceSpec],
    sampling: Option<Sampling>,
    progress: &dyn Progress,
) -> Result<InstancesReport> {
    let atlas = &ctx.atlas;
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
    check_folders(specs.iter().map(|s| (s.name.clone(), "another instance")))?;
    // An atlas without a mean mesh (build --no-mesh): the shapes alone.
    let morpher = atlas.has_mesh().then(|| ctx.morpher()).transpose()?;
    // The same view of every instance (3D pictures): the mean in the data's frame, widened.
    let view = (D == 3 && morpher.is_some()).then(|| {
        let mean: Vec<Point<3>> = atlas
            .to_data_frame(&atlas.mean)
            .iter()
            .map(same_dim::<D, 3>)
            .collect();
        crate::report::render::View::fitting(&widened(&mean, 1.15))
    });
    let job = Instances {
        ctx,
        morpher,
        view,
        parameters: serde_json::to_value(&ctx.params).unwrap_or_default(),
        sampling,
    };
    run_items(&job, specs, ctx.looping(INSTANCE_RECORD), progress)
}

/// The instances of a run.
struct Instances<'a, const D: usize> {
    ctx: &'a RunContext<D>,
    morpher: Option<Arc<Morpher<D>>>,
    view: Option<crate::report::render::View>,
    parameters: serde_json::Value,
    sampling: Option<Sampling>,
}

impl<const D: usize> Job for Instances<'_, D> {
    type Item = InstanceSpec;
    type Key = usize;
    type Report = InstanceReport;
    type Output = InstancesReport;
    const LABEL: &'static str = "instance";
    const REPORT: &'static str = "instances.json";

    fn name(&self, spec: &InstanceSpec) -> String {
        spec.name.clone()
    }

    fn key(&self, k: usize, _: &InstanceSpec) -> usize {
        k
    }

    fn run(
        &self,
        spec: &InstanceSpec,
        units: &Units<'_>,
    ) -> Vec<std::result::Result<InstanceReport, FailedSubject>> {
        let origin = Origin {
            input: "",
            input_crc32: 0,
            run_crc32: run_crc(self.ctx.atlas_crc, &self.parameters, spec),
        };
        vec![
            units
                .make(&file_name(&spec.name), origin, |dir| self.write(spec, dir))
                .map_err(|e| FailedSubject::new(&spec.name, "", &e)),
        ]
    }

    fn finish(&self, outcome: RunOutcome<InstanceReport>) -> Result<InstancesReport> {
        let RunOutcome {
            reports: instances,
            failed,
            resumed,
        } = outcome;
        let ctx = self.ctx;
        let mut summary = InstancesSummary::of(&instances, failed.len());
        summary.resumed = resumed;
        let report = InstancesReport {
            atlas: ctx.atlas_file.clone(),
            dimension: D,
            modes: ctx.atlas.num_modes(),
            eigenvalues: ctx.atlas.eigenvalues.clone(),
            data_unit: ctx.atlas.data_frame.is_some(),
            sampling: self.sampling.clone(),
            shard: ctx.place.shard.map(|s| s.label()),
            parameters: self.parameters.clone(),
            summary,
            failed,
            instances,
            atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        let out = &ctx.place.out;
        report.write(&out.join("instances.json"))?;
        if ctx.params.plots {
            crate::report::html::write_instances(&out.join("instances.html"), &report, out)?;
        }
        Ok(report)
    }
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

impl<const D: usize> Instances<'_, D> {
    /// One instance of [`write_instances`], written into `dir` (files named relative to it);
    /// the surface alone without a morph (an atlas without a mesh).
    /// The picture of an instance's mesh (`NAME.png`, coloured by scaled Jacobian) and its
    /// thumbnail (`NAME_thumb.png`) in `dir`; their names.
    fn pictures(
        &self,
        spec: &InstanceSpec,
        surface: &Shape<D>,
        im: &InstanceMesh<D>,
        dir: &Path,
    ) -> Result<Vec<String>> {
        let (atlas, view) = (&*self.ctx.atlas, self.view.as_ref());
        let base = file_name(&spec.name);
        let mut files = Vec::new();
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
        // The thumbnail `instances.html` shows.
        let bytes = std::fs::read(dir.join(&name)).map_err(|e| Error::io(dir.join(&name), e))?;
        files.push(name);
        let thumb = format!("{base}_thumb.png");
        write_atomic(
            &dir.join(&thumb),
            &crate::report::render::thumbnail(&bytes, 200)?,
        )?;
        files.push(thumb);
        Ok(files)
    }

    fn write(&self, spec: &InstanceSpec, dir: &Path) -> Result<InstanceReport> {
        let (atlas, params) = (&*self.ctx.atlas, &self.ctx.params);
        let morpher = self.morpher.as_deref();
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
        let mut files = Vec::new();
        if let Some(im) = &made {
            let mean_mesh = atlas
                .mesh
                .with_nodes(atlas.to_data_frame(&atlas.mesh.nodes));
            for f in &params.formats {
                let name = format!("{base}_mesh.{}", f.extension());
                write_mesh(&dir.join(&name), &im.mesh, Some(&mean_mesh), &im.quality)?;
                files.push(name);
            }
            if let Some(deck) = &params.deck {
                let name = format!("{base}_deck.{}", deck.extension());
                write_atomic(
                    &dir.join(&name),
                    deck.with_nodes(&im.mesh.nodes)?.as_bytes(),
                )?;
                files.push(name);
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
            files.push(name);
        }
        if let (true, Some(im)) = (params.plots, &made) {
            files.extend(self.pictures(spec, &surface, im, dir)?);
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
        Ok(report)
    }
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
    super::run::merge(paths)
}

//! One subject: fit (Algorithm 1), morph (eq. 9), repair and the measures of section 5, as a
//! value; nothing is written here.

use super::baselines::baseline_correlations;
use super::params::RunParams;
use crate::error::{Error, Result};
use crate::eval::{
    SurfaceDistances, e_d, normal_correlation, normals_at, surface_distances, two_way_rms,
};
use crate::fit::{FitResult, Fitter};
use crate::geometry::{ClosestPointIndex, Shape};
use crate::mesh::quality::{ElementQuality, distribution, summarize};
use crate::mesh::{FeMesh, Morpher, boundary_surface, repair_with_quality};
use crate::model::Atlas;
use crate::report::{SubjectCut, SubjectReport, jacobian_histogram};
use std::time::Instant;

/// What one subject's fit, morph and repair produced, in memory.
#[derive(Clone)]
pub struct SubjectOutcome<const D: usize> {
    /// The fit (Algorithm 1): weights, pose, instance and its projection (subject frame).
    pub fit: FitResult<D>,
    /// The subject's FE mesh: the mean mesh morphed and repaired (subject frame and units).
    pub mesh: FeMesh<D>,
    /// Corner Jacobians of every element of `mesh` (section 5.3).
    pub quality: Vec<ElementQuality>,
    /// The subject's closest-point index (the pictures measure distances with it); of the
    /// subject trimmed to the atlas's common cut where it reaches beyond it.
    pub index: ClosestPointIndex<D>,
    /// The measures of `report.json` (`files` empty until the subject is written).
    pub report: SubjectReport,
    /// The mesh's materials from the subject's CT (none without a CT).
    pub materials: Option<crate::materials::MaterialMap>,
}

/// Fits `subject` with the atlas (Algorithm 1), morphs the mean mesh onto it (eq. 9), repairs
/// the morphed mesh and takes the measures of section 5, among them the delivered mesh's
/// distance to the subject (its boundary against the subject's surface) and the checks of
/// `success` (`fit`, `mesh_distance`, `mesh_quality`); a fit that is not close is compared
/// with a fit of the subject's mirror image (a warning when that fits clearly better).
/// Writes nothing ([`write_subject`](super::write_subject) does).
///
/// # Errors
/// [`Error::NotConverged`] when the fitted instance stays farther from the subject than the
/// misfit guard allows (`params.max_misfit`, see `check_misfit`); the errors of the fit, the
/// morph and the repair.
pub fn fit_subject<const D: usize>(
    atlas: &Atlas<D>,
    fitter: &Fitter<D>,
    morpher: &Morpher<D>,
    subject: &Shape<D>,
    params: &RunParams,
) -> Result<SubjectOutcome<D>> {
    let own_index = ClosestPointIndex::from_shape(subject);
    let t0 = Instant::now();
    let fit = fitter.fit(subject, &own_index, &params.fit)?;
    let fit_seconds = t0.elapsed().as_secs_f64();
    // A subject beyond the atlas's common cut is measured on the part they share.
    let shared = SharedPart::of(atlas, &fit.instance, subject, params);
    let (whole, index, params) = shared.as_ref().map_or((subject, &own_index, params), |s| {
        (&s.shape, &s.index, &s.params)
    });
    let (rms, to_instance) = fit_distances(atlas, &fit, whole, index, params.fit.partial);
    let rel = rms / whole.bbox_diagonal();
    let (mirrored_rms, mut warnings) =
        checked_misfit(atlas, fitter, whole, params, (rms, to_instance))?;
    let atlas_cut = atlas_cut_facts(atlas, &fit, shared.as_ref(), &mut warnings);
    let morph = morpher.morph(&fit.correspondence())?;
    let mut mesh = morph.mesh;
    let mut per_element = morph.quality;
    let unrepaired = summarize(&per_element);
    let mut repair = None;
    if let Some(rp) = &params.repair {
        let (r, q) = repair_with_quality(&mut mesh, Some(index), rp, &per_element)?;
        per_element = q;
        repair = Some(r);
    }
    let delivered = delivered_distances(&mesh, whole, index, params);
    let on = (index, whole);
    let delivered_mesh = (mesh, per_element, delivered);
    let (mesh, per_element, delivered) =
        boundary_fitted_and_flat(delivered_mesh, on, params, &mut warnings)?;
    let q = summarize(&per_element);
    check_valid(whole, &mesh, &q, params)?;
    let surface_distance_change = repair.map_or(0.0, |r| r.surface_distance_change);
    let dist = distribution(&mesh, &per_element);
    let mean_normals = atlas.mean_shape().vertex_normals();
    let nc = normal_correlation(&mean_normals, &normals_at(subject, &fit.projected));
    let baselines = params
        .baselines
        .then(|| baseline_correlations(atlas, subject, &own_index, &mean_normals))
        .transpose()?;
    let mut report = SubjectReport {
        name: subject.name.clone(),
        iterations: fit.iterations,
        fit_seconds,
        seconds: f64::NAN,
        heap_peak_mb: None,
        e_d: e_d(&fit.instance, index),
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
        morph_escalated: morph.alpha > params.morph.alpha * (1.0 + 1e-9),
        scaled_jacobian_histogram: jacobian_histogram(
            per_element.iter().map(|e| e.scaled_jacobian_min),
        ),
        scaled_jacobian_p01: dist.scaled_jacobian_p01,
        scaled_jacobian_p05: dist.scaled_jacobian_p05,
        edge_ratio_max: dist.edge_ratio_max,
        elements_below_bound: dist.elements_below_bound,
        mesh_rms_distance: delivered.distances.rms,
        mesh_rms_distance_relative: delivered.distances.rms / whole.bbox_diagonal(),
        mesh_p95_distance: delivered.distances.p95,
        mesh_max_distance: delivered.distances.max,
        mesh_share_beyond_element: delivered.distances.share_beyond,
        element_size: delivered.element_size,
        failed_checks: Vec::new(),
        success: false,
        mirrored_rms_distance: mirrored_rms,
        voxel_size: None,
        atlas_cut,
        materials: None,
        warnings,
        converged: fit.converged,
        e_d_history: fit.e_d_history.clone(),
        sd: atlas.in_sd(&fit.weights),
        pose: Some(crate::report::Pose::of(&fit.similarity)),
        fold: None,
        files: Vec::new(),
    };
    report.failed_checks = failed_checks(&report, delivered.finite, params);
    report.success = report.failed_checks.is_empty();
    Ok(SubjectOutcome {
        fit,
        mesh,
        quality: per_element,
        index: shared.map_or(own_index, |s| s.index),
        report,
        materials: None,
    })
}

/// How far a boundary node may move onto the subject in the boundary fit, in element sizes:
/// far for a whole subject (the tips a smooth morph leaves short), one element for a partial
/// one (where the subject has no counterpart, nothing is pulled in).
const BOUNDARY_REACH: f64 = 8.0;
const BOUNDARY_REACH_PARTIAL: f64 = 1.0;

/// The morphed (and repaired) `mesh` after the boundary fit ([`crate::mesh::fit_boundary`]),
/// repaired again with its boundary sliding on the subject, with its quality and distances.
///
/// The fit goes in stages: up to [`BOUNDARY_STAGES`] steps each move the boundary
/// [`BOUNDARY_STAGE_STEP`] of the way that is left onto the subject, each repaired and kept
/// while it leaves no element poor (inverted, or a smallest scaled Jacobian below the repair
/// bound, or below the mesh's before when that was lower), so that a process's tip far from
/// the morph is reached through valid meshes; then the full step. Where the full step leaves
/// elements poor, the nodes around them retreat towards the last valid stage, halfway in each
/// of [`BOUNDARY_RETREAT_ROUNDS`] rounds (all the way after a few), and the rest of the fit is
/// kept (with a warning in `warnings` saying how many nodes retreated). `None` when no mesh
/// passes (with a warning), or when the one that does has a two-way RMS or 95th percentile
/// distance larger than before.
#[allow(
    clippy::type_complexity,
    reason = "the three parts of the delivered mesh"
)]
fn boundary_fitted<const D: usize>(
    mesh: &FeMesh<D>,
    (index, subject): (&ClosestPointIndex<D>, &Shape<D>),
    params: &RunParams,
    before: &Delivered,
    warnings: &mut Vec<String>,
) -> Result<Option<(FeMesh<D>, Vec<ElementQuality>, Delivered)>> {
    if !before.element_size.is_finite() {
        return Ok(None);
    }
    let reach = before.element_size
        * if params.fit.partial {
            BOUNDARY_REACH_PARTIAL
        } else {
            BOUNDARY_REACH
        };
    // A repair that has not untangled the moves in a few sweeps rarely does: the nodes
    // around what is left retreat instead.
    let rp = crate::mesh::repair::RepairParams {
        max_sweeps: BOUNDARY_REPAIR_SWEEPS,
        ..params.repair.unwrap_or_default()
    };
    let was = summarize(&crate::mesh::quality::mesh_quality(mesh));
    let bound = rp
        .bound
        .unwrap_or_else(|| crate::mesh::repair::default_bound(mesh.kind))
        .min(was.scaled_jacobian_min);
    let keep = cut_face_nodes(mesh);
    let poor = |quality: &[ElementQuality]| -> Vec<usize> {
        (0..quality.len())
            .filter(|&e| {
                let sj = quality[e].scaled_jacobian_min;
                sj.is_nan() || sj < bound || quality[e].jacobian_min <= 0.0
            })
            .collect()
    };
    let closer = |fitted: FeMesh<D>, quality: Vec<ElementQuality>| {
        let after = delivered_distances(&fitted, subject, index, params);
        let closer = after.distances.rms <= before.distances.rms
            && after.distances.p95 <= before.distances.p95;
        closer.then_some((fitted, quality, after))
    };
    // The stages: each a share of the way left, kept while valid.
    let mut valid = mesh.clone();
    for _ in 0..BOUNDARY_STAGES {
        let mut staged = valid.clone();
        let moved =
            crate::mesh::fit_boundary(&mut staged, index, reach, &keep, BOUNDARY_STAGE_STEP);
        if moved.moved == 0 {
            break;
        }
        let quality = crate::mesh::quality::mesh_quality(&staged);
        let (_, quality) = repair_with_quality(&mut staged, Some(index), &rp, &quality)?;
        if !poor(&quality).is_empty() {
            break;
        }
        valid = staged;
    }
    // The full step.
    let mut fitted = valid.clone();
    let moved = crate::mesh::fit_boundary(&mut fitted, index, reach, &keep, 1.0);
    if moved.moved == 0 {
        return Ok(None);
    }
    let quality = crate::mesh::quality::mesh_quality(&fitted);
    let (_, quality) = repair_with_quality(&mut fitted, Some(index), &rp, &quality)?;
    let mut bad = poor(&quality);
    if bad.is_empty() {
        return Ok(closer(fitted, quality));
    }
    // The retreat: the nodes around each element still poor go halfway back towards the
    // last valid stage in each round (all the way once within a fifth of it), the
    // transition repaired, so that one poor tip does not cost the whole fit.
    let full = fitted.clone();
    let mut share = vec![1.0_f64; mesh.nodes.len()];
    for _ in 0..BOUNDARY_RETREAT_ROUNDS {
        let mut around = vec![false; mesh.nodes.len()];
        mark_around(&fitted, &bad, BOUNDARY_RETREAT_RINGS, &mut around);
        for (n, p) in fitted.nodes.iter_mut().enumerate() {
            if around[n] {
                share[n] = if share[n] > 0.2 { 0.5 * share[n] } else { 0.0 };
                *p = std::array::from_fn(|d| {
                    valid.nodes[n][d] + share[n] * (full.nodes[n][d] - valid.nodes[n][d])
                });
            }
        }
        let quality = crate::mesh::quality::mesh_quality(&fitted);
        let (_, quality) = repair_with_quality(&mut fitted, Some(index), &rp, &quality)?;
        bad = poor(&quality);
        if bad.is_empty() {
            let kept = closer(fitted, quality);
            if kept.is_some() {
                let n = share.iter().filter(|&&s| s < 1.0).count();
                let all = share.iter().filter(|&&s| s == 0.0).count();
                warnings.push(format!(
                    "the boundary fit held back around elements it left poor ({n} nodes, {:.1} % of the mesh's, {all} of them all the way): there the mesh is short of the subject",
                    100.0 * n as f64 / mesh.nodes.len().max(1) as f64
                ));
            }
            return Ok(kept);
        }
    }
    warnings.push(
        "the boundary fit was not kept (every try left elements below the repair bound): the mesh is where the morph put it".to_string(),
    );
    Ok(None)
}

/// The boundary fit ([`boundary_fitted`]) where it brings the mesh closer, then the face on an
/// atlas's common cut made flat ([`crate::mesh::flatten_cut_face`]); the mesh with its quality
/// and distances.
#[allow(
    clippy::type_complexity,
    reason = "the three parts of the delivered mesh"
)]
fn boundary_fitted_and_flat<const D: usize>(
    (mut mesh, mut per_element, mut delivered): (FeMesh<D>, Vec<ElementQuality>, Delivered),
    (index, subject): (&ClosestPointIndex<D>, &Shape<D>),
    params: &RunParams,
    warnings: &mut Vec<String>,
) -> Result<(FeMesh<D>, Vec<ElementQuality>, Delivered)> {
    if params.boundary_fit
        && let Some(better) =
            boundary_fitted(&mesh, (index, subject), params, &delivered, warnings)?
    {
        (mesh, per_element, delivered) = better;
    }
    if let Some(flat) = flat_cut_face(&mesh, &per_element, index, params)? {
        delivered = delivered_distances(&flat.0, subject, index, params);
        (mesh, per_element) = flat;
    }
    Ok((mesh, per_element, delivered))
}

/// `mesh` with the face on an atlas's common cut made flat ([`crate::mesh::flatten_cut_face`])
/// and its quality: repaired where flattening took an element below the repair's bound
/// (inverted ones too), first the interior alone with the boundary held, then the boundary
/// sliding on the subject with the face put back on its plane after, twice at most; or the
/// mesh it had (`None`) when that is not enough. `None` too for a mesh without a cut, or one
/// already flat.
fn flat_cut_face<const D: usize>(
    mesh: &FeMesh<D>,
    per_element: &[ElementQuality],
    index: &ClosestPointIndex<D>,
    params: &RunParams,
) -> Result<Option<(FeMesh<D>, Vec<ElementQuality>)>> {
    let mut flat = mesh.clone();
    if !crate::mesh::cut_face_on_its_plane(&mut flat).is_some_and(|moved| moved > 0.0) {
        return Ok(None);
    }
    let bound = params
        .repair
        .and_then(|r| r.bound)
        .unwrap_or_else(|| crate::mesh::repair::default_bound(mesh.kind))
        .min(summarize(per_element).scaled_jacobian_min);
    let passes = |q: &[ElementQuality]| summarize(q).scaled_jacobian_min >= bound;
    let mut quality = crate::mesh::quality::mesh_quality(&flat);
    if passes(&quality) {
        return Ok(Some((flat, quality)));
    }
    let Some(rp) = &params.repair else {
        return Ok(None);
    };
    for _ in 0..FLAT_CUT_REPAIRS {
        let mut inner = flat.clone();
        let (_, q) = repair_with_quality(&mut inner, None, rp, &quality)?;
        if passes(&q) {
            return Ok(Some((inner, q)));
        }
        repair_with_quality(&mut flat, Some(index), rp, &quality)?;
        crate::mesh::cut_face_on_its_plane(&mut flat);
        quality = crate::mesh::quality::mesh_quality(&flat);
        if passes(&quality) {
            return Ok(Some((flat, quality)));
        }
    }
    Ok(None)
}

/// Rounds of repair of a cut face made flat.
const FLAT_CUT_REPAIRS: usize = 2;

/// The part of a subject an atlas built on a common cut shares with it, when the subject
/// reaches beyond the cut ([`super::trimmed_to_cut`]): the delivered mesh is measured against
/// it, and nothing of it is partial.
struct SharedPart<const D: usize> {
    shape: Shape<D>,
    index: ClosestPointIndex<D>,
    params: RunParams,
    /// Share of the subject's surface beyond the cut.
    removed: f64,
}

impl<const D: usize> SharedPart<D> {
    fn of(
        atlas: &Atlas<D>,
        instance: &[crate::geometry::Point<D>],
        subject: &Shape<D>,
        params: &RunParams,
    ) -> Option<Self> {
        let (shape, removed) =
            super::trimmed_to_cut(instance, &atlas.facets, &atlas.cut_facets, subject)?;
        let mut params = params.clone();
        params.fit.partial = false;
        Some(SharedPart {
            index: ClosestPointIndex::from_shape(&shape),
            shape,
            params,
            removed,
        })
    }
}

/// With an atlas built on a common cut: where the subject's mesh ends and what share of the
/// atlas the subject covers ([`SubjectCut`]), with a warning when the subject reaches beyond
/// the cut or does not reach it.
fn atlas_cut_facts<const D: usize>(
    atlas: &Atlas<D>,
    fit: &FitResult<D>,
    shared: Option<&SharedPart<D>>,
    warnings: &mut Vec<String>,
) -> Option<SubjectCut> {
    let plane = super::cut_plane_of(&fit.instance, &atlas.facets, &atlas.cut_facets)?;
    let covered = super::covered_share(
        &fit.instance,
        &atlas.facets,
        &atlas.cut_facets,
        &fit.corresponded,
    );
    let beyond = shared.map_or(0.0, |s| s.removed);
    if beyond > 0.0 {
        warnings.push(format!(
            "it reaches beyond the atlas's common cut: compared on the part they share, {:.1} % of its surface beyond the cut left out",
            100.0 * beyond
        ));
    }
    if covered < COVERED_IN_FULL {
        warnings.push(format!(
            "it ends short of the atlas's common cut: it covers {:.1} % of the atlas's surface, and its mesh follows the model beyond",
            100.0 * covered
        ));
    }
    Some(SubjectCut {
        point: plane.point.to_vec(),
        normal: plane.normal.to_vec(),
        beyond_share: beyond,
        atlas_covered_share: covered,
    })
}

/// A subject covering this share of an atlas's surface covers it all (a few facets at the cut
/// may lack a partner).
const COVERED_IN_FULL: f64 = 0.995;

/// Sweeps of the repair after a boundary fit's try.
const BOUNDARY_REPAIR_SWEEPS: usize = 8;

/// The nodes of the face on an atlas's common cut, marked: not anatomy, they stay where the
/// morph put them in the boundary fit.
fn cut_face_nodes<const D: usize>(mesh: &FeMesh<D>) -> Vec<bool> {
    let mut cut = vec![false; mesh.nodes.len()];
    for &v in mesh
        .sets
        .node_sets
        .get(crate::mesh::CUT_SET)
        .into_iter()
        .flatten()
    {
        if let Some(k) = cut.get_mut(v) {
            *k = true;
        }
    }
    cut
}

/// Stages of the boundary fit before its full step, each [`BOUNDARY_STAGE_STEP`] of the way
/// left (measured on the VerSe vertebrae in 5 folds: the largest distance of the worst subject
/// from 5.8 to 3.2 element sizes, at no extra time).
const BOUNDARY_STAGES: usize = 3;

/// The share of the way left that a stage of the boundary fit moves.
const BOUNDARY_STAGE_STEP: f64 = 0.5;

/// Rounds of the boundary fit's retreat around the elements its full step left poor.
const BOUNDARY_RETREAT_ROUNDS: usize = 6;

/// Rings of elements around a poor one whose nodes retreat.
const BOUNDARY_RETREAT_RINGS: usize = 1;

/// Marks in `keep` the nodes of `elements` and of `rings - 1` rings of elements around them.
fn mark_around<const D: usize>(
    mesh: &FeMesh<D>,
    elements: &[usize],
    rings: usize,
    keep: &mut [bool],
) {
    let mut marked: std::collections::HashSet<usize> = elements
        .iter()
        .flat_map(|&e| mesh.element(e).iter().copied())
        .collect();
    for _ in 1..rings {
        let more: Vec<usize> = (0..mesh.num_elements())
            .filter(|&e| mesh.element(e).iter().any(|n| marked.contains(n)))
            .flat_map(|e| mesh.element(e).iter().copied())
            .collect();
        marked.extend(more);
    }
    for n in marked {
        keep[n] = true;
    }
}

/// Refuses a morphed (and repaired) mesh no solver could use: no elements, a node with a NaN
/// or infinite coordinate, or an inverted element (a corner Jacobian ≤ 0).
pub(crate) fn check_valid<const D: usize>(
    subject: &Shape<D>,
    mesh: &crate::mesh::FeMesh<D>,
    q: &crate::mesh::quality::QualitySummary,
    params: &RunParams,
) -> Result<()> {
    let what = if mesh.num_elements() == 0 {
        "has no elements".to_string()
    } else if let Some(i) = mesh
        .nodes
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        format!("has a node with a NaN or infinite coordinate (node {i})")
    } else if q.inverted_elements > 0 {
        format!(
            "has {} inverted element(s) (smallest corner Jacobian {:.3e}){}",
            q.inverted_elements,
            q.jacobian_min,
            if params.repair.is_some() {
                " the repair could not untangle"
            } else {
                ", and --repair is off"
            }
        )
    } else {
        return Ok(());
    };
    Err(Error::Mesh(format!(
        "{}: the morphed mesh {what}; it is not written (check the subject's surface for stray \
         vertices or parts the atlas does not model)",
        subject.name
    )))
}

/// A fit farther from its subject than this share of the diagonal (two-way RMS) is compared
/// with a fit of the subject's mirror image.
pub const MIRROR_CHECK_ABOVE: f64 = 0.0075;

/// The mirror image fitting at less than this share of the given subject's RMS distance
/// gives the warning that the subject may be mirrored.
pub const MIRROR_BETTER: f64 = 0.7;

/// The two-way RMS distance at which the model fits `subject` mirrored across the plane
/// `x = 0` (its facets reversed, so that it stays outward), or `None` when that fit fails.
fn mirrored_fit_rms<const D: usize>(
    atlas: &Atlas<D>,
    fitter: &Fitter<D>,
    subject: &Shape<D>,
    params: &RunParams,
) -> Option<f64> {
    let mirror = Shape {
        name: subject.name.clone(),
        points: subject
            .points
            .iter()
            .map(|p| {
                let mut q = *p;
                q[0] = -q[0];
                q
            })
            .collect(),
        facets: subject
            .facets
            .iter()
            .map(|f| {
                let mut g = *f;
                g.swap(0, 1);
                g
            })
            .collect(),
        landmarks: subject.landmarks.clone(),
    };
    let index = ClosestPointIndex::from_shape(&mirror);
    let fit = fitter.fit(&mirror, &index, &params.fit).ok()?;
    Some(two_way_rms(&fit.instance, &atlas.facets, &mirror, &index))
}

/// The delivered mesh measured against its subject.
pub(crate) struct Delivered {
    pub(crate) distances: SurfaceDistances,
    pub(crate) element_size: f64,
    pub(crate) finite: bool,
}

/// The boundary of the mesh written against the subject (two-way, or subject → mesh for a
/// partial subject or an open outline), with the mesh's element size (median boundary edge).
pub(crate) fn delivered_distances<const D: usize>(
    mesh: &FeMesh<D>,
    subject: &Shape<D>,
    index: &ClosestPointIndex<D>,
    params: &RunParams,
) -> Delivered {
    let finite = mesh.nodes.iter().flatten().all(|v| v.is_finite());
    let boundary = boundary_surface(mesh);
    if !finite || boundary.facets.is_empty() {
        let nan = f64::NAN;
        return Delivered {
            distances: SurfaceDistances {
                rms: nan,
                p95: nan,
                max: nan,
                share_beyond: nan,
            },
            element_size: nan,
            finite,
        };
    }
    let element_size = boundary.median_edge_length();
    let open_outline = D == 2 && subject.facets.len() < subject.points.len();
    let two_way = !params.fit.partial && !open_outline;
    Delivered {
        distances: surface_distances(&boundary, subject, index, two_way, element_size),
        element_size,
        finite,
    }
}

/// How much farther than the fitted instance a delivered mesh may be (two-way RMS), in element
/// sizes: its faces' chord error on a curved surface.
const CHORD_ALLOWANCE_ELEMENTS: f64 = 0.1;

/// Whether a delivered mesh at the two-way RMS distance `mesh_rms` from its subject is farther
/// than the fitted instance it was morphed to (`instance_rms`): the morph and the boundary fit
/// are there to carry the fit to the mesh, and such a mesh has lost what the fit found. Its
/// linear faces may cut the chords of a curved surface the instance's finer facets follow: up
/// to [`CHORD_ALLOWANCE_ELEMENTS`] of its `element_size` farther is that (the chord error of a
/// feature about one element round), not a loss. Subject units; NaN is never farther.
fn farther_than_fit(mesh_rms: f64, instance_rms: f64, element_size: f64) -> bool {
    mesh_rms > instance_rms + CHORD_ALLOWANCE_ELEMENTS * element_size
}

/// The checks of `success` that `report` fails: `fit`, `mesh_distance`,
/// `mesh_farther_than_fit`, `mesh_quality`.
fn failed_checks(report: &SubjectReport, finite: bool, params: &RunParams) -> Vec<String> {
    let mut failed = Vec::new();
    if !within(report.rms_distance_relative, params.max_instance_distance) {
        failed.push("fit".to_string());
    }
    if !within(report.mesh_rms_distance_relative, params.max_mesh_distance) {
        failed.push("mesh_distance".to_string());
    }
    if farther_than_fit(
        report.mesh_rms_distance,
        report.rms_distance,
        report.element_size,
    ) {
        failed.push("mesh_farther_than_fit".to_string());
    }
    let below_bound =
        params.repair.is_some() && !within(report.repair_bound, report.scaled_jacobian_min);
    if !finite || report.inverted_elements > 0 || below_bound {
        failed.push("mesh_quality".to_string());
    }
    failed
}

/// The instance's points with a partner on a partial subject, the cap of an atlas built on a
/// common cut left out (it is not anatomy).
fn partnered_anatomy<const D: usize>(atlas: &Atlas<D>, fit: &FitResult<D>) -> Vec<bool> {
    let mut counted = fit.corresponded.clone();
    for &f in &atlas.cut_facets {
        for &i in atlas.facets.get(f).into_iter().flatten() {
            if let Some(c) = counted.get_mut(i) {
                *c = false;
            }
        }
    }
    counted
}

/// The fitted instance against its subject (indexed by `index`): the two-way RMS distance
/// ([`two_way_rms`]) and the distance of every subject point to the instance, from one
/// index of the instance; of a `partial` subject, only the instance's points with a partner
/// ([`partnered_anatomy`]) go into the distance from the instance. Subject units.
fn fit_distances<const D: usize>(
    atlas: &Atlas<D>,
    fit: &FitResult<D>,
    subject: &Shape<D>,
    index: &ClosestPointIndex<D>,
    partial: bool,
) -> (f64, Vec<f64>) {
    let instance = &fit.instance;
    let on_instance = ClosestPointIndex::new(instance, &atlas.facets);
    let to_instance: Vec<f64> = subject
        .points
        .iter()
        .map(|p| on_instance.closest(p).dist2.sqrt())
        .collect();
    let mean_sq = |v: &mut dyn Iterator<Item = f64>, n: usize| v.sum::<f64>() / n.max(1) as f64;
    let counted = partial.then(|| partnered_anatomy(atlas, fit));
    let counts = |i: usize| {
        counted
            .as_ref()
            .is_none_or(|c| c.get(i).copied().unwrap_or(true))
    };
    let forward = mean_sq(
        &mut (0..instance.len())
            .filter(|&i| counts(i))
            .map(|i| index.closest(&instance[i]).dist2),
        (0..instance.len()).filter(|&i| counts(i)).count(),
    );
    let backward = mean_sq(&mut to_instance.iter().map(|d| d * d), to_instance.len());
    ((0.5 * (forward + backward)).sqrt(), to_instance)
}

/// The misfit guard: the fit did not converge when the instance stays farther from the
/// subject than `params.max_misfit` of the subject's robust size
/// ([`Shape::robust_diagonal`], which a stray vertex or a far fragment does not inflate),
/// by the two-way RMS distance (`rms`), or when the 95th percentile of the subject's
/// points' distances to the instance (`d`) exceeds twice that (a part of the subject the instance
/// does not reach). A partial subject (`--partial`) misses parts of the model: only its own
/// points' distances count.
fn check_misfit<const D: usize>(
    subject: &Shape<D>,
    rms: f64,
    mut d: Vec<f64>,
    params: &RunParams,
) -> Result<()> {
    let size = subject.robust_diagonal();
    let one_way = (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
    d.sort_by(f64::total_cmp);
    let p95 = d
        .get(((d.len().max(1) - 1) as f64 * 0.95).round() as usize)
        .copied()
        .unwrap_or(f64::NAN);
    let rms = if params.fit.partial { one_way } else { rms };
    let (rel, rel95) = (rms / size, p95 / size);
    if !within(rel, params.max_misfit) || !within(rel95, 2.0 * params.max_misfit) {
        return Err(Error::NotConverged {
            name: subject.name.clone(),
            message: format!(
                "the fitted model instance stays {rms:.4} (RMS distance; {:.1} % of the \
                 subject's size) from the subject, 95 % of the subject within {p95:.4} ({:.1} \
                 %), above the bound of {:.1} % (RMS) or {:.1} % (95th percentile) \
                 (--max-misfit): the subject lies outside what the model can represent",
                100.0 * rel,
                100.0 * rel95,
                100.0 * params.max_misfit,
                200.0 * params.max_misfit
            ),
        });
    }
    Ok(())
}

/// Whether `value <= bound` (false when either is NaN).
fn within(value: f64, bound: f64) -> bool {
    value <= bound
}

/// The misfit guard of a fit at the two-way RMS distance `rms` (its subject's distances to
/// the instance `to_instance`), and the mirror check: a refused subject whose mirror image
/// fits clearly better is said to be mirrored; an accepted one far from its fit is checked
/// too, with a warning. Returns the mirror's RMS distance (when it was fitted) and the
/// warnings.
///
/// # Errors
/// [`Error::NotConverged`] from `check_misfit`, naming the mirror where it fits better.
fn checked_misfit<const D: usize>(
    atlas: &Atlas<D>,
    fitter: &Fitter<D>,
    subject: &Shape<D>,
    params: &RunParams,
    (rms, to_instance): (f64, Vec<f64>),
) -> Result<(Option<f64>, Vec<String>)> {
    let rel = rms / subject.bbox_diagonal();
    if let Err(e) = check_misfit(subject, rms, to_instance, params) {
        // A refused subject may be a mirror image: say so when its mirror fits clearly better.
        return Err(
            match (e, mirrored_fit_rms(atlas, fitter, subject, params)) {
                (Error::NotConverged { name, message }, Some(m)) if m < MIRROR_BETTER * rms => {
                    Error::NotConverged {
                        name,
                        message: format!(
                            "{message}; its mirror image fits at an RMS distance of {m:.4}: the \
                         subject may be mirrored (mirror it, or use an atlas of the other side)"
                        ),
                    }
                }
                (e, _) => e,
            },
        );
    }
    let mut warnings = Vec::new();
    let mirrored_rms = if rel > MIRROR_CHECK_ABOVE {
        mirrored_fit_rms(atlas, fitter, subject, params)
    } else {
        None
    };
    if let Some(m) = mirrored_rms
        && m < MIRROR_BETTER * rms
    {
        warnings.push(format!(
            "the subject may be mirrored: its mirror image fits the model at an RMS distance \
             of {m:.4}, against {rms:.4} as given (mirror it, or use an atlas of the other side)"
        ));
    }
    Ok((mirrored_rms, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{ElementKind, FeMesh};

    /// A mesh is farther than its fit beyond the chord error of its faces only.
    #[test]
    fn a_mesh_farther_than_its_fit_beyond_its_chord_error_fails() {
        assert!(!farther_than_fit(0.18, 0.06, 5.0));
        assert!(!farther_than_fit(0.10, 0.15, 1.0));
        assert!(farther_than_fit(2.3, 1.4, 2.0));
        assert!(farther_than_fit(0.5, 0.3, 1.0));
        assert!(!farther_than_fit(f64::NAN, 0.3, 1.0));
    }

    /// A mesh with an inverted element, a non-finite node or no element is refused, naming
    /// the subject and what is wrong; a valid one passes.
    #[test]
    fn meshes_no_solver_could_use_are_refused() {
        let subject = Shape::<2>::polyline("s", vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], true);
        let square = FeMesh::<2> {
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            kind: ElementKind::Quad4,
            connectivity: vec![0, 1, 2, 3],
            sets: Default::default(),
        };
        let check = |m: &FeMesh<2>| {
            let q = crate::mesh::quality::summarize(&crate::mesh::quality::mesh_quality(m));
            check_valid(&subject, m, &q, &RunParams::default())
        };
        assert!(check(&square).is_ok());
        let mut inverted = square.clone();
        inverted.connectivity = vec![0, 3, 2, 1];
        let e = check(&inverted).unwrap_err().to_string();
        assert!(
            e.contains("s:") && e.contains("1 inverted") && e.contains("not written"),
            "{e}"
        );
        let mut nan = square.clone();
        nan.nodes[2][0] = f64::NAN;
        let e = check(&nan).unwrap_err().to_string();
        assert!(e.contains("NaN or infinite"), "{e}");
        let mut empty = square;
        empty.connectivity.clear();
        assert!(
            check(&empty)
                .unwrap_err()
                .to_string()
                .contains("no elements")
        );
    }
}

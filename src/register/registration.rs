//! Pairwise registration by a B-spline FFD minimizing eq. 2, and the correspondence by
//! projection along the normals (section 2.1).

use super::pre_align::pre_align_scored;
use crate::error::{Error, Result};
use crate::ffd::FfdSystem;
use crate::geometry::{
    ClosestPointIndex, Point, QueryMemo, REFERENCE_POINTS, Shape, Similarity, SurfacePoint, dist2,
    dot, project_along_normals, vertex_normals,
};

/// Parameters of the registration (eq. 2).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RegisterParams {
    /// Control points along the longest axis of the template's bounding box; the other axes
    /// get the same spacing (paper, hands: 20 × 20).
    pub grid: usize,
    /// First smoothing weight `alpha` (paper, hands: 30 000).
    pub alpha_start: f64,
    /// The schedule stops once `alpha` is below this (paper: 10).
    pub alpha_stop: f64,
    /// Correspondence updates per `alpha`; then `alpha` halves (paper: 8).
    pub iterations_per_alpha: usize,
    /// Landmark weight `beta` (paper: 5), for `N = 2001` points; scaled by `N / 2001`.
    pub beta: f64,
    /// An `alpha` ends early once no point moved more than this fraction of the template's
    /// extent in one update (the correspondences have settled); 0 runs every update.
    pub tolerance: f64,
    /// Starting rotations of the pre-alignment without landmarks (2D; 3D uses the 4
    /// proper sign choices of the principal axes).
    pub starts: usize,
}

impl RegisterParams {
    /// The defaults for shapes of dimension `dim`: the paper's 20 control points per axis in
    /// 2D; 16 along the longest axis in 3D (the paper gives no 3D lattice; on the femur pairs
    /// 16 finds correspondences within 2-4 % of 20's error in half the time, README).
    pub fn for_dimension(dim: usize) -> Self {
        RegisterParams {
            grid: if dim == 3 { 16 } else { 20 },
            ..Self::default()
        }
    }
}

impl Default for RegisterParams {
    /// The paper's hand parameters (2D).
    fn default() -> Self {
        RegisterParams {
            grid: 20,
            alpha_start: 30_000.0,
            alpha_stop: 10.0,
            iterations_per_alpha: 8,
            beta: 5.0,
            tolerance: 1e-4,
            starts: 8,
        }
    }
}

/// The largest two-way RMS distance after the ICP pre-alignment, as a share of the target's
/// RMS radius, for which the registration goes on. Measured: the IMM hands, the femurs and
/// geomstats' 650 cells stay below 0.34 (an ellipse against a spiral, a cross or a line:
/// 0.25-0.37), so this guards against gross failures only; the misfit of every pair is in
/// [`Registration::misfit`].
pub const MAX_ALIGNMENT_MISFIT: f64 = 0.5;

/// The result of registering a template to a target.
#[derive(Clone, Debug)]
pub struct Registration<const D: usize> {
    /// Pre-alignment: template frame to target frame.
    pub similarity: Similarity<D>,
    /// The template's points after the FFD, target frame.
    pub deformed: Vec<Point<D>>,
    /// The deformed template projected onto the target along its normals: for every
    /// template point, its corresponding point on the target.
    pub correspondence: Vec<SurfacePoint<D>>,
    /// Mean squared distance from the deformed template to the target after each update.
    pub history: Vec<f64>,
    /// Without landmarks, the two-way RMS distance after the pre-alignment over the target's
    /// RMS radius (0 with landmarks).
    pub misfit: f64,
}

/// How far a registered template lies from its target, both ways (target units): the
/// deformed template (its surface) against the target's.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RegistrationResiduals {
    /// Two-way RMS distance.
    pub rms: f64,
    /// The larger of the two directions' 95th percentiles.
    pub p95: f64,
    /// The largest distance either way.
    pub max: f64,
    /// RMS distance from the deformed template's points to the target.
    pub template_to_target_rms: f64,
    /// `rms` over the target's bounding-box diagonal.
    pub rms_relative: f64,
    /// `p95` over the target's bounding-box diagonal.
    pub p95_relative: f64,
}

/// A registration whose two-way 95th-percentile residual exceeds this share of the target's
/// bounding-box diagonal is reported with a warning (the template did not reach part of the
/// target, or reached past it).
pub const REGISTRATION_WARNING_P95: f64 = 0.03;

impl<const D: usize> Registration<D> {
    /// The residuals of the registration of `template` to `target` (indexed by `index`): the
    /// deformed template's surface against the target's, both ways.
    pub fn residuals(
        &self,
        template: &Shape<D>,
        target: &Shape<D>,
        index: &ClosestPointIndex<D>,
    ) -> RegistrationResiduals {
        let deformed = Shape {
            name: template.name.clone(),
            points: self.deformed.clone(),
            facets: template.facets.clone(),
            landmarks: Vec::new(),
        };
        let d = crate::geometry::surface_distances(&deformed, target, index, true, f64::INFINITY);
        let one_way = (self
            .deformed
            .iter()
            .map(|p| index.closest(p).dist2)
            .sum::<f64>()
            / self.deformed.len().max(1) as f64)
            .sqrt();
        let diag = target.bbox_diagonal();
        RegistrationResiduals {
            rms: d.rms,
            p95: d.p95,
            max: d.max,
            template_to_target_rms: one_way,
            rms_relative: d.rms / diag,
            p95_relative: d.p95 / diag,
        }
    }

    /// The target resampled at the template's points: the template's connectivity and
    /// landmarks, the corresponding points' positions. Named after the target.
    pub fn resampled(&self, template: &Shape<D>, target: &Shape<D>) -> Shape<D> {
        Shape {
            name: target.name.clone(),
            points: self.correspondence.iter().map(|c| c.point).collect(),
            facets: template.facets.clone(),
            landmarks: template.landmarks.clone(),
        }
    }
}

/// Refuses a pair that cannot be registered: invalid shapes, point sets, unpaired landmarks.
fn check_pair<const D: usize>(template: &Shape<D>, target: &Shape<D>) -> Result<()> {
    template.validate()?;
    target.validate()?;
    if template.facets.is_empty() || target.facets.is_empty() {
        return Err(Error::Population(format!(
            "registration of {} to {}: both need segments/facets",
            template.name, target.name
        )));
    }
    if !template.landmarks.is_empty()
        && !target.landmarks.is_empty()
        && template.landmarks.len() != target.landmarks.len()
    {
        return Err(Error::Population(format!(
            "{} has {} landmarks but {} has {}; landmarks must pair up",
            template.name,
            template.landmarks.len(),
            target.name,
            target.landmarks.len()
        )));
    }
    Ok(())
}

/// The pre-alignment of `template` to `target` and its misfit, refused when it is not finite
/// or its misfit exceeds [`MAX_ALIGNMENT_MISFIT`].
fn aligned<const D: usize>(
    template: &Shape<D>,
    target: &Shape<D>,
    target_index: &ClosestPointIndex<D>,
    starts: usize,
) -> Result<(Similarity<D>, f64)> {
    let (sim, misfit) = pre_align_scored(template, target, target_index, starts)?;
    let finite = sim.s.is_finite()
        && sim.s > 0.0
        && sim
            .t
            .iter()
            .chain(sim.r.iter().flatten())
            .all(|v| v.is_finite());
    if !finite || misfit.is_nan() || misfit > MAX_ALIGNMENT_MISFIT {
        return Err(Error::Population(format!(
            "the ICP pre-alignment could not align {} to {}: after the best of its starts the \
             two-way RMS distance is {:.0} % of the target's RMS radius (at most {:.0} % is \
             accepted); check that the shapes show the same structure, or give landmarks",
            template.name,
            target.name,
            100.0 * misfit,
            100.0 * MAX_ALIGNMENT_MISFIT
        )));
    }
    Ok((sim, misfit))
}

/// The data and landmark terms of eq. 2 folded per point: point `j`'s weight `1 + beta` when it
/// is a template landmark (1 otherwise) and the target landmark it is drawn to.
struct LandmarkPull<const D: usize> {
    weight: Vec<f64>,
    target: Vec<Option<Point<D>>>,
}

impl<const D: usize> LandmarkPull<D> {
    fn of(template: &Shape<D>, target: &Shape<D>, beta: f64) -> Self {
        let n = template.points.len();
        let mut weight = vec![1.0; n];
        let mut to: Vec<Option<Point<D>>> = vec![None; n];
        if template.landmarks.len() == target.landmarks.len() && !target.landmarks.is_empty() {
            for (&a, &b) in template.landmarks.iter().zip(&target.landmarks) {
                weight[a] += beta;
                to[a] = Some(target.points[b]);
            }
        }
        LandmarkPull { weight, target: to }
    }

    /// Each deformed point's target: its closest point on the target (itself where the sides
    /// face each other: facing sides do not pull), averaged with its landmark by the weights;
    /// and the mean squared closest-point distance.
    fn targets(
        &self,
        deformed: &[Point<D>],
        facets: &[[usize; D]],
        target_index: &ClosestPointIndex<D>,
        memos: &mut [QueryMemo<D>],
    ) -> (Vec<Point<D>>, f64) {
        let normals = vertex_normals(deformed, facets);
        let mut ms = 0.0;
        let targets = (0..deformed.len())
            .map(|j| {
                let c = target_index.closest_memo(&deformed[j], &mut memos[j]);
                ms += c.dist2;
                let facing = target_index
                    .normal_at(&c)
                    .is_some_and(|nt| dot(nt, normals[j]) < 0.5);
                let c_point = if facing { deformed[j] } else { c.point };
                let w = self.weight[j];
                match self.target[j] {
                    Some(q) => std::array::from_fn(|d| (c_point[d] + (w - 1.0) * q[d]) / w),
                    None => c_point,
                }
            })
            .collect();
        (targets, ms / deformed.len().max(1) as f64)
    }
}

/// Registers `template` to `target` (section 2.1, eq. 2): pre-alignment ([`pre_align`](super::pre_align)),
/// then, with the template's points `p_j` fixed as the FFD's sources, for each `alpha` of the
/// schedule `iterations_per_alpha` times: the closest point `c_j` on the target of every
/// deformed point `f(p_j)`, and the control points minimizing
/// `Σ_j ||f(p_j) - c_j||² + alpha E_smooth + beta Σ_l ||f(p_l) - q_l||²` (the last over the
/// landmark pairs), a sparse linear least-squares problem (faer's sparse Cholesky). Last, the
/// deformed template is projected onto the target along its normals.
///
/// Units: `E_smooth` is in lattice units (see [`crate::ffd`]) and positions in units of the
/// lattice's extent, so `alpha` means the same for a unit hand and a femur in mm; `beta` is
/// relative to the data term and scaled by `N / 2001` (the paper's hands had 2001 points).
/// Pairs whose normals differ by more than 60° (facing sides) do not pull, as in the fit.
pub fn register<const D: usize>(
    template: &Shape<D>,
    target: &Shape<D>,
    target_index: &ClosestPointIndex<D>,
    params: &RegisterParams,
) -> Result<Registration<D>> {
    check_pair(template, target)?;
    let (sim, misfit) = aligned(template, target, target_index, params.starts)?;
    let sources: Vec<Point<D>> = template.points.iter().map(|p| sim.apply(p)).collect();
    let n = sources.len();
    let pull = LandmarkPull::of(template, target, params.beta * n as f64 / REFERENCE_POINTS);
    let weight = &pull.weight;
    let mut deformed = sources.clone();
    let mut history = Vec::new();
    let mut memos = vec![QueryMemo::default(); n];
    let mut alpha = params.alpha_start;
    if params.grid < 4 {
        return Err(Error::Parameter(format!(
            "registration grid {} is below 4 control points per axis",
            params.grid
        )));
    }
    let extent = {
        let (lo, hi) = crate::geometry::bounding_box(&sources);
        (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max)
    };
    let lattice = crate::ffd::Lattice::around_isotropic(&sources, params.grid, 0.1);
    let mut system = FfdSystem::on_lattice(lattice, &sources, Some(weight))?;
    loop {
        let fit = system.factor(alpha)?;
        for _ in 0..params.iterations_per_alpha.max(1) {
            let (targets, ms) = pull.targets(&deformed, &template.facets, target_index, &mut memos);
            history.push(ms);
            let f = fit.solve(&targets);
            let next: Vec<Point<D>> = sources.iter().map(|p| f.apply(p)).collect();
            let moved = next
                .iter()
                .zip(&deformed)
                .map(|(a, b)| dist2(*a, *b))
                .fold(0.0, f64::max)
                .sqrt();
            deformed = next;
            if moved < params.tolerance * extent {
                break;
            }
        }
        if alpha < params.alpha_stop {
            break;
        }
        alpha *= 0.5;
    }
    let correspondence = project_along_normals(
        &deformed,
        &template.facets,
        target_index,
        false,
        Some(&mut memos),
    );
    Ok(Registration {
        similarity: sim,
        deformed,
        correspondence,
        history,
        misfit,
    })
}

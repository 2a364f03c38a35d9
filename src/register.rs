//! Pairwise registration of a template to a target that is not in correspondence with it
//! (section 2.1): pre-alignment, a cubic B-spline FFD minimizing eq. 2 with an annealed
//! smoothing weight, and the correspondence by projection along the normals.
//!
//! Frames: the template in its own frame is first brought to the target's frame by the
//! pre-alignment similarity; the FFD then deforms it there. All outputs are in the target's
//! frame and units.

use crate::error::{Error, Result};
use crate::ffd::FfdSystem;
use crate::fit::project_along_normals;
use crate::geometry::{
    ClosestPointIndex, Point, QueryMemo, Shape, Similarity, SurfacePoint, centroid, dist2, dot,
    sub, vertex_normals,
};
use crate::procrustes::fit_similarity;

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

impl<const D: usize> Registration<D> {
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

/// Pre-alignment of `template` to `target`: the similarity of the landmark pairs when both
/// have the same number of landmarks; otherwise centroids and RMS radii matched, `starts`
/// rotations (2D) or the principal axes (3D) tried, each refined by a similarity ICP on the
/// closest points both ways, and the one of least two-way mean squared distance kept.
pub fn pre_align<const D: usize>(
    template: &Shape<D>,
    target: &Shape<D>,
    target_index: &ClosestPointIndex<D>,
    starts: usize,
) -> Result<Similarity<D>> {
    pre_align_scored(template, target, target_index, starts).map(|(s, _)| s)
}

/// [`pre_align`] and, without landmarks, the relative misfit of the alignment: the two-way
/// RMS distance between the aligned template and the target over the target's RMS radius
/// (0 when the landmarks aligned them).
fn pre_align_scored<const D: usize>(
    template: &Shape<D>,
    target: &Shape<D>,
    target_index: &ClosestPointIndex<D>,
    starts: usize,
) -> Result<(Similarity<D>, f64)> {
    if !template.landmarks.is_empty() && template.landmarks.len() == target.landmarks.len() {
        let src: Vec<Point<D>> = template
            .landmarks
            .iter()
            .map(|&i| template.points[i])
            .collect();
        let dst: Vec<Point<D>> = target.landmarks.iter().map(|&i| target.points[i]).collect();
        return Ok((fit_similarity(&src, &dst, None), 0.0));
    }
    let ct = centroid(&template.points);
    let cs = centroid(&target.points);
    let rms = |p: &[Point<D>], c: Point<D>| {
        (p.iter().map(|q| dist2(*q, c)).sum::<f64>() / p.len() as f64).sqrt()
    };
    // A shape of no extent (numerically: below 1e-9 of its coordinates' size) has no pose.
    for (s, c) in [(template, ct), (target, cs)] {
        let size = s
            .points
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let r = rms(&s.points, c);
        if r.is_nan() || r <= 1e-9 * size {
            return Err(Error::Population(format!(
                "the ICP pre-alignment could not align {} to {}: {} has no extent (RMS radius \
                 {r:.3e} at coordinates of size {size:.3e})",
                template.name, target.name, s.name
            )));
        }
    }
    let s0 = rms(&target.points, cs) / rms(&template.points, ct).max(f64::MIN_POSITIVE);
    let rotations = start_rotations(&template.points, ct, &target.points, cs, starts);
    let sample = |n: usize, k: usize| -> Vec<usize> {
        let step = (n / k).max(1);
        (0..n).step_by(step).collect()
    };
    // Backward pairs are searched in the template's frame (a similarity keeps closest
    // points): its index is built once.
    let tindex = ClosestPointIndex::new(&template.points, &template.facets);
    // Similarity ICP from `sim` on the template points `ts` and target points `ss`, for at
    // most `iterations` updates; returns the two-way mean squared distance and the pose.
    let icp = |mut sim: Similarity<D>, ts: &[usize], ss: &[usize], iterations: usize| {
        let mut score = f64::INFINITY;
        let mut forward_memo = vec![QueryMemo::default(); ts.len()];
        let mut backward_memo = vec![QueryMemo::default(); ss.len()];
        let mut src = Vec::with_capacity(ts.len() + ss.len());
        let mut dst = Vec::with_capacity(ts.len() + ss.len());
        for _ in 0..iterations {
            src.clear();
            dst.clear();
            let mut fwd = 0.0;
            for (&j, memo) in ts.iter().zip(&mut forward_memo) {
                let c = target_index.closest_memo(&sim.apply(&template.points[j]), memo);
                fwd += c.dist2;
                src.push(template.points[j]);
                dst.push(c.point);
            }
            let mut bwd = 0.0;
            for (&i, memo) in ss.iter().zip(&mut backward_memo) {
                let c = tindex.closest_memo(&sim.apply_inverse(&target.points[i]), memo);
                bwd += c.dist2 * sim.s * sim.s;
                src.push(c.point);
                dst.push(target.points[i]);
            }
            let previous = score;
            score = 0.5 * (fwd / ts.len() as f64 + bwd / ss.len() as f64);
            sim = fit_similarity(&src, &dst, None);
            // Settled: the closest points no longer change the alignment's error.
            if (previous - score).abs() <= 1e-4 * score {
                break;
            }
        }
        (score, sim)
    };
    // Every start on a rough sampling, a few updates each; the best two go on to the
    // finer sampling until settled.
    let (rough_t, rough_s) = (
        sample(template.points.len(), ROUGH_POINTS),
        sample(target.points.len(), ROUGH_POINTS),
    );
    let mut rough: Vec<(f64, Similarity<D>)> = rotations
        .into_iter()
        .map(|r| {
            icp(
                Similarity::centred(s0, r, &ct, &cs),
                &rough_t,
                &rough_s,
                ROUGH_ITERATIONS,
            )
        })
        .collect();
    rough.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (ts, ss) = (
        sample(template.points.len(), FINE_POINTS),
        sample(target.points.len(), FINE_POINTS),
    );
    let best = rough
        .into_iter()
        .take(FINE_STARTS)
        .map(|(_, sim)| icp(sim, &ts, &ss, 30))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let radius = rms(&target.points, cs);
    best.map(|(score, sim)| (sim, score.sqrt() / radius.max(f64::MIN_POSITIVE)))
        .ok_or_else(|| Error::Numerical(format!("{}: no pre-alignment start", target.name)))
}

/// Starting rotations of a pre-alignment of `template` (centroid `ct`) to `target` (centroid
/// `cs`): in 2D `starts` angles evenly round the circle; in 3D the four proper rotations that
/// map the template's principal axes onto the target's (the signs of the axes are unknown),
/// and the identity.
pub(crate) fn start_rotations<const D: usize>(
    template: &[Point<D>],
    ct: Point<D>,
    target: &[Point<D>],
    cs: Point<D>,
    starts: usize,
) -> Vec<[[f64; D]; D]> {
    if D == 2 {
        return (0..starts.max(1))
            .map(|k| {
                Similarity::<D>::planar_rotation(
                    std::f64::consts::TAU * k as f64 / starts.max(1) as f64,
                )
                .r
            })
            .collect();
    }
    let a = principal_axes(template, ct);
    let b = principal_axes(target, cs);
    let mut r: Vec<[[f64; D]; D]> = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ]
    .iter()
    .map(|sg| {
        // R maps template axis k to sign_k × target axis k: R = B diag(sg) A^T.
        std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..D).map(|k| b[k][i] * sg[k] * a[k][j]).sum())
        })
    })
    .collect();
    r.push(Similarity::<D>::identity().r);
    r
}

/// Principal axes (rows, unit, right-handed) of a point set about `c`, by Jacobi sweeps on
/// the 3 × 3 covariance; for `D = 2` the first two rows of the identity are returned.
fn principal_axes<const D: usize>(points: &[Point<D>], c: Point<D>) -> [[f64; D]; D] {
    let mut a = [[0.0; D]; D];
    for p in points {
        let d = sub(*p, c);
        for i in 0..D {
            for j in 0..D {
                a[i][j] += d[i] * d[j];
            }
        }
    }
    let mut v: [[f64; D]; D] =
        std::array::from_fn(|i| std::array::from_fn(|j| f64::from(u8::from(i == j))));
    for _ in 0..50 {
        for p in 0..D {
            for q in p + 1..D {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let th = 0.5 * (2.0 * a[p][q]).atan2(a[q][q] - a[p][p]);
                let (s, co) = th.sin_cos();
                for k in 0..D {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = co * akp - s * akq;
                    a[k][q] = s * akp + co * akq;
                }
                for k in 0..D {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = co * apk - s * aqk;
                    a[q][k] = s * apk + co * aqk;
                }
                for k in 0..D {
                    let (vkp, vkq) = (v[k][p], v[k][q]);
                    v[k][p] = co * vkp - s * vkq;
                    v[k][q] = s * vkp + co * vkq;
                }
            }
        }
    }
    // Columns of v are eigenvectors; order by decreasing eigenvalue.
    let mut idx: Vec<usize> = (0..D).collect();
    idx.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let mut axes: [[f64; D]; D] = std::array::from_fn(|r| std::array::from_fn(|k| v[k][idx[r]]));
    if D == 3 {
        // Right-handed: third = first × second.
        let (x, y) = (axes[0], axes[1]);
        axes[2][0] = x[1] * y[2] - x[2] * y[1];
        axes[2][1] = x[2] * y[0] - x[0] * y[2];
        axes[2][2] = x[0] * y[1] - x[1] * y[0];
    }
    axes
}

/// Principal axes of `points` about their centroid (rows, decreasing variance, right-handed
/// in 3D).
pub(crate) fn principal_axes_of<const D: usize>(points: &[Point<D>]) -> [[f64; D]; D] {
    principal_axes(points, centroid(points))
}

/// Points per shape of the ICP pre-alignment's rough stage, where every start rotation
/// runs [`ROUGH_ITERATIONS`] updates; then the best [`FINE_STARTS`] go on with
/// [`FINE_POINTS`] points per shape until settled.
const ROUGH_POINTS: usize = 100;
const ROUGH_ITERATIONS: usize = 8;
const FINE_STARTS: usize = 2;
const FINE_POINTS: usize = 400;

/// Registers `template` to `target` (section 2.1, eq. 2): pre-alignment ([`pre_align`]),
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
    let (sim, misfit) = pre_align_scored(template, target, target_index, params.starts)?;
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
    let sources: Vec<Point<D>> = template.points.iter().map(|p| sim.apply(p)).collect();
    let n = sources.len();
    let beta = params.beta * n as f64 / crate::fit::REFERENCE_POINTS;
    let paired = template.landmarks.len() == target.landmarks.len() && !target.landmarks.is_empty();
    let mut weight = vec![1.0; n];
    let mut landmark_target: Vec<Option<Point<D>>> = vec![None; n];
    if paired {
        for (&a, &b) in template.landmarks.iter().zip(&target.landmarks) {
            weight[a] += beta;
            landmark_target[a] = Some(target.points[b]);
        }
    }
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
    let mut system = FfdSystem::on_lattice(lattice, &sources, Some(&weight))?;
    loop {
        let fit = system.factor(alpha)?;
        for _ in 0..params.iterations_per_alpha.max(1) {
            let normals = vertex_normals(&deformed, &template.facets);
            let mut ms = 0.0;
            let targets: Vec<Point<D>> = (0..n)
                .map(|j| {
                    let c = target_index.closest_memo(&deformed[j], &mut memos[j]);
                    ms += c.dist2;
                    // Facing sides do not pull: the point is asked to stay.
                    let facing = target_index
                        .normal_at(&c)
                        .is_some_and(|nt| dot(nt, normals[j]) < 0.5);
                    let c_point = if facing { deformed[j] } else { c.point };
                    match landmark_target[j] {
                        Some(q) => std::array::from_fn(|d| {
                            (c_point[d] + (weight[j] - 1.0) * q[d]) / weight[j]
                        }),
                        None => c_point,
                    }
                })
                .collect();
            history.push(ms / n as f64);
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

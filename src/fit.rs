//! Fitting the atlas to a subject: shape instantiation and projection (section 3,
//! Algorithm 1, eq. 5-8).
//!
//! Frames: the model lives in the atlas's reference frame; the subject in its own frame
//! (its file's units). `t_{R,T,s}` maps reference to subject.

use crate::error::{Error, Result};
use crate::geometry::{
    ClosestPointIndex, Point, QueryMemo, Shape, Similarity, SurfacePoint, add, centroid, dist2,
    dot, facet_normal, norm, scale, sub, vertex_normals,
};
use crate::model::Atlas;
use faer::Mat;
use faer::linalg::solvers::Solve;

/// Parameters of Algorithm 1.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitParams {
    /// First regularization weight `gamma_1` (paper: 0.3).
    pub gamma_start: f64,
    /// Factor from one `gamma` to the next (paper: 1/4).
    pub gamma_factor: f64,
    /// The schedule stops after the first `gamma` below this (paper: 0.008).
    pub gamma_stop: f64,
    /// Inner loop ends when the change of `w` (and of the pose) is below this (paper: 1e-6).
    /// `||Δw||` is taken as for the paper's 2001 points, `||Δw|| sqrt(2001 / n)` for an atlas
    /// of `n` points, so that the tolerance does not tighten as the atlas gets finer.
    pub tolerance: f64,
    /// Cap on correspondence updates per `gamma`.
    pub max_iterations: usize,
    /// Add the subject-to-instance closest points to `E_d` (see [`Fitter::fit`]).
    pub symmetric: bool,
    /// Starting rotations tried by the pre-alignment in 2D (evenly spaced; 1 = identity
    /// only). In 3D the starts are the principal-axes rotations and the identity.
    pub starts: usize,
    /// Coarse fits run from the best distinct pre-alignments; the least two-way distance wins.
    pub full_starts: usize,
    /// Points per direction (model and subject) used by the pre-alignment and the coarse
    /// stage; the last `gamma` runs on all points. 0 = all points throughout. The coarse
    /// model (see [`Fitter::fit`]) is built for the default value; with another, the coarse
    /// stage samples the full model.
    pub coarse_points: usize,
    /// The subject may miss parts (paper, fig. 21-22): `E_d` takes only the distances from
    /// the subject's points to the instance (weighted as both directions of a symmetric fit
    /// together, so that `gamma` acts alike), and model points that have no partner on the
    /// subject (`FitResult::corresponded`) are left out of the morph's data term.
    #[serde(default)]
    pub partial: bool,
}

/// Pose-only updates per start rotation in the pre-alignment.
const PRE_ALIGNMENT_ITERATIONS: usize = 6;

/// Pose-only updates after which the pre-alignment drops the starts whose two-way distance
/// is [`PRE_PRUNE_FACTOR`] times the best start's. The factor is wider than the
/// [`PRUNE_FACTOR`] between the coarse fits: the pre-alignment has no mode to close a gap.
const PRE_PRUNE_AFTER: usize = 2;
const PRE_PRUNE_FACTOR: f64 = 10.0;

/// Cap on the updates per `gamma` of the coarse stage (the final stage has
/// [`FitParams::max_iterations`]).
const COARSE_MAX_ITERATIONS: usize = 20;

/// The coarse stage stops each `gamma` at this multiple of the tolerance; the last `gamma`,
/// on all points, meets the tolerance itself.
const COARSE_TOLERANCE_FACTOR: f64 = 100.0;

/// Pairs whose normals (instance and subject) make an angle above 60° are left out of the
/// update: they join facing sides (a finger's side and its neighbour's), the pull that traps a
/// fit in a local minimum. Up to 41° (cosine 0.75) they weigh fully.
const COMPATIBLE_NORMALS_COS: f64 = 0.5;
const FULL_WEIGHT_COS: f64 = 0.75;

/// Root of the weight of a pair whose normals make an angle of cosine `cos`: 1 up to
/// [`FULL_WEIGHT_COS`], down to 0 at [`COMPATIBLE_NORMALS_COS`] (smoothly, so that a pair
/// crossing the bound does not make the next update jump).
fn compatibility(cos: f64) -> f64 {
    let t = ((cos - COMPATIBLE_NORMALS_COS) / (FULL_WEIGHT_COS - COMPATIBLE_NORMALS_COS))
        .clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The angle of the rotation `a^T b` (radians; 2D and 3D).
fn rotation_angle<const D: usize>(a: &[[f64; D]; D], b: &[[f64; D]; D]) -> f64 {
    let tr: f64 = (0..D)
        .map(|i| (0..D).map(|k| a[k][i] * b[k][i]).sum::<f64>())
        .sum();
    let c = if D == 2 { tr / 2.0 } else { (tr - 1.0) / 2.0 };
    c.clamp(-1.0, 1.0).acos()
}

/// After each `gamma`, starts whose two-way mean squared distance exceeds the best one's
/// by this factor are dropped.
const PRUNE_FACTOR: f64 = 4.0;
const COARSE_MODEL_FACTOR: usize = 4;

/// Updates after which a start of the coarse stage gives up a `gamma` when its two-way
/// distance is still [`PRUNE_FACTOR`] times the best start's (it is then dropped).
const GIVE_UP_AFTER: usize = 3;

/// With both directions, the last `gamma` takes the backward pairs from every subject vertex
/// up to one per this many model points (evenly spread over the subject's vertices).
const FULL_BACKWARD_SHARE: usize = 2;

/// Number of points of the paper's hands (2001), for which its `gamma` values were chosen.
pub const REFERENCE_POINTS: f64 = 2001.0;

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            gamma_start: 0.3,
            gamma_factor: 0.25,
            gamma_stop: 0.008,
            tolerance: 1e-6,
            max_iterations: 50,
            symmetric: true,
            starts: 8,
            full_starts: 2,
            coarse_points: 200,
            partial: false,
        }
    }
}

impl FitParams {
    /// The schedule `gamma_1 > gamma_2 > …`: multiply by the factor until below the stop.
    pub fn gammas(&self) -> Vec<f64> {
        let mut g = self.gamma_start;
        let mut out = vec![g];
        while g >= self.gamma_stop && out.len() < 64 {
            g *= self.gamma_factor;
            out.push(g);
        }
        out
    }

    fn validate(&self) -> Result<()> {
        let ok = self.gamma_start.is_finite()
            && self.gamma_start >= 0.0
            && self.gamma_factor > 0.0
            && self.gamma_factor < 1.0
            && self.gamma_stop.is_finite()
            && self.tolerance.is_finite()
            && self.tolerance > 0.0;
        if ok {
            Ok(())
        } else {
            Err(Error::Parameter(format!(
                "fit parameters out of range: gamma {} × {} down to {}, tolerance {} \
                 (need gamma >= 0, 0 < factor < 1, tolerance > 0)",
                self.gamma_start, self.gamma_factor, self.gamma_stop, self.tolerance
            )))
        }
    }
}

/// Result of a fit.
#[derive(Clone, Debug)]
pub struct FitResult<const D: usize> {
    /// Mode weights `w`.
    pub weights: Vec<f64>,
    /// `t_{R,T,s}`: reference to subject frame.
    pub similarity: Similarity<D>,
    /// The fitted instance `t ∘ (S_bar + Psi w)`, subject frame.
    pub instance: Vec<Point<D>>,
    /// `S_tilde^P`: the instance projected onto the subject along its normals, subject frame.
    pub projected: Vec<SurfacePoint<D>>,
    /// Whether each model point has a partner on the subject (always, unless the fit was
    /// `partial` and the subject misses the part where the point lies).
    pub corresponded: Vec<bool>,
    /// `E_d` (eq. 6, subject units squared) at every correspondence update of the winning
    /// start. In the coarse stage, the sum over the sampled model points scaled by
    /// `N / samples`.
    pub e_d_history: Vec<f64>,
    /// The instance at the start and after every `gamma` (the locus of fig. 9), subject frame.
    pub locus: Vec<Vec<Point<D>>>,
    /// Correspondence updates of the winning start (coarse stage and final stage).
    pub iterations: usize,
    /// Whether the inner loop met the tolerance at the last `gamma`.
    pub converged: bool,
}

/// Number of rotation parameters in `D` dimensions.
const fn rotation_params(d: usize) -> usize {
    d * (d - 1) / 2
}

/// `G_k x`: the `k`-th infinitesimal rotation applied to `x` (2D: `(-x_1, x_0)`; 3D:
/// `e_k × x`).
#[inline]
fn generator<const D: usize>(k: usize, x: &Point<D>) -> Point<D> {
    let mut out = [0.0; D];
    match D {
        2 => {
            out[0] = -x[1];
            out[1] = x[0];
        }
        3 => {
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            out[a] = -x[b];
            out[b] = x[a];
        }
        _ => unreachable!("atlasmesh supports D = 2 and D = 3"),
    }
    out
}

/// For a subject with missing parts: a model point has no partner where its projection lands
/// on the subject's open border (a segment end, or an edge of a single facet) from farther than
/// one median edge length.
fn partnered<const D: usize>(subject: &Shape<D>, projected: &[SurfacePoint<D>]) -> Vec<bool> {
    use std::collections::HashMap;
    let mut count: HashMap<Vec<usize>, u32> = HashMap::new();
    for f in &subject.facets {
        for skip in 0..D {
            let mut e: Vec<usize> = (0..D).filter(|&k| k != skip).map(|k| f[k]).collect();
            e.sort_unstable();
            *count.entry(e).or_default() += 1;
        }
    }
    let mut border_vertex = vec![false; subject.points.len()];
    for (e, c) in &count {
        if *c == 1 {
            for &v in e {
                border_vertex[v] = true;
            }
        }
    }
    let tol = subject.median_edge_length();
    projected
        .iter()
        .map(|p| {
            let f = &subject.facets[p.facet];
            let on_border = (0..D)
                .filter(|&k| p.weights[k] > 0.0)
                .all(|k| border_vertex[f[k]])
                && p.weights.contains(&0.0);
            !(on_border && p.dist2.sqrt() > tol)
        })
        .collect()
}

/// Sign of the orientation of a shape: the signed area enclosed by an outline (closed by
/// the chord between its ends when open), or the signed volume under a surface (closed by
/// the cone from the centroid when open).
fn orientation<const D: usize>(points: &[Point<D>], facets: &[[usize; D]]) -> f64 {
    let c = centroid(points);
    let mut total = 0.0;
    for f in facets {
        let a = sub(points[f[0]], c);
        let b = sub(points[f[1]], c);
        total += match D {
            2 => a[0] * b[1] - a[1] * b[0],
            3 => {
                let e = sub(points[f[2]], c);
                a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0])
                    + a[2] * (b[0] * e[1] - b[1] * e[0])
            }
            _ => 0.0,
        };
    }
    total.signum()
}

/// Indices of `k` points spread evenly over `0..n` (all of them when `k` is 0 or `>= n`).
fn spread(n: usize, k: usize) -> Vec<usize> {
    if k == 0 || k >= n {
        return (0..n).collect();
    }
    if k == 1 {
        return vec![0];
    }
    let mut v: Vec<usize> = (0..k)
        .map(|i| ((i as f64) * (n - 1) as f64 / (k - 1) as f64).round() as usize)
        .collect();
    v.dedup();
    v
}

/// Which model points (forward pairs) and subject vertices (backward pairs) take part.
struct Sampling {
    /// Which of a fit's samplings this is.
    pass: Pass,
    forward: Vec<usize>,
    backward: Vec<usize>,
}

/// The samplings of a fit: the pre-alignment's, the coarse stage's, the full stage's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pass {
    Rough,
    Coarse,
    Full,
}

impl Sampling {
    /// The effective number of pairs: the forward ones (the backward ones are weighted to
    /// count as many), or the backward ones when there are no forward pairs.
    fn pairs(&self) -> usize {
        if self.forward.is_empty() {
            self.backward.len().max(1)
        } else {
            self.forward.len()
        }
    }
}

/// A subject prepared for fitting.
struct Subject<'s, const D: usize> {
    shape: &'s Shape<D>,
    index: &'s ClosestPointIndex<D>,
    normals: Vec<Point<D>>,
    /// -1 where the subject runs the other way round than the atlas (its normals are turned
    /// round), else 1.
    sign: f64,
}

/// State of Algorithm 1: pose and weights.
#[derive(Clone)]
struct State<const D: usize> {
    sim: Similarity<D>,
    w: Vec<f64>,
    /// What the closest-point searches of the last update learned, per forward and per
    /// backward pair of the sampling `memos_for` (by place in its lists): the next update's
    /// queries start from there. A new sampling starts them afresh: they are a few hundred
    /// bytes per pair (allocated for every point of every start, they cost a fit more in
    /// page faults than they saved), and what a coarse sampling learned helps little at
    /// the next (the coarse model's index is another, and most of its points' memos
    /// missed at the full model's first update).
    forward_memo: Vec<QueryMemo<D>>,
    backward_memo: Vec<QueryMemo<D>>,
    memos_for: Option<Pass>,
}

/// A stage of Algorithm 1: the model and points it runs on, and when its inner loop stops:
/// after `max_iterations` updates, when the changes are below `tolerance`, or after
/// [`GIVE_UP_AFTER`] updates if the two-way distance is still above `give_up`.
struct Stage<'a> {
    level: Level,
    sampling: &'a Sampling,
    max_iterations: usize,
    tolerance: f64,
    give_up: f64,
}

/// What one correspondence update measured and did.
struct Step {
    /// Forward `Σ ||y_j - c_j||²` over the sampled model points (subject units squared).
    forward: f64,
    /// Mean squared distances forward and backward (subject units squared).
    two_way_ms: f64,
    /// Largest change of a pose parameter and `||Δw||`.
    pose_change: f64,
    weight_change: f64,
}

/// The shape model at one resolution: the mean's points (a subset of the atlas's, or all),
/// their rows of the modes, and the index of the mean's facets on them (it keeps the
/// facets).
struct Model<const D: usize> {
    mean: Vec<Point<D>>,
    /// Rows of `Psi` of the points, row-major (`(point · D + d) · m + k`).
    psi: Vec<f64>,
    /// Index of the mean's facets, refitted to every instance.
    index: ClosestPointIndex<D>,
}

impl<const D: usize> Model<D> {
    fn new(atlas: &Atlas<D>, ids: Vec<usize>, facets: Vec<[usize; D]>) -> Self {
        let m = atlas.num_modes();
        let mut psi = vec![0.0; ids.len() * D * m];
        for (j, &i) in ids.iter().enumerate() {
            for d in 0..D {
                for k in 0..m {
                    psi[(j * D + d) * m + k] = atlas.modes[(i * D + d, k)];
                }
            }
        }
        let mean: Vec<Point<D>> = ids.iter().map(|&i| atlas.mean[i]).collect();
        let index = ClosestPointIndex::new(&mean, &facets);
        Model { mean, psi, index }
    }

    fn len(&self) -> usize {
        self.mean.len()
    }

    /// The coarse model of about `k` points: for outlines, `k` of the points evenly spread
    /// over their order and the segments joining each to the next kept one along the
    /// outline; for surfaces, the vertex-clustering decimation of the mean (original points
    /// kept) with a cell chosen for about `k` points. `None`
    /// where that is no smaller than the atlas, or the decimation fails or leaves the shape
    /// without facets.
    fn coarse(atlas: &Atlas<D>, k: usize) -> Option<Self> {
        let n = atlas.mean.len();
        if k == 0 || 2 * k >= n {
            return None;
        }
        if D == 2 {
            let ids = spread(n, k);
            let mut at = vec![usize::MAX; n];
            for (j, &i) in ids.iter().enumerate() {
                at[i] = j;
            }
            // Each kept point joins the next one along the outline (segment by segment).
            let mut next = vec![usize::MAX; n];
            for f in &atlas.facets {
                next[f[0]] = f[1];
            }
            let mut facets = Vec::new();
            for &start in &ids {
                let mut v = next[start];
                let mut steps = 0;
                while v != usize::MAX && at[v] == usize::MAX && steps < n {
                    v = next[v];
                    steps += 1;
                }
                if v != usize::MAX && at[v] != usize::MAX && v != start {
                    let mut f = [0; D];
                    f[0] = at[start];
                    f[1] = at[v];
                    facets.push(f);
                }
            }
            return (!facets.is_empty()).then(|| Model::new(atlas, ids, facets));
        }
        let shape = Shape {
            name: "mean".into(),
            points: atlas.mean.clone(),
            facets: atlas.facets.clone(),
            landmarks: Vec::new(),
        };
        let area: f64 = atlas
            .facets
            .iter()
            .map(|f| 0.5 * norm(facet_normal(&atlas.mean, f)))
            .sum();
        let mut cell = (area / k as f64).sqrt();
        for _ in 0..4 {
            let (small, ids) = shape.decimate_by_clustering(cell, [0.0; D]).ok()?;
            let got = small.points.len();
            if (k / 2..=2 * k).contains(&got) || got == 0 {
                return (!small.facets.is_empty() && 2 * got < n)
                    .then(|| Model::new(atlas, ids, small.facets));
            }
            cell *= (got as f64 / k as f64).sqrt();
        }
        None
    }
}

/// The atlas prepared for fitting: the model at full resolution and a coarse one for the
/// first stages (see [`Fitter::fit`]), `Lambda^{-1}`. Build once, fit many.
pub struct Fitter<'a, const D: usize> {
    atlas: &'a Atlas<D>,
    m: usize,
    lambda_inv: Vec<f64>,
    full: Model<D>,
    /// Built for [`FitParams::default`]'s `coarse_points`; `None` when the atlas is small.
    coarse: Option<Model<D>>,
    coarse_points: usize,
    /// The buffers of finished fits, for the next ones: megabytes for a femur (the instance's
    /// index, the rows of the linear system), whose pages, allocated afresh for every fit,
    /// cost it a few percent in page faults.
    spare: std::sync::Mutex<Vec<Scratches<D>>>,
}

/// Spare buffers a [`Fitter`] keeps at most (one per worker of a batch, typically).
const SPARE_SCRATCHES: usize = 16;

/// Which of the fitter's models.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Level {
    Coarse,
    Full,
}

impl<'a, const D: usize> Fitter<'a, D> {
    pub fn new(atlas: &'a Atlas<D>) -> Self {
        let n = atlas.mean.len();
        let coarse_points = FitParams::default().coarse_points;
        Fitter {
            atlas,
            m: atlas.num_modes(),
            lambda_inv: atlas.eigenvalues.iter().map(|l| 1.0 / l).collect(),
            full: Model::new(atlas, (0..n).collect(), atlas.facets.clone()),
            coarse: Model::coarse(atlas, COARSE_MODEL_FACTOR * coarse_points),
            coarse_points,
            spare: std::sync::Mutex::new(Vec::new()),
        }
    }

    /// Buffers for a fit with `params`: spare ones if there are any, else new ones.
    fn scratches(&self, params: &FitParams) -> Scratches<D> {
        let use_coarse = !std::ptr::eq(self.model(Level::Coarse, params), &self.full);
        let spare = {
            let mut spare = self
                .spare
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let k = spare.iter().position(|x| x.use_coarse == use_coarse);
            k.map(|k| spare.swap_remove(k))
        };
        match spare {
            Some(mut x) => {
                // Their instances are another fit's.
                x.full.w = None;
                x.coarse.w = None;
                x
            }
            None => Scratches::new(self, params),
        }
    }

    /// Keeps the buffers of a finished fit for the next one.
    fn recycle(&self, x: Scratches<D>) {
        let mut spare = self
            .spare
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if spare.len() < SPARE_SCRATCHES {
            spare.push(x);
        }
    }

    /// The model of a level: the coarse one when there is one for `params`, else the full.
    fn model(&self, level: Level, params: &FitParams) -> &Model<D> {
        match (level, &self.coarse) {
            (Level::Coarse, Some(c)) if params.coarse_points == self.coarse_points => c,
            _ => &self.full,
        }
    }

    /// The instance `S_bar + Psi w` at the model's points.
    fn instance(&self, model: &Model<D>, w: &[f64], out: &mut Vec<Point<D>>) {
        out.clear();
        out.extend(model.mean.iter().enumerate().map(|(i, p)| {
            std::array::from_fn(|d| {
                let row = &model.psi[(i * D + d) * self.m..(i * D + d + 1) * self.m];
                p[d] + row.iter().zip(w).map(|(a, b)| a * b).sum::<f64>()
            })
        }));
    }

    /// Fits the atlas to `subject` (Algorithm 1, eq. 5-8) and projects the result onto it.
    ///
    /// Lengths: the subject in its own units and frame; the model in the reference frame
    /// (mean in the unit box); `t_{R,T,s}` maps the latter to the former.
    ///
    /// Each correspondence update (i) takes, for every model point, the closest point on the
    /// subject's segments/facets (through the spatial index), (ii) minimizes eq. 5 for that
    /// correspondence over `R, T, s, w` together, (iii) instantiates. The inner loop ends when
    /// `||Δw||` (per point, see [`FitParams::tolerance`]) and the pose change are below
    /// `params.tolerance`; then `gamma` decreases.
    ///
    /// # Deviations from the paper
    /// - Step (ii): the paper alternates the similarity and eq. 8 (Cootes' protocol 1) on
    ///   the squared distances to the closest points. We take one Gauss-Newton step of eq. 5
    ///   in all parameters at once, with each residual measured along the subject's normal at
    ///   the closest point (point-to-plane, Chen & Medioni 1992). At a closest point the
    ///   residual is normal to the subject, so both variants have the same fixed points, the
    ///   stationary points of eq. 5 with the true distance to the subject; point-to-point
    ///   creeps along the outline over hundreds of updates (the paper: 168-581), this takes
    ///   tens.
    /// - `E_d` is measured in the reference frame (eq. 8 without the `1/s²`), so that
    ///   `gamma` means the same whatever the subject's units (the paper's hands were in the
    ///   unit box, `s ≈ 1`). Test `fit_is_invariant_to_the_subject_units`.
    /// - `E_d` sums over the `N` model points and the eigenvalues grow with `N`, so the
    ///   regularization's strength depends on `N`; the paper chose `gamma` for `N = 2001`.
    ///   We use `gamma · n / 2001` with `n` the points in use; for the same reason the
    ///   tolerance applies to `||Δw|| sqrt(2001 / n)`.
    /// - Pairs whose two normals (the instance's and the subject's, at the pair's two ends)
    ///   differ by more than 60° are left out of step (ii). Such a pair joins two facing
    ///   sides, a finger's edge to its neighbour's; those pairs are what holds a fit in the
    ///   local minimum that caught the paper's S38 (our subject `37`). Between 41° and 60° a
    ///   pair's weight falls smoothly to 0, so that a pair crossing the bound does not make
    ///   the next update jump (a hard cut let a hand fit cycle between two sets of pairs).
    ///   The subject's normals are turned round first if it is listed in the other
    ///   orientation than the atlas.
    /// - With `symmetric`, `E_d` also sums, over the subject's vertices, the squared distance
    ///   to their closest point on the instance (weighted so both directions count equally):
    ///   a one-way distance is blind to a part of the subject that the instance leaves
    ///   uncovered. Test `symmetric_fit_recovers_a_far_instance`. That term is a coverage
    ///   check, not the paper's measure: it takes at most one subject vertex per two model
    ///   points (evenly spread; all of them for a `partial` fit, where it is the only term),
    ///   which halves the cost of the last `gamma` on a subject as dense as the atlas and
    ///   keeps a dense subject from costing more than the atlas.
    /// - Algorithm 1 starts from `R = I, T = 0, s = 1`. We start from the centroid and
    ///   RMS-radius match, try start rotations (2D: `params.starts` angles; 3D: the four
    ///   that map the mean's principal axes onto the subject's, and the identity, so that a
    ///   subject in any orientation is found) with a pose-only fit (`w = 0`) on
    ///   `coarse_points / 4` points (after 2 updates, the starts whose two-way distance is 10
    ///   times the best one's stop there), and run Algorithm 1 from the `params.full_starts`
    ///   best distinct ones left (more than 20° apart) together on `params.coarse_points`
    ///   evenly spread points, dropping after each `gamma` the starts whose two-way distance
    ///   is 4 times the best (a start still that far behind after 3 updates gives the `gamma`
    ///   up at once);
    ///   the best start then runs the last `gamma` again on all points, to the tolerance.
    ///   The coarse stage is a quadrature of the same `E_d` with fewer points (its `gamma`
    ///   scaled as above), stopped at 100 times the tolerance. It works on a coarse model of
    ///   about `4 · coarse_points` of the atlas's points (every `k`-th point of an outline; the
    ///   vertex-clustering decimation of a surface), so that its updates do not instantiate,
    ///   index and take the normals of the whole instance: the backward pairs take their
    ///   closest points on the coarse instance.
    pub fn fit(
        &self,
        subject: &Shape<D>,
        subject_index: &ClosestPointIndex<D>,
        params: &FitParams,
    ) -> Result<FitResult<D>> {
        crate::clear_simd_upper_state();
        let (subj, coarse, full) = self.prepare(subject, subject_index, params)?;
        // The pre-alignment needs only the rough layout.
        let rough_model = self.model(Level::Coarse, params);
        let rough = Sampling {
            pass: Pass::Rough,
            forward: if params.partial {
                Vec::new()
            } else {
                spread(rough_model.len(), params.coarse_points / 4)
            },
            backward: spread(subject.points.len(), params.coarse_points / 4),
        };
        let mut x = self.scratches(params);

        // Pre-alignment: centroids, RMS radii, and a pose-only fit from each start rotation.
        let pts = &subject.points;
        let cs = centroid(pts);
        let cm = centroid(&self.atlas.mean);
        let rms = |p: &[Point<D>], c: Point<D>| {
            (p.iter().map(|q| dist2(*q, c)).sum::<f64>() / p.len() as f64).sqrt()
        };
        let s0 = rms(pts, cs) / rms(&self.atlas.mean, cm).max(f64::MIN_POSITIVE);
        let rotations =
            crate::register::start_rotations(&self.atlas.mean, cm, pts, cs, params.starts);
        // All starts take their pose-only updates together; after the first
        // [`PRE_PRUNE_AFTER`], those whose two-way distance is [`PRE_PRUNE_FACTOR`] times the
        // best one's stop (a start in a wrong pose is also the costliest: its points are far
        // from the surface, where a closest-point search meets many boxes).
        let mut pre: Vec<(f64, bool, State<D>)> = rotations
            .into_iter()
            .map(|r| {
                let st = State {
                    sim: Similarity::centred(s0, r, &cm, &cs),
                    w: vec![0.0; self.m],
                    forward_memo: Vec::new(),
                    backward_memo: Vec::new(),
                    memos_for: None,
                };
                (f64::INFINITY, false, st)
            })
            .collect();
        for k in 0..PRE_ALIGNMENT_ITERATIONS {
            for (score, done, st) in pre.iter_mut().filter(|p| !p.1) {
                let step = self.update(Level::Coarse, &subj, st, &rough, None, &mut x)?;
                *score = step.two_way_ms;
                *done = step.pose_change < 1e-3;
            }
            if k + 1 >= PRE_PRUNE_AFTER {
                let best = pre.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
                pre.retain(|p| p.0 <= PRE_PRUNE_FACTOR * best);
            }
        }
        pre.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut chosen: Vec<State<D>> = Vec::new();
        for (_, _, st) in pre {
            let distinct = chosen
                .iter()
                .all(|c| rotation_angle(&c.sim.r, &st.sim.r) > 20f64.to_radians());
            if distinct {
                chosen.push(st);
            }
            if chosen.len() >= params.full_starts.max(1) {
                break;
            }
        }

        let result = self.run_starts(&subj, chosen, &coarse, &full, params, &mut x);
        self.recycle(x);
        result
    }

    /// Algorithm 1 (with the final projection) from a given pose `t_{R,T,s}` and weights,
    /// without the pre-alignment: e.g. to refine a fit, or to fit a time series from the
    /// previous frame's result. See [`Fitter::fit`].
    pub fn fit_from(
        &self,
        subject: &Shape<D>,
        subject_index: &ClosestPointIndex<D>,
        params: &FitParams,
        similarity: Similarity<D>,
        weights: &[f64],
    ) -> Result<FitResult<D>> {
        let (subj, coarse, full) = self.prepare(subject, subject_index, params)?;
        if weights.len() != self.m || weights.iter().any(|w| !w.is_finite()) {
            return Err(Error::Parameter(format!(
                "{} finite starting weights needed, got {}",
                self.m,
                weights.len()
            )));
        }
        let mut x = self.scratches(params);
        let st = State {
            sim: similarity,
            w: weights.to_vec(),
            forward_memo: Vec::new(),
            backward_memo: Vec::new(),
            memos_for: None,
        };
        let result = self.run_starts(&subj, vec![st], &coarse, &full, params, &mut x);
        self.recycle(x);
        result
    }

    #[allow(clippy::type_complexity)]
    fn prepare<'s>(
        &self,
        subject: &'s Shape<D>,
        subject_index: &'s ClosestPointIndex<D>,
        params: &FitParams,
    ) -> Result<(Subject<'s, D>, Sampling, Sampling)> {
        subject.validate()?;
        params.validate()?;
        if subject.facets.is_empty() {
            return Err(Error::shape(
                &subject.name,
                "has no segments/facets to fit to",
            ));
        }
        // A subject listed in the other order than the atlas (clockwise against
        // counter-clockwise, or inward facets) gets its normals turned round, so that
        // corresponding normals agree.
        let sign = if orientation(&subject.points, &subject.facets)
            * orientation(&self.atlas.mean, &self.atlas.facets)
            < 0.0
        {
            -1.0
        } else {
            1.0
        };
        // The index's normals are the subject's (it keeps them for its queries' answers).
        if subject_index.points().len() != subject.points.len()
            || subject_index.facets().len() != subject.facets.len()
        {
            return Err(Error::shape(
                &subject.name,
                "comes with a closest-point index of another shape",
            ));
        }
        let mut normals = Vec::new();
        subject_index.vertex_normals_into(&mut normals);
        normals.iter_mut().for_each(|v| *v = scale(*v, sign));
        let subj = Subject {
            shape: subject,
            index: subject_index,
            normals,
            sign,
        };
        let n = self.atlas.mean.len();
        let forward = !params.partial;
        let backward = params.symmetric || params.partial;
        let coarse_model = self.model(Level::Coarse, params);
        let coarse = Sampling {
            pass: Pass::Coarse,
            forward: if forward {
                spread(coarse_model.len(), params.coarse_points)
            } else {
                Vec::new()
            },
            backward: if backward {
                spread(subject.points.len(), params.coarse_points)
            } else {
                Vec::new()
            },
        };
        let full = Sampling {
            pass: Pass::Full,
            forward: if forward {
                (0..n).collect()
            } else {
                Vec::new()
            },
            backward: if backward && forward {
                spread(subject.points.len(), n.div_ceil(FULL_BACKWARD_SHARE))
            } else if backward {
                (0..subject.points.len()).collect()
            } else {
                Vec::new()
            },
        };
        Ok((subj, coarse, full))
    }

    /// Algorithm 1 on the coarse sampling from every start; the least two-way distance
    /// wins, and its last `gamma` runs on all points; then the projection.
    fn run_starts(
        &self,
        subj: &Subject<D>,
        chosen: Vec<State<D>>,
        coarse: &Sampling,
        full: &Sampling,
        params: &FitParams,
        x: &mut Scratches<D>,
    ) -> Result<FitResult<D>> {
        let n = self.atlas.mean.len();
        // Algorithm 1 on the coarse sampling from every chosen start; the least two-way
        // distance wins.
        // All starts go through each `gamma` together; after each, those whose two-way
        // distance is far above the best one's stop.
        let gammas = params.gammas();
        let tol = COARSE_TOLERANCE_FACTOR * params.tolerance;
        let mut runs: Vec<(f64, Run<D>)> = chosen
            .into_iter()
            .map(|st| (f64::INFINITY, Run::new(st, self, x)))
            .collect();
        for &gamma in &gammas {
            // Best first: a start that is still far behind the best after a few updates
            // gives up this `gamma` (and is dropped below).
            runs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut best = f64::INFINITY;
            for (score, run) in runs.iter_mut() {
                let stage = Stage {
                    level: Level::Coarse,
                    sampling: coarse,
                    max_iterations: COARSE_MAX_ITERATIONS.min(params.max_iterations),
                    tolerance: tol,
                    give_up: PRUNE_FACTOR * best,
                };
                *score = self.schedule(subj, run, &stage, &[gamma], x)?;
                best = best.min(*score);
            }
            runs.retain(|r| r.0 <= PRUNE_FACTOR * best);
        }
        let (_, mut run) = runs
            .into_iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .ok_or_else(|| Error::Numerical("no start was tried".into()))?;
        // The last gamma on all points.
        let coarse_model = self.model(Level::Coarse, params);
        if coarse_model.len() < n
            || coarse.forward.len() < n
            || coarse.backward.len() < full.backward.len()
        {
            let last = gammas[gammas.len() - 1..].to_vec();
            run.locus.pop();
            let stage = Stage {
                level: Level::Full,
                sampling: full,
                max_iterations: params.max_iterations,
                tolerance: params.tolerance,
                give_up: f64::INFINITY,
            };
            self.schedule(subj, &mut run, &stage, &last, x)?;
        }
        let full_x = &mut x.full;
        full_x.set_weights(self, &self.full, &run.state.w, false);
        let sim = run.state.sim;
        let instance: Vec<Point<D>> = full_x.x.iter().map(|p| sim.apply(p)).collect();
        let projected = project_along_normals(
            &instance,
            &self.atlas.facets,
            subj.index,
            subj.sign < 0.0,
            // By place in the last sampling's forward list: every point in order where it
            // has all of them (project_along_normals takes memos of the right length only).
            Some(&mut run.state.forward_memo),
        );
        let corresponded = if params.partial {
            partnered(subj.shape, &projected)
        } else {
            vec![true; projected.len()]
        };
        Ok(FitResult {
            corresponded,
            weights: run.state.w,
            similarity: sim,
            instance,
            projected,
            e_d_history: run.e_d_history,
            locus: run.locus,
            iterations: run.iterations,
            converged: run.converged,
        })
    }

    /// Runs the inner loop of Algorithm 1 for every `gamma` of `gammas`; returns the two-way
    /// mean squared distance at the last update.
    fn schedule(
        &self,
        subj: &Subject<D>,
        run: &mut Run<D>,
        stage: &Stage,
        gammas: &[f64],
        x: &mut Scratches<D>,
    ) -> Result<f64> {
        let Stage {
            level,
            sampling,
            max_iterations,
            tolerance,
            give_up,
        } = *stage;
        let n = self.atlas.mean.len() as f64;
        let pairs = sampling.pairs() as f64;
        let scale_e_d = if sampling.forward.is_empty() {
            1.0
        } else {
            n / pairs
        };
        let mut score = f64::INFINITY;
        for &gamma in gammas {
            let gamma = gamma * pairs / REFERENCE_POINTS;
            run.converged = false;
            for k in 0..max_iterations.max(1) {
                let step = self.update(level, subj, &mut run.state, sampling, Some(gamma), x)?;
                run.iterations += 1;
                run.e_d_history.push(step.forward * scale_e_d);
                score = step.two_way_ms;
                if step.weight_change < tolerance && step.pose_change < tolerance {
                    run.converged = true;
                    break;
                }
                if k + 1 >= GIVE_UP_AFTER && score > give_up {
                    break;
                }
            }
            x.full.set_weights(self, &self.full, &run.state.w, false);
            run.locus
                .push(x.full.x.iter().map(|p| run.state.sim.apply(p)).collect());
        }
        Ok(score)
    }

    /// One correspondence update: (i) closest points at the current state, (ii) one
    /// Gauss-Newton step of eq. 5 (all pose parameters, and `w` unless `gamma` is `None`),
    /// (iii) the new state.
    ///
    /// Linearization, in the reference frame: with `x = S_bar + Ψ w`, the update
    /// `t' = t ∘ (x ↦ (1 + δs)(I + Σ δω_k G_k) x + δt)`, `w' = w + δw`, the residual of a
    /// pair along its unit normal `ñ` (reference frame) is
    /// `ñ · (x - t^{-1}(c) + δs x + Σ δω_k G_k x + δt + Ψ δw)`.
    fn update(
        &self,
        level: Level,
        subj: &Subject<D>,
        st: &mut State<D>,
        sampling: &Sampling,
        gamma: Option<f64>,
        scratches: &mut Scratches<D>,
    ) -> Result<Step> {
        let model = match level {
            Level::Coarse => scratches.coarse_model(self),
            Level::Full => &self.full,
        };
        let scratch = match level {
            Level::Coarse if !std::ptr::eq(model, &self.full) => &mut scratches.coarse,
            _ => &mut scratches.full,
        };
        let m = self.m;
        let r = rotation_params(D);
        let pose = 1 + r + D;
        let p = if gamma.is_some() { pose + m } else { pose };
        let cols = p + 1;
        let sim = st.sim;
        scratch.set_weights(self, model, &st.w, true);
        let x = &scratch.x;
        let buf = &mut scratch.rows;
        buf.clear();
        // One allocation for all the rows, not a doubling series.
        buf.reserve(cols * (sampling.forward.len() + sampling.backward.len()));
        if st.memos_for != Some(sampling.pass) {
            st.forward_memo.clear();
            st.forward_memo
                .resize(sampling.forward.len(), QueryMemo::default());
            st.backward_memo.clear();
            st.backward_memo
                .resize(sampling.backward.len(), QueryMemo::default());
            st.memos_for = Some(sampling.pass);
        }
        // Appends the row of the model point combination `(ids, bw)` with unit normal `nr`
        // and target `z` (both in the reference frame), scaled by `sw` (root of its weight).
        let push =
            |buf: &mut Vec<f64>, ids: &[usize], bw: &[f64], nr: Point<D>, z: Point<D>, sw: f64| {
                let at = buf.len();
                buf.resize(at + cols, 0.0);
                let row = &mut buf[at..];
                let mut xc = [0.0; D];
                for (&i, &b) in ids.iter().zip(bw) {
                    xc = add(xc, scale(x[i], b));
                }
                row[0] = sw * dot(nr, xc);
                for k in 0..r {
                    row[1 + k] = sw * dot(nr, generator(k, &xc));
                }
                for d in 0..D {
                    row[1 + r + d] = sw * nr[d];
                }
                if p > pose {
                    let rw = &mut row[pose..pose + m];
                    for (&i, &b) in ids.iter().zip(bw) {
                        if b == 0.0 {
                            continue;
                        }
                        for d in 0..D {
                            let f = sw * b * nr[d];
                            let pr = &model.psi[(i * D + d) * m..(i * D + d + 1) * m];
                            for (o, v) in rw.iter_mut().zip(pr) {
                                *o += f * v;
                            }
                        }
                    }
                }
                row[p] = sw * dot(nr, sub(xc, z));
            };
        // Forward pairs: model point -> closest point on the subject (subject frame).
        let mut forward = 0.0;
        for (&j, memo) in sampling.forward.iter().zip(&mut st.forward_memo) {
            let c = subj.index.closest_memo(&sim.apply(&x[j]), memo);
            forward += c.dist2;
            // From the index, which the search has just read.
            let Some(n) = subj.index.normal_at(&c) else {
                continue;
            };
            let n = scale(n, subj.sign);
            let nr = sim.rotate_inverse(&n);
            let cw = compatibility(dot(nr, scratch.normals[j]));
            if cw == 0.0 {
                continue;
            }
            push(buf, &[j], &[1.0], nr, sim.apply_inverse(&c.point), cw);
        }
        // Backward pairs: subject vertex -> closest point on the instance, searched in the
        // reference frame (a similarity keeps closest points), so the instance's index
        // changes only with `w`.
        let mut backward = 0.0;
        if !sampling.backward.is_empty() {
            // Backward pairs weigh as much as the forward ones together; alone (a partial
            // subject), as much as both directions would (so that `gamma` acts alike).
            let total = if sampling.forward.is_empty() {
                2.0
            } else {
                1.0
            };
            let sw = (total * sampling.pairs() as f64 / sampling.backward.len() as f64).sqrt();
            for (&i, memo) in sampling.backward.iter().zip(&mut st.backward_memo) {
                let z = sim.apply_inverse(&subj.shape.points[i]);
                let c = scratch.index.closest_memo(&z, memo);
                backward += c.dist2 * sim.s * sim.s;
                let (Some(n), Some(f)) = (
                    scratch.index.normal_at(&c),
                    scratch.index.facet_vertices(&c),
                ) else {
                    continue;
                };
                let cw = compatibility(dot(n, sim.rotate_inverse(&subj.normals[i])));
                if cw == 0.0 {
                    continue;
                }
                push(buf, &f, &c.weights, n, z, sw * cw);
            }
        }
        let two_way_ms = if sampling.backward.is_empty() {
            forward / sampling.forward.len() as f64
        } else if sampling.forward.is_empty() {
            backward / sampling.backward.len() as f64
        } else {
            0.5 * (forward / sampling.forward.len() as f64
                + backward / sampling.backward.len() as f64)
        };
        let nrows = buf.len() / cols;
        let a = faer::MatRef::from_row_major_slice(buf, nrows, cols);
        let ata = a.transpose() * a;
        let mut h = Mat::<f64>::zeros(p, p);
        let mut g = Mat::<f64>::zeros(p, 1);
        for i in 0..p {
            for j in 0..p {
                h[(i, j)] = ata[(i, j)];
            }
            g[(i, 0)] = -ata[(i, p)];
        }
        if let Some(gamma) = gamma {
            for k in 0..m {
                h[(pose + k, pose + k)] += gamma * self.lambda_inv[k];
                g[(pose + k, 0)] -= gamma * self.lambda_inv[k] * st.w[k];
            }
        }
        // A tiny ridge, relative to each diagonal entry (they span many orders of magnitude
        // when a mode's eigenvalue is near zero), keeps the system solvable on degenerate
        // input (a straight outline, or no pair left).
        let floor = 1e-12 * (0..pose).map(|i| h[(i, i)]).fold(0.0, f64::max) + 1e-300;
        for i in 0..p {
            h[(i, i)] += 1e-12 * h[(i, i)] + floor;
        }
        let llt = h
            .llt(faer::Side::Lower)
            .map_err(|_| Error::Numerical("the system of eq. 5 is singular".into()))?;
        let z = llt.solve(&g);
        crate::clear_simd_upper_state();
        let mut dz: Vec<f64> = (0..p).map(|i| z[(i, 0)]).collect();
        if dz.iter().any(|v| !v.is_finite()) {
            return Err(Error::Numerical(format!(
                "the fit of {} diverged (NaN in the pose or the mode weights)",
                subj.shape.name
            )));
        }
        // A trust region for the first updates, far from the subject: at most 0.2 in scale
        // and rotation, 0.1 of the unit box in translation, 1 sigma per mode.
        let mut shrink: f64 = 1.0;
        let big = |v: f64, lim: f64| if v > lim { lim / v } else { 1.0 };
        shrink = shrink.min(big(
            dz[..1 + r].iter().fold(0.0, |a, v| a.max(v.abs())),
            0.2,
        ));
        shrink = shrink.min(big(
            dz[1 + r..pose].iter().map(|v| v * v).sum::<f64>().sqrt(),
            0.1,
        ));
        if p > pose {
            let maha = dz[pose..]
                .iter()
                .zip(&self.lambda_inv)
                .map(|(v, li)| v * v * li)
                .sum::<f64>()
                .sqrt();
            shrink = shrink.min(big(maha, 1.0));
        }
        dz.iter_mut().for_each(|v| *v *= shrink);
        // (iii) the new state.
        let dt: Point<D> = std::array::from_fn(|d| dz[1 + r + d]);
        let mut new = st.sim;
        new.t = add(sim.t, scale(sim.rotate(&dt), sim.s));
        new.s = sim.s * dz[0].exp();
        let rot = crate::geometry::rotation_exp::<D>(&dz[1..1 + r]);
        new.r = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..D).map(|k| sim.r[i][k] * rot[k][j]).sum::<f64>())
        });
        st.sim = new;
        let mut weight_change = 0.0;
        if p > pose {
            for k in 0..m {
                st.w[k] += dz[pose + k];
                weight_change += dz[pose + k] * dz[pose + k];
            }
        }
        // The modes are orthonormal over all `D n` coordinates, so `||Δw||` is the root of
        // the sum of the squared point moves: the same move of the shape gives a larger
        // `||Δw||` the more points the atlas has. Measured as for the paper's 2001 points
        // (the root mean square move times the root of 2001), the tolerance means the same
        // at every resolution.
        let weight_change =
            (weight_change * REFERENCE_POINTS / self.atlas.mean.len() as f64).sqrt();
        Ok(Step {
            forward: if sampling.forward.is_empty() {
                backward
            } else {
                forward
            },
            two_way_ms,
            pose_change: dz[..pose].iter().fold(0.0, |a, v| a.max(v.abs())),
            weight_change,
        })
    }
}

/// Buffers reused by every update of a fit on one model: the instance (reference frame), the
/// index of its facets and its vertex normals, for the weights `w`; the rows of the linear
/// system.
struct Scratch<const D: usize> {
    x: Vec<Point<D>>,
    w: Option<Vec<f64>>,
    indexed: bool,
    index: ClosestPointIndex<D>,
    normals: Vec<Point<D>>,
    rows: Vec<f64>,
}

impl<const D: usize> Scratch<D> {
    fn new(model: &Model<D>) -> Self {
        Scratch {
            x: Vec::new(),
            w: None,
            indexed: false,
            index: model.index.clone(),
            normals: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// Makes `x` the instance of `w` (and, with `index`, its index and normals current).
    fn set_weights(&mut self, fitter: &Fitter<D>, model: &Model<D>, w: &[f64], index: bool) {
        if self.w.as_deref() != Some(w) {
            fitter.instance(model, w, &mut self.x);
            self.w = Some(w.to_vec());
            self.indexed = false;
        }
        if index && !self.indexed {
            self.index.refit(&self.x);
            self.index.vertex_normals_into(&mut self.normals);
            self.indexed = true;
        }
    }
}

/// The scratch of each model of a fit, and which coarse model the fit uses.
struct Scratches<const D: usize> {
    full: Scratch<D>,
    coarse: Scratch<D>,
    /// Whether the fit's parameters select the fitter's coarse model.
    use_coarse: bool,
}

impl<const D: usize> Scratches<D> {
    fn new(fitter: &Fitter<D>, params: &FitParams) -> Self {
        let coarse = fitter.model(Level::Coarse, params);
        Scratches {
            full: Scratch::new(&fitter.full),
            coarse: Scratch::new(coarse),
            use_coarse: !std::ptr::eq(coarse, &fitter.full),
        }
    }

    /// The model of the coarse level for this fit.
    fn coarse_model<'f>(&self, fitter: &'f Fitter<D>) -> &'f Model<D> {
        match &fitter.coarse {
            Some(c) if self.use_coarse => c,
            _ => &fitter.full,
        }
    }
}

/// One start's way through Algorithm 1.
struct Run<const D: usize> {
    state: State<D>,
    e_d_history: Vec<f64>,
    locus: Vec<Vec<Point<D>>>,
    iterations: usize,
    converged: bool,
}

impl<const D: usize> Run<D> {
    fn new(state: State<D>, fitter: &Fitter<D>, x: &mut Scratches<D>) -> Self {
        x.full.set_weights(fitter, &fitter.full, &state.w, false);
        let locus = vec![x.full.x.iter().map(|p| state.sim.apply(p)).collect()];
        Run {
            state,
            e_d_history: Vec::new(),
            locus,
            iterations: 0,
            converged: false,
        }
    }
}

/// Projects every point of `points` (with the connectivity `facets`, for its vertex normals)
/// onto the indexed subject along its normal (section 3, last step of Algorithm 1): the
/// nearest crossing of the normal line within three times the closest-point distance plus
/// half the local edge length, among the crossings where the subject faces the same way
/// (its normal, [`ClosestPointIndex::normal_at`], turned round with `flip`, within 60° of
/// the point's); the closest point where there is none. Without that condition a normal
/// line near a concave corner (between two fingers) crosses the neighbouring side first and
/// the correspondence jumps.
/// `memos`, one per point, are those of the closest-point queries of the same points (e.g.
/// a fit's last update): they make the closest points cheap.
pub fn project_along_normals<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
    subject: &ClosestPointIndex<D>,
    flip: bool,
    memos: Option<&mut [QueryMemo<D>]>,
) -> Vec<SurfacePoint<D>> {
    let normals = vertex_normals(points, facets);
    let h = 0.5 * crate::geometry::median_edge_length(points, facets);
    let mut fresh = Vec::new();
    let memos = match memos {
        Some(m) if m.len() == points.len() => m,
        _ => {
            fresh.resize(points.len(), QueryMemo::default());
            &mut fresh[..]
        }
    };
    points
        .iter()
        .zip(&normals)
        .zip(memos.iter_mut())
        .map(|((p, nrm), memo)| {
            let c = subject.closest_memo(p, memo);
            if norm(*nrm) == 0.0 {
                return c;
            }
            let max_t = 3.0 * c.dist2.sqrt() + h;
            subject
                .ray_where(p, nrm, max_t, |hit| {
                    subject.normal_at(hit).is_some_and(|ns| {
                        let cos = dot(ns, *nrm);
                        (if flip { -cos } else { cos }) >= COMPATIBLE_NORMALS_COS
                    })
                })
                .unwrap_or(c)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{AtlasParams, ModeSelection};

    fn atlas() -> Atlas<2> {
        atlas_of(120)
    }

    /// Mode weights of `sigmas` standard deviations along the first modes.
    fn weights_at(a: &Atlas<2>, sigmas: [f64; 3]) -> Vec<f64> {
        a.eigenvalues
            .iter()
            .zip(sigmas)
            .map(|(l, f)| f * l.sqrt())
            .collect()
    }

    /// The egg population with `points` points per outline.
    fn atlas_of(points: usize) -> Atlas<2> {
        let shapes: Vec<Shape<2>> = (0..12)
            .map(|k| {
                let a = 1.0 + 0.1 * (k as f64 * 1.7).sin();
                let b = 0.6 + 0.06 * (k as f64 * 2.3).cos();
                let c = 0.05 * (k as f64 * 0.9).cos();
                let pts = (0..points)
                    .map(|i| {
                        let t = i as f64 / points as f64 * std::f64::consts::TAU;
                        // An egg (no symmetry, so the pose is identifiable) with three modes.
                        let egg = 1.0 + 0.25 * t.cos();
                        [
                            egg * (a * t.cos() + c * (3.0 * t).cos()),
                            egg * (b * t.sin() + c * (2.0 * t).sin()),
                        ]
                    })
                    .collect();
                Shape::polyline(format!("s{k}"), pts, true)
            })
            .collect();
        Atlas::build(
            &shapes,
            &AtlasParams {
                modes: ModeSelection::Count(3),
                element_size: 0.05,
                smoothing_passes: 2,
            },
        )
        .unwrap()
    }

    fn subject(atlas: &Atlas<2>, w: &[f64], sim: &Similarity<2>) -> Shape<2> {
        let pts: Vec<Point<2>> = atlas.instance(w).iter().map(|p| sim.apply(p)).collect();
        // Resample coarser and shifted so that no point coincides with a model point.
        let n = pts.len();
        let sub_pts = (0..n / 2)
            .map(|i| {
                let a = pts[(2 * i) % n];
                let b = pts[(2 * i + 1) % n];
                [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
            })
            .collect();
        Shape::polyline("subject", sub_pts, true)
    }

    #[test]
    fn the_tolerance_means_the_same_at_every_resolution() {
        // The same shapes sampled 8 times finer: `||Δw||` for the same move grows with the
        // root of the points, the updates must not.
        let mut sim = Similarity::<2>::planar_rotation(0.5);
        sim.s = 20.0;
        let mut fits = Vec::new();
        for points in [120, 960] {
            let a = atlas_of(points);
            let w = weights_at(&a, [1.2, -0.8, 0.5]);
            let s = subject(&a, &w, &sim);
            let idx = ClosestPointIndex::from_shape(&s);
            let r = Fitter::new(&a)
                .fit(&s, &idx, &FitParams::default())
                .unwrap();
            assert!(r.converged);
            let sigmas: Vec<f64> = r
                .weights
                .iter()
                .zip(&a.eigenvalues)
                .map(|(w, l)| w / l.sqrt())
                .collect();
            fits.push((r.iterations, sigmas));
        }
        let ((coarse, w0), (fine, w1)) = (&fits[0], &fits[1]);
        assert!(
            fine.abs_diff(*coarse) <= 1,
            "{coarse} updates at 120 points, {fine} at 960"
        );
        for (a, b) in w0.iter().zip(w1) {
            assert!((a - b).abs() < 0.05, "weights {w0:?} vs {w1:?} (sigmas)");
        }
    }

    #[test]
    fn fit_recovers_the_weights_and_pose_of_a_model_instance() {
        let a = atlas();
        let w = weights_at(&a, [1.5, -1.0, 0.8]);
        let mut sim = Similarity::<2>::planar_rotation(2.0);
        sim.s = 40.0;
        sim.t = [100.0, -20.0];
        let s = subject(&a, &w, &sim);
        let idx = ClosestPointIndex::from_shape(&s);
        let r = Fitter::new(&a)
            .fit(&s, &idx, &FitParams::default())
            .unwrap();
        for (k, (got, want)) in r.weights.iter().zip(&w).enumerate() {
            assert!(
                (got - want).abs() < 0.05 * a.eigenvalues[0].sqrt(),
                "mode {k}: {got} vs {want}"
            );
        }
        assert!(
            (r.similarity.s - 40.0).abs() < 0.4,
            "scale {}",
            r.similarity.s
        );
    }

    #[test]
    fn fit_is_invariant_to_the_subject_units() {
        let a = atlas();
        let w = weights_at(&a, [-1.0, 1.0, 0.5]);
        let mut small = Similarity::<2>::identity();
        small.s = 1.0;
        let mut big = small;
        big.s = 1000.0;
        let fa = Fitter::new(&a);
        let s1 = subject(&a, &w, &small);
        let s2 = subject(&a, &w, &big);
        let r1 = fa
            .fit(
                &s1,
                &ClosestPointIndex::from_shape(&s1),
                &FitParams::default(),
            )
            .unwrap();
        let r2 = fa
            .fit(
                &s2,
                &ClosestPointIndex::from_shape(&s2),
                &FitParams::default(),
            )
            .unwrap();
        for (x, y) in r1.weights.iter().zip(&r2.weights) {
            assert!(
                (x - y).abs() < 1e-6 * a.eigenvalues[0].sqrt() + 1e-9,
                "{x} vs {y}"
            );
        }
    }

    #[test]
    fn symmetric_fit_recovers_a_far_instance() {
        let a = atlas();
        let w = weights_at(&a, [2.8, -2.5, 2.5]);
        let s = subject(&a, &w, &Similarity::identity());
        let idx = ClosestPointIndex::from_shape(&s);
        let r = Fitter::new(&a)
            .fit(&s, &idx, &FitParams::default())
            .unwrap();
        let err: f64 = r
            .weights
            .iter()
            .zip(&w)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(err < 0.1 * a.eigenvalues[0].sqrt(), "weight error {err}");
    }
}

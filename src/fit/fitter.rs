//! The fit of Algorithm 1: starts, the schedule of `gamma`, the loop to convergence.

use super::params::{
    COARSE_MAX_ITERATIONS, COARSE_MODEL_FACTOR, COARSE_TOLERANCE_FACTOR, FULL_BACKWARD_SHARE,
    FitParams, GIVE_UP_AFTER, PRE_ALIGNMENT_ITERATIONS, PRE_PRUNE_AFTER, PRE_PRUNE_FACTOR,
    PRUNE_FACTOR, rotation_angle,
};
use super::resolution::{Level, Model, spread};
use super::result::FitResult;
use super::scratch::{Run, Scratches};
use super::state::{Pass, Sampling, Stage, State, Subject};
use crate::error::{Error, Result};
use crate::geometry::{
    ClosestPointIndex, Point, REFERENCE_POINTS, Shape, Similarity, SurfacePoint, centroid, dist2,
    project_along_normals, scale, start_rotations, sub,
};
use crate::model::Atlas;

/// For a subject with missing parts: a model point has no partner where its projection lands
/// on the subject's open border (a segment end, or an edge of a single facet) from farther than
/// one median edge length.
pub(super) fn partnered<const D: usize>(
    subject: &Shape<D>,
    projected: &[SurfacePoint<D>],
) -> Vec<bool> {
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
pub(super) fn orientation<const D: usize>(points: &[Point<D>], facets: &[[usize; D]]) -> f64 {
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

/// The atlas prepared for fitting: the model at full resolution and a coarse one for the
/// first stages (see [`Fitter::fit`]), `Lambda^{-1}`. Build once, fit many.
pub struct Fitter<const D: usize> {
    pub(super) atlas: std::sync::Arc<Atlas<D>>,
    pub(super) m: usize,
    pub(super) lambda_inv: Vec<f64>,
    pub(super) full: Model<D>,
    /// Built for [`FitParams::default`]'s `coarse_points`; `None` when the atlas is small.
    pub(super) coarse: Option<Model<D>>,
    pub(super) coarse_points: usize,
    /// The buffers of finished fits, for the next ones: megabytes for a femur (the instance's
    /// index, the rows of the linear system), whose pages, allocated afresh for every fit,
    /// cost it a few percent in page faults.
    pub(super) spare: std::sync::Mutex<Vec<Scratches<D>>>,
    /// The cap of an atlas built on a common cut ([`super::cut_cap`]), where no pair ends.
    pub(super) cap: Option<super::cut_cap::Cap<D>>,
}

/// Spare buffers a [`Fitter`] keeps at most (one per worker of a batch, typically).
pub(super) const SPARE_SCRATCHES: usize = 16;

impl<const D: usize> Fitter<D> {
    /// A fitter of `atlas`: its model at full and coarse resolution, precomputed once for every subject.
    ///
    /// # Panics
    /// For an atlas without facets (a model of point sets, [`Atlas::build_model`]), which has
    /// no surface to fit: check [`Atlas::has_mesh`] or [`Atlas::morpher`] first.
    pub fn new(atlas: std::sync::Arc<Atlas<D>>) -> Self {
        let n = atlas.mean.len();
        let coarse_points = FitParams::default().coarse_points;
        Fitter {
            m: atlas.num_modes(),
            lambda_inv: atlas.eigenvalues.iter().map(|l| 1.0 / l).collect(),
            full: Model::new(&atlas, (0..n).collect(), atlas.facets.clone()),
            coarse: Model::coarse(&atlas, COARSE_MODEL_FACTOR * coarse_points),
            coarse_points,
            spare: std::sync::Mutex::new(Vec::new()),
            cap: super::cut_cap::Cap::of(&atlas),
            atlas,
        }
    }

    /// The atlas this fitter fits.
    pub fn atlas(&self) -> &std::sync::Arc<Atlas<D>> {
        &self.atlas
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
            None => Scratches::new(&self.full, self.model(Level::Coarse, params)),
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
    pub(super) fn model(&self, level: Level, params: &FitParams) -> &Model<D> {
        match (level, &self.coarse) {
            (Level::Coarse, Some(c)) if params.coarse_points == self.coarse_points => c,
            _ => &self.full,
        }
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
        let rotations = start_rotations(&self.atlas.mean, cm, pts, cs, params.starts);
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
            .map(|st| (f64::INFINITY, Run::new(st, &self.full, x)))
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
        full_x.set_weights(&self.full, &run.state.w, false);
        let sim = run.state.sim;
        let instance: Vec<Point<D>> = full_x.x.iter().map(|p| sim.apply(p)).collect();
        let mut projected = project_along_normals(
            &instance,
            &self.atlas.facets,
            subj.index,
            subj.sign < 0.0,
            // By place in the last sampling's forward list: every point in order where it
            // has all of them (project_along_normals takes memos of the right length only).
            Some(&mut run.state.forward_memo),
        );
        let mut corresponded = if params.partial {
            partnered(subj.shape, &projected)
        } else {
            vec![true; projected.len()]
        };
        // The cap of an atlas of cut bones is where the delivered mesh ends, whether the
        // subject reaches it or not: the morph follows the instance's cap itself (projected
        // along its normal, a cap point would land on a longer shaft).
        if let Some(cap) = &self.cap {
            for ((c, pr), (&inside, &x)) in corresponded
                .iter_mut()
                .zip(&mut projected)
                .zip(cap.on_cap.iter().zip(&instance))
            {
                if inside {
                    *c = true;
                    pr.point = x;
                    pr.dist2 = 0.0;
                }
            }
        }
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
            x.full.set_weights(&self.full, &run.state.w, false);
            run.locus
                .push(x.full.x.iter().map(|p| run.state.sim.apply(p)).collect());
        }
        Ok(score)
    }
}

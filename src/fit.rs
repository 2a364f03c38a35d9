//! Fitting the atlas to a subject: shape instantiation and projection (section 3,
//! Algorithm 1, eq. 5-8).
//!
//! Frames: the model lives in the atlas's reference frame; the subject in its own frame
//! (its file's units). `t_{R,T,s}` maps reference to subject.

use crate::error::{Error, Result};
use crate::geometry::{
    ClosestPointIndex, Point, Shape, Similarity, SurfacePoint, centroid, dist2, norm, sub,
};
use crate::model::Atlas;
use crate::procrustes::fit_similarity;
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
    /// Inner loop ends when `||Δw|| < tolerance` (paper: 1e-6).
    pub tolerance: f64,
    /// Cap on correspondence updates per `gamma`.
    pub max_iterations: usize,
    /// Alternations of similarity and weights per correspondence (Cootes' protocol 1).
    pub protocol_iterations: usize,
    /// Add the subject-to-instance closest points to `E_d` (see [`fit`]).
    pub symmetric: bool,
    /// Starting rotations tried by the pre-alignment (2D; evenly spaced). 1 = identity only.
    pub starts: usize,
    /// Full fits run from the best distinct pre-alignments; the least two-way distance wins.
    pub full_starts: usize,
}

/// Number of points of the paper's hands (2001), for which its `gamma` values were chosen.
pub const REFERENCE_POINTS: f64 = 2001.0;

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            gamma_start: 0.3,
            gamma_factor: 0.25,
            gamma_stop: 0.008,
            tolerance: 1e-6,
            max_iterations: 100,
            protocol_iterations: 3,
            symmetric: true,
            starts: 8,
            full_starts: 2,
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
    /// `E_d` (eq. 6, subject units squared) at every correspondence update.
    pub e_d_history: Vec<f64>,
    /// The instance at the start and after every `gamma` (the locus of fig. 9), subject frame.
    pub locus: Vec<Vec<Point<D>>>,
    /// Correspondence updates done.
    pub iterations: usize,
    /// Whether the inner loop met the tolerance at the last `gamma`.
    pub converged: bool,
}

/// The atlas prepared for fitting: modes row-major, `Lambda^{-1}`. Build once, fit many.
pub struct Fitter<'a, const D: usize> {
    atlas: &'a Atlas<D>,
    psi: Vec<f64>,
    m: usize,
    lambda_inv: Vec<f64>,
}

impl<'a, const D: usize> Fitter<'a, D> {
    pub fn new(atlas: &'a Atlas<D>) -> Self {
        let m = atlas.num_modes();
        let rows = atlas.mean.len() * D;
        let mut psi = vec![0.0; rows * m];
        for r in 0..rows {
            for k in 0..m {
                psi[r * m + k] = atlas.modes[(r, k)];
            }
        }
        Fitter {
            atlas,
            psi,
            m,
            lambda_inv: atlas.eigenvalues.iter().map(|l| 1.0 / l).collect(),
        }
    }

    fn instance(&self, w: &[f64], out: &mut Vec<Point<D>>) {
        out.clear();
        out.extend(self.atlas.mean.iter().enumerate().map(|(i, p)| {
            std::array::from_fn(|d| {
                let row = &self.psi[(i * D + d) * self.m..(i * D + d + 1) * self.m];
                p[d] + row.iter().zip(w).map(|(a, b)| a * b).sum::<f64>()
            })
        }));
    }

    /// Fits the atlas to `subject` (Algorithm 1) and projects the result onto it.
    ///
    /// Each correspondence update (i) takes the closest point on the subject's facets of every
    /// instance point; step (ii) alternates the similarity (Umeyama) and the weights
    /// (eq. 8) `params.protocol_iterations` times; (iii) instantiates. The inner loop ends when
    /// `||Δw|| < tolerance`; then `gamma` decreases.
    ///
    /// # Deviations from the paper
    /// - Eq. 8 reads `w = (I + gamma/s² Λ^{-1})^{-1} Ψ^T (t^{-1}(Ŝ^c) - S_bar)`; we drop the
    ///   `1/s²`, i.e. measure `E_d` in the reference frame (mean in the unit box), so that
    ///   `gamma` means the same whatever the subject's units (the paper's hands were in the
    ///   unit box, `s ≈ 1`). Test `fit_is_invariant_to_the_subject_units`.
    /// - With `symmetric`, `E_d` also sums, over the subject's vertices, the squared distance
    ///   to their closest point on the instance (weighted so both directions count equally).
    ///   The one-way term lets an instance settle on part of the subject (a finger on its
    ///   neighbour) at a local minimum; the two-way term does not. Test
    ///   `symmetric_fit_recovers_a_far_instance` and the hands leave-one-out.
    /// - `E_d` sums over the `N` model points and the eigenvalues grow with `N`, so the
    ///   regularization's strength depends on `N`; the paper chose `gamma` for `N = 2001`.
    ///   We use `gamma · N / 2001`, which keeps its effect for any sampling.
    /// - Algorithm 1 starts from `R = I, T = 0, s = 1`. We start from the centroid and
    ///   RMS-radius match, try `params.starts` rotations with a similarity-only ICP (w = 0),
    ///   run Algorithm 1 from the `full_starts` best distinct ones, and keep the result of
    ///   least two-way distance (test `symmetric_fit_recovers_a_far_instance`).
    pub fn fit(
        &self,
        subject: &Shape<D>,
        subject_index: &ClosestPointIndex<D>,
        params: &FitParams,
    ) -> Result<FitResult<D>> {
        subject.validate()?;
        if subject.facets.is_empty() {
            return Err(Error::shape(
                &subject.name,
                "has no segments/facets to fit to",
            ));
        }
        let n = self.atlas.mean.len();
        let subj = &subject.points;
        let w_back = n as f64 / subj.len() as f64;

        // Pre-alignment.
        let cs = centroid(subj);
        let cm = centroid(&self.atlas.mean);
        let rms = |pts: &[Point<D>], c: Point<D>| {
            (pts.iter().map(|p| dist2(*p, c)).sum::<f64>() / pts.len() as f64).sqrt()
        };
        let s0 = rms(subj, cs) / rms(&self.atlas.mean, cm).max(f64::MIN_POSITIVE);
        let starts = if D == 2 { params.starts.max(1) } else { 1 };
        let zero = vec![0.0; self.m];
        let mut x = Vec::new();
        self.instance(&zero, &mut x);
        let mut pre: Vec<(f64, f64, Similarity<D>)> = Vec::new();
        for k in 0..starts {
            let angle = std::f64::consts::TAU * k as f64 / starts as f64;
            let mut sim = Similarity::<D>::planar_rotation(angle);
            sim.s = s0;
            let rc = sim.apply(&cm);
            sim.t = sub(cs, rc);
            for _ in 0..15 {
                let (src, dst, wts) =
                    self.correspondences(&x, &sim, subject, subject_index, w_back, true);
                sim = fit_similarity(&src, &dst, Some(&wts));
            }
            let d = self.two_way_ms(&x, &sim, subject, subject_index);
            pre.push((d, sim.r[1][0].atan2(sim.r[0][0]), sim));
        }
        pre.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Full fits from the best pre-alignments with distinct rotations; keep the least
        // two-way distance.
        let mut chosen: Vec<Similarity<D>> = Vec::new();
        let mut angles: Vec<f64> = Vec::new();
        for (_, a, sim) in &pre {
            let distinct = angles.iter().all(|b| {
                let d = (a - b).rem_euclid(std::f64::consts::TAU);
                d.min(std::f64::consts::TAU - d) > 20f64.to_radians()
            });
            if distinct {
                chosen.push(*sim);
                angles.push(*a);
            }
            if chosen.len() >= params.full_starts.max(1) {
                break;
            }
        }
        let mut best: Option<(f64, FitResult<D>)> = None;
        for sim in chosen {
            let r = self.fit_from(sim, subject, subject_index, params, w_back)?;
            let x_ref: Vec<Point<D>> = r
                .instance
                .iter()
                .map(|p| r.similarity.apply_inverse(p))
                .collect();
            let d = self.two_way_ms(&x_ref, &r.similarity, subject, subject_index);
            if best.as_ref().is_none_or(|(b, _)| d < *b) {
                best = Some((d, r));
            }
        }
        best.map(|b| b.1)
            .ok_or_else(|| Error::Numerical("no start was tried".into()))
    }

    /// Algorithm 1 from the pose `sim` with `w = 0`.
    fn fit_from(
        &self,
        mut sim: Similarity<D>,
        subject: &Shape<D>,
        subject_index: &ClosestPointIndex<D>,
        params: &FitParams,
        w_back: f64,
    ) -> Result<FitResult<D>> {
        let n = self.atlas.mean.len();
        let mut w = vec![0.0; self.m];
        let mut x = Vec::new();
        self.instance(&w, &mut x);
        let mut e_d_history = Vec::new();
        let mut locus = vec![x.iter().map(|p| sim.apply(p)).collect()];
        let mut iterations = 0;
        let mut converged = false;
        let gamma_scale = n as f64 / REFERENCE_POINTS;
        for gamma in params.gammas() {
            let gamma = gamma * gamma_scale;
            converged = false;
            for _ in 0..params.max_iterations {
                iterations += 1;
                // (i) correspondence.
                let (src_idx, dst, wts) = self.correspondence_sets(
                    &x,
                    &sim,
                    subject,
                    subject_index,
                    w_back,
                    params.symmetric,
                );
                e_d_history.push(
                    src_idx
                        .iter()
                        .zip(&dst)
                        .take(n)
                        .map(|(c, y)| dist2(sim.apply(&x[c.0[0]]), *y))
                        .sum(),
                );
                // (ii) similarity and weights for this correspondence.
                let w_old = w.clone();
                for _ in 0..params.protocol_iterations.max(1) {
                    let src: Vec<Point<D>> = src_idx.iter().map(|c| combo(&x, c)).collect();
                    sim = fit_similarity(&src, &dst, Some(&wts));
                    w = self.solve_weights(&src_idx, &dst, &wts, &sim, gamma)?;
                    // (iii) instantiate.
                    self.instance(&w, &mut x);
                }
                let dw = w
                    .iter()
                    .zip(&w_old)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt();
                if dw < params.tolerance {
                    converged = true;
                    break;
                }
            }
            locus.push(x.iter().map(|p| sim.apply(p)).collect());
        }
        let instance: Vec<Point<D>> = x.iter().map(|p| sim.apply(p)).collect();
        let projected = project_along_normals(&instance, &self.atlas.facets, subject_index);
        Ok(FitResult {
            weights: w,
            similarity: sim,
            instance,
            projected,
            e_d_history,
            locus,
            iterations,
            converged,
        })
    }

    /// Correspondences as (model point combination, subject-frame target, weight): first the
    /// `N` forward pairs (instance point → closest subject point), then, if `symmetric`, the
    /// backward pairs (subject vertex → closest point on the instance's facets).
    #[allow(clippy::type_complexity)]
    fn correspondence_sets(
        &self,
        x: &[Point<D>],
        sim: &Similarity<D>,
        subject: &Shape<D>,
        index: &ClosestPointIndex<D>,
        w_back: f64,
        symmetric: bool,
    ) -> (Vec<([usize; D], [f64; D])>, Vec<Point<D>>, Vec<f64>) {
        let xs: Vec<Point<D>> = x.iter().map(|p| sim.apply(p)).collect();
        let mut src = Vec::with_capacity(xs.len() * 2);
        let mut dst = Vec::with_capacity(xs.len() * 2);
        let mut wts = Vec::with_capacity(xs.len() * 2);
        let mut one = [0.0; D];
        one[0] = 1.0;
        for (j, p) in xs.iter().enumerate() {
            let c = index.closest(p);
            src.push(([j; D], one));
            dst.push(c.point);
            wts.push(1.0);
        }
        if symmetric {
            let inst = ClosestPointIndex::new(&xs, &self.atlas.facets);
            for q in &subject.points {
                let c = inst.closest(q);
                src.push((self.atlas.facets[c.facet], c.weights));
                dst.push(*q);
                wts.push(w_back);
            }
        }
        (src, dst, wts)
    }

    #[allow(clippy::type_complexity)]
    fn correspondences(
        &self,
        x: &[Point<D>],
        sim: &Similarity<D>,
        subject: &Shape<D>,
        index: &ClosestPointIndex<D>,
        w_back: f64,
        symmetric: bool,
    ) -> (Vec<Point<D>>, Vec<Point<D>>, Vec<f64>) {
        let (s, d, w) = self.correspondence_sets(x, sim, subject, index, w_back, symmetric);
        (s.iter().map(|c| combo(x, c)).collect(), d, w)
    }

    /// Mean of the two one-way mean squared distances between the instance `t ∘ x` and the
    /// subject (subject units squared).
    fn two_way_ms(
        &self,
        x: &[Point<D>],
        sim: &Similarity<D>,
        subject: &Shape<D>,
        index: &ClosestPointIndex<D>,
    ) -> f64 {
        let xs: Vec<Point<D>> = x.iter().map(|p| sim.apply(p)).collect();
        let f = xs.iter().map(|p| index.closest(p).dist2).sum::<f64>() / xs.len() as f64;
        let inst = ClosestPointIndex::new(&xs, &self.atlas.facets);
        let b = subject
            .points
            .iter()
            .map(|q| inst.closest(q).dist2)
            .sum::<f64>()
            / subject.points.len() as f64;
        0.5 * (f + b)
    }

    /// Minimizes `Σ_c ω_c ||t^{-1}(y_c) - A_c (S_bar + Ψ w)||² + gamma w^T Λ^{-1} w` over `w`
    /// for fixed `t` (eq. 8 generalized to weighted combinations of model points; with only
    /// the forward pairs `Σ A^T A = Ψ^T Ψ = I` and this is eq. 8 exactly).
    fn solve_weights(
        &self,
        src: &[([usize; D], [f64; D])],
        dst: &[Point<D>],
        wts: &[f64],
        sim: &Similarity<D>,
        gamma: f64,
    ) -> Result<Vec<f64>> {
        let m = self.m;
        let mut a = Mat::<f64>::zeros(m, m);
        let mut rhs = Mat::<f64>::zeros(m, 1);
        for k in 0..m {
            a[(k, k)] = gamma * self.lambda_inv[k];
        }
        let mut row = vec![0.0; m];
        for ((ids, bw), (y, &om)) in src.iter().zip(dst.iter().zip(wts)) {
            let z = sim.apply_inverse(y);
            let single = bw[0] == 1.0 && bw[1..].iter().all(|&b| b == 0.0);
            for d in 0..D {
                row.iter_mut().for_each(|r| *r = 0.0);
                let mut mean = 0.0;
                for (k, &i) in ids.iter().enumerate() {
                    if bw[k] == 0.0 {
                        continue;
                    }
                    let pr = &self.psi[(i * D + d) * m..(i * D + d + 1) * m];
                    for (r, p) in row.iter_mut().zip(pr) {
                        *r += bw[k] * p;
                    }
                    mean += bw[k] * self.atlas.mean[i][d];
                    if single {
                        break;
                    }
                }
                let r = z[d] - mean;
                for p in 0..m {
                    rhs[(p, 0)] += om * row[p] * r;
                    if !single {
                        for q in 0..m {
                            a[(p, q)] += om * row[p] * row[q];
                        }
                    }
                }
            }
        }
        let forward: f64 = src
            .iter()
            .zip(wts)
            .filter(|(c, _)| c.1[0] == 1.0 && c.1[1..].iter().all(|&b| b == 0.0))
            .map(|(_, w)| *w)
            .sum::<f64>();
        // Forward pairs cover all N model points with weight 1: their Gram matrix is Ψ^T Ψ = I.
        let nf = forward / self.atlas.mean.len() as f64;
        for k in 0..m {
            a[(k, k)] += nf;
        }
        let llt = a
            .llt(faer::Side::Lower)
            .map_err(|_| Error::Numerical("the weight system of eq. 8 is singular".into()))?;
        let sol = llt.solve(&rhs);
        let w: Vec<f64> = (0..m).map(|k| sol[(k, 0)]).collect();
        if w.iter().any(|v| !v.is_finite()) {
            return Err(Error::Numerical("the mode weights became NaN".into()));
        }
        Ok(w)
    }
}

#[inline]
fn combo<const D: usize>(x: &[Point<D>], c: &([usize; D], [f64; D])) -> Point<D> {
    let mut p = [0.0; D];
    for k in 0..D {
        if c.1[k] != 0.0 {
            for d in 0..D {
                p[d] += c.1[k] * x[c.0[k]][d];
            }
        }
    }
    p
}

/// Projects every point of `points` (with the connectivity `facets`, for its vertex normals)
/// onto the indexed subject along its normal (section 3, last step of Algorithm 1): the
/// nearest crossing of the normal line within three times the closest-point distance plus
/// half the local edge length; the closest point where the normal misses.
pub fn project_along_normals<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
    subject: &ClosestPointIndex<D>,
) -> Vec<SurfacePoint<D>> {
    let shape = Shape {
        name: String::new(),
        points: points.to_vec(),
        facets: facets.to_vec(),
        landmarks: Vec::new(),
    };
    let normals = shape.vertex_normals();
    let h = 0.5 * shape.median_edge_length();
    points
        .iter()
        .zip(&normals)
        .map(|(p, nrm)| {
            let c = subject.closest(p);
            if norm(*nrm) == 0.0 {
                return c;
            }
            let max_t = 3.0 * c.dist2.sqrt() + h;
            subject.ray(p, nrm, max_t).unwrap_or(c)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{AtlasParams, ModeSelection};

    fn atlas() -> Atlas<2> {
        let shapes: Vec<Shape<2>> = (0..12)
            .map(|k| {
                let a = 1.0 + 0.1 * (k as f64 * 1.7).sin();
                let b = 0.6 + 0.06 * (k as f64 * 2.3).cos();
                let c = 0.05 * (k as f64 * 0.9).cos();
                let pts = (0..120)
                    .map(|i| {
                        let t = i as f64 / 120.0 * std::f64::consts::TAU;
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
    fn fit_recovers_the_weights_and_pose_of_a_model_instance() {
        let a = atlas();
        let w: Vec<f64> = a
            .eigenvalues
            .iter()
            .zip([1.5, -1.0, 0.8])
            .map(|(l, f)| f * l.sqrt())
            .collect();
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
        let w: Vec<f64> = a
            .eigenvalues
            .iter()
            .zip([-1.0, 1.0, 0.5])
            .map(|(l, f)| f * l.sqrt())
            .collect();
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
        let w: Vec<f64> = a
            .eigenvalues
            .iter()
            .zip([2.8, -2.5, 2.5])
            .map(|(l, f)| f * l.sqrt())
            .collect();
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

//! One update of the shape parameters and the pose: eq. 5-8 linearized along the normals.

use super::fitter::Fitter;
use super::params::compatibility;
use super::resolution::Level;
use super::scratch::Scratches;
use super::state::{Sampling, State, Step, Subject};
use crate::error::{Error, Result};
use crate::geometry::{
    ClosestPointIndex, Point, QueryMemo, REFERENCE_POINTS, Similarity, add, dot, scale, sub,
};
use faer::Mat;
use faer::linalg::solvers::Solve;

/// Number of rotation parameters in `D` dimensions.
pub(super) const fn rotation_params(d: usize) -> usize {
    d * (d - 1) / 2
}

/// `G_k x`: the `k`-th infinitesimal rotation applied to `x` (2D: `(-x_1, x_0)`; 3D:
/// `e_k × x`).
#[inline]
pub(super) fn generator<const D: usize>(k: usize, x: &Point<D>) -> Point<D> {
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

impl<const D: usize> Fitter<D> {
    /// One correspondence update: (i) closest points at the current state, (ii) one
    /// Gauss-Newton step of eq. 5 (all pose parameters, and `w` unless `gamma` is `None`),
    /// (iii) the new state.
    ///
    /// Linearization, in the reference frame: with `x = S_bar + Ψ w`, the update
    /// `t' = t ∘ (x ↦ (1 + δs)(I + Σ δω_k G_k) x + δt)`, `w' = w + δw`, the residual of a
    /// pair along its unit normal `ñ` (reference frame) is
    /// `ñ · (x - t^{-1}(c) + δs x + Σ δω_k G_k x + δt + Ψ δw)`.
    pub(super) fn update(
        &self,
        level: Level,
        subj: &Subject<D>,
        st: &mut State<D>,
        sampling: &Sampling,
        gamma: Option<f64>,
        scratches: &mut Scratches<D>,
    ) -> Result<Step> {
        let model = match level {
            Level::Coarse => match &self.coarse {
                Some(c) if scratches.use_coarse => c,
                _ => &self.full,
            },
            Level::Full => &self.full,
        };
        let scratch = match level {
            Level::Coarse if !std::ptr::eq(model, &self.full) => &mut scratches.coarse,
            _ => &mut scratches.full,
        };
        let m = self.m;
        let pose = 1 + rotation_params(D) + D;
        let p = if gamma.is_some() { pose + m } else { pose };
        let sim = st.sim;
        scratch.set_weights(model, &st.w, true);
        let rows = Rows {
            x: &scratch.x,
            psi: &model.psi,
            m,
            p,
            cap: self.cap.as_ref(),
        };
        let buf = &mut scratch.rows;
        buf.clear();
        // One allocation for all the rows, not a doubling series.
        buf.reserve((p + 1) * (sampling.forward.len() + sampling.backward.len()));
        if st.memos_for != Some(sampling.pass) {
            st.forward_memo.clear();
            st.forward_memo
                .resize(sampling.forward.len(), QueryMemo::default());
            st.backward_memo.clear();
            st.backward_memo
                .resize(sampling.backward.len(), QueryMemo::default());
            st.memos_for = Some(sampling.pass);
        }
        let forward = rows.forward(
            subj,
            &sim,
            &scratch.normals,
            sampling,
            &mut st.forward_memo,
            buf,
        );
        let backward = rows.backward(
            subj,
            &sim,
            &scratch.index,
            sampling,
            &mut st.backward_memo,
            buf,
        );
        let two_way_ms = if sampling.backward.is_empty() {
            forward / sampling.forward.len() as f64
        } else if sampling.forward.is_empty() {
            backward / sampling.backward.len() as f64
        } else {
            0.5 * (forward / sampling.forward.len() as f64
                + backward / sampling.backward.len() as f64)
        };
        let dz = self.solve_step(buf, p, gamma, &st.w, &subj.shape.name)?;
        // (iii) the new state.
        let weight_change = self.apply_step(st, &dz);
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

    /// (ii) The Gauss-Newton step of eq. 5 from the rows `buf` (each `p + 1` numbers: the
    /// derivatives by the `p` parameters, then the residual) and, with `gamma`, the
    /// regularization of eq. 7 at the weights `w`: `(AᵀA + γ Λ⁻¹) δ = -(Aᵀr + γ Λ⁻¹ w)`, in
    /// a trust region (at most 0.2 in scale and rotation, 0.1 of the unit box in translation,
    /// 1 σ per mode). `name` (the subject's) is for messages.
    fn solve_step(
        &self,
        buf: &[f64],
        p: usize,
        gamma: Option<f64>,
        w: &[f64],
        name: &str,
    ) -> Result<Vec<f64>> {
        let m = self.m;
        let r = rotation_params(D);
        let pose = 1 + r + D;
        let cols = p + 1;
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
                g[(pose + k, 0)] -= gamma * self.lambda_inv[k] * w[k];
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
                name
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
        Ok(dz)
    }

    /// (iii) The new state: the pose composed with the step `dz` (scale, rotation, translation
    /// in the reference frame), the weights moved by it. Returns the weights' change, per
    /// point as for the paper's 2001 points.
    fn apply_step(&self, st: &mut State<D>, dz: &[f64]) -> f64 {
        let m = self.m;
        let r = rotation_params(D);
        let pose = 1 + r + D;
        let p = dz.len();
        let sim = st.sim;
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
        (weight_change * REFERENCE_POINTS / self.atlas.mean.len() as f64).sqrt()
    }
}

/// The rows of the linearized problem of eq. 5 at an instance `x` (reference frame): each
/// `p + 1` numbers, the derivatives by scale, rotations, translations and (when `p` exceeds
/// the pose's parameters) the `m` weights, then the residual.
struct Rows<'a, const D: usize> {
    x: &'a [Point<D>],
    /// The model's modes, `(i * D + d) * m + k`.
    psi: &'a [f64],
    m: usize,
    p: usize,
    /// The cap of an atlas of cut shapes: no pair ends on it.
    cap: Option<&'a super::cut_cap::Cap<D>>,
}

impl<const D: usize> Rows<'_, D> {
    /// Appends the row of the model point combination `(ids, bw)` with unit normal `nr` and
    /// target `z` (both in the reference frame), scaled by `sw` (root of its weight).
    fn push(
        &self,
        buf: &mut Vec<f64>,
        ids: &[usize],
        bw: &[f64],
        nr: Point<D>,
        z: Point<D>,
        sw: f64,
    ) {
        let (r, m, p) = (rotation_params(D), self.m, self.p);
        let pose = 1 + r + D;
        let at = buf.len();
        buf.resize(at + p + 1, 0.0);
        let row = &mut buf[at..];
        let mut xc = [0.0; D];
        for (&i, &b) in ids.iter().zip(bw) {
            xc = add(xc, scale(self.x[i], b));
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
                    let pr = &self.psi[(i * D + d) * m..(i * D + d + 1) * m];
                    for (o, v) in rw.iter_mut().zip(pr) {
                        *o += f * v;
                    }
                }
            }
        }
        row[p] = sw * dot(nr, sub(xc, z));
    }

    /// The forward pairs' rows: model point -> closest point on the subject (searched in the
    /// subject's frame). `normals` are the instance's. Returns the sum of squared distances.
    fn forward(
        &self,
        subj: &Subject<D>,
        sim: &Similarity<D>,
        normals: &[Point<D>],
        sampling: &Sampling,
        memos: &mut [QueryMemo<D>],
        buf: &mut Vec<f64>,
    ) -> f64 {
        let mut forward = 0.0;
        for (&j, memo) in sampling.forward.iter().zip(memos) {
            if self
                .cap
                .is_some_and(|cap| cap.holds(&self.x[j], &normals[j]))
            {
                continue;
            }
            let c = subj.index.closest_memo(&sim.apply(&self.x[j]), memo);
            forward += c.dist2;
            // From the index, which the search has just read.
            let Some(n) = subj.index.normal_at(&c) else {
                continue;
            };
            let n = scale(n, subj.sign);
            let nr = sim.rotate_inverse(&n);
            let cw = compatibility(dot(nr, normals[j]));
            if cw == 0.0 {
                continue;
            }
            self.push(buf, &[j], &[1.0], nr, sim.apply_inverse(&c.point), cw);
        }
        forward
    }

    /// The backward pairs' rows: subject vertex -> closest point on the instance (`index`),
    /// searched in the reference frame (a similarity keeps closest points), so the instance's
    /// index changes only with `w`. Returns the sum of squared distances (subject's units).
    fn backward(
        &self,
        subj: &Subject<D>,
        sim: &Similarity<D>,
        index: &ClosestPointIndex<D>,
        sampling: &Sampling,
        memos: &mut [QueryMemo<D>],
        buf: &mut Vec<f64>,
    ) -> f64 {
        let mut backward = 0.0;
        if sampling.backward.is_empty() {
            return backward;
        }
        // Backward pairs weigh as much as the forward ones together; alone (a partial
        // subject), as much as both directions would (so that `gamma` acts alike).
        let total = if sampling.forward.is_empty() {
            2.0
        } else {
            1.0
        };
        let sw = (total * sampling.pairs() as f64 / sampling.backward.len() as f64).sqrt();
        for (&i, memo) in sampling.backward.iter().zip(memos) {
            let z = sim.apply_inverse(&subj.shape.points[i]);
            if self.cap.is_some_and(|cap| cap.beyond(&z)) {
                continue;
            }
            let c = index.closest_memo(&z, memo);
            let (Some(n), Some(f)) = (index.normal_at(&c), index.facet_vertices(&c)) else {
                backward += c.dist2 * sim.s * sim.s;
                continue;
            };
            if self.cap.is_some_and(|cap| cap.holds(&c.point, &n)) {
                continue;
            }
            backward += c.dist2 * sim.s * sim.s;
            let cw = compatibility(dot(n, sim.rotate_inverse(&subj.normals[i])));
            if cw == 0.0 {
                continue;
            }
            self.push(buf, &f, &c.weights, n, z, sw * cw);
        }
        backward
    }
}

//! The shape model's vocabulary (as scalismo names it): the mean, instances, coefficients and
//! projections (eq. 4), the model truncated to its first modes, random shapes drawn from it,
//! the marginal model of some of its points, and the posterior model given some of its points
//! observed with noise.
//!
//! All of it is the linear Gaussian model of eq. 4: `S = S_bar + Psi w` with the weights
//! `w ~ N(0, Lambda)`, `Lambda = diag(lambda_1..lambda_m)`, points in the atlas's reference
//! frame (see [`crate::model`]), in correspondence with the mean (point `i` of a shape is
//! point `i` of the mean).

use super::Atlas;
use super::standard_normal::standard_normal;
use crate::error::{Error, Result};
use crate::geometry::Point;
use faer::Mat;
use faer::linalg::solvers::Solve;

/// The model restricted to some of its points (scalismo's `marginal`): the same weights, the
/// rows of the modes for those points. Reference frame.
#[derive(Clone, Debug)]
pub struct MarginalModel<const D: usize> {
    /// The atlas's indices of the points kept.
    pub points: Vec<usize>,
    /// The mean at those points.
    pub mean: Vec<Point<D>>,
    /// The rows of `Psi` of those points: `points.len()·D × m` (not orthonormal).
    pub modes: Mat<f64>,
    /// The eigenvalues `lambda_k` (the weights' variances), unchanged.
    pub eigenvalues: Vec<f64>,
}

impl<const D: usize> MarginalModel<D> {
    /// `S_bar_I + Psi_I w` (eq. 4 at the kept points).
    #[track_caller]
    pub fn instance(&self, w: &[f64]) -> Vec<Point<D>> {
        assert_eq!(
            w.len(),
            self.eigenvalues.len(),
            "instance: one weight per mode"
        );
        super::atlas::combine(&self.mean, &self.modes, w)
    }

    /// The model's covariance of one kept point (`D × D`, reference-frame units squared):
    /// `Psi_i Lambda Psi_i^T`.
    pub fn covariance(&self, k: usize) -> [[f64; D]; D] {
        point_covariance::<D>(&self.modes, k, |a, b| {
            if a == b { self.eigenvalues[a] } else { 0.0 }
        })
    }
}

/// The posterior model given some points observed with noise (scalismo's `posterior`): the
/// weights' Gaussian `N(weights, covariance)`, its mean shape and each point's spread.
/// Reference frame.
#[derive(Clone, Debug)]
pub struct PosteriorModel<const D: usize> {
    /// The posterior mean of the weights.
    pub weights: Vec<f64>,
    /// The posterior covariance of the weights (`m × m`).
    pub covariance: Mat<f64>,
    /// The posterior mean shape, `S_bar + Psi weights`, every point of the model.
    pub mean: Vec<Point<D>>,
    /// Per point, the root of the expected squared distance between the shape and the
    /// posterior mean, `sqrt(trace(Psi_i Sigma Psi_i^T))` (reference-frame units): the
    /// spread the posterior leaves at that point.
    pub point_sd: Vec<f64>,
}

impl<const D: usize> Atlas<D> {
    /// The mean shape's points `S_bar` (eq. 4 with `w = 0`), reference frame.
    pub fn mean(&self) -> &[Point<D>] {
        &self.mean
    }

    /// The closest model instance to `x` (reference frame, `N` points in correspondence,
    /// aligned to the mean): `S_bar + Psi Psi^T (x - S_bar)`, the orthogonal projection onto
    /// the model's span (eq. 4 at [`Atlas::coefficients`]).
    #[track_caller]
    pub fn project(&self, x: &[Point<D>]) -> Vec<Point<D>> {
        self.instance(&self.coefficients(x))
    }

    /// The model of the first `m` modes (`1 <= m <= num_modes()`): the same mean, mesh and
    /// facets; `cumulative_variance` stays that of the training PCA.
    ///
    /// # Errors
    /// [`Error::Parameter`] for `m` out of range.
    pub fn truncate(&self, m: usize) -> Result<Atlas<D>> {
        if m == 0 || m > self.num_modes() {
            return Err(Error::Parameter(format!(
                "truncate: {m} modes asked, the model has {} (at least 1)",
                self.num_modes()
            )));
        }
        let mut a = self.clone();
        a.modes = self.modes.subcols(0, m).to_owned();
        a.eigenvalues.truncate(m);
        Ok(a)
    }

    /// The weights `w` in standard deviations of each mode: `w_k / sqrt(lambda_k)` (eq. 4,
    /// `Lambda` of eq. 7), the shape space's coordinates a user compares across subjects.
    pub fn in_sd(&self, w: &[f64]) -> Vec<f64> {
        w.iter()
            .zip(&self.eigenvalues)
            .map(|(w, l)| w / l.sqrt())
            .collect()
    }

    /// Random weights of the model: `w_k = sqrt(lambda_k) z_k`, `z_k` standard normal
    /// (eq. 4's prior `w ~ N(0, Lambda)`); with `max_sd`, each `z_k` is drawn again until
    /// `|z_k| <= max_sd` (a normal truncated at `max_sd` standard deviations).
    ///
    /// # Errors
    /// [`Error::Parameter`] when `max_sd` is not a finite number of at least 0.5.
    pub fn sample_weights(
        &self,
        rng: &mut rand_chacha::ChaCha8Rng,
        max_sd: Option<f64>,
    ) -> Result<Vec<f64>> {
        let bound = match max_sd {
            Some(k) if !(k.is_finite() && k >= 0.5) => {
                return Err(Error::Parameter(format!(
                    "sample: the bound of {k} standard deviations must be a finite number of at least 0.5"
                )));
            }
            Some(k) => k,
            None => f64::INFINITY,
        };
        Ok(self
            .eigenvalues
            .iter()
            .map(|l| {
                let z = loop {
                    let z = standard_normal(rng);
                    if z.abs() <= bound {
                        break z;
                    }
                };
                z * l.sqrt()
            })
            .collect())
    }

    /// A random shape of the model, [`Atlas::instance`] of [`Atlas::sample_weights`].
    ///
    /// # Errors
    /// As [`Atlas::sample_weights`].
    pub fn sample(
        &self,
        rng: &mut rand_chacha::ChaCha8Rng,
        max_sd: Option<f64>,
    ) -> Result<Vec<Point<D>>> {
        Ok(self.instance(&self.sample_weights(rng, max_sd)?))
    }

    /// The model at the points `points` only (scalismo's `marginal`).
    ///
    /// # Errors
    /// [`Error::Parameter`] for no point or a point out of range.
    pub fn marginal(&self, points: &[usize]) -> Result<MarginalModel<D>> {
        let n = self.mean.len();
        if points.is_empty() {
            return Err(Error::Parameter("marginal: no point given".into()));
        }
        if let Some(i) = points.iter().find(|&&i| i >= n) {
            return Err(Error::Parameter(format!(
                "marginal: point {i} is out of range (the model has {n} points)"
            )));
        }
        let m = self.num_modes();
        Ok(MarginalModel {
            points: points.to_vec(),
            mean: points.iter().map(|&i| self.mean[i]).collect(),
            modes: Mat::from_fn(points.len() * D, m, |r, c| {
                self.modes[(points[r / D] * D + r % D, c)]
            }),
            eigenvalues: self.eigenvalues.clone(),
        })
    }

    /// The posterior model given the points `observed` (`(index, position)`, reference
    /// frame) observed with isotropic Gaussian noise of variance `sigma2` (reference-frame
    /// units squared): the conditioning of eq. 4's Gaussian on `y_I = S_bar_I + Psi_I w + e`,
    /// `e ~ N(0, sigma2 I)`:
    ///
    /// `Sigma = (Lambda^-1 + Psi_I^T Psi_I / sigma2)^-1`,
    /// `w_post = Sigma Psi_I^T (y_I - S_bar_I) / sigma2`.
    ///
    /// With no observation it is the prior (`w_post = 0`, `Sigma = Lambda`).
    ///
    /// # Errors
    /// [`Error::Parameter`] for a point out of range, a point observed twice, a non-finite
    /// position or a `sigma2` that is not finite and positive; [`Error::Numerical`] when the
    /// system cannot be solved.
    pub fn posterior(
        &self,
        observed: &[(usize, Point<D>)],
        sigma2: f64,
    ) -> Result<PosteriorModel<D>> {
        if !(sigma2.is_finite() && sigma2 > 0.0) {
            return Err(Error::Parameter(format!(
                "posterior: the noise variance {sigma2} must be finite and positive"
            )));
        }
        let mut seen = std::collections::BTreeSet::new();
        for (i, p) in observed {
            if !seen.insert(*i) {
                return Err(Error::Parameter(format!(
                    "posterior: point {i} is observed twice"
                )));
            }
            if p.iter().any(|c| !c.is_finite()) {
                return Err(Error::Parameter(format!(
                    "posterior: point {i} has a NaN or infinite coordinate"
                )));
            }
        }
        let m = self.num_modes();
        let points: Vec<usize> = observed.iter().map(|o| o.0).collect();
        let (precision, rhs) = if points.is_empty() {
            (
                Mat::from_fn(m, m, |a, b| {
                    if a == b {
                        1.0 / self.eigenvalues[a]
                    } else {
                        0.0
                    }
                }),
                Mat::<f64>::zeros(m, 1),
            )
        } else {
            let mg = self.marginal(&points)?;
            let a = &mg.modes;
            let mut h = a.transpose() * a;
            for x in 0..m {
                for y in 0..m {
                    h[(x, y)] /= sigma2;
                }
                h[(x, x)] += 1.0 / self.eigenvalues[x];
            }
            let resid = Mat::from_fn(points.len() * D, 1, |r, _| {
                observed[r / D].1[r % D] - mg.mean[r / D][r % D]
            });
            let mut g = a.transpose() * &resid;
            for x in 0..m {
                g[(x, 0)] /= sigma2;
            }
            (h, g)
        };
        let llt = precision
            .llt(faer::Side::Lower)
            .map_err(|_| Error::Numerical("posterior: the precision matrix is singular".into()))?;
        let covariance = llt.solve(Mat::<f64>::identity(m, m));
        let wm = &covariance * &rhs;
        crate::clear_simd_upper_state();
        let weights: Vec<f64> = (0..m).map(|k| wm[(k, 0)]).collect();
        if weights.iter().any(|w| !w.is_finite()) {
            return Err(Error::Numerical(
                "posterior: the weights are not finite".into(),
            ));
        }
        let point_sd = (0..self.mean.len())
            .map(|i| {
                let c = point_covariance::<D>(&self.modes, i, |a, b| covariance[(a, b)]);
                (0..D).map(|d| c[d][d]).sum::<f64>().max(0.0).sqrt()
            })
            .collect();
        Ok(PosteriorModel {
            mean: self.instance(&weights),
            weights,
            covariance,
            point_sd,
        })
    }
}

/// `Psi_i S Psi_i^T` (`D × D`) for the point `i` of `modes` and a weight covariance `S`
/// given entry by entry.
fn point_covariance<const D: usize>(
    modes: &Mat<f64>,
    i: usize,
    s: impl Fn(usize, usize) -> f64,
) -> [[f64; D]; D] {
    let m = modes.ncols();
    let mut c = [[0.0; D]; D];
    for a in 0..m {
        for b in 0..m {
            let sab = s(a, b);
            if sab == 0.0 {
                continue;
            }
            for (x, row) in c.iter_mut().enumerate() {
                for (y, v) in row.iter_mut().enumerate() {
                    *v += modes[(i * D + x, a)] * sab * modes[(i * D + y, b)];
                }
            }
        }
    }
    c
}

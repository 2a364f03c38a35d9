//! Principal component analysis of aligned shapes (section 2.3), by a thin SVD of the centred
//! data matrix (never the `N·D × N·D` covariance).

use crate::error::{Error, Result};
use crate::geometry::Point;
use faer::Mat;

/// Principal components of a set of aligned shapes.
#[derive(Clone, Debug)]
pub struct Pca {
    /// Eigenmodes `Psi`: `N·D × m` with `m ≤ min(n_s - 1, N·D)`, orthonormal columns, coordinates interleaved
    /// `[x_1, y_1, (z_1,) x_2, ...]` as in the paper's vectorization.
    pub modes: Mat<f64>,
    /// Eigenvalues `lambda_k` of the covariance `Phi Phi^T / (n_s - 1)`, decreasing.
    pub eigenvalues: Vec<f64>,
    /// The total variance `trace(Phi Phi^T) / (n_s - 1)`: the sum of every eigenvalue, those
    /// of the modes not computed (a truncated PCA's) included.
    pub total_variance: f64,
}

impl Pca {
    /// Cumulative share of the total variance explained by the first `1, 2, …` modes.
    pub fn cumulative_variance(&self) -> Vec<f64> {
        let total = self.total_variance;
        let mut acc = 0.0;
        self.eigenvalues
            .iter()
            .map(|l| {
                acc += l;
                if total > 0.0 { acc / total } else { 1.0 }
            })
            .collect()
    }

    /// The number of modes needed to explain at least the share `p` of the variance.
    pub fn modes_for_variance(&self, p: f64) -> usize {
        let cum = self.cumulative_variance();
        cum.iter()
            .position(|&c| c >= p - 1e-12)
            .map_or(cum.len(), |i| i + 1)
    }
}

/// PCA of the shapes `aligned` (each `N` points) about `mean` (section 2.3): thin SVD of the
/// `N·D × n_s` matrix `Phi = [S_k^a - S_bar]`; `Psi = U`, `lambda = sigma² / (n_s - 1)`.
/// Keeps the modes of non-zero variance: at most `n_s - 1` (the last singular value of
/// centred data is zero) and at most `N·D` (more shapes than coordinates: the data span at
/// most the coordinate space), dropping the trailing ones at round-off level.
pub fn pca<const D: usize>(aligned: &[Vec<Point<D>>], mean: &[Point<D>]) -> Result<Pca> {
    let ns = aligned.len();
    if ns < 2 {
        return Err(Error::Population("PCA needs at least 2 shapes".into()));
    }
    let rows = mean.len() * D;
    let phi = Mat::<f64>::from_fn(rows, ns, |r, k| {
        aligned[k][r / D][r % D] - mean[r / D][r % D]
    });
    let svd = phi.thin_svd().map_or_else(
        |_| {
            Err(Error::Numerical(
                "the SVD of the shape data did not converge".into(),
            ))
        },
        Ok,
    )?;
    crate::clear_simd_upper_state();
    let s = svd.S().column_vector();
    let eigenvalues = eigenvalues_of(&s, ns, (ns - 1).min(rows))?;
    let modes = svd.U().subcols(0, eigenvalues.len()).to_owned();
    let total_variance = eigenvalues.iter().sum();
    Ok(Pca {
        modes,
        eigenvalues,
        total_variance,
    })
}

/// The eigenvalues `sigma_k² / (n_s - 1)` of the first `available` singular values `s`
/// (decreasing) of centred data of `ns` shapes, without the trailing ones at round-off level
/// (below 1e-24 of the largest).
///
/// # Errors
/// [`Error::Population`] when none is above round-off: the shapes are identical.
pub(crate) fn eigenvalues_of(
    s: &faer::ColRef<'_, f64>,
    ns: usize,
    available: usize,
) -> Result<Vec<f64>> {
    let mut eigenvalues: Vec<f64> = (0..available.min(s.nrows()))
        .map(|k| s[k] * s[k] / (ns - 1) as f64)
        .collect();
    let largest = eigenvalues.first().copied().unwrap_or(0.0);
    eigenvalues.retain(|&l| l.is_finite() && l > largest * 1e-24);
    if largest.is_nan() || largest <= 0.0 || eigenvalues.is_empty() {
        return Err(Error::Population(
            "the shapes are identical after alignment: there is no variance to model".into(),
        ));
    }
    Ok(eigenvalues)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pca_reconstructs_its_data() {
        let mean: Vec<Point<2>> = (0..10).map(|i| [i as f64, (i * i) as f64 * 0.1]).collect();
        let shapes: Vec<Vec<Point<2>>> = (0..6)
            .map(|k| {
                mean.iter()
                    .enumerate()
                    .map(|(i, p)| {
                        [
                            p[0] + 0.1 * ((k * i) as f64).sin(),
                            p[1] + 0.05 * (k as f64 - 2.5),
                        ]
                    })
                    .collect()
            })
            .collect();
        let mut m = vec![[0.0; 2]; 10];
        for s in &shapes {
            for (a, p) in m.iter_mut().zip(s) {
                a[0] += p[0] / 6.0;
                a[1] += p[1] / 6.0;
            }
        }
        let p = pca(&shapes, &m).unwrap();
        for s in &shapes {
            let x: Vec<f64> = (0..20).map(|r| s[r / 2][r % 2] - m[r / 2][r % 2]).collect();
            for r in 0..20 {
                let rec: f64 = (0..p.modes.ncols())
                    .map(|k| p.modes[(r, k)] * (0..20).map(|q| p.modes[(q, k)] * x[q]).sum::<f64>())
                    .sum();
                assert!((rec - x[r]).abs() < 1e-10);
            }
        }
        assert!(p.eigenvalues.windows(2).all(|w| w[0] >= w[1]));
    }

    /// Far more shapes than coordinates (240 shapes of 5 points in 2D: 10 coordinates): at
    /// most 10 modes, orthonormal, and they reconstruct every shape.
    #[test]
    fn pca_with_more_shapes_than_coordinates() {
        let shapes: Vec<Vec<Point<2>>> = (0..240)
            .map(|k| {
                (0..5)
                    .map(|i| {
                        let a = i as f64 * 1.2566;
                        // A pseudo-random offset per shape, point and axis (full rank).
                        let wobble = |d: usize| {
                            let h = (k * 10 + i * 2 + d).wrapping_mul(2_654_435_761) % 1000;
                            0.1 * (h as f64 / 1000.0 - 0.5)
                        };
                        [a.cos() + wobble(0), a.sin() + wobble(1)]
                    })
                    .collect()
            })
            .collect();
        let mut m = vec![[0.0; 2]; 5];
        for s in &shapes {
            for (a, p) in m.iter_mut().zip(s) {
                a[0] += p[0] / 240.0;
                a[1] += p[1] / 240.0;
            }
        }
        let p = pca(&shapes, &m).unwrap();
        assert_eq!(p.modes.ncols(), 10);
        assert_eq!(p.modes.ncols(), p.eigenvalues.len());
        assert!(p.eigenvalues.iter().all(|&l| l > 0.0));
        for a in 0..p.modes.ncols() {
            for b in 0..p.modes.ncols() {
                let d: f64 = (0..10).map(|r| p.modes[(r, a)] * p.modes[(r, b)]).sum();
                assert!((d - f64::from(u8::from(a == b))).abs() < 1e-9);
            }
        }
        for s in &shapes {
            let x: Vec<f64> = (0..10).map(|r| s[r / 2][r % 2] - m[r / 2][r % 2]).collect();
            for r in 0..10 {
                let rec: f64 = (0..p.modes.ncols())
                    .map(|k| p.modes[(r, k)] * (0..10).map(|q| p.modes[(q, k)] * x[q]).sum::<f64>())
                    .sum();
                assert!((rec - x[r]).abs() < 1e-9);
            }
        }
    }
}

//! The correlation of normals at corresponding points (section 5.2, eq. 10-13).

use crate::geometry::{Point, Shape, SurfacePoint, normalize};

/// The subject's normals at points on its facets, interpolated from its vertex normals.
pub fn normals_at<const D: usize>(subject: &Shape<D>, points: &[SurfacePoint<D>]) -> Vec<Point<D>> {
    let vn = subject.vertex_normals();
    points
        .iter()
        .map(|sp| {
            let f = subject.facets[sp.facet];
            let mut n = [0.0; D];
            for k in 0..D {
                for d in 0..D {
                    n[d] += sp.weights[k] * vn[f[k]][d];
                }
            }
            normalize(n)
        })
        .collect()
}

/// Correlation of two random vectors sampled at corresponding points (eq. 10-13):
/// `ϱ(X, Y) = sqrt(Σ_i ϱ_i² σ_ii / Σ_i σ_ii)`, with `ϱ_i² σ_ii = Σ12 Σ22^{-1} Σ21` the variance
/// of `x_i` explained by linear regression on `Y` (eq. 12). In [0, 1]; invariant to rotations
/// of either set, so the normals may be in different frames.
#[track_caller]
pub fn normal_correlation<const D: usize>(x: &[Point<D>], y: &[Point<D>]) -> f64 {
    assert_eq!(
        x.len(),
        y.len(),
        "normal_correlation: corresponding samples"
    );
    let n = x.len() as f64;
    if x.len() < 2 {
        return 0.0;
    }
    let mean = |v: &[Point<D>]| -> Point<D> {
        std::array::from_fn(|d| v.iter().map(|p| p[d]).sum::<f64>() / n)
    };
    let (mx, my) = (mean(x), mean(y));
    let mut sxy = [[0.0; D]; D];
    let mut syy = [[0.0; D]; D];
    let mut sxx = [0.0; D];
    for (a, b) in x.iter().zip(y) {
        for i in 0..D {
            sxx[i] += (a[i] - mx[i]).powi(2);
            for j in 0..D {
                sxy[i][j] += (a[i] - mx[i]) * (b[j] - my[j]);
                syy[i][j] += (b[i] - my[i]) * (b[j] - my[j]);
            }
        }
    }
    let total: f64 = sxx.iter().sum();
    if total <= 0.0 {
        return 0.0;
    }
    // Σ22^{-1} Σ21 for every component by Gaussian elimination with a tiny ridge.
    let ridge = 1e-12
        * (0..D)
            .map(|i| syy[i][i])
            .sum::<f64>()
            .max(f64::MIN_POSITIVE);
    let mut explained = 0.0;
    for i in 0..D {
        let mut a = syy;
        for (k, row) in a.iter_mut().enumerate() {
            row[k] += ridge;
        }
        let mut b = sxy[i];
        // Solve a z = b.
        for c in 0..D {
            let piv = (c..D)
                .max_by(|&p, &q| a[p][c].abs().total_cmp(&a[q][c].abs()))
                .unwrap_or(c);
            a.swap(c, piv);
            b.swap(c, piv);
            if a[c][c].abs() < f64::MIN_POSITIVE {
                continue;
            }
            for r in c + 1..D {
                let f = a[r][c] / a[c][c];
                for k in c..D {
                    a[r][k] -= f * a[c][k];
                }
                b[r] -= f * b[c];
            }
        }
        let mut z = [0.0; D];
        for c in (0..D).rev() {
            let s: f64 = (c + 1..D).map(|k| a[c][k] * z[k]).sum();
            z[c] = if a[c][c].abs() < f64::MIN_POSITIVE {
                0.0
            } else {
                (b[c] - s) / a[c][c]
            };
        }
        explained += (0..D).map(|k| sxy[i][k] * z[k]).sum::<f64>();
    }
    (explained / total).clamp(0.0, 1.0).sqrt()
}

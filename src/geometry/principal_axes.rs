//! Principal axes of a point set, and the starting rotations they give an alignment.

use super::{Point, Similarity, centroid, sub};

/// Starting rotations of a pre-alignment of `template` (centroid `ct`) to `target` (centroid
/// `cs`): in 2D `starts` angles evenly round the circle; in 3D the four proper rotations that
/// map the template's principal axes onto the target's (the signs of the axes are unknown),
/// and the identity.
pub fn start_rotations<const D: usize>(
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
pub(super) fn principal_axes<const D: usize>(points: &[Point<D>], c: Point<D>) -> [[f64; D]; D] {
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
pub fn principal_axes_of<const D: usize>(points: &[Point<D>]) -> [[f64; D]; D] {
    principal_axes(points, centroid(points))
}

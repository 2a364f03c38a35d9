//! Similarity alignment (Umeyama) and generalized Procrustes analysis (section 2.2).

use crate::error::{Error, Result};
use crate::geometry::{Point, Similarity, centroid, dot, scale, sub};
use faer::Mat;

/// The similarity `t` minimizing `Σ_j w_j ||dst_j - t(src_j)||²` (Umeyama 1991), with
/// `det R = +1`. `weights = None` means all ones. Both lists have the same length, at least 2.
///
/// Frames: `src` in the reference frame, `dst` in the subject frame; `t` maps the former to the
/// latter.
#[track_caller]
pub fn fit_similarity<const D: usize>(
    src: &[Point<D>],
    dst: &[Point<D>],
    weights: Option<&[f64]>,
) -> Similarity<D> {
    assert_eq!(
        src.len(),
        dst.len(),
        "fit_similarity: lists of different lengths"
    );
    let w = |j: usize| weights.map_or(1.0, |w| w[j]);
    let wsum: f64 = (0..src.len()).map(w).sum();
    let mut ms = [0.0; D];
    let mut md = [0.0; D];
    for j in 0..src.len() {
        for d in 0..D {
            ms[d] += w(j) * src[j][d];
            md[d] += w(j) * dst[j][d];
        }
    }
    ms = scale(ms, 1.0 / wsum);
    md = scale(md, 1.0 / wsum);
    // H = Σ w (dst - md)(src - ms)^T and the source variance.
    let mut h = [[0.0; D]; D];
    let mut var = 0.0;
    for j in 0..src.len() {
        let a = sub(src[j], ms);
        let b = sub(dst[j], md);
        let wj = w(j);
        var += wj * dot(a, a);
        for i in 0..D {
            for k in 0..D {
                h[i][k] += wj * b[i] * a[k];
            }
        }
    }
    let (r, trace) = optimal_rotation(&h);
    let s = if var > 0.0 {
        (trace / var).max(f64::MIN_POSITIVE)
    } else {
        1.0
    };
    let mut t = Similarity { s, r, t: [0.0; D] };
    let rms = t.apply(&ms);
    t.t = sub(md, rms);
    t
}

/// The rotation `R` maximizing `trace(R^T H)` and that maximum (`trace(S D)` of the SVD).
fn optimal_rotation<const D: usize>(h: &[[f64; D]; D]) -> ([[f64; D]; D], f64) {
    if D == 2 {
        let a = h[0][0] + h[1][1];
        let b = h[1][0] - h[0][1];
        let th = b.atan2(a);
        let (sn, c) = th.sin_cos();
        let mut r = [[0.0; D]; D];
        r[0][0] = c;
        r[0][1] = -sn;
        r[1][0] = sn;
        r[1][1] = c;
        return (r, (a * a + b * b).sqrt());
    }
    let m = Mat::<f64>::from_fn(D, D, |i, j| h[i][j]);
    let Ok(svd) = m.svd() else {
        return (Similarity::<D>::identity().r, 0.0);
    };
    crate::clear_simd_upper_state();
    let (u, sv, v) = (svd.U(), svd.S(), svd.V());
    let det = |x: faer::MatRef<f64>| -> f64 {
        // 3x3 determinant (D = 3 is the only other supported dimension).
        x[(0, 0)] * (x[(1, 1)] * x[(2, 2)] - x[(1, 2)] * x[(2, 1)])
            - x[(0, 1)] * (x[(1, 0)] * x[(2, 2)] - x[(1, 2)] * x[(2, 0)])
            + x[(0, 2)] * (x[(1, 0)] * x[(2, 1)] - x[(1, 1)] * x[(2, 0)])
    };
    let sign = if det(u) * det(v) < 0.0 { -1.0 } else { 1.0 };
    let mut r = [[0.0; D]; D];
    let mut trace = 0.0;
    for k in 0..D {
        let f = if k == D - 1 { sign } else { 1.0 };
        trace += f * sv[k];
        for i in 0..D {
            for j in 0..D {
                r[i][j] += f * u[(i, k)] * v[(j, k)];
            }
        }
    }
    (r, trace)
}

/// `s` centred at the origin and scaled to unit norm (Frobenius, over all points); `None`
/// when all its points are at one place.
pub(crate) fn normalized<const D: usize>(s: &[Point<D>]) -> Option<Vec<Point<D>>> {
    let c = centroid(s);
    let x: Vec<Point<D>> = s.iter().map(|p| sub(*p, c)).collect();
    let nrm = x.iter().map(|p| dot(*p, *p)).sum::<f64>().sqrt();
    (nrm > 0.0).then(|| x.iter().map(|p| scale(*p, 1.0 / nrm)).collect())
}

/// GPA stops when its mean moves less than this (Frobenius norm; the mean has norm 1).
pub(crate) const GPA_TOLERANCE: f64 = 1e-12;

/// GPA's iterations at most.
pub(crate) const GPA_MAX_ITERATIONS: usize = 100;

/// One GPA update of the mean (section 2.2): `sum`, the average of the shapes aligned to the
/// current mean `mean`, normalized and rotated back to the orientation of `reference` (the
/// first shape: the mean's orientation stays fixed). Returns the new mean and how far it
/// moved from `mean`.
pub(crate) fn next_mean<const D: usize>(
    sum: &[Point<D>],
    mean: &[Point<D>],
    reference: &[Point<D>],
) -> Result<(Vec<Point<D>>, f64)> {
    let m = normalized(sum)
        .ok_or_else(|| Error::Numerical("the Procrustes mean collapsed to a point".into()))?;
    // Keep the mean's orientation fixed to the reference (rotation only).
    let t = fit_similarity(&m, reference, None);
    let rot = Similarity {
        s: 1.0,
        r: t.r,
        t: [0.0; D],
    };
    let m: Vec<Point<D>> = m.iter().map(|p| rot.apply(p)).collect();
    let change: f64 = m
        .iter()
        .zip(mean)
        .map(|(a, b)| crate::geometry::dist2(*a, *b))
        .sum::<f64>()
        .sqrt();
    Ok((m, change))
}

/// Result of generalized Procrustes analysis.
#[derive(Clone, Debug)]
pub struct Gpa<const D: usize> {
    /// Mean shape `S_bar` (eq. 3), centred at the origin, `||S_bar|| = 1` (Frobenius norm over
    /// all points).
    pub mean: Vec<Point<D>>,
    /// The shapes aligned to the mean and projected to its tangent space: `x / (x · S_bar)`.
    pub aligned: Vec<Vec<Point<D>>>,
    /// Iterations used.
    pub iterations: usize,
}

/// Generalized Procrustes analysis with projection to the tangent space of the mean (section
/// 2.2; Cootes & Taylor's algorithm): centre and scale every shape to unit norm, align them
/// iteratively to their mean (similarity; the mean's rotation is kept at the first shape's
/// orientation), then project each aligned shape `x` to the tangent space `x / (x · S_bar)`.
///
/// `shapes`: `n_s` shapes of `N` corresponding points each, `n_s >= 2`.
pub fn generalized_procrustes<const D: usize>(shapes: &[Vec<Point<D>>]) -> Result<Gpa<D>> {
    if shapes.len() < 2 {
        return Err(Error::Population(format!(
            "{} shape(s); at least 2 are needed",
            shapes.len()
        )));
    }
    let n = shapes[0].len();
    if shapes.iter().any(|s| s.len() != n) {
        return Err(Error::Population(
            "shapes have different point counts".into(),
        ));
    }
    let mut x: Vec<Vec<Point<D>>> = Vec::with_capacity(shapes.len());
    for (k, s) in shapes.iter().enumerate() {
        x.push(normalized(s).ok_or_else(|| {
            Error::Population(format!("shape {k} has all its points at one place"))
        })?);
    }
    let reference = x[0].clone();
    let mut mean = reference.clone();
    let mut iterations = 0;
    for it in 0..GPA_MAX_ITERATIONS {
        iterations = it + 1;
        for s in x.iter_mut() {
            let t = fit_similarity(s, &mean, None);
            *s = s.iter().map(|p| t.apply(p)).collect();
        }
        let mut m = vec![[0.0; D]; n];
        for s in &x {
            for (a, p) in m.iter_mut().zip(s) {
                for d in 0..D {
                    a[d] += p[d] / x.len() as f64;
                }
            }
        }
        let (m, change) = next_mean(&m, &mean, &reference)?;
        mean = m;
        if change < GPA_TOLERANCE {
            break;
        }
    }
    // Final alignment to the converged mean, then tangent-space projection.
    let aligned = x.iter().map(|s| align_to_mean(s, &mean)).collect();
    Ok(Gpa {
        mean,
        aligned,
        iterations,
    })
}

/// A shape in the frame of a Procrustes mean `mean` (centred, unit norm): aligned by the
/// least-squares similarity, then projected to the mean's tangent space, `x / (x · S_bar)`
/// (section 2.2). For a shape outside the population (a held-out one).
pub fn align_to_mean<const D: usize>(shape: &[Point<D>], mean: &[Point<D>]) -> Vec<Point<D>> {
    let t = fit_similarity(shape, mean, None);
    let a: Vec<Point<D>> = shape.iter().map(|p| t.apply(p)).collect();
    let proj: f64 = a.iter().zip(mean).map(|(p, q)| dot(*p, *q)).sum();
    a.iter().map(|p| scale(*p, 1.0 / proj)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::dist2;

    fn sample3() -> Vec<Point<3>> {
        (0..30)
            .map(|i| {
                let t = i as f64 * 0.37;
                [t.sin() * 2.0, (1.3 * t).cos(), 0.2 * t]
            })
            .collect()
    }

    #[test]
    fn procrustes_recovers_a_known_similarity_2d() {
        let src: Vec<Point<2>> = (0..40)
            .map(|i| {
                [
                    (i as f64 * 0.3).cos() * (1.0 + 0.1 * i as f64),
                    (i as f64 * 0.7).sin(),
                ]
            })
            .collect();
        let mut truth = Similarity::<2>::planar_rotation(2.4);
        truth.s = 3.7;
        truth.t = [-4.0, 12.5];
        let dst: Vec<Point<2>> = src.iter().map(|p| truth.apply(p)).collect();
        let t = fit_similarity(&src, &dst, None);
        assert!((t.s - truth.s).abs() < 1e-12);
        for i in 0..2 {
            assert!((t.t[i] - truth.t[i]).abs() < 1e-10);
            for j in 0..2 {
                assert!((t.r[i][j] - truth.r[i][j]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn procrustes_recovers_a_known_similarity_3d() {
        let src = sample3();
        // Rotation about a skew axis (Rodrigues).
        let axis = crate::geometry::normalize([1.0, -2.0, 0.5]);
        let (sn, c) = 1.1f64.sin_cos();
        let k = [
            [0.0, -axis[2], axis[1]],
            [axis[2], 0.0, -axis[0]],
            [-axis[1], axis[0], 0.0],
        ];
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let k2: f64 = (0..3).map(|l| k[i][l] * k[l][j]).sum();
                r[i][j] = if i == j { 1.0 } else { 0.0 } + sn * k[i][j] + (1.0 - c) * k2;
            }
        }
        let truth = Similarity {
            s: 0.25,
            r,
            t: [3.0, 2.0, -1.0],
        };
        let dst: Vec<Point<3>> = src.iter().map(|p| truth.apply(p)).collect();
        let t = fit_similarity(&src, &dst, None);
        for (p, q) in src.iter().zip(&dst) {
            assert!(dist2(t.apply(p), *q) < 1e-20);
        }
        assert!((t.s - 0.25).abs() < 1e-12);
    }

    #[test]
    fn gpa_of_similar_copies_gives_zero_residual() {
        let base: Vec<Point<2>> = (0..25)
            .map(|i| [(i as f64).cos() + 0.1 * i as f64, (i as f64 * 1.3).sin()])
            .collect();
        let shapes: Vec<Vec<Point<2>>> = (0..5)
            .map(|k| {
                let mut t = Similarity::<2>::planar_rotation(k as f64);
                t.s = 1.0 + k as f64;
                t.t = [k as f64, -2.0 * k as f64];
                base.iter().map(|p| t.apply(p)).collect()
            })
            .collect();
        let g = generalized_procrustes(&shapes).unwrap();
        for a in &g.aligned {
            let r: f64 = a.iter().zip(&g.mean).map(|(p, q)| dist2(*p, *q)).sum();
            assert!(r < 1e-20, "residual {r}");
        }
    }
}

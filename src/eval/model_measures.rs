//! Compactness, generalization and specificity of a shape model (Styner et al. 2003).

use crate::geometry::{Point, Shape};

/// The standard measures of a shape model built from shapes in correspondence (Davies 2002;
/// Styner et al. 2003), for the first `1..=modes.len()` modes. Distances are mean point-to-
/// point distances between corresponding points, in the units of the input shapes (the
/// Procrustes frame scaled by the shapes' mean centroid size); standard errors beside them.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShapeModelMeasures {
    /// Number of modes `M` of each entry: `1, 2, ...`.
    pub modes: Vec<usize>,
    /// Compactness `C(M) = Σ_{m<=M} λ_m / Σ λ`: the share of the variance explained.
    pub compactness: Vec<f64>,
    /// Standard error of `C(M)`: `Σ_{m<=M} sqrt(2 / n_s) λ_m / Σ λ`.
    pub compactness_sd: Vec<f64>,
    /// Generalization `G(M)`: each shape left out, the model of the others with `M` modes,
    /// the left-out shape (Procrustes-aligned to that model's mean) projected into it; the
    /// mean distance between it and its projection, averaged over the shapes.
    pub generalization: Vec<f64>,
    /// Standard error of `G(M)` over the left-out shapes.
    pub generalization_sd: Vec<f64>,
    /// Specificity `S(M)`: random instances of the model (weights drawn from `N(0, λ_m)`),
    /// each one's mean distance to the nearest training shape, averaged.
    pub specificity: Vec<f64>,
    /// Standard error of `S(M)` over the instances.
    pub specificity_sd: Vec<f64>,
    /// Random instances per `M` in the specificity.
    pub specificity_samples: usize,
}

/// Compactness, generalization and specificity (see [`ShapeModelMeasures`]) of the model of
/// `shapes` (in correspondence: same point count), for `1..=max_modes` modes (at most
/// `n_s - 2`, the modes of every leave-one-out model), with `samples` random instances per
/// `M` drawn from a generator seeded with `seed`. Units of the shapes.
pub fn shape_model_measures<const D: usize>(
    shapes: &[Shape<D>],
    max_modes: usize,
    samples: usize,
    seed: u64,
) -> crate::error::Result<ShapeModelMeasures> {
    use crate::error::Error;
    use crate::model::{align_to_mean, generalized_procrustes};
    use rayon::prelude::*;
    let ns = shapes.len();
    if ns < 4 {
        return Err(Error::Population(format!(
            "{ns} shapes; the shape-model measures need at least 4"
        )));
    }
    let mm = max_modes.min(ns - 2);
    if mm == 0 || samples == 0 {
        return Err(Error::Parameter(
            "shape-model measures: at least one mode and one sample".into(),
        ));
    }
    let raw: Vec<Vec<Point<D>>> = shapes.iter().map(|s| s.points.clone()).collect();
    // Shape units per Procrustes unit: the mean centroid size (the mean has norm 1).
    let unit = raw
        .iter()
        .map(|s| crate::geometry::centroid_size(s))
        .sum::<f64>()
        / ns as f64;
    let mean_distance = |a: &[Point<D>], b: &[Point<D>]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| crate::geometry::dist2(*p, *q).sqrt())
            .sum::<f64>()
            / a.len() as f64
            * unit
    };
    let gpa = generalized_procrustes(&raw)?;
    let full = crate::model::pca(&gpa.aligned, &gpa.mean)?;
    let total: f64 = full.eigenvalues.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(Error::Population(
            "the shapes are identical after alignment: no variance to model".into(),
        ));
    }
    // (A population may have fewer modes than shapes less one: PCA drops the round-off ones.)
    let mm = mm.min(full.eigenvalues.len());
    let mut out = ShapeModelMeasures {
        modes: (1..=mm).collect(),
        specificity_samples: samples,
        ..Default::default()
    };
    let (mut c, mut csd) = (0.0, 0.0);
    for &l in &full.eigenvalues[..mm] {
        c += l / total;
        csd += (2.0 / ns as f64).sqrt() * l / total;
        out.compactness.push(c);
        out.compactness_sd.push(csd);
    }
    // Generalization: per left-out shape, its error for every M.
    let errors: Vec<Vec<f64>> = (0..ns)
        .into_par_iter()
        .map(|i| {
            let rest: Vec<Vec<Point<D>>> = raw
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != i)
                .map(|(_, s)| s.clone())
                .collect();
            let g = generalized_procrustes(&rest)?;
            let p = crate::model::pca(&g.aligned, &g.mean)?;
            let x = align_to_mean(&raw[i], &g.mean);
            let mut recon = g.mean.clone();
            let mut e = Vec::with_capacity(mm);
            for m in 0..mm {
                // A left-out model with fewer modes: the reconstruction stays.
                if m >= p.modes.ncols() {
                    e.push(mean_distance(&recon, &x));
                    continue;
                }
                let col = p.modes.col(m);
                let w: f64 = x
                    .iter()
                    .zip(&g.mean)
                    .enumerate()
                    .map(|(j, (a, b))| (0..D).map(|d| col[j * D + d] * (a[d] - b[d])).sum::<f64>())
                    .sum();
                for (j, r) in recon.iter_mut().enumerate() {
                    for d in 0..D {
                        r[d] += w * col[j * D + d];
                    }
                }
                e.push(mean_distance(&recon, &x));
            }
            Ok(e)
        })
        .collect::<crate::error::Result<_>>()?;
    let mean_sd = |v: &[f64]| -> (f64, f64) {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0).max(1.0);
        (m, (var / n).sqrt())
    };
    for m in 0..mm {
        let (g, sd) = mean_sd(&errors.iter().map(|e| e[m]).collect::<Vec<_>>());
        out.generalization.push(g);
        out.generalization_sd.push(sd);
    }
    // Specificity: the same weights for every M (the first M of them), seeded per sample.
    let spec: Vec<Vec<f64>> = (0..samples)
        .into_par_iter()
        .map(|k| {
            use rand::SeedableRng;
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
                seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
            );
            let mut inst = gpa.mean.clone();
            (0..mm)
                .map(|m| {
                    let w = standard_normal(&mut rng) * full.eigenvalues[m].sqrt();
                    let col = full.modes.col(m);
                    for (j, r) in inst.iter_mut().enumerate() {
                        for d in 0..D {
                            r[d] += w * col[j * D + d];
                        }
                    }
                    gpa.aligned
                        .iter()
                        .map(|t| mean_distance(&inst, t))
                        .fold(f64::INFINITY, f64::min)
                })
                .collect()
        })
        .collect();
    for m in 0..mm {
        let (s, sd) = mean_sd(&spec.iter().map(|e| e[m]).collect::<Vec<_>>());
        out.specificity.push(s);
        out.specificity_sd.push(sd);
    }
    Ok(out)
}

/// Standard normal deviate (Box-Muller) from a seeded generator.
pub(crate) fn standard_normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::RngExt;
    let u: f64 = rng.random_range(1e-12..1.0);
    let v: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

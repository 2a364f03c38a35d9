//! Compactness, generalization and specificity of a shape model (Styner et al. 2003).

use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, centroid_size, dist2};
use crate::model::{Atlas, AtlasParams, ModeSelection, align_to_mean, standard_normal};
use rand::SeedableRng;
use rayon::prelude::*;

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
    /// mean distance between it and its projection, averaged over the shapes. A population
    /// of more than [`LEAVE_ONE_OUT_UP_TO`] shapes leaves out each of
    /// [`GENERALIZATION_FOLDS`] consecutive groups in turn instead of each shape
    /// (`generalization_folds`): as many models as folds, not as shapes.
    pub generalization: Vec<f64>,
    /// `None`: the generalization left out each shape in turn; `Some(K)`: each of K
    /// consecutive groups of shapes (a population of more than [`LEAVE_ONE_OUT_UP_TO`]).
    #[serde(default)]
    pub generalization_folds: Option<usize>,
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

/// The largest population whose generalization leaves out each shape in turn (a model of
/// the others each: as many models as shapes); a larger one leaves out each of
/// [`GENERALIZATION_FOLDS`] groups.
pub const LEAVE_ONE_OUT_UP_TO: usize = 200;

/// The folds of a large population's generalization (10-fold, the usual choice).
pub const GENERALIZATION_FOLDS: usize = 10;

/// Compactness, generalization and specificity (see [`ShapeModelMeasures`]) of the model of
/// `shapes` (in correspondence: same point count), for `1..=max_modes` modes (at most
/// `n_s - 2`, the modes of every leave-one-out model), with `samples` random instances per
/// `M` drawn from a generator seeded with `seed`. Units of the shapes. Built on the model's
/// vocabulary: [`crate::model::Atlas::build_model`] of the shapes (and of each leave-one-out
/// population), [`crate::model::Atlas::truncate`], [`crate::model::Atlas::project`],
/// [`crate::model::Atlas::instance`].
pub fn shape_model_measures<const D: usize>(
    shapes: &[Shape<D>],
    max_modes: usize,
    samples: usize,
    seed: u64,
) -> Result<ShapeModelMeasures> {
    let folds = (shapes.len() > LEAVE_ONE_OUT_UP_TO).then_some(GENERALIZATION_FOLDS);
    measures_with_folds(shapes, max_modes, samples, seed, folds)
}

/// [`shape_model_measures`] with the generalization's folds chosen: `None` leaves out each
/// shape in turn, `Some(K)` each of K consecutive groups.
pub(crate) fn measures_with_folds<const D: usize>(
    shapes: &[Shape<D>],
    max_modes: usize,
    samples: usize,
    seed: u64,
    folds: Option<usize>,
) -> Result<ShapeModelMeasures> {
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
    let pop = Measured::of(shapes);
    let full = pop.model_of(shapes)?;
    // (A population may have fewer modes than shapes less one: PCA drops the round-off ones.)
    let mm = mm.min(full.num_modes());
    let mut out = ShapeModelMeasures {
        modes: (1..=mm).collect(),
        specificity_samples: samples,
        ..Default::default()
    };
    let variance: f64 = full.eigenvalues.iter().sum();
    let (mut c, mut csd) = (0.0, 0.0);
    for &l in &full.eigenvalues[..mm] {
        c += l / variance;
        csd += (2.0 / ns as f64).sqrt() * l / variance;
        out.compactness.push(c);
        out.compactness_sd.push(csd);
    }
    out.generalization_folds = folds;
    let groups: Vec<Vec<usize>> = match folds {
        None => (0..ns).map(|i| vec![i]).collect(),
        Some(k) => super::fold_groups(ns, k)?,
    };
    let errors = pop.generalization_errors(&groups, mm)?;
    for m in 0..mm {
        let (g, sd) = mean_sd(&errors.iter().map(|e| e[m]).collect::<Vec<_>>());
        out.generalization.push(g);
        out.generalization_sd.push(sd);
    }
    let spec = pop.specificity_distances(&full, mm, samples, seed);
    for m in 0..mm {
        let (s, sd) = mean_sd(&spec.iter().map(|e| e[m]).collect::<Vec<_>>());
        out.specificity.push(s);
        out.specificity_sd.push(sd);
    }
    Ok(out)
}

/// A population being measured: its shapes, their points and the unit distances are given in.
struct Measured<'a, const D: usize> {
    shapes: &'a [Shape<D>],
    raw: Vec<Vec<Point<D>>>,
    /// Shape units per Procrustes unit: the mean centroid size (the Procrustes mean has
    /// norm 1).
    unit: f64,
    /// Every model keeps all its modes; `truncate` gives the first M.
    params: AtlasParams,
}

impl<'a, const D: usize> Measured<'a, D> {
    fn of(shapes: &'a [Shape<D>]) -> Self {
        let raw: Vec<Vec<Point<D>>> = shapes.iter().map(|s| s.points.clone()).collect();
        let unit = raw.iter().map(|s| centroid_size(s)).sum::<f64>() / shapes.len() as f64;
        Measured {
            shapes,
            raw,
            unit,
            params: AtlasParams {
                modes: ModeSelection::Variance(1.0),
                ..AtlasParams::default()
            },
        }
    }

    fn model_of(&self, shapes: &[Shape<D>]) -> Result<Atlas<D>> {
        Atlas::build_model(shapes, &self.params).map_err(|e| match e {
            Error::Population(m) if m.contains("identical") => Error::Population(
                "the shapes are identical after alignment: no variance to model".into(),
            ),
            e => e,
        })
    }

    /// The mean distance between corresponding points of `a` and `b` (a model's reference
    /// frame of mean norm `r`), in shape units.
    fn mean_distance(&self, a: &[Point<D>], b: &[Point<D>], r: f64) -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| dist2(*p, *q).sqrt())
            .sum::<f64>()
            / a.len() as f64
            * self.unit
            / r
    }

    /// Shape `i`'s points in `model`'s reference frame: aligned to its unit mean (tangent
    /// space), then scaled back by `r`.
    fn in_frame(&self, i: usize, unit_mean: &[Point<D>], r: f64) -> Vec<Point<D>> {
        align_to_mean(&self.raw[i], unit_mean)
            .iter()
            .map(|p| p.map(|c| c * r))
            .collect()
    }

    /// Generalization: per group of left-out shapes (`groups`: one shape each for the
    /// leave-one-out), the model of the others truncated to M modes, each left-out shape
    /// projected into it (`truncate(M).project`); its mean distance for every M, one row per
    /// shape.
    fn generalization_errors(&self, groups: &[Vec<usize>], mm: usize) -> Result<Vec<Vec<f64>>> {
        let per_group: Vec<Vec<Vec<f64>>> = groups
            .par_iter()
            .map(|group| {
                let mut left_out = vec![false; self.shapes.len()];
                group.iter().for_each(|&i| left_out[i] = true);
                let rest: Vec<Shape<D>> = self
                    .shapes
                    .iter()
                    .zip(&left_out)
                    .filter(|(_, out)| !**out)
                    .map(|(s, _)| s.clone())
                    .collect();
                let model = self.model_of(&rest)?;
                let (unit_mean, r) = frame(&model);
                group
                    .iter()
                    .map(|&i| {
                        let x = self.in_frame(i, &unit_mean, r);
                        (0..mm)
                            .map(|m| {
                                // A left-out model with fewer modes: its projection stays.
                                let kept = (m + 1).min(model.num_modes());
                                let projected = model.truncate(kept)?.project(&x);
                                Ok(self.mean_distance(&projected, &x, r))
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect::<Result<_>>()?;
        Ok(per_group.into_iter().flatten().collect())
    }

    /// Specificity: per sample, the distance of the instance of the first M weights to the
    /// nearest training shape, for every M; the same weights for every M, seeded per sample;
    /// the training shapes aligned to the full model's mean as the left-out ones above.
    fn specificity_distances(
        &self,
        full: &Atlas<D>,
        mm: usize,
        samples: usize,
        seed: u64,
    ) -> Vec<Vec<f64>> {
        let (unit_mean, r) = frame(full);
        let training: Vec<Vec<Point<D>>> = (0..self.raw.len())
            .map(|i| self.in_frame(i, &unit_mean, r))
            .collect();
        (0..samples)
            .into_par_iter()
            .map(|k| {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
                    seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
                );
                let mut w = vec![0.0; full.num_modes()];
                (0..mm)
                    .map(|m| {
                        w[m] = standard_normal(&mut rng) * full.eigenvalues[m].sqrt();
                        let inst = full.instance(&w);
                        training
                            .iter()
                            .map(|t| self.mean_distance(&inst, t, r))
                            .fold(f64::INFINITY, f64::min)
                    })
                    .collect()
            })
            .collect()
    }
}

/// A model's reference frame is its Procrustes frame scaled to a mean of norm `r`: its unit
/// mean and `r`. (Distances there are brought to shape units by `unit / r`.)
fn frame<const D: usize>(a: &Atlas<D>) -> (Vec<Point<D>>, f64) {
    let r = a
        .mean
        .iter()
        .map(|p| p.iter().map(|c| c * c).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    (a.mean.iter().map(|p| p.map(|c| c / r)).collect(), r)
}

/// The mean of `v` and its standard error.
fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, (var / n).sqrt())
}

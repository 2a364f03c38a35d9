//! Parameters of Algorithm 1 and the constants of its schedule.

use crate::error::{Error, Result};
use crate::geometry::COMPATIBLE_NORMALS_COS;

/// Parameters of Algorithm 1.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitParams {
    /// First regularization weight `gamma_1` (paper: 0.3).
    pub gamma_start: f64,
    /// Factor from one `gamma` to the next (paper: 1/4).
    pub gamma_factor: f64,
    /// The schedule stops after the first `gamma` below this (paper: 0.008).
    pub gamma_stop: f64,
    /// Inner loop ends when the change of `w` (and of the pose) is below this (paper: 1e-6).
    /// `||Δw||` is taken as for the paper's 2001 points, `||Δw|| sqrt(2001 / n)` for an atlas
    /// of `n` points, so that the tolerance does not tighten as the atlas gets finer.
    pub tolerance: f64,
    /// Cap on correspondence updates per `gamma`.
    pub max_iterations: usize,
    /// Add the subject-to-instance closest points to `E_d` (see [`Fitter::fit`](crate::fit::Fitter::fit)).
    pub symmetric: bool,
    /// Starting rotations tried by the pre-alignment in 2D (evenly spaced; 1 = identity
    /// only). In 3D the starts are the principal-axes rotations and the identity.
    pub starts: usize,
    /// Coarse fits run from the best distinct pre-alignments; the least two-way distance wins.
    pub full_starts: usize,
    /// Points per direction (model and subject) used by the pre-alignment and the coarse
    /// stage; the last `gamma` runs on all points. 0 = all points throughout. The coarse
    /// model (see [`Fitter::fit`](crate::fit::Fitter::fit)) is built for the default value; with another, the coarse
    /// stage samples the full model.
    pub coarse_points: usize,
    /// The subject may miss parts (paper, fig. 21-22): `E_d` takes only the distances from
    /// the subject's points to the instance (weighted as both directions of a symmetric fit
    /// together, so that `gamma` acts alike), and model points that have no partner on the
    /// subject (`FitResult::corresponded`) are left out of the morph's data term.
    #[serde(default)]
    pub partial: bool,
}

/// Pose-only updates per start rotation in the pre-alignment.
pub(super) const PRE_ALIGNMENT_ITERATIONS: usize = 6;

/// Pose-only updates after which the pre-alignment drops the starts whose two-way distance
/// is [`PRE_PRUNE_FACTOR`] times the best start's. The factor is wider than the
/// [`PRUNE_FACTOR`] between the coarse fits: the pre-alignment has no mode to close a gap.
pub(super) const PRE_PRUNE_AFTER: usize = 2;
pub(super) const PRE_PRUNE_FACTOR: f64 = 10.0;

/// Cap on the updates per `gamma` of the coarse stage (the final stage has
/// [`FitParams::max_iterations`]).
pub(super) const COARSE_MAX_ITERATIONS: usize = 20;

/// The coarse stage stops each `gamma` at this multiple of the tolerance; the last `gamma`,
/// on all points, meets the tolerance itself.
pub(super) const COARSE_TOLERANCE_FACTOR: f64 = 100.0;

pub(super) const FULL_WEIGHT_COS: f64 = 0.75;

/// Root of the weight of a pair whose normals make an angle of cosine `cos`: 1 up to
/// [`FULL_WEIGHT_COS`], down to 0 at [`COMPATIBLE_NORMALS_COS`] (smoothly, so that a pair
/// crossing the bound does not make the next update jump).
pub(super) fn compatibility(cos: f64) -> f64 {
    let t = ((cos - COMPATIBLE_NORMALS_COS) / (FULL_WEIGHT_COS - COMPATIBLE_NORMALS_COS))
        .clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The angle of the rotation `a^T b` (radians; 2D and 3D).
pub(super) fn rotation_angle<const D: usize>(a: &[[f64; D]; D], b: &[[f64; D]; D]) -> f64 {
    let tr: f64 = (0..D)
        .map(|i| (0..D).map(|k| a[k][i] * b[k][i]).sum::<f64>())
        .sum();
    let c = if D == 2 { tr / 2.0 } else { (tr - 1.0) / 2.0 };
    c.clamp(-1.0, 1.0).acos()
}

/// After each `gamma`, starts whose two-way mean squared distance exceeds the best one's
/// by this factor are dropped.
pub(super) const PRUNE_FACTOR: f64 = 4.0;
pub(super) const COARSE_MODEL_FACTOR: usize = 4;

/// Updates after which a start of the coarse stage gives up a `gamma` when its two-way
/// distance is still [`PRUNE_FACTOR`] times the best start's (it is then dropped).
pub(super) const GIVE_UP_AFTER: usize = 3;

/// With both directions, the last `gamma` takes the backward pairs from every subject vertex
/// up to one per this many model points (evenly spread over the subject's vertices).
pub(super) const FULL_BACKWARD_SHARE: usize = 2;

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            gamma_start: 0.3,
            gamma_factor: 0.25,
            gamma_stop: 0.008,
            tolerance: 1e-6,
            max_iterations: 50,
            symmetric: true,
            starts: 8,
            full_starts: 2,
            coarse_points: 200,
            partial: false,
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

    pub(super) fn validate(&self) -> Result<()> {
        let ok = self.gamma_start.is_finite()
            && self.gamma_start >= 0.0
            && self.gamma_factor > 0.0
            && self.gamma_factor < 1.0
            && self.gamma_stop.is_finite()
            && self.tolerance.is_finite()
            && self.tolerance > 0.0;
        if ok {
            Ok(())
        } else {
            Err(Error::Parameter(format!(
                "fit parameters out of range: gamma {} × {} down to {}, tolerance {} \
                 (need gamma >= 0, 0 < factor < 1, tolerance > 0)",
                self.gamma_start, self.gamma_factor, self.gamma_stop, self.tolerance
            )))
        }
    }
}

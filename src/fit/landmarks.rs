//! The model fitted to a few landmark positions alone: the Gaussian posterior of eq. 4 given
//! the landmarks observed with noise ([`Atlas::posterior`]), in the subject's frame through a
//! similarity `t_{R,T,s}` (reference → subject, as in eq. 5) estimated alongside.

use crate::error::{Error, Result};
use crate::geometry::{Point, Similarity};
use crate::model::{Atlas, PosteriorModel, fit_similarity};

/// The model given landmark positions: the similarity to the subject, the posterior (in the
/// reference frame), its mean shape and per-point spread in the subject's frame and unit.
#[derive(Clone, Debug)]
pub struct LandmarkFit<const D: usize> {
    /// `t_{R,T,s}`: reference frame → subject frame.
    pub similarity: Similarity<D>,
    /// The posterior model (reference frame).
    pub posterior: PosteriorModel<D>,
    /// The posterior mean shape, subject frame (every model point).
    pub mean: Vec<Point<D>>,
    /// Per model point, the posterior's standard deviation of its position (root of the
    /// trace of its covariance), subject units.
    pub point_sd: Vec<f64>,
    /// RMS distance between the given landmarks and the posterior mean's (subject units).
    pub landmark_rms: f64,
    /// Alternations of similarity and posterior until the similarity settled.
    pub iterations: usize,
}

/// A posterior beyond this many standard deviations along a mode is no shape of the
/// population: landmarks misplaced, or in another unit or frame.
pub const MAX_POSTERIOR_SD: f64 = 20.0;

/// Refuses landmarks that cannot fix a pose: all at one place, or (3D) all on one line (the
/// rotation about it is free), to 1e-6 of their extent.
pub(crate) fn check_spread<const D: usize>(given: &[Point<D>]) -> Result<()> {
    let mut far = (0, 0, 0.0);
    for (i, a) in given.iter().enumerate() {
        for (j, b) in given.iter().enumerate().skip(i + 1) {
            let d = crate::geometry::dist2(*a, *b);
            if d > far.2 {
                far = (i, j, d);
            }
        }
    }
    let extent = far.2.sqrt();
    let scale = given
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1.0);
    if extent.is_nan() || extent <= 1e-9 * scale {
        return Err(Error::Parameter(
            "the landmarks are all at one place: their positions fix no pose or size".into(),
        ));
    }
    if D == 3 {
        let (a, b) = (given[far.0], given[far.1]);
        let u: Point<D> = std::array::from_fn(|d| (b[d] - a[d]) / extent);
        let off_line = given
            .iter()
            .map(|p| {
                let v: Point<D> = std::array::from_fn(|d| p[d] - a[d]);
                let along: f64 = (0..D).map(|d| v[d] * u[d]).sum();
                ((0..D).map(|d| v[d] * v[d]).sum::<f64>() - along * along)
                    .max(0.0)
                    .sqrt()
            })
            .fold(0.0, f64::max);
        if off_line <= 1e-6 * extent {
            return Err(Error::Parameter(
                "the landmarks lie on one line: the rotation about it is not fixed; give at \
                 least three not on a line"
                    .into(),
            ));
        }
    }
    Ok(())
}

/// Fits the model to the landmark positions `observed` (`(model point, position)`, subject
/// frame) observed with isotropic noise of standard deviation `sd` (subject units): the
/// similarity from the mean's landmarks to the observed ones (Umeyama), then, alternately,
/// the posterior of eq. 4 given the observed positions brought to the reference frame
/// (`sigma = sd / s`) and the similarity from the posterior mean's landmarks, until the
/// similarity changes by less than 1e-9 of the shape's size (at most 50 times).
///
/// # Errors
/// [`Error::Parameter`] for fewer than `D` landmarks (3 in 3D, 2 in 2D: a similarity needs
/// them), a `sd` that is not finite and positive, or the errors of [`Atlas::posterior`].
pub fn fit_landmarks<const D: usize>(
    atlas: &Atlas<D>,
    observed: &[(usize, Point<D>)],
    sd: f64,
) -> Result<LandmarkFit<D>> {
    if observed.len() < D {
        return Err(Error::Parameter(format!(
            "{} landmark(s): fitting the model's pose and size to landmarks alone needs at least {D}",
            observed.len()
        )));
    }
    if !(sd.is_finite() && sd > 0.0) {
        return Err(Error::Parameter(format!(
            "--landmark-sd {sd}: a positive length in the landmarks' unit"
        )));
    }
    if let Some((i, _)) = observed.iter().find(|(i, _)| *i >= atlas.mean.len()) {
        return Err(Error::Parameter(format!(
            "landmark on model point {i}, the model has {}",
            atlas.mean.len()
        )));
    }
    let given: Vec<Point<D>> = observed.iter().map(|o| o.1).collect();
    check_spread(&given)?;
    let at =
        |shape: &[Point<D>]| -> Vec<Point<D>> { observed.iter().map(|(i, _)| shape[*i]).collect() };
    let mut t = fit_similarity(&at(&atlas.mean), &given, None);
    let size = crate::geometry::centroid_size(&given).max(f64::MIN_POSITIVE);
    let mut iterations = 0;
    let posterior = loop {
        iterations += 1;
        let in_reference: Vec<(usize, Point<D>)> = observed
            .iter()
            .map(|(i, p)| (*i, t.apply_inverse(p)))
            .collect();
        let sigma = sd / t.s;
        let post = atlas.posterior(&in_reference, sigma * sigma)?;
        let next = fit_similarity(&at(&post.mean), &given, None);
        let moved = at(&post.mean)
            .iter()
            .map(|p| crate::geometry::dist2(next.apply(p), t.apply(p)))
            .sum::<f64>()
            .sqrt();
        t = next;
        if moved < 1e-9 * size || iterations >= 50 {
            break atlas.posterior(
                &observed
                    .iter()
                    .map(|(i, p)| (*i, t.apply_inverse(p)))
                    .collect::<Vec<_>>(),
                (sd / t.s).powi(2),
            )?;
        }
    };
    let sd_weights = atlas.in_sd(&posterior.weights);
    if let Some((k, w)) = sd_weights
        .iter()
        .enumerate()
        .find(|(_, w)| w.is_nan() || w.abs() > MAX_POSTERIOR_SD)
    {
        return Err(Error::Parameter(format!(
            "the landmarks lie far outside the model: its mode {} would need {w:.3e} standard \
             deviations (at most {MAX_POSTERIOR_SD}); check the landmarks' positions, unit and \
             frame",
            k + 1
        )));
    }
    let mean: Vec<Point<D>> = posterior.mean.iter().map(|p| t.apply(p)).collect();
    let landmark_rms = (at(&mean)
        .iter()
        .zip(&given)
        .map(|(a, b)| crate::geometry::dist2(*a, *b))
        .sum::<f64>()
        / given.len() as f64)
        .sqrt();
    Ok(LandmarkFit {
        similarity: t,
        point_sd: posterior.point_sd.iter().map(|v| v * t.s).collect(),
        mean,
        posterior,
        landmark_rms,
        iterations,
    })
}

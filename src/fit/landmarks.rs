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

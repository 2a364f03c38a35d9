//! Generalized Procrustes analysis in passes over a [`ShapeSource`] (section 2.2, as
//! [`crate::model::generalized_procrustes`]): the memory of the mean and one batch of shapes,
//! whatever the number of shapes.

use super::procrustes::{GPA_MAX_ITERATIONS, GPA_TOLERANCE, next_mean, normalized};
use super::shape_source::{ShapeSource, for_each_batch};
use super::{align_to_mean, fit_similarity};
use crate::error::{Error, Result};
use crate::geometry::Point;

/// The mean of a streamed GPA.
#[derive(Clone, Debug)]
pub struct StreamedGpa<const D: usize> {
    /// The Procrustes mean `S_bar` (eq. 3): centred at the origin, unit norm, in the
    /// orientation of the first shape.
    pub mean: Vec<Point<D>>,
    /// GPA iterations (one pass over the shapes each).
    pub iterations: usize,
}

/// Shape `k` of a batch centred and scaled to unit norm, with its name in the error.
pub(crate) fn normalized_shape<const D: usize>(
    source: &dyn ShapeSource<D>,
    k: usize,
    s: &[Point<D>],
) -> Result<Vec<Point<D>>> {
    normalized(s).ok_or_else(|| {
        Error::Population(format!(
            "{} has all its points at one place",
            source.name(k)
        ))
    })
}

/// Generalized Procrustes analysis of the shapes of `source` read `batch` at a time (section
/// 2.2; Cootes & Taylor's algorithm, as [`crate::model::generalized_procrustes`]): every
/// shape centred and scaled to unit norm, aligned (similarity) to the current mean, the mean
/// their average, normalized, its rotation kept at the first shape's; until the mean moves
/// less than 1e-12. Each iteration aligns the normalized shape itself to the mean, which is
/// the same least-squares similarity as aligning the shape aligned before (the similarities
/// form a group), so the mean equals the in-memory GPA's to rounding. One pass over the
/// shapes per iteration; memory: the mean, its sum and one batch.
///
/// The shapes aligned to the mean and projected to its tangent space are not kept: each is
/// [`crate::model::align_to_mean`] of the normalized shape, computed where it is used.
pub fn generalized_procrustes_streamed<const D: usize>(
    source: &dyn ShapeSource<D>,
    batch: usize,
) -> Result<StreamedGpa<D>> {
    let n = source.len();
    if n < 2 {
        return Err(Error::Population(format!(
            "{n} shape(s); at least 2 are needed"
        )));
    }
    let first = source.read(0..1)?;
    let points = first.first().map_or(0, Vec::len);
    let reference = normalized_shape(source, 0, &first[0])?;
    let mut mean = reference.clone();
    let mut iterations = 0;
    for it in 0..GPA_MAX_ITERATIONS {
        iterations = it + 1;
        let mut sum = vec![[0.0; D]; points];
        for_each_batch(source, batch, points, |start, shapes| {
            for (k, s) in shapes.iter().enumerate() {
                let x = normalized_shape(source, start + k, s)?;
                let t = fit_similarity(&x, &mean, None);
                for (a, p) in sum.iter_mut().zip(&x) {
                    let q = t.apply(p);
                    for d in 0..D {
                        a[d] += q[d] / n as f64;
                    }
                }
            }
            Ok(())
        })?;
        let (m, change) = next_mean(&sum, &mean, &reference)?;
        mean = m;
        if change < GPA_TOLERANCE {
            break;
        }
    }
    Ok(StreamedGpa { mean, iterations })
}

/// Shape `s` (shape `k` of `source`) in the mean's frame: normalized, aligned to `mean` and
/// projected to its tangent space (section 2.2), as [`crate::model::Gpa::aligned`] holds it.
pub(crate) fn tangent_shape<const D: usize>(
    source: &dyn ShapeSource<D>,
    k: usize,
    s: &[Point<D>],
    mean: &[Point<D>],
) -> Result<Vec<Point<D>>> {
    Ok(align_to_mean(&normalized_shape(source, k, s)?, mean))
}

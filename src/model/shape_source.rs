//! Shapes in point correspondence read a batch at a time: the population of a streamed
//! model ([`crate::model::Atlas::build_model_streamed`]), held in memory or read from files
//! on each pass, so that a cohort larger than the memory is modelled with the memory of its
//! mean and one batch.

use crate::error::{Error, Result};
use crate::geometry::Point;
use std::ops::Range;

/// Shapes in point correspondence (the same number of points, in the same order), read in
/// batches.
pub trait ShapeSource<const D: usize>: Sync {
    /// The number of shapes.
    fn len(&self) -> usize;

    /// Whether there is no shape.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The shapes `range` (indices into `0..len()`), in order, each with the same number of
    /// points as the first. Units and frame: the shapes' own (the model removes the pose).
    fn read(&self, range: Range<usize>) -> Result<Vec<Vec<Point<D>>>>;

    /// A name for shape `k` in messages (its file, when it has one).
    fn name(&self, k: usize) -> String {
        format!("shape {k}")
    }
}

/// Shapes held in memory.
impl<const D: usize> ShapeSource<D> for Vec<Vec<Point<D>>> {
    fn len(&self) -> usize {
        Vec::len(self)
    }

    fn read(&self, range: Range<usize>) -> Result<Vec<Vec<Point<D>>>> {
        self.get(range.clone()).map(<[_]>::to_vec).ok_or_else(|| {
            Error::Parameter(format!(
                "shapes {}..{} of a population of {}",
                range.start,
                range.end,
                Vec::len(self)
            ))
        })
    }
}

/// The shapes `range` of `source`, checked: as many as asked, each with `points` points, every
/// coordinate finite (errors name the shape).
pub(crate) fn read_checked<const D: usize>(
    source: &dyn ShapeSource<D>,
    range: Range<usize>,
    points: usize,
) -> Result<Vec<Vec<Point<D>>>> {
    let shapes = source.read(range.clone())?;
    if shapes.len() != range.len() {
        return Err(Error::Population(format!(
            "{} shapes read for {} asked (from {})",
            shapes.len(),
            range.len(),
            source.name(range.start)
        )));
    }
    for (k, s) in shapes.iter().enumerate() {
        if s.len() != points {
            return Err(Error::Population(format!(
                "{} has {} points but the first shape has {points}: the shapes are not in \
                 point correspondence",
                source.name(range.start + k),
                s.len()
            )));
        }
        if s.iter().flatten().any(|c| !c.is_finite()) {
            return Err(Error::Population(format!(
                "{} has a NaN or infinite coordinate",
                source.name(range.start + k)
            )));
        }
    }
    Ok(shapes)
}

/// One pass over `source` in batches of `batch` shapes: `f(first index, shapes)` for each,
/// in order; every shape checked by [`read_checked`] with `points` points.
pub(crate) fn for_each_batch<const D: usize>(
    source: &dyn ShapeSource<D>,
    batch: usize,
    points: usize,
    mut f: impl FnMut(usize, &[Vec<Point<D>>]) -> Result<()>,
) -> Result<()> {
    let n = source.len();
    let batch = batch.max(1);
    let mut start = 0;
    while start < n {
        let end = (start + batch).min(n);
        let shapes = read_checked(source, start..end, points)?;
        f(start, &shapes)?;
        start = end;
    }
    Ok(())
}

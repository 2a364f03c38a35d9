//! The cap of an atlas built on a common cut (`--cut`): the flat face where the population was
//! cut is not anatomy, so no pair of the fit ends on it. A subject whose bone goes on beyond
//! the atlas's cut (a longer shaft) is fitted on the part the two share: its points beyond the
//! mean's cap plane, or whose closest point on the instance lies on the cap, pull nothing, and
//! neither do the cap's own points.
//!
//! Frame: the atlas's reference frame (the instance before the pose).

use crate::geometry::{Point, cap_plane, centroid, dot, sub};
use crate::model::Atlas;

/// A point lies on the cap when its normal is within this angle's cosine (25°) of the cap's.
const FACING: f64 = 0.906;
/// ... and it lies within this share of the mean's RMS radius of the mean's cap plane.
const NEAR: f64 = 0.1;

/// The mean's cap plane and how near to it a point of an instance is on the cap.
#[derive(Clone, Debug)]
pub(super) struct Cap<const D: usize> {
    point: Point<D>,
    normal: Point<D>,
    near: f64,
    /// The model's points on the cap (its rim included): they pull nothing in the fit, and
    /// the morph takes them where the instance has them (the delivered mesh ends at the
    /// atlas's cut, as far as the subject reaches or not; along its normal, a rim point would
    /// land anywhere on a longer shaft or on the subject's own cut).
    pub(super) on_cap: Vec<bool>,
}

impl<const D: usize> Cap<D> {
    /// The cap of `atlas` (its `cut_facets`), or `None` for an atlas of uncut shapes.
    pub(super) fn of(atlas: &Atlas<D>) -> Option<Self> {
        let (ids, point, normal) = cap_plane(&atlas.mean, &atlas.facets, &atlas.cut_facets)?;
        let c = centroid(&atlas.mean);
        let radius = (atlas
            .mean
            .iter()
            .map(|p| crate::geometry::dist2(*p, c))
            .sum::<f64>()
            / atlas.mean.len() as f64)
            .sqrt();
        let mut on_cap = vec![false; atlas.mean.len()];
        for &i in &ids {
            on_cap[i] = true;
        }
        Some(Cap {
            point,
            normal,
            near: NEAR * radius,
            on_cap,
        })
    }

    /// Whether a point of a subject at `z` (reference frame) lies beyond the mean's cap plane:
    /// a part of the bone the atlas does not have (a longer shaft), which pulls nothing.
    #[inline]
    pub(super) fn beyond(&self, z: &Point<D>) -> bool {
        dot(sub(*z, self.point), self.normal) > 0.0
    }

    /// Whether a point of an instance at `p` with unit normal `n` (reference frame) lies on
    /// the cap.
    #[inline]
    pub(super) fn holds(&self, p: &Point<D>, n: &Point<D>) -> bool {
        dot(*n, self.normal) > FACING && dot(sub(*p, self.point), self.normal).abs() < self.near
    }
}

//! The state a fit carries from one update to the next.

use super::resolution::Level;
use crate::geometry::{ClosestPointIndex, Point, QueryMemo, Shape, Similarity};

/// Which model points (forward pairs) and subject vertices (backward pairs) take part.
pub(super) struct Sampling {
    /// Which of a fit's samplings this is.
    pub(super) pass: Pass,
    pub(super) forward: Vec<usize>,
    pub(super) backward: Vec<usize>,
}

/// The samplings of a fit: the pre-alignment's, the coarse stage's, the full stage's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Pass {
    Rough,
    Coarse,
    Full,
}

impl Sampling {
    /// The effective number of pairs: the forward ones (the backward ones are weighted to
    /// count as many), or the backward ones when there are no forward pairs.
    pub(super) fn pairs(&self) -> usize {
        if self.forward.is_empty() {
            self.backward.len().max(1)
        } else {
            self.forward.len()
        }
    }
}

/// A subject prepared for fitting.
pub(super) struct Subject<'s, const D: usize> {
    pub(super) shape: &'s Shape<D>,
    pub(super) index: &'s ClosestPointIndex<D>,
    pub(super) normals: Vec<Point<D>>,
    /// -1 where the subject runs the other way round than the atlas (its normals are turned
    /// round), else 1.
    pub(super) sign: f64,
}

/// State of Algorithm 1: pose and weights.
#[derive(Clone)]
pub(super) struct State<const D: usize> {
    pub(super) sim: Similarity<D>,
    pub(super) w: Vec<f64>,
    /// What the closest-point searches of the last update learned, per forward and per
    /// backward pair of the sampling `memos_for` (by place in its lists): the next update's
    /// queries start from there. A new sampling starts them afresh: they are a few hundred
    /// bytes per pair (allocated for every point of every start, they cost a fit more in
    /// page faults than they saved), and what a coarse sampling learned helps little at
    /// the next (the coarse model's index is another, and most of its points' memos
    /// missed at the full model's first update).
    pub(super) forward_memo: Vec<QueryMemo<D>>,
    pub(super) backward_memo: Vec<QueryMemo<D>>,
    pub(super) memos_for: Option<Pass>,
}

/// A stage of Algorithm 1: the model and points it runs on, and when its inner loop stops:
/// after `max_iterations` updates, when the changes are below `tolerance`, or after
/// [`GIVE_UP_AFTER`] updates if the two-way distance is still above `give_up`.
pub(super) struct Stage<'a> {
    pub(super) level: Level,
    pub(super) sampling: &'a Sampling,
    pub(super) max_iterations: usize,
    pub(super) tolerance: f64,
    pub(super) give_up: f64,
}

/// What one correspondence update measured and did.
pub(super) struct Step {
    /// Forward `Σ ||y_j - c_j||²` over the sampled model points (subject units squared).
    pub(super) forward: f64,
    /// Mean squared distances forward and backward (subject units squared).
    pub(super) two_way_ms: f64,
    /// Largest change of a pose parameter and `||Δw||`.
    pub(super) pose_change: f64,
    pub(super) weight_change: f64,
}

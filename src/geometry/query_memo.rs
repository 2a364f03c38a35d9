//! What a closest-point search remembers of its neighbourhood for the next query.

use super::Point;

/// Candidate facets kept by a [`QueryMemo`].
pub(super) const MEMO_FACETS: usize = 4;

/// What an exact closest-point search learned around its query point: the nearest facets
/// it met and how far everything else was. The next query of the same point, after the
/// point and the surface moved a little (a fit's or a registration's next iteration), is
/// then answered by testing those few facets, with a proof that no other facet can be
/// nearer; where the proof fails, by a search from the nearest one
/// ([`ClosestPointIndex::closest_memo`](super::ClosestPointIndex::closest_memo)).
#[derive(Clone, Copy, Debug)]
pub struct QueryMemo<const D: usize> {
    /// The index the memo belongs to (0: none yet).
    pub(super) index: u64,
    /// The query point of the last search.
    pub(super) at: Point<D>,
    /// The index's `drift` at the last search.
    pub(super) drift: f64,
    /// Every facet but `near` was at least this far from `at` (shape units).
    pub(super) bound: f64,
    /// The slots of the nearest facets met, nearest first (`u32::MAX`: none), and their
    /// distances.
    pub(super) near: [u32; MEMO_FACETS],
    pub(super) dist: [f64; MEMO_FACETS],
}

impl<const D: usize> Default for QueryMemo<D> {
    fn default() -> Self {
        QueryMemo {
            index: 0,
            at: [0.0; D],
            drift: 0.0,
            bound: f64::NEG_INFINITY,
            near: [u32::MAX; MEMO_FACETS],
            dist: [f64::INFINITY; MEMO_FACETS],
        }
    }
}

/// What a search reports besides its answer: every facet it tested (by slot) and every box
/// it skipped, with their squared distances.
pub(super) trait Track {
    fn facet(&mut self, slot: usize, d2: f64);
    fn skipped(&mut self, d2: f64);
}

impl Track for () {
    #[inline(always)]
    fn facet(&mut self, _: usize, _: f64) {}
    #[inline(always)]
    fn skipped(&mut self, _: f64) {}
}

/// The [`MEMO_FACETS`] nearest facets tested, and the least squared distance of everything
/// else (facets tested and dropped from the list, boxes skipped).
pub(super) struct Nearest {
    pub(super) near: [(f64, u32); MEMO_FACETS],
    pub(super) rest: f64,
}

/// `if c { a } else { b }` without a branch (for choices the branch predictor cannot
/// guess, such as where a distance goes in a sorted list).
#[inline(always)]
pub(super) fn select_f64(c: bool, a: f64, b: f64) -> f64 {
    let m = u64::from(c).wrapping_neg();
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// `if c { a } else { b }` without a branch.
#[inline(always)]
pub(super) fn select_u32(c: bool, a: u32, b: u32) -> u32 {
    let m = u32::from(c).wrapping_neg();
    (a & m) | (b & !m)
}

impl Track for Nearest {
    #[inline]
    fn facet(&mut self, slot: usize, d2: f64) {
        let slot = slot as u32;
        if self
            .near
            .iter()
            .fold(false, |dup, &(_, s)| dup | (s == slot))
        {
            return;
        }
        // Insertion into the sorted list, without branches.
        let (mut d, mut s) = (d2, slot);
        for e in self.near.iter_mut() {
            let (ed, es) = *e;
            let lt = d < ed;
            *e = (select_f64(lt, d, ed), select_u32(lt, s, es));
            d = select_f64(lt, ed, d);
            s = select_u32(lt, es, s);
        }
        // `d` is now the farthest of the list plus the new one (infinite for an empty
        // place): it leaves the list.
        self.rest = self.rest.min(d);
    }
    #[inline]
    fn skipped(&mut self, d2: f64) {
        self.rest = self.rest.min(d2);
    }
}

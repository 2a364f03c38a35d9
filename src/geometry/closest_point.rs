//! Exact closest points on a shape's facets through a bounding-volume hierarchy.

use super::normals::vertex_normals_of;
use super::query_memo::{MEMO_FACETS, Nearest, QueryMemo, Track, select_f64};
use super::{Point, Shape, add, dist2, dot, facet_normal, norm, scale, sub};

/// Closest point on the segment `[a, b]` to `p`; returns the barycentric weight of `b`.
#[inline]
pub(super) fn closest_on_segment<const D: usize>(p: Point<D>, a: Point<D>, b: Point<D>) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    if l2 <= 0.0 {
        return 0.0;
    }
    (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
}

/// Closest point on the triangle `abc` to `p` (Ericson, Real-Time Collision Detection, 5.1.5);
/// returns the barycentric weights `(u, v, w)` of `a, b, c`. Works in any dimension.
pub(super) fn closest_on_triangle<const D: usize>(
    p: Point<D>,
    a: Point<D>,
    b: Point<D>,
    c: Point<D>,
) -> [f64; 3] {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    [1.0 - v - w, v, w]
}

/// A point on a shape's boundary: the facet it lies on and its barycentric weights there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint<const D: usize> {
    /// Position (shape units, shape frame).
    pub point: Point<D>,
    /// Index of the facet in the shape's facet list.
    pub facet: usize,
    /// Barycentric weights of the facet's `D` vertices (sum to one).
    pub weights: [f64; D],
    /// Squared distance from the query.
    pub dist2: f64,
    /// Where the [`ClosestPointIndex`] that found the point keeps its facet (`u32::MAX`:
    /// unknown): it spares [`ClosestPointIndex::normal_at`] a lookup that missed the cache.
    pub slot: u32,
}

/// Closest-point and ray queries on the facets of a shape, through a bounding-volume
/// hierarchy of the facets' axis-aligned boxes (median splits, leaves of up to
/// [`LEAF_FACETS`] facets). Queries are exact: a subtree is skipped only when its box is
/// farther than the best facet found.
///
/// Written here rather than taken from a crate (parry, kiddo) for one reason: an iterative
/// fit asks for the closest point of the same query point again and again after small
/// moves, and [`ClosestPointIndex::closest_from`] starts from the facet found last time,
/// which prunes nearly the whole tree at once; and it is generic over `D = 2, 3`.
pub struct ClosestPointIndex<const D: usize> {
    /// Identity of this index (every clone gets its own), checked by [`QueryMemo`]s.
    pub(super) id: u64,
    /// Sum over every [`refit`](Self::refit) of the largest move of a point: no point of any
    /// facet moved farther than the difference of two readings (shape units).
    pub(super) drift: f64,
    pub(super) points: Vec<Point<D>>,
    pub(super) facets: Vec<[usize; D]>,
    pub(super) nodes: Vec<BvhNode<D>>,
    /// Facet indices, ordered so that every node covers a contiguous range; a facet's place
    /// in this order is its slot.
    pub(super) order: Vec<u32>,
    /// The facet of every slot, its corners numbered as in `corners`.
    pub(super) slots: Vec<[u32; D]>,
    /// The facets' corners, numbered in the order of their first use by `slots`, so that
    /// the corners of a leaf lie together in memory (a search's facet tests read nothing
    /// else, and cache misses were what they spent most of their time on).
    pub(super) corners: Vec<Point<D>>,
    /// The point of every corner.
    pub(super) corner_point: Vec<u32>,
    /// Unit vertex normal of every corner (as [`vertex_normals`](super::vertex_normals) gives them).
    pub(super) corner_normals: Vec<Point<D>>,
    /// Corner of every point (`u32::MAX`: on no facet).
    pub(super) corner_of: Vec<u32>,
    /// Slot of every facet.
    pub(super) slot_of: Vec<u32>,
    /// Parent of every node (the root's is itself).
    pub(super) parent: Vec<u32>,
    /// Leaf of every slot.
    pub(super) leaf_of: Vec<u32>,
}

/// A fresh identity for a [`ClosestPointIndex`].
pub(super) fn next_index_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl<const D: usize> Clone for ClosestPointIndex<D> {
    fn clone(&self) -> Self {
        ClosestPointIndex {
            id: next_index_id(),
            drift: self.drift,
            points: self.points.clone(),
            facets: self.facets.clone(),
            nodes: self.nodes.clone(),
            order: self.order.clone(),
            slots: self.slots.clone(),
            corners: self.corners.clone(),
            corner_point: self.corner_point.clone(),
            corner_normals: self.corner_normals.clone(),
            corner_of: self.corner_of.clone(),
            slot_of: self.slot_of.clone(),
            parent: self.parent.clone(),
            leaf_of: self.leaf_of.clone(),
        }
    }
}

/// Facets per leaf of the [`ClosestPointIndex`] hierarchy.
pub const LEAF_FACETS: usize = 4;

#[derive(Clone, Copy, Debug)]
pub(super) struct BvhNode<const D: usize> {
    pub(super) lo: Point<D>,
    pub(super) hi: Point<D>,
    /// Index of the first child (the second is `child + 1`); 0 for a leaf.
    pub(super) child: u32,
    pub(super) start: u32,
    pub(super) count: u32,
}

/// Squared distance from `p` to the box `[lo, hi]` (0 inside).
#[inline]
pub(super) fn box_dist2<const D: usize>(p: &Point<D>, lo: &Point<D>, hi: &Point<D>) -> f64 {
    let mut d2 = 0.0;
    for d in 0..D {
        let v = (lo[d] - p[d]).max(p[d] - hi[d]).max(0.0);
        d2 += v * v;
    }
    d2
}

/// The bounding-volume hierarchy over the facets: nodes (root first) and the facet order its
/// leaves' ranges index. Each node's box holds its facets (padded by a hair so box tests stay
/// conservative under rounding); a node splits at the median centroid of its longest extent.
fn build_hierarchy<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
) -> (Vec<BvhNode<D>>, Vec<u32>) {
    let centroids: Vec<Point<D>> = facets
        .iter()
        .map(|f| {
            let c = f.iter().fold([0.0; D], |acc, &i| add(acc, points[i]));
            scale(c, 1.0 / D as f64)
        })
        .collect();
    let mut order: Vec<u32> = (0..facets.len() as u32).collect();
    let mut nodes = Vec::with_capacity(2 * facets.len() / LEAF_FACETS + 2);
    nodes.push(BvhNode {
        lo: [0.0; D],
        hi: [0.0; D],
        child: 0,
        start: 0,
        count: facets.len() as u32,
    });
    let mut stack = vec![0usize];
    while let Some(ni) = stack.pop() {
        let (start, count) = (nodes[ni].start as usize, nodes[ni].count as usize);
        let range = &mut order[start..start + count];
        let ([lo, hi], [clo, chi]) = node_bounds(points, facets, &centroids, range);
        // A hair of padding keeps the box tests conservative under rounding.
        let pad = 1e-9 * (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max) + 1e-300;
        nodes[ni].lo = lo.map(|v| v - pad);
        nodes[ni].hi = hi.map(|v| v + pad);
        if count <= LEAF_FACETS {
            continue;
        }
        let axis = (0..D)
            .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
            .unwrap_or(0);
        let half = count / 2;
        range.select_nth_unstable_by(half, |&a, &b| {
            centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
        });
        let child = nodes.len();
        nodes[ni].child = child as u32;
        for (s, c) in [(start, half), (start + half, count - half)] {
            nodes.push(BvhNode {
                lo: [0.0; D],
                hi: [0.0; D],
                child: 0,
                start: s as u32,
                count: c as u32,
            });
        }
        stack.push(child);
        stack.push(child + 1);
    }
    (nodes, order)
}

/// The box of the facets in `range` and the box of their centroids.
fn node_bounds<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
    centroids: &[Point<D>],
    range: &[u32],
) -> ([Point<D>; 2], [Point<D>; 2]) {
    let mut lo = [f64::INFINITY; D];
    let mut hi = [f64::NEG_INFINITY; D];
    let mut clo = [f64::INFINITY; D];
    let mut chi = [f64::NEG_INFINITY; D];
    for &fi in range {
        for &v in &facets[fi as usize] {
            for d in 0..D {
                lo[d] = lo[d].min(points[v][d]);
                hi[d] = hi[d].max(points[v][d]);
            }
        }
        let c = centroids[fi as usize];
        for d in 0..D {
            clo[d] = clo[d].min(c[d]);
            chi[d] = chi[d].max(c[d]);
        }
    }
    ([lo, hi], [clo, chi])
}

/// Each node's parent and each facet slot's leaf, for refitting the boxes bottom-up.
fn hierarchy_links<const D: usize>(nodes: &[BvhNode<D>], n_facets: usize) -> (Vec<u32>, Vec<u32>) {
    let mut parent = vec![0u32; nodes.len()];
    let mut leaf_of = vec![0u32; n_facets];
    for (ni, node) in nodes.iter().enumerate() {
        if node.child == 0 {
            let s = node.start as usize;
            leaf_of[s..s + node.count as usize].fill(ni as u32);
        } else {
            parent[node.child as usize] = ni as u32;
            parent[node.child as usize + 1] = ni as u32;
        }
    }
    (parent, leaf_of)
}

/// The facets' corners renumbered in hierarchy order (a compact, cache-friendly copy of the
/// points the facets use).
struct CornerSlots<const D: usize> {
    /// Each slot's (facet in hierarchy order) corners, as corner numbers.
    slots: Vec<[u32; D]>,
    /// Each corner's point.
    point: Vec<u32>,
    /// Each point's corner (`u32::MAX` for a point no facet uses).
    of: Vec<u32>,
    /// Each facet's slot.
    slot_of: Vec<u32>,
}

impl<const D: usize> CornerSlots<D> {
    fn of(points: &[Point<D>], facets: &[[usize; D]], order: &[u32]) -> Self {
        let mut of = vec![u32::MAX; points.len()];
        let mut point = Vec::new();
        let mut slot_of = vec![0u32; facets.len()];
        let slots = order
            .iter()
            .enumerate()
            .map(|(slot, &fi)| {
                slot_of[fi as usize] = slot as u32;
                facets[fi as usize].map(|v| {
                    if of[v] == u32::MAX {
                        of[v] = point.len() as u32;
                        point.push(v as u32);
                    }
                    of[v]
                })
            })
            .collect();
        CornerSlots {
            slots,
            point,
            of,
            slot_of,
        }
    }
}

impl<const D: usize> ClosestPointIndex<D> {
    /// Builds the index. The shape must have at least one facet.
    #[track_caller]
    pub fn new(points: &[Point<D>], facets: &[[usize; D]]) -> Self {
        assert!(
            !facets.is_empty(),
            "ClosestPointIndex needs at least one facet"
        );
        let (nodes, order) = build_hierarchy(points, facets);
        let (parent, leaf_of) = hierarchy_links(&nodes, facets.len());
        let corners = CornerSlots::of(points, facets, &order);
        let mut index = ClosestPointIndex {
            id: next_index_id(),
            drift: 0.0,
            points: points.to_vec(),
            facets: facets.to_vec(),
            nodes,
            order,
            slots: corners.slots,
            corners: corners.point.iter().map(|&v| points[v as usize]).collect(),
            corner_point: corners.point,
            corner_normals: Vec::new(),
            corner_of: corners.of,
            slot_of: corners.slot_of,
            parent,
            leaf_of,
        };
        index.update_normals();
        index
    }

    /// From a shape.
    pub fn from_shape(shape: &Shape<D>) -> Self {
        Self::new(&shape.points, &shape.facets)
    }

    /// The same facets on moved points: keeps the hierarchy, recomputes its boxes (linear
    /// time; a fraction of a rebuild). Queries stay exact; they slow down only if the points
    /// moved far from where the index was built.
    #[track_caller]
    pub fn refit(&mut self, points: &[Point<D>]) {
        assert_eq!(
            points.len(),
            self.points.len(),
            "ClosestPointIndex::refit: one point per indexed point"
        );
        let moved = self
            .points
            .iter()
            .zip(points)
            .map(|(a, b)| dist2(*a, *b))
            .fold(0.0, f64::max);
        self.drift += moved.sqrt();
        self.points.copy_from_slice(points);
        for (c, &v) in self.corners.iter_mut().zip(&self.corner_point) {
            *c = points[v as usize];
        }
        self.update_normals();
        // Children always come after their parent: a reverse sweep sees children first.
        for ni in (0..self.nodes.len()).rev() {
            let node = self.nodes[ni];
            let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
            if node.child == 0 {
                let s = node.start as usize;
                for f in &self.slots[s..s + node.count as usize] {
                    for &c in f {
                        for d in 0..D {
                            lo[d] = lo[d].min(self.corners[c as usize][d]);
                            hi[d] = hi[d].max(self.corners[c as usize][d]);
                        }
                    }
                }
                let pad = 1e-9 * (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max) + 1e-300;
                lo = lo.map(|v| v - pad);
                hi = hi.map(|v| v + pad);
            } else {
                for c in [node.child as usize, node.child as usize + 1] {
                    for d in 0..D {
                        lo[d] = lo[d].min(self.nodes[c].lo[d]);
                        hi[d] = hi[d].max(self.nodes[c].hi[d]);
                    }
                }
            }
            self.nodes[ni].lo = lo;
            self.nodes[ni].hi = hi;
        }
    }

    /// The corners' vertex normals, from the corners and the facets (as [`vertex_normals`]).
    fn update_normals(&mut self) {
        let facets = self.slots.iter().map(|f| f.map(|c| c as usize));
        vertex_normals_of(&self.corners, facets, &mut self.corner_normals);
    }

    /// The slot of the facet of `sp`: its own `slot` where this index gave it (the search
    /// has just read `order` there), else looked up.
    #[inline]
    fn slot_of_point(&self, sp: &SurfacePoint<D>) -> Option<usize> {
        let given = sp.slot as usize;
        if self
            .order
            .get(given)
            .is_some_and(|&f| f as usize == sp.facet)
        {
            return Some(given);
        }
        self.slot_of.get(sp.facet).map(|&s| s as usize)
    }

    /// Unit normal at the point `sp` of this index's facets (a query's answer): the vertex
    /// normals (area-weighted facet normals, section 2.1) blended by its barycentric weights,
    /// or the facet's own normal where they cancel; `None` on a degenerate facet. It reads
    /// what the query that found `sp` has just read, not the shape's arrays.
    pub fn normal_at(&self, sp: &SurfacePoint<D>) -> Option<Point<D>> {
        let slot = self.slot_of_point(sp)?;
        let f = self.slots[slot].map(|c| c as usize);
        let mut n = [0.0; D];
        for k in 0..D {
            n = add(n, scale(self.corner_normals[f[k]], sp.weights[k]));
        }
        let l = norm(n);
        if l > 1e-12 {
            return Some(scale(n, 1.0 / l));
        }
        let n = facet_normal(&self.corners, &f);
        let l = norm(n);
        (l > 0.0).then(|| scale(n, 1.0 / l))
    }

    /// The vertices of the facet of `sp` (as in the shape's facets; `None` for a facet the
    /// index does not have).
    pub fn facet_vertices(&self, sp: &SurfacePoint<D>) -> Option<[usize; D]> {
        let slot = self.slot_of_point(sp)?;
        Some(self.slots[slot].map(|c| self.corner_point[c as usize] as usize))
    }

    /// The unit vertex normal of every point (as [`vertex_normals`](super::vertex_normals) gives them; zero for a
    /// point on no facet), into `out`.
    pub fn vertex_normals_into(&self, out: &mut Vec<Point<D>>) {
        out.clear();
        out.extend(self.corner_of.iter().map(|&c| {
            if c == u32::MAX {
                [0.0; D]
            } else {
                self.corner_normals[c as usize]
            }
        }));
    }

    /// The closest point to `p` on the facet in `slot`.
    #[inline]
    fn closest_on_slot(&self, p: Point<D>, slot: usize) -> SurfacePoint<D> {
        let c = self.slots[slot].map(|v| self.corners[v as usize]);
        let mut weights = [0.0; D];
        match D {
            2 => {
                let t = closest_on_segment(p, c[0], c[1]);
                weights[0] = 1.0 - t;
                weights[1] = t;
            }
            3 => {
                let w = closest_on_triangle(p, c[0], c[1], c[2]);
                weights.copy_from_slice(&w);
            }
            _ => unreachable!(),
        }
        let mut q = [0.0; D];
        for k in 0..D {
            q = add(q, scale(c[k], weights[k]));
        }
        SurfacePoint {
            point: q,
            facet: self.order[slot] as usize,
            weights,
            dist2: dist2(p, q),
            slot: slot as u32,
        }
    }

    /// The closest point to `p` on the shape's facets (not only its vertices).
    pub fn closest(&self, p: &Point<D>) -> SurfacePoint<D> {
        self.search(p, None, &mut ())
    }

    /// [`closest`](Self::closest), starting from the facet `hint` (e.g. the answer of the
    /// previous iteration for a point that moved a little): the same answer, found faster
    /// when the hint is near.
    pub fn closest_from(&self, p: &Point<D>, hint: usize) -> SurfacePoint<D> {
        let slot = self.slot_of.get(hint).map(|&s| s as usize);
        self.search(p, slot, &mut ())
    }

    /// [`closest`](Self::closest) for a point queried again and again as it and the surface
    /// move (the points of an iterative fit): `memo` keeps what the last search of this
    /// point learned (start from `QueryMemo::default()`, one per query point). The answer is
    /// the exact closest point, as [`closest`](Self::closest) gives it; when neither the
    /// point nor the surface (through [`refit`](Self::refit)) moved more than a fraction of
    /// the gap between the nearest facets and the rest, it takes a few facet tests instead
    /// of a search.
    pub fn closest_memo(&self, p: &Point<D>, memo: &mut QueryMemo<D>) -> SurfacePoint<D> {
        if memo.index == self.id {
            // Every facet but `near` was at least `bound` from `at`; since then the query
            // moved by `dist(p, at)` and no facet point by more than the drift.
            let slack = norm(sub(*p, memo.at)) + (self.drift - memo.drift);
            let mut best: Option<SurfacePoint<D>> = None;
            for (&slot, &d) in memo.near.iter().zip(&memo.dist) {
                if slot == u32::MAX {
                    break;
                }
                if let Some(b) = &best
                    && (d - slack).max(0.0).powi(2) >= b.dist2
                {
                    break;
                }
                let c = self.closest_on_slot(*p, slot as usize);
                if best.as_ref().is_none_or(|b| c.dist2 < b.dist2) {
                    best = Some(c);
                }
            }
            if let Some(b) = best {
                let reach = memo.bound - slack;
                // The rounding of the distances is far below this margin.
                if reach > 0.0 && b.dist2 <= reach * reach * (1.0 - 1e-9) {
                    return b;
                }
            }
        }
        // A memo of another index (or none) knows nothing about this one: no hint.
        let hint = if memo.index == self.id {
            memo.near[0] as usize
        } else {
            usize::MAX
        };
        let mut track = Nearest {
            near: [(f64::INFINITY, u32::MAX); MEMO_FACETS],
            rest: f64::INFINITY,
        };
        let best = self.search(p, (hint < self.facets.len()).then_some(hint), &mut track);
        *memo = QueryMemo {
            index: self.id,
            at: *p,
            drift: self.drift,
            bound: track.rest.sqrt(),
            near: track.near.map(|(_, f)| f),
            dist: track.near.map(|(d2, _)| d2.sqrt()),
        };
        best
    }

    /// The exact closest point, searched from the root or from the facet in slot `hint`.
    fn search(&self, p: &Point<D>, hint: Option<usize>, track: &mut impl Track) -> SurfacePoint<D> {
        let mut best = SurfacePoint {
            point: *p,
            facet: usize::MAX,
            weights: [0.0; D],
            dist2: f64::INFINITY,
            slot: u32::MAX,
        };
        let Some(h) = hint else {
            self.descend(p, 0, &mut best, track);
            return best;
        };
        // From the hint: its leaf, then, climbing to the root, the sibling subtree of every
        // node on the way. Every facet lies in exactly one of these; a sibling whose box is
        // farther than the best found is skipped at once.
        best = self.closest_on_slot(*p, h);
        track.facet(h, best.dist2);
        let mut ni = self.leaf_of[h] as usize;
        self.descend(p, ni, &mut best, track);
        while ni != 0 {
            let parent = self.parent[ni] as usize;
            let first = self.nodes[parent].child as usize;
            let sibling = if ni == first { first + 1 } else { first };
            self.descend(p, sibling, &mut best, track);
            ni = parent;
        }
        best
    }

    /// Improves `best` with the facets of the subtree at `root` (pruned by box distance).
    #[inline]
    fn descend(
        &self,
        p: &Point<D>,
        root: usize,
        best: &mut SurfacePoint<D>,
        track: &mut impl Track,
    ) {
        let r = &self.nodes[root];
        let d = box_dist2(p, &r.lo, &r.hi);
        if d >= best.dist2 {
            track.skipped(d);
            return;
        }
        // Nodes to visit; a node pushed before `best` improved is checked again when it
        // comes off the stack. (Storing the box distances beside the nodes was slower: the
        // bigger stack costs more to set up.)
        let mut stack = [0u32; 48];
        stack[0] = root as u32;
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let d = box_dist2(p, &node.lo, &node.hi);
            if d >= best.dist2 {
                track.skipped(d);
                continue;
            }
            if node.child == 0 {
                let s = node.start as usize;
                for slot in s..s + node.count as usize {
                    if self.order[slot] as usize == best.facet {
                        continue;
                    }
                    let c = self.closest_on_slot(*p, slot);
                    track.facet(slot, c.dist2);
                    if c.dist2 < best.dist2 {
                        *best = c;
                    }
                }
                continue;
            }
            let a = node.child;
            let da = box_dist2(p, &self.nodes[a as usize].lo, &self.nodes[a as usize].hi);
            let db = box_dist2(
                p,
                &self.nodes[a as usize + 1].lo,
                &self.nodes[a as usize + 1].hi,
            );
            // Push the farther child first so that the nearer one is searched first. Written
            // without branches (selects, and a push that always writes and moves the top by
            // 0 or 1): which child is nearer, and whether a child is pruned, are coin flips to
            // the branch predictor, and its misses were a third of a search's time. The stack
            // never holds more than the depth plus one nodes (each visit pops one and pushes
            // at most two), and a tree of `u32` facets is less than 33 levels deep.
            let swap = da > db;
            let near = a + u32::from(swap);
            let far = a + u32::from(!swap);
            let (dn, df) = (da.min(db), da.max(db));
            let bound = best.dist2;
            stack[top] = far;
            top += usize::from(df < bound);
            track.skipped(select_f64(df < bound, f64::INFINITY, df));
            stack[top] = near;
            top += usize::from(dn < bound);
            track.skipped(select_f64(dn < bound, f64::INFINITY, dn));
        }
    }

    /// Points of the indexed shape.
    pub fn points(&self) -> &[Point<D>] {
        &self.points
    }
    /// Facets of the indexed shape.
    pub fn facets(&self) -> &[[usize; D]] {
        &self.facets
    }
}

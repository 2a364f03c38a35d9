//! Shapes as points plus connectivity; normals, closest points and projection along normals.
//!
//! A shape in `D` dimensions is a list of points and a list of boundary facets, each facet a
//! `(D-1)`-simplex given by `D` point indices: segments `[a, b]` for outlines (`D = 2`),
//! triangles `[a, b, c]` for surfaces (`D = 3`). Coordinates are in the shape's own units and
//! frame; nothing here changes them.

use crate::error::{Error, Result};

/// A point (or vector) in `D` dimensions.
pub type Point<const D: usize> = [f64; D];

/// A shape: points and boundary facets (`D` point indices each), with its landmark indices.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape<const D: usize> {
    /// Name used in messages and reports (file stem, or the shape's id in a CSV).
    pub name: String,
    /// `#V` points.
    pub points: Vec<Point<D>>,
    /// `#F` facets, each `D` indices into `points`, oriented consistently.
    pub facets: Vec<[usize; D]>,
    /// Indices of landmark points (may be empty).
    pub landmarks: Vec<usize>,
}

/// A 2D outline (polyline, open or closed).
pub type Contour2 = Shape<2>;
/// A 3D triangle surface.
pub type Surface3 = Shape<3>;

impl Shape<2> {
    /// A polyline through `points` in order; `closed` adds the segment from the last point to
    /// the first.
    pub fn polyline(name: impl Into<String>, points: Vec<Point<2>>, closed: bool) -> Self {
        let n = points.len();
        let mut facets: Vec<[usize; 2]> = (1..n).map(|i| [i - 1, i]).collect();
        if closed && n > 2 {
            facets.push([n - 1, 0]);
        }
        Shape {
            name: name.into(),
            points,
            facets,
            landmarks: Vec::new(),
        }
    }

    /// Whether the outline is closed (its last segment returns to the first point).
    pub fn is_closed(&self) -> bool {
        self.facets.len() == self.points.len() && self.points.len() > 2
    }
}

impl<const D: usize> Shape<D> {
    /// Checks that the shape can be used: at least `D + 1` points, finite coordinates, facet
    /// indices in range, non-zero extent.
    pub fn validate(&self) -> Result<()> {
        if self.points.len() < D + 1 {
            return Err(Error::shape(
                &self.name,
                format!(
                    "has {} points; at least {} are needed",
                    self.points.len(),
                    D + 1
                ),
            ));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(Error::shape(
                &self.name,
                format!("point {i} has a coordinate that is NaN or infinite"),
            ));
        }
        if let Some(f) = self
            .facets
            .iter()
            .position(|f| f.iter().any(|&i| i >= self.points.len()))
        {
            return Err(Error::shape(
                &self.name,
                format!("facet {f} refers to a point that does not exist"),
            ));
        }
        if let Some(&l) = self.landmarks.iter().find(|&&l| l >= self.points.len()) {
            return Err(Error::shape(
                &self.name,
                format!(
                    "landmark index {l} is out of range (the shape has {} points)",
                    self.points.len()
                ),
            ));
        }
        let (lo, hi) = bounding_box(&self.points);
        if (0..D).all(|d| hi[d] - lo[d] <= 0.0) {
            return Err(Error::shape(&self.name, "all points coincide"));
        }
        Ok(())
    }

    /// Length of the bounding box diagonal (shape units).
    pub fn bbox_diagonal(&self) -> f64 {
        let (lo, hi) = bounding_box(&self.points);
        norm(sub(hi, lo))
    }

    /// Vertex normals: the area-weighted average of the surrounding facet normals (section
    /// 2.1; in 2D the length-weighted average of the segment normals), normalized. For a
    /// counter-clockwise outline or an outward-oriented surface they point outwards.
    pub fn vertex_normals(&self) -> Vec<Point<D>> {
        vertex_normals(&self.points, &self.facets)
    }

    /// Median facet size: see [`median_edge_length`].
    pub fn median_edge_length(&self) -> f64 {
        median_edge_length(&self.points, &self.facets)
    }

    /// Vertex-clustering decimation (Rossignac and Borrel 1993): the points are binned in
    /// cubic cells of side `cell` (shape units) whose grid starts at `offset`; each occupied
    /// cell keeps one point, the one nearest to the cell's mean (an original point, not a
    /// new one); facets are mapped to the kept points, and those that collapse (two corners
    /// in one cell) or repeat are dropped. Returns the decimated shape (landmarks dropped:
    /// re-pick them on it) and, per kept point, the index of the original point it is.
    /// The result may be non-manifold where the shape is thinner than a cell.
    pub fn decimate_by_clustering(
        &self,
        cell: f64,
        offset: Point<D>,
    ) -> Result<(Self, Vec<usize>)> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::Parameter(format!(
                "decimation cell size {cell} must be positive"
            )));
        }
        self.validate()?;
        let key = |p: &Point<D>| -> [i64; D] {
            std::array::from_fn(|d| ((p[d] - offset[d]) / cell).floor() as i64)
        };
        let mut cells: std::collections::HashMap<[i64; D], Vec<usize>> =
            std::collections::HashMap::new();
        for (i, p) in self.points.iter().enumerate() {
            cells.entry(key(p)).or_default().push(i);
        }
        let mut groups: Vec<Vec<usize>> = cells.into_values().collect();
        // Deterministic order: by the smallest original index in the cell.
        groups.sort_by_key(|g| g[0]);
        let mut map = vec![0usize; self.points.len()];
        let mut kept = Vec::with_capacity(groups.len());
        for (k, g) in groups.iter().enumerate() {
            let m = centroid(&g.iter().map(|&i| self.points[i]).collect::<Vec<_>>());
            let rep = g
                .iter()
                .copied()
                .min_by(|&a, &b| dist2(self.points[a], m).total_cmp(&dist2(self.points[b], m)))
                .unwrap_or(g[0]);
            kept.push(rep);
            for &i in g {
                map[i] = k;
            }
        }
        // Facets on the same kept points: a repeat of the same orientation is dropped; a
        // pair of opposite orientations (a fold of zero volume, where two sides of the
        // surface met in one cell) is dropped whole.
        let mut by_key: std::collections::HashMap<[usize; D], Vec<usize>> =
            std::collections::HashMap::new();
        let mut mapped = Vec::with_capacity(self.facets.len());
        for f in &self.facets {
            let g: [usize; D] = std::array::from_fn(|k| map[f[k]]);
            if (0..D).all(|a| (a + 1..D).all(|b| g[a] != g[b])) {
                let mut sorted = g;
                sorted.sort_unstable();
                by_key.entry(sorted).or_default().push(mapped.len());
                mapped.push(g);
            }
        }
        // Orientation of a facet relative to its sorted vertices: the parity of the
        // permutation (even = +1).
        let parity = |g: &[usize; D]| -> i32 {
            let mut inversions = 0;
            for a in 0..D {
                for b in a + 1..D {
                    if g[a] > g[b] {
                        inversions += 1;
                    }
                }
            }
            if D == 2 || inversions % 2 == 0 { 1 } else { -1 }
        };
        let mut keep = vec![false; mapped.len()];
        for ids in by_key.values() {
            let net: i32 = ids.iter().map(|&i| parity(&mapped[i])).sum();
            if D == 2 || net != 0 {
                let want = net.signum();
                if let Some(&i) = ids.iter().find(|&&i| D == 2 || parity(&mapped[i]) == want) {
                    keep[i] = true;
                }
            }
        }
        let facets: Vec<[usize; D]> = mapped
            .iter()
            .zip(&keep)
            .filter_map(|(g, &k)| k.then_some(*g))
            .collect();
        let shape = Shape {
            name: self.name.clone(),
            points: kept.iter().map(|&i| self.points[i]).collect(),
            facets,
            landmarks: Vec::new(),
        };
        Ok((shape, kept))
    }
}

/// `exp(Σ_k ω_k G_k)`: the rotation by the angle `ω` (2D) or the rotation vector `ω` (3D,
/// Rodrigues).
pub fn rotation_exp<const D: usize>(w: &[f64]) -> [[f64; D]; D] {
    let mut r = Similarity::<D>::identity().r;
    match D {
        2 => {
            let (s, c) = w[0].sin_cos();
            r[0][0] = c;
            r[0][1] = -s;
            r[1][0] = s;
            r[1][1] = c;
        }
        3 => {
            let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            if th > 0.0 {
                let k = [w[0] / th, w[1] / th, w[2] / th];
                let (s, c) = th.sin_cos();
                for i in 0..3 {
                    for j in 0..3 {
                        let kk = (1.0 - c) * k[i] * k[j];
                        let cross = match (i, j) {
                            (0, 1) => -k[2],
                            (1, 0) => k[2],
                            (0, 2) => k[1],
                            (2, 0) => -k[1],
                            (1, 2) => -k[0],
                            (2, 1) => k[0],
                            _ => 0.0,
                        };
                        r[i][j] = if i == j { c } else { 0.0 } + kk + s * cross;
                    }
                }
            }
        }
        _ => unreachable!("atlasmesh supports D = 2 and D = 3"),
    }
    r
}

/// Median length of the facets' first edges (segment lengths in 2D); 0 without facets.
pub fn median_edge_length<const D: usize>(points: &[Point<D>], facets: &[[usize; D]]) -> f64 {
    let mut l: Vec<f64> = facets
        .iter()
        .map(|f| norm(sub(points[f[1]], points[f[0]])))
        .collect();
    if l.is_empty() {
        return 0.0;
    }
    let mid = l.len() / 2;
    *l.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// A triangulated sphere-like surface: a pole, `rings - 1` rings of `sectors` points, a pole;
/// point `(theta, phi)` (latitude from -pi/2 to pi/2, longitude) placed by `at`. The facets
/// face outwards for the unit sphere.
pub fn uv_sphere(
    sectors: usize,
    rings: usize,
    at: impl Fn(f64, f64) -> Point<3>,
) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    let mut points = vec![at(-FRAC_PI_2, 0.0)];
    for j in 1..rings {
        let th = PI * j as f64 / rings as f64 - FRAC_PI_2;
        for i in 0..sectors {
            points.push(at(th, TAU * i as f64 / sectors as f64));
        }
    }
    points.push(at(FRAC_PI_2, 0.0));
    let top = points.len() - 1;
    let ring = |j: usize, i: usize| 1 + (j - 1) * sectors + i % sectors;
    let mut facets = Vec::new();
    for i in 0..sectors {
        facets.push([0, ring(1, i + 1), ring(1, i)]);
        facets.push([top, ring(rings - 1, i), ring(rings - 1, i + 1)]);
    }
    for j in 1..rings - 1 {
        for i in 0..sectors {
            facets.push([ring(j, i), ring(j, i + 1), ring(j + 1, i + 1)]);
            facets.push([ring(j, i), ring(j + 1, i + 1), ring(j + 1, i)]);
        }
    }
    (points, facets)
}

/// Vertex normals of `points` with connectivity `facets`: see [`Shape::vertex_normals`].
pub fn vertex_normals<const D: usize>(points: &[Point<D>], facets: &[[usize; D]]) -> Vec<Point<D>> {
    let mut n = Vec::new();
    vertex_normals_of(points, facets.iter().copied(), &mut n);
    n
}

/// [`vertex_normals`] into `out`, for facets given one by one.
fn vertex_normals_of<const D: usize>(
    points: &[Point<D>],
    facets: impl Iterator<Item = [usize; D]>,
    out: &mut Vec<Point<D>>,
) {
    out.clear();
    out.resize(points.len(), [0.0; D]);
    for f in facets {
        let fn_ = facet_normal(points, &f);
        for &i in &f {
            out[i] = add(out[i], fn_);
        }
    }
    for v in out.iter_mut() {
        *v = normalize(*v);
    }
}

/// Unnormalized facet normal: for a segment `(a, b)` the vector `(b - a)` turned clockwise
/// (length = segment length); for a triangle the cross product (length = twice the area).
pub fn facet_normal<const D: usize>(points: &[Point<D>], f: &[usize; D]) -> Point<D> {
    let mut out = [0.0; D];
    match D {
        2 => {
            let t = sub(points[f[1]], points[f[0]]);
            out[0] = t[1];
            out[1] = -t[0];
        }
        3 => {
            let a = sub(points[f[1]], points[f[0]]);
            let b = sub(points[f[2]], points[f[0]]);
            out[0] = a[1] * b[2] - a[2] * b[1];
            out[1] = a[2] * b[0] - a[0] * b[2];
            out[2] = a[0] * b[1] - a[1] * b[0];
        }
        _ => unreachable!("atlasmesh supports D = 2 and D = 3"),
    }
    out
}

/// Axis-aligned bounding box `(min, max)` of a non-empty point list.
pub fn bounding_box<const D: usize>(points: &[Point<D>]) -> (Point<D>, Point<D>) {
    let mut lo = [f64::INFINITY; D];
    let mut hi = [f64::NEG_INFINITY; D];
    for p in points {
        for d in 0..D {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

#[inline]
pub fn sub<const D: usize>(a: Point<D>, b: Point<D>) -> Point<D> {
    std::array::from_fn(|d| a[d] - b[d])
}
#[inline]
pub fn add<const D: usize>(a: Point<D>, b: Point<D>) -> Point<D> {
    std::array::from_fn(|d| a[d] + b[d])
}
#[inline]
pub fn scale<const D: usize>(a: Point<D>, s: f64) -> Point<D> {
    std::array::from_fn(|d| a[d] * s)
}
#[inline]
pub fn dot<const D: usize>(a: Point<D>, b: Point<D>) -> f64 {
    (0..D).map(|d| a[d] * b[d]).sum()
}
#[inline]
pub fn norm<const D: usize>(a: Point<D>) -> f64 {
    dot(a, a).sqrt()
}
#[inline]
pub fn dist2<const D: usize>(a: Point<D>, b: Point<D>) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}
/// `a / |a|`, or zero for the zero vector.
#[inline]
pub fn normalize<const D: usize>(a: Point<D>) -> Point<D> {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

/// Centroid of a non-empty point list.
pub fn centroid<const D: usize>(points: &[Point<D>]) -> Point<D> {
    let mut c = [0.0; D];
    for p in points {
        for d in 0..D {
            c[d] += p[d];
        }
    }
    scale(c, 1.0 / points.len().max(1) as f64)
}

/// Closest point on the segment `[a, b]` to `p`; returns the barycentric weight of `b`.
#[inline]
fn closest_on_segment<const D: usize>(p: Point<D>, a: Point<D>, b: Point<D>) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    if l2 <= 0.0 {
        return 0.0;
    }
    (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
}

/// Closest point on the triangle `abc` to `p` (Ericson, Real-Time Collision Detection, 5.1.5);
/// returns the barycentric weights `(u, v, w)` of `a, b, c`. Works in any dimension.
fn closest_on_triangle<const D: usize>(
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
    id: u64,
    /// Sum over every [`refit`](Self::refit) of the largest move of a point: no point of any
    /// facet moved farther than the difference of two readings (shape units).
    drift: f64,
    points: Vec<Point<D>>,
    facets: Vec<[usize; D]>,
    nodes: Vec<BvhNode<D>>,
    /// Facet indices, ordered so that every node covers a contiguous range; a facet's place
    /// in this order is its slot.
    order: Vec<u32>,
    /// The facet of every slot, its corners numbered as in `corners`.
    slots: Vec<[u32; D]>,
    /// The facets' corners, numbered in the order of their first use by `slots`, so that
    /// the corners of a leaf lie together in memory (a search's facet tests read nothing
    /// else, and cache misses were what they spent most of their time on).
    corners: Vec<Point<D>>,
    /// The point of every corner.
    corner_point: Vec<u32>,
    /// Unit vertex normal of every corner (as [`vertex_normals`] gives them).
    corner_normals: Vec<Point<D>>,
    /// Corner of every point (`u32::MAX`: on no facet).
    corner_of: Vec<u32>,
    /// Slot of every facet.
    slot_of: Vec<u32>,
    /// Parent of every node (the root's is itself).
    parent: Vec<u32>,
    /// Leaf of every slot.
    leaf_of: Vec<u32>,
}

/// A fresh identity for a [`ClosestPointIndex`].
fn next_index_id() -> u64 {
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

/// Candidate facets kept by a [`QueryMemo`].
const MEMO_FACETS: usize = 4;

/// What an exact closest-point search learned around its query point: the nearest facets
/// it met and how far everything else was. The next query of the same point, after the
/// point and the surface moved a little (a fit's or a registration's next iteration), is
/// then answered by testing those few facets, with a proof that no other facet can be
/// nearer; where the proof fails, by a search from the nearest one
/// ([`ClosestPointIndex::closest_memo`]).
#[derive(Clone, Copy, Debug)]
pub struct QueryMemo<const D: usize> {
    /// The index the memo belongs to (0: none yet).
    index: u64,
    /// The query point of the last search.
    at: Point<D>,
    /// The index's `drift` at the last search.
    drift: f64,
    /// Every facet but `near` was at least this far from `at` (shape units).
    bound: f64,
    /// The slots of the nearest facets met, nearest first (`u32::MAX`: none), and their
    /// distances.
    near: [u32; MEMO_FACETS],
    dist: [f64; MEMO_FACETS],
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
trait Track {
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
struct Nearest {
    near: [(f64, u32); MEMO_FACETS],
    rest: f64,
}

/// `if c { a } else { b }` without a branch (for choices the branch predictor cannot
/// guess, such as where a distance goes in a sorted list).
#[inline(always)]
fn select_f64(c: bool, a: f64, b: f64) -> f64 {
    let m = u64::from(c).wrapping_neg();
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// `if c { a } else { b }` without a branch.
#[inline(always)]
fn select_u32(c: bool, a: u32, b: u32) -> u32 {
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

/// Facets per leaf of the [`ClosestPointIndex`] hierarchy.
pub const LEAF_FACETS: usize = 4;

#[derive(Clone, Copy, Debug)]
struct BvhNode<const D: usize> {
    lo: Point<D>,
    hi: Point<D>,
    /// Index of the first child (the second is `child + 1`); 0 for a leaf.
    child: u32,
    start: u32,
    count: u32,
}

/// Squared distance from `p` to the box `[lo, hi]` (0 inside).
#[inline]
fn box_dist2<const D: usize>(p: &Point<D>, lo: &Point<D>, hi: &Point<D>) -> f64 {
    let mut d2 = 0.0;
    for d in 0..D {
        let v = (lo[d] - p[d]).max(p[d] - hi[d]).max(0.0);
        d2 += v * v;
    }
    d2
}

impl<const D: usize> ClosestPointIndex<D> {
    /// Builds the index. The shape must have at least one facet.
    #[track_caller]
    pub fn new(points: &[Point<D>], facets: &[[usize; D]]) -> Self {
        assert!(
            !facets.is_empty(),
            "ClosestPointIndex needs at least one facet"
        );
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
            let mut lo = [f64::INFINITY; D];
            let mut hi = [f64::NEG_INFINITY; D];
            let mut clo = [f64::INFINITY; D];
            let mut chi = [f64::NEG_INFINITY; D];
            for &fi in range.iter() {
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
        let mut parent = vec![0u32; nodes.len()];
        let mut leaf_of = vec![0u32; facets.len()];
        for (ni, node) in nodes.iter().enumerate() {
            if node.child == 0 {
                let s = node.start as usize;
                leaf_of[s..s + node.count as usize].fill(ni as u32);
            } else {
                parent[node.child as usize] = ni as u32;
                parent[node.child as usize + 1] = ni as u32;
            }
        }
        let mut corner_of = vec![u32::MAX; points.len()];
        let mut corner_point = Vec::new();
        let mut slot_of = vec![0u32; facets.len()];
        let slots: Vec<[u32; D]> = order
            .iter()
            .enumerate()
            .map(|(slot, &fi)| {
                slot_of[fi as usize] = slot as u32;
                facets[fi as usize].map(|v| {
                    if corner_of[v] == u32::MAX {
                        corner_of[v] = corner_point.len() as u32;
                        corner_point.push(v as u32);
                    }
                    corner_of[v]
                })
            })
            .collect();
        let mut index = ClosestPointIndex {
            id: next_index_id(),
            drift: 0.0,
            points: points.to_vec(),
            facets: facets.to_vec(),
            nodes,
            order,
            slots,
            corners: corner_point.iter().map(|&v| points[v as usize]).collect(),
            corner_point,
            corner_normals: Vec::new(),
            corner_of,
            slot_of,
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

    /// The unit vertex normal of every point (as [`vertex_normals`] gives them; zero for a
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

    /// The nearest intersection of the line `p + t n` with the facets, with `|t| <= max_t`
    /// (both directions, the nearest wins), or `None`.
    pub fn ray(&self, p: &Point<D>, n: &Point<D>, max_t: f64) -> Option<SurfacePoint<D>> {
        self.ray_where(p, n, max_t, |_| true)
    }

    /// [`ray`](Self::ray) among the hits that `accept` takes (e.g. those where the surface
    /// faces the same way as the ray's origin).
    pub fn ray_where(
        &self,
        p: &Point<D>,
        n: &Point<D>,
        max_t: f64,
        accept: impl Fn(&SurfacePoint<D>) -> bool,
    ) -> Option<SurfacePoint<D>> {
        let mut best: Option<(f64, SurfacePoint<D>)> = None;
        let inv = n.map(|v| 1.0 / v);
        // As in `descend`: children tested as they are pushed, without branches (a push
        // that always writes and moves the top by 0 or 1), and again as they come off the
        // stack, in case a hit found since shortened the segment.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let lim = best.as_ref().map_or(max_t, |(t, _)| t.abs());
            if !segment_hits_box(p, &inv, lim, &node.lo, &node.hi) {
                continue;
            }
            if node.child == 0 {
                let s = node.start as usize;
                for slot in s..s + node.count as usize {
                    let fi = self.order[slot] as usize;
                    let c = self.slots[slot].map(|v| self.corners[v as usize]);
                    let hit = match D {
                        2 => ray_segment(*p, *n, c[0], c[1]),
                        3 => ray_triangle(*p, *n, c[0], c[1], c[2]),
                        _ => unreachable!(),
                    };
                    if let Some((t, w)) = hit
                        && t.abs() <= max_t
                        && best.as_ref().is_none_or(|(bt, _)| t.abs() < bt.abs())
                    {
                        let mut weights = [0.0; D];
                        weights.copy_from_slice(&w[..D]);
                        let q = add(*p, scale(*n, t));
                        let sp = SurfacePoint {
                            point: q,
                            facet: fi,
                            weights,
                            dist2: t * t * dot(*n, *n),
                            slot: slot as u32,
                        };
                        if accept(&sp) {
                            best = Some((t, sp));
                        }
                    }
                }
                continue;
            }
            for c in [node.child, node.child + 1] {
                let child = &self.nodes[c as usize];
                stack[top] = c;
                top += usize::from(segment_hits_box(p, &inv, lim, &child.lo, &child.hi));
            }
        }
        best.map(|(_, s)| s)
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

/// Whether the segment `p + t n`, `|t| <= max_t`, meets the box `[lo, hi]`; `inv` is
/// `1 / n` per axis (infinite where `n` is 0). The slab test without branches: a segment
/// parallel to a slab gives infinite bounds (no `t`) outside it, and a NaN (`0 · ∞`) on
/// its boundary, taken as no bound (the boundary belongs to the box).
#[inline]
fn segment_hits_box<const D: usize>(
    p: &Point<D>,
    inv: &Point<D>,
    max_t: f64,
    lo: &Point<D>,
    hi: &Point<D>,
) -> bool {
    let (mut t0, mut t1) = (-max_t, max_t);
    for d in 0..D {
        let a = (lo[d] - p[d]) * inv[d];
        let b = (hi[d] - p[d]) * inv[d];
        let on_face = a.is_nan() | b.is_nan();
        t0 = t0.max(if on_face { f64::NEG_INFINITY } else { a.min(b) });
        t1 = t1.min(if on_face { f64::INFINITY } else { a.max(b) });
    }
    t0 <= t1
}

/// Line `p + t n` against segment `ab` (2D); returns `t` and the weights `(1-u, u, 0)`.
fn ray_segment<const D: usize>(
    p: Point<D>,
    n: Point<D>,
    a: Point<D>,
    b: Point<D>,
) -> Option<(f64, [f64; 3])> {
    let e = sub(b, a);
    let den = n[0] * e[1] - n[1] * e[0];
    if den.abs() < 1e-300 {
        return None;
    }
    let ap = sub(a, p);
    let t = (ap[0] * e[1] - ap[1] * e[0]) / den;
    let u = (ap[0] * n[1] - ap[1] * n[0]) / den;
    if (0.0..=1.0).contains(&u) {
        Some((t, [1.0 - u, u, 0.0]))
    } else {
        None
    }
}

/// Line `p + t n` against triangle `abc` (Möller–Trumbore); returns `t` and the weights.
fn ray_triangle<const D: usize>(
    p: Point<D>,
    n: Point<D>,
    a: Point<D>,
    b: Point<D>,
    c: Point<D>,
) -> Option<(f64, [f64; 3])> {
    let cross = |x: Point<D>, y: Point<D>| -> [f64; 3] {
        [
            x[1] * y[2] - x[2] * y[1],
            x[2] * y[0] - x[0] * y[2],
            x[0] * y[1] - x[1] * y[0],
        ]
    };
    let d3 = |x: [f64; 3], y: Point<D>| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let e1 = sub(b, a);
    let e2 = sub(c, a);
    let h = cross(n, e2);
    let det = d3(h, e1);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = sub(p, a);
    let u = inv * d3(h, s);
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = cross(s, e1);
    let v = inv * d3(q, n);
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = inv * d3(q, e2);
    Some((t, [1.0 - u - v, u, v]))
}

/// A similarity transform `t_{R,T,s}(p) = s R p + T` (section 3), from a reference frame to a
/// subject frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity<const D: usize> {
    /// Scale `s > 0`.
    pub s: f64,
    /// Rotation `R` (row-major, `det R = +1`).
    pub r: [[f64; D]; D],
    /// Translation `T`.
    pub t: Point<D>,
}

impl<const D: usize> Default for Similarity<D> {
    fn default() -> Self {
        Self::identity()
    }
}

impl<const D: usize> Similarity<D> {
    /// The identity.
    pub fn identity() -> Self {
        Similarity {
            s: 1.0,
            r: std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 })),
            t: [0.0; D],
        }
    }

    /// The similarity of scale `s` and rotation `r` that maps the point `from` onto `to`
    /// (e.g. one shape's centroid onto another's).
    pub fn centred(s: f64, r: [[f64; D]; D], from: &Point<D>, to: &Point<D>) -> Self {
        let mut sim = Similarity { s, r, t: [0.0; D] };
        sim.t = sub(*to, sim.apply(from));
        sim
    }

    /// `s R p + T`.
    #[inline]
    pub fn apply(&self, p: &Point<D>) -> Point<D> {
        std::array::from_fn(|i| {
            self.s * (0..D).map(|j| self.r[i][j] * p[j]).sum::<f64>() + self.t[i]
        })
    }

    /// `R^T (q - T) / s`.
    #[inline]
    pub fn apply_inverse(&self, q: &Point<D>) -> Point<D> {
        let d = sub(*q, self.t);
        std::array::from_fn(|i| (0..D).map(|j| self.r[j][i] * d[j]).sum::<f64>() / self.s)
    }

    /// `R v` (a direction: no scale, no translation).
    #[inline]
    pub fn rotate(&self, v: &Point<D>) -> Point<D> {
        std::array::from_fn(|i| (0..D).map(|j| self.r[i][j] * v[j]).sum::<f64>())
    }

    /// `R^T v` (a direction from the subject frame to the reference frame).
    #[inline]
    pub fn rotate_inverse(&self, v: &Point<D>) -> Point<D> {
        std::array::from_fn(|i| (0..D).map(|j| self.r[j][i] * v[j]).sum::<f64>())
    }

    /// The composition `self ∘ other`.
    pub fn compose(&self, other: &Similarity<D>) -> Similarity<D> {
        let r = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..D).map(|k| self.r[i][k] * other.r[k][j]).sum::<f64>())
        });
        Similarity {
            s: self.s * other.s,
            r,
            t: self.apply(&other.t),
        }
    }

    /// A rotation by `angle` (radians) in the plane of the first two axes.
    pub fn planar_rotation(angle: f64) -> Self {
        let mut s = Self::identity();
        let (sn, c) = angle.sin_cos();
        s.r[0][0] = c;
        s.r[0][1] = -sn;
        s.r[1][0] = sn;
        s.r[1][1] = c;
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clustering_decimation_keeps_original_points_and_a_closed_surface() {
        let (points, facets) = uv_sphere(64, 32, |t, p| {
            [
                10.0 * t.cos() * p.cos(),
                10.0 * t.cos() * p.sin(),
                10.0 * t.sin(),
            ]
        });
        let s = Shape {
            name: "sphere".into(),
            points,
            facets,
            landmarks: vec![],
        };
        let (d, kept) = s.decimate_by_clustering(1.5, [0.3, 0.1, 0.7]).unwrap();
        assert!(
            d.points.len() < s.points.len() / 2,
            "{} points",
            d.points.len()
        );
        assert_eq!(kept.len(), d.points.len());
        for (p, &k) in d.points.iter().zip(&kept) {
            assert_eq!(*p, s.points[k]);
        }
        // Every edge shared by exactly two facets, each way once (closed, oriented).
        let mut edges = std::collections::HashMap::new();
        for f in &d.facets {
            for e in 0..3 {
                *edges.entry((f[e], f[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        assert!(
            edges
                .iter()
                .all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1))
        );
        assert!(s.decimate_by_clustering(0.0, [0.0; 3]).is_err());
    }

    #[test]
    fn hinted_closest_points_equal_the_plain_ones() {
        // A wiggly closed outline, queries near and far, hints good and bad.
        let pts: Vec<Point<2>> = (0..400)
            .map(|i| {
                let t = i as f64 / 400.0 * std::f64::consts::TAU;
                let r = 1.0 + 0.3 * (5.0 * t).sin();
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        let s = Shape::polyline("w", pts, true);
        let idx = ClosestPointIndex::from_shape(&s);
        for k in 0..500 {
            let a = k as f64 * 0.7;
            let q = [1.6 * (a * 1.3).cos() * (k % 7) as f64 / 5.0, 1.4 * a.sin()];
            let plain = idx.closest(&q);
            for hint in [0, 57, 399, (k * 13) % 400] {
                let h = idx.closest_from(&q, hint);
                assert!(
                    (h.dist2 - plain.dist2).abs() <= 1e-15 * (1.0 + plain.dist2),
                    "query {q:?} hint {hint}: {} vs {}",
                    h.dist2,
                    plain.dist2
                );
            }
        }
    }

    #[test]
    fn memo_queries_equal_plain_ones_as_points_and_surface_move() {
        // A bumpy closed surface whose shape changes from step to step (refit), and query
        // points that drift, jump now and then, and sit near and far.
        let surface = |t: f64| {
            uv_sphere(24, 16, |th, ph| {
                let r = 1.0 + 0.2 * (3.0 * ph + t).cos() * th.cos() + 0.05 * t;
                [
                    r * th.cos() * ph.cos(),
                    0.8 * r * th.cos() * ph.sin(),
                    r * th.sin(),
                ]
            })
        };
        let (points, facets) = surface(0.0);
        let mut idx = ClosestPointIndex::new(&points, &facets);
        let queries = |step: usize| -> Vec<Point<3>> {
            (0..300)
                .map(|k| {
                    let a = k as f64 * 0.37 + 0.001 * step as f64;
                    let r = 0.6 + (k % 9) as f64 * 0.1 + if step % 7 == 3 { 0.3 } else { 0.0 };
                    [r * a.cos(), r * (1.3 * a).sin(), r * (0.7 * a).cos()]
                })
                .collect()
        };
        let mut memos = vec![QueryMemo::default(); 300];
        let mut hits = 0;
        let mut now = points.clone();
        for step in 0..20 {
            if step % 4 == 2 {
                now = surface(0.002 * step as f64).0;
                idx.refit(&now);
            }
            for (q, memo) in queries(step).iter().zip(&mut memos) {
                let before = *memo;
                let m = idx.closest_memo(q, memo);
                let plain = idx.closest(q);
                assert!(
                    (m.dist2 - plain.dist2).abs() <= 1e-12 * (1.0 + plain.dist2),
                    "step {step} query {q:?}: {} vs {}",
                    m.dist2,
                    plain.dist2
                );
                // Against every facet of the surface as it is now (not the index's copy),
                // and the answer's facet and weights give its point.
                if step % 4 == 2 {
                    let brute = facets
                        .iter()
                        .map(|f| {
                            let w = closest_on_triangle(*q, now[f[0]], now[f[1]], now[f[2]]);
                            let c = (0..3).fold([0.0; 3], |c, k| add(c, scale(now[f[k]], w[k])));
                            dist2(*q, c)
                        })
                        .fold(f64::INFINITY, f64::min);
                    assert!((m.dist2 - brute).abs() <= 1e-12 * (1.0 + brute));
                    let f = facets[m.facet];
                    let at = (0..3).fold([0.0; 3], |c, k| add(c, scale(now[f[k]], m.weights[k])));
                    assert!(dist2(at, m.point) < 1e-24, "step {step} query {q:?}");
                }
                hits += usize::from(memo.at == before.at && before.index != 0);
            }
        }
        // The memos did answer most queries without a search.
        assert!(hits > 1500, "only {hits} memo answers of 6000");
        // A memo from another index is not trusted.
        let other = ClosestPointIndex::new(&points, &facets);
        let q = [2.0, 0.0, 0.0];
        let mut memo = QueryMemo::default();
        let _ = idx.closest_memo(&q, &mut memo);
        let c = other.closest_memo(&q, &mut memo);
        assert!((c.dist2 - other.closest(&q).dist2).abs() < 1e-12);
    }

    #[test]
    fn the_index_normals_follow_the_surface_through_refits() {
        // The index's own vertex normals (kept in its corner order) against those of the
        // shape's arrays, before and after the surface moves.
        let surface = |t: f64| {
            uv_sphere(20, 12, |th, ph| {
                let r = 1.0 + 0.3 * (2.0 * ph + t).sin() * th.cos();
                [
                    r * th.cos() * ph.cos(),
                    r * th.cos() * ph.sin(),
                    0.7 * r * th.sin(),
                ]
            })
        };
        let (points, facets) = surface(0.0);
        let mut idx = ClosestPointIndex::new(&points, &facets);
        let mut out = Vec::new();
        for t in [0.0, 0.5, 1.5] {
            let now = surface(t).0;
            idx.refit(&now);
            let vn = vertex_normals(&now, &facets);
            idx.vertex_normals_into(&mut out);
            assert_eq!(out.len(), vn.len());
            for (a, b) in out.iter().zip(&vn) {
                assert!(dist2(*a, *b) < 1e-24);
            }
            for k in 0..200 {
                let a = k as f64 * 0.61;
                let q = [1.5 * a.cos(), 1.3 * (0.9 * a).sin(), (0.4 * a).cos() - 0.2];
                let c = idx.closest(&q);
                let f = facets[c.facet];
                assert_eq!(idx.facet_vertices(&c), Some(f));
                let blend = (0..3).fold([0.0; 3], |n, i| add(n, scale(vn[f[i]], c.weights[i])));
                let n = idx.normal_at(&c).expect("no degenerate facet here");
                assert!(dist2(n, normalize(blend)) < 1e-20, "t {t} query {q:?}");
            }
        }
    }

    #[test]
    fn rays_agree_with_brute_force() {
        // A bumpy closed surface, rays in every direction and along the axes (zero
        // components: the slab test's infinite bounds), from inside, outside and far.
        let (points, facets) = uv_sphere(18, 11, |th, ph| {
            let r = 1.0 + 0.25 * (3.0 * ph).sin() * th.cos();
            [
                r * th.cos() * ph.cos(),
                r * th.cos() * ph.sin(),
                0.8 * r * th.sin(),
            ]
        });
        let idx = ClosestPointIndex::new(&points, &facets);
        let mut hits = 0;
        for k in 0..400 {
            let a = k as f64 * 0.37;
            let p = [
                1.8 * (0.7 * a).cos() * (k % 5) as f64 / 4.0,
                1.5 * (1.1 * a).sin() * (k % 3) as f64 / 2.0,
                (0.3 * a).cos() - 0.1,
            ];
            let n = match k % 4 {
                0 => [1.0, 0.0, 0.0],
                1 => [0.0, -1.0, 0.0],
                2 => [0.0, 0.6, 0.8],
                _ => normalize([a.cos(), (2.0 * a).sin(), 0.5 - (k % 7) as f64 / 7.0]),
            };
            let max_t = 0.3 + (k % 6) as f64 * 0.4;
            let brute = facets
                .iter()
                .filter_map(|f| ray_triangle(p, n, points[f[0]], points[f[1]], points[f[2]]))
                .map(|(t, _)| t.abs())
                .filter(|t| *t <= max_t)
                .fold(f64::INFINITY, f64::min);
            match idx.ray(&p, &n, max_t) {
                Some(h) => {
                    hits += 1;
                    assert!((h.dist2.sqrt() - brute).abs() < 1e-12, "ray {k}");
                }
                None => assert!(brute.is_infinite(), "ray {k} missed a hit at {brute}"),
            }
        }
        assert!(hits > 100, "only {hits} rays hit");
    }

    #[test]
    fn closest_point_on_segments_is_exact_not_vertex() {
        // A long segment: the closest point is in its middle, far from both vertices.
        let s = Shape::polyline("l", vec![[0.0, 0.0], [10.0, 0.0], [10.0, 1.0]], false);
        let idx = ClosestPointIndex::from_shape(&s);
        let c = idx.closest(&[4.0, 2.0]);
        assert!((c.point[0] - 4.0).abs() < 1e-12 && c.point[1].abs() < 1e-12);
        assert!((c.dist2 - 4.0).abs() < 1e-12);
    }

    #[test]
    fn closest_point_agrees_with_brute_force() {
        let n = 200;
        let pts: Vec<Point<2>> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                let r = 1.0 + 0.3 * (5.0 * t).cos();
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        let s = Shape::polyline("star", pts, true);
        let idx = ClosestPointIndex::from_shape(&s);
        for k in 0..500 {
            let q = [
                ((k * 37) % 101) as f64 / 40.0 - 1.25,
                ((k * 53) % 97) as f64 / 38.0 - 1.25,
            ];
            let c = idx.closest(&q);
            // Straight from the shape's own points, not the index's copies.
            let brute = s
                .facets
                .iter()
                .map(|f| {
                    let (a, b) = (s.points[f[0]], s.points[f[1]]);
                    let t = closest_on_segment(q, a, b);
                    dist2(q, add(a, scale(sub(b, a), t)))
                })
                .fold(f64::INFINITY, f64::min);
            assert!((c.dist2 - brute).abs() < 1e-12, "query {q:?}");
        }
    }

    #[test]
    fn similarity_inverse_undoes_apply() {
        let mut t = Similarity::<2>::planar_rotation(0.7);
        t.s = 2.5;
        t.t = [1.0, -3.0];
        let p = [0.3, 0.9];
        let q = t.apply_inverse(&t.apply(&p));
        assert!(dist2(p, q) < 1e-24);
    }

    #[test]
    fn ccw_circle_normals_point_outwards() {
        let pts: Vec<Point<2>> = (0..50)
            .map(|i| {
                let t = i as f64 / 50.0 * std::f64::consts::TAU;
                [t.cos(), t.sin()]
            })
            .collect();
        let s = Shape::polyline("c", pts.clone(), true);
        for (p, n) in pts.iter().zip(s.vertex_normals()) {
            assert!(dot(*p, n) > 0.99);
        }
    }
}

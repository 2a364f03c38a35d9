//! Shapes as points plus connectivity; normals, closest points and projection along normals.
//!
//! A shape in `D` dimensions is a list of points and a list of boundary facets, each facet a
//! `(D-1)`-simplex given by `D` point indices: segments `[a, b]` for outlines (`D = 2`),
//! triangles `[a, b, c]` for surfaces (`D = 3`). Coordinates are in the shape's own units and
//! frame; nothing here changes them.

use crate::error::{Error, Result};
use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;

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
        let mut n = vec![[0.0; D]; self.points.len()];
        for f in &self.facets {
            let fn_ = facet_normal(&self.points, f);
            for &i in f {
                for d in 0..D {
                    n[i][d] += fn_[d];
                }
            }
        }
        n.iter().map(|v| normalize(*v)).collect()
    }

    /// Median facet size (segment length, or square root of twice the triangle area).
    pub fn median_edge_length(&self) -> f64 {
        let mut l: Vec<f64> = self
            .facets
            .iter()
            .map(|f| norm(sub(self.points[f[1]], self.points[f[0]])))
            .collect();
        if l.is_empty() {
            return 0.0;
        }
        l.sort_by(f64::total_cmp);
        l[l.len() / 2]
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
}

/// Closest-point and ray queries on the facets of a shape, through a k-d tree of the facet
/// centroids (exact: candidates are all facets whose centroid lies within the current best
/// distance plus the largest centroid-to-vertex radius).
pub struct ClosestPointIndex<const D: usize> {
    points: Vec<Point<D>>,
    facets: Vec<[usize; D]>,
    tree: ImmutableKdTree<f64, u64, D, 32>,
    radius: f64,
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
        let radius = facets
            .iter()
            .zip(&centroids)
            .map(|(f, c)| f.iter().map(|&i| dist2(points[i], *c)).fold(0.0, f64::max))
            .fold(0.0, f64::max)
            .sqrt();
        ClosestPointIndex {
            points: points.to_vec(),
            facets: facets.to_vec(),
            tree: ImmutableKdTree::new_from_slice(&centroids),
            radius,
        }
    }

    /// From a shape.
    pub fn from_shape(shape: &Shape<D>) -> Self {
        Self::new(&shape.points, &shape.facets)
    }

    fn closest_on_facet(&self, p: Point<D>, fi: usize) -> SurfacePoint<D> {
        let f = self.facets[fi];
        let mut weights = [0.0; D];
        match D {
            2 => {
                let t = closest_on_segment(p, self.points[f[0]], self.points[f[1]]);
                weights[0] = 1.0 - t;
                weights[1] = t;
            }
            3 => {
                let w =
                    closest_on_triangle(p, self.points[f[0]], self.points[f[1]], self.points[f[2]]);
                weights.copy_from_slice(&w);
            }
            _ => unreachable!(),
        }
        let mut q = [0.0; D];
        for k in 0..D {
            q = add(q, scale(self.points[f[k]], weights[k]));
        }
        SurfacePoint {
            point: q,
            facet: fi,
            weights,
            dist2: dist2(p, q),
        }
    }

    /// The closest point to `p` on the shape's facets (not only its vertices).
    pub fn closest(&self, p: &Point<D>) -> SurfacePoint<D> {
        let nn = self.tree.nearest_one::<SquaredEuclidean>(p);
        let mut best = self.closest_on_facet(*p, nn.item as usize);
        let r = best.dist2.sqrt() + self.radius;
        if r * r > nn.distance {
            for c in self.tree.within_unsorted::<SquaredEuclidean>(p, r * r) {
                let fi = c.item as usize;
                if fi == best.facet {
                    continue;
                }
                let cand = self.closest_on_facet(*p, fi);
                if cand.dist2 < best.dist2 {
                    best = cand;
                }
            }
        }
        best
    }

    /// The nearest intersection of the line `p + t n` with the facets, with `|t| <= max_t`
    /// (both directions, the nearest wins), or `None`.
    pub fn ray(&self, p: &Point<D>, n: &Point<D>, max_t: f64) -> Option<SurfacePoint<D>> {
        let r = max_t + self.radius;
        let mut best: Option<(f64, SurfacePoint<D>)> = None;
        for c in self.tree.within_unsorted::<SquaredEuclidean>(p, r * r) {
            let fi = c.item as usize;
            let f = self.facets[fi];
            let hit = match D {
                2 => ray_segment(*p, *n, self.points[f[0]], self.points[f[1]]),
                3 => ray_triangle(
                    *p,
                    *n,
                    self.points[f[0]],
                    self.points[f[1]],
                    self.points[f[2]],
                ),
                _ => unreachable!(),
            };
            if let Some((t, w)) = hit
                && t.abs() <= max_t
                && best.as_ref().is_none_or(|(bt, _)| t.abs() < bt.abs())
            {
                let mut weights = [0.0; D];
                weights.copy_from_slice(&w[..D]);
                let q = add(*p, scale(*n, t));
                best = Some((
                    t,
                    SurfacePoint {
                        point: q,
                        facet: fi,
                        weights,
                        dist2: t * t * dot(*n, *n),
                    },
                ));
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
            let brute = (0..s.facets.len())
                .map(|f| idx.closest_on_facet(q, f).dist2)
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

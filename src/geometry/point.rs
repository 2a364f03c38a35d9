//! Points and vectors in `D` dimensions, with the vector operations the algorithms use.

/// A point (or vector) in `D` dimensions.
pub type Point<const D: usize> = [f64; D];

/// The largest coordinate magnitude read: areas, volumes and Jacobians are products of up to
/// three coordinate differences, which stay finite in f64 below it (1e100³ = 1e300).
pub const MAX_COORDINATE: f64 = 1e100;

/// What is wrong with a point's coordinates, if anything: a NaN or infinite one, or one
/// beyond [`MAX_COORDINATE`] (the message says to rescale).
pub fn coordinate_problem(p: &[f64]) -> Option<String> {
    if p.iter().any(|c| !c.is_finite()) {
        return Some("has a NaN or infinite coordinate".into());
    }
    p.iter().find(|c| c.abs() > MAX_COORDINATE).map(|c| {
        format!(
            "has the coordinate {c:e}, beyond ±{MAX_COORDINATE:e}: areas and Jacobians would overflow; rescale the file"
        )
    })
}

/// The centroid size of a point set: the root of the summed squared distances to its
/// centroid (the size GPA scales away; units of the points).
pub fn centroid_size<const D: usize>(points: &[Point<D>]) -> f64 {
    let c = centroid(points);
    points.iter().map(|p| dist2(*p, c)).sum::<f64>().sqrt()
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

/// `a - b`.
#[inline]
pub fn sub<const D: usize>(a: Point<D>, b: Point<D>) -> Point<D> {
    std::array::from_fn(|d| a[d] - b[d])
}
/// `a + b`.
#[inline]
pub fn add<const D: usize>(a: Point<D>, b: Point<D>) -> Point<D> {
    std::array::from_fn(|d| a[d] + b[d])
}
/// `s a`.
#[inline]
pub fn scale<const D: usize>(a: Point<D>, s: f64) -> Point<D> {
    std::array::from_fn(|d| a[d] * s)
}
/// `a · b`.
#[inline]
pub fn dot<const D: usize>(a: Point<D>, b: Point<D>) -> f64 {
    (0..D).map(|d| a[d] * b[d]).sum()
}
/// `a × b` (3D).
#[inline]
pub fn cross(a: Point<3>, b: Point<3>) -> Point<3> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// `|a|`.
#[inline]
pub fn norm<const D: usize>(a: Point<D>) -> f64 {
    dot(a, a).sqrt()
}
/// `|a - b|²`.
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

/// A point of dimension `D` in dimension 3: 2D points at z = 0.
pub fn in_3d<const D: usize>(p: &Point<D>) -> Point<3> {
    std::array::from_fn(|d| if d < D { p[d] } else { 0.0 })
}

/// Converts between `[f64; D]` and `[f64; E]` when `D == E` (a no-op used to call
/// dimension-specific code from generic code).
pub fn same_dim<const D: usize, const E: usize>(p: &Point<D>) -> Point<E> {
    std::array::from_fn(|d| p[d])
}

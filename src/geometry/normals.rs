//! Facet and vertex normals (section 2.1).

use super::{Point, add, normalize, sub};

/// Vertex normals of `points` with connectivity `facets`: see [`Shape::vertex_normals`](super::Shape::vertex_normals).
pub fn vertex_normals<const D: usize>(points: &[Point<D>], facets: &[[usize; D]]) -> Vec<Point<D>> {
    let mut n = Vec::new();
    vertex_normals_of(points, facets.iter().copied(), &mut n);
    n
}

/// [`vertex_normals`] into `out`, for facets given one by one.
pub(super) fn vertex_normals_of<const D: usize>(
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

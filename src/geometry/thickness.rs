//! Local thickness of a closed shape: how far the inside reaches across from each point.

use super::{ClosestPointIndex, Point, Shape, dot, scale, sub};

/// The local thickness at every point of the closed, outward-oriented `shape`: the distance
/// from the point, inwards along its normal, to the first facet that faces the other way
/// (the opposite wall); `None` where the ray leaves without one (an open shape, a point on a
/// degenerate facet). Shape units. The wall of a shaft, a lamina or a finger is the
/// distance across it.
pub fn local_thickness<const D: usize>(shape: &Shape<D>) -> Vec<Option<f64>> {
    let index = ClosestPointIndex::from_shape(shape);
    let normals = shape.vertex_normals();
    let reach = 2.0 * shape.bbox_diagonal();
    let eps = 1e-9 * reach;
    shape
        .points
        .iter()
        .zip(&normals)
        .map(|(p, n)| {
            if !dot(*n, *n).is_finite() || dot(*n, *n) < 0.5 {
                return None;
            }
            let start = sub(*p, scale(*n, eps));
            let inward = scale(*n, -1.0);
            index
                .ray_where(&start, &inward, reach, |hit| {
                    let ahead = dot(sub(hit.point, start), inward) > 0.0;
                    let facing = index
                        .normal_at(hit)
                        .is_some_and(|m: Point<D>| dot(m, *n) < 0.0);
                    ahead && facing
                })
                .map(|hit| hit.dist2.sqrt() + eps)
        })
        .collect()
}

/// The `q`-quantile (0..1) of the thicknesses found, or `None` when none was.
pub fn thickness_quantile(thickness: &[Option<f64>], q: f64) -> Option<f64> {
    let mut t: Vec<f64> = thickness
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    if t.is_empty() {
        return None;
    }
    t.sort_by(f64::total_cmp);
    Some(t[((t.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize])
}

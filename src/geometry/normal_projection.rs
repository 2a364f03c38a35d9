//! Projection along normals onto a subject (section 2.1 and the last step of Algorithm 1).

use super::{ClosestPointIndex, Point, QueryMemo, SurfacePoint, dot, norm, vertex_normals};

/// Pairs whose normals (instance and subject) make an angle above 60° are left out of the
/// update: they join facing sides (a finger's side and its neighbour's), the pull that traps a
/// fit in a local minimum. The projection along normals accepts no crossing beyond it either.
pub const COMPATIBLE_NORMALS_COS: f64 = 0.5;

/// Projects every point of `points` (with the connectivity `facets`, for its vertex normals)
/// onto the indexed subject along its normal (section 3, last step of Algorithm 1): the
/// nearest crossing of the normal line within three times the closest-point distance plus
/// half the local edge length, among the crossings where the subject faces the same way
/// (its normal, [`ClosestPointIndex::normal_at`], turned round with `flip`, within 60° of
/// the point's); the closest point where there is none. Without that condition a normal
/// line near a concave corner (between two fingers) crosses the neighbouring side first and
/// the correspondence jumps.
/// `memos`, one per point, are those of the closest-point queries of the same points (e.g.
/// a fit's last update): they make the closest points cheap.
pub fn project_along_normals<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
    subject: &ClosestPointIndex<D>,
    flip: bool,
    memos: Option<&mut [QueryMemo<D>]>,
) -> Vec<SurfacePoint<D>> {
    let normals = vertex_normals(points, facets);
    let h = 0.5 * crate::geometry::median_edge_length(points, facets);
    let mut fresh = Vec::new();
    let memos = match memos {
        Some(m) if m.len() == points.len() => m,
        _ => {
            fresh.resize(points.len(), QueryMemo::default());
            &mut fresh[..]
        }
    };
    points
        .iter()
        .zip(&normals)
        .zip(memos.iter_mut())
        .map(|((p, nrm), memo)| {
            let c = subject.closest_memo(p, memo);
            if norm(*nrm) == 0.0 {
                return c;
            }
            let max_t = 3.0 * c.dist2.sqrt() + h;
            subject
                .ray_where(p, nrm, max_t, |hit| {
                    subject.normal_at(hit).is_some_and(|ns| {
                        let cos = dot(ns, *nrm);
                        (if flip { -cos } else { cos }) >= COMPATIBLE_NORMALS_COS
                    })
                })
                .unwrap_or(c)
        })
        .collect()
}

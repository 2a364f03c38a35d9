//! Ray casts against a shape's facets (the projection along normals).

use super::{ClosestPointIndex, Point, SurfacePoint, add, dot, scale, sub};

impl<const D: usize> ClosestPointIndex<D> {
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
}

/// Whether the segment `p + t n`, `|t| <= max_t`, meets the box `[lo, hi]`; `inv` is
/// `1 / n` per axis (infinite where `n` is 0). The slab test without branches: a segment
/// parallel to a slab gives infinite bounds (no `t`) outside it, and a NaN (`0 · ∞`) on
/// its boundary, taken as no bound (the boundary belongs to the box).
#[inline]
pub(super) fn segment_hits_box<const D: usize>(
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
pub(super) fn ray_segment<const D: usize>(
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
pub(super) fn ray_triangle<const D: usize>(
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

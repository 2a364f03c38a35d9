//! A surface cut by a plane and closed by a flat cap: what lies beyond the plane removed, the
//! section closed by triangles in the plane (a constrained Delaunay triangulation of the
//! section's loops, `spade`, with interior points about one edge length apart so that the cap
//! is sampled as densely as the rest of the surface). The cap's facets are marked: they are
//! where the shape was cut, not anatomy.
//!
//! The cut is watertight: the cap shares the section's points with the kept surface, so a
//! closed surface stays closed, and an open one whose openings all lie beyond the plane (a
//! bone cut by its image's border, cut again below the border) comes out closed. Points within
//! 2 % of an edge of the plane are moved onto it first, so that the cut makes no slivers.
//!
//! Frames: the surface's own (world, mm for a scan); the plane in the same frame.

use super::{Point, Shape, add, cross, dot, median_edge_length, normalize, scale, sub};
use crate::error::{Error, Result};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
use std::collections::HashMap;

/// A plane: a point on it and its unit normal, which points to the side a cut removes.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Plane {
    /// A point of the plane (the shape's frame).
    pub point: Point<3>,
    /// Unit normal, towards the removed side.
    pub normal: Point<3>,
}

impl Plane {
    /// The signed distance of `p` from the plane (positive on the removed side).
    pub fn signed_distance(&self, p: Point<3>) -> f64 {
        dot(sub(p, self.point), self.normal)
    }
}

/// A surface cut by a plane: the kept part closed by a flat cap.
#[derive(Clone, Debug)]
pub struct PlaneCut {
    /// The kept surface with its cap (the cap's facets last).
    pub shape: Shape<3>,
    /// The first facet of the cap: `shape.facets[cap_start..]` lie in the plane.
    pub cap_start: usize,
    /// The cap's area (the section's area, squared units).
    pub cap_area: f64,
    /// The share of the surface's area the cut removed (0 to 1).
    pub removed_share: f64,
}

/// Points closer to the plane than this share of the median edge are moved onto it.
const SNAP: f64 = 0.02;

/// The cap of a shape cut by a plane, from the shape's `points` and the `cap` facets among its
/// `facets`: the cap's points (sorted indices), the least-squares plane's point (their
/// centroid) and unit normal, turned away from the centroid of all `points` (outwards, towards
/// the side cut off). `None` when the cap has `D` points or fewer.
pub fn cap_plane<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
    cap: &[usize],
) -> Option<(Vec<usize>, Point<D>, Point<D>)> {
    let mut ids: Vec<usize> = cap
        .iter()
        .filter_map(|&f| facets.get(f))
        .flatten()
        .copied()
        .filter(|&i| i < points.len())
        .collect();
    ids.sort_unstable();
    ids.dedup();
    if ids.len() <= D {
        return None;
    }
    let on: Vec<Point<D>> = ids.iter().map(|&i| points[i]).collect();
    let point = super::centroid(&on);
    let mut normal = super::principal_axes_of(&on)[D - 1];
    if dot(normal, sub(point, super::centroid(points))) < 0.0 {
        normal = normal.map(|x| -x);
    }
    Some((ids, point, normal))
}

/// `shape` cut by `plane`: everything on the normal's side removed, the section closed by a
/// flat cap (see the module doc). Landmarks on the removed side are dropped.
///
/// # Errors
/// [`Error::Population`] naming the shape when the plane misses it (nothing kept, or nothing
/// cut), when the surface is open where the plane cuts it or below it (the cut would leave a
/// hole), or when the section crosses itself.
pub fn cut_by_plane(shape: &Shape<3>, plane: &Plane) -> Result<PlaneCut> {
    let name = &shape.name;
    let fail = |why: &str| Error::Population(format!("{name}: {why}"));
    let n = normalize(plane.normal);
    let plane = Plane {
        point: plane.point,
        normal: n,
    };
    let h = median_edge_length(&shape.points, &shape.facets);
    if !(h > 0.0 && n.iter().all(|c| c.is_finite())) {
        return Err(fail("a cut needs a surface with facets and a finite plane"));
    }
    let mut points = shape.points.clone();
    let mut s: Vec<f64> = points.iter().map(|&p| plane.signed_distance(p)).collect();
    for (p, d) in points.iter_mut().zip(s.iter_mut()) {
        if d.abs() < SNAP * h {
            *p = sub(*p, scale(n, *d));
            *d = 0.0;
        }
    }
    if s.iter().all(|&d| d >= 0.0) {
        return Err(fail("the cut plane leaves nothing of the shape"));
    }
    if s.iter().all(|&d| d <= 0.0) {
        return Err(fail(
            "the cut plane misses the shape (nothing lies beyond it)",
        ));
    }
    let total_area = area(&shape.points, &shape.facets);
    let mut crossing: HashMap<(usize, usize), usize> = HashMap::new();
    let mut facets = Vec::with_capacity(shape.facets.len());
    for f in &shape.facets {
        let mut poly: Vec<usize> = Vec::with_capacity(4);
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if s[a] <= 0.0 {
                poly.push(a);
            }
            if (s[a] < 0.0 && s[b] > 0.0) || (s[a] > 0.0 && s[b] < 0.0) {
                let key = (a.min(b), a.max(b));
                let i = *crossing.entry(key).or_insert_with(|| {
                    let t = s[a] / (s[a] - s[b]);
                    points.push(add(points[a], scale(sub(points[b], points[a]), t)));
                    points.len() - 1
                });
                poly.push(i);
            }
        }
        for k in 1..poly.len().saturating_sub(1) {
            let t = [poly[0], poly[k], poly[k + 1]];
            let on_plane = |i: usize| i >= s.len() || s[i] == 0.0;
            if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] && !t.iter().all(|&i| on_plane(i)) {
                facets.push(t);
            }
        }
    }
    let on_plane = |i: usize| i >= s.len() || s[i] == 0.0;
    let loops = section_loops(&facets, &on_plane).map_err(|why| fail(&why))?;
    let cap_start = facets.len();
    let cap = cap_triangles(&mut points, &loops, &plane, h).map_err(|why| fail(&why))?;
    facets.extend(cap);
    let cap_area = area(&points, &facets[cap_start..]);
    let kept_area = area(&points, &facets[..cap_start]);
    let landmarks = shape
        .landmarks
        .iter()
        .copied()
        .filter(|&i| s[i] <= 0.0)
        .collect();
    let (points, facets, landmarks) = compact(points, facets, landmarks);
    Ok(PlaneCut {
        shape: Shape {
            name: name.clone(),
            points,
            facets,
            landmarks,
        },
        cap_start,
        cap_area,
        removed_share: (1.0 - kept_area / total_area).clamp(0.0, 1.0),
    })
}

/// The area of `facets`.
fn area(points: &[Point<3>], facets: &[[usize; 3]]) -> f64 {
    facets
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| points[i]);
            0.5 * super::norm(cross(sub(b, a), sub(c, a)))
        })
        .sum()
}

/// The loops of the section: the kept surface's boundary edges, each directed as its facet
/// has it, chained. Every boundary edge must lie in the plane (else the surface is open below
/// the cut) and every loop close.
fn section_loops(
    facets: &[[usize; 3]],
    on_plane: &dyn Fn(usize) -> bool,
) -> std::result::Result<Vec<Vec<usize>>, String> {
    let mut directed: HashMap<(usize, usize), usize> = HashMap::new();
    for f in facets {
        for k in 0..3 {
            *directed.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut next: HashMap<usize, usize> = HashMap::new();
    for (&(a, b), &count) in &directed {
        if directed.contains_key(&(b, a)) {
            continue;
        }
        if count > 1 || !on_plane(a) || !on_plane(b) {
            return Err(
                "the surface is open (or not manifold) on the kept side of the cut: a cut closes only a surface whose openings all lie beyond the plane"
                    .into(),
            );
        }
        if next.insert(a, b).is_some() {
            return Err("the section touches itself at a point: move the cut plane".into());
        }
    }
    let mut loops = Vec::new();
    let mut starts: Vec<usize> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut used: std::collections::HashSet<usize> = std::collections::HashSet::new();
    for start in starts {
        if used.contains(&start) {
            continue;
        }
        let mut l = vec![start];
        used.insert(start);
        let mut at = start;
        loop {
            let Some(&b) = next.get(&at) else {
                return Err("the section does not close (the surface is open at the cut)".into());
            };
            if b == start {
                break;
            }
            if !used.insert(b) {
                return Err("the section crosses itself: move the cut plane".into());
            }
            l.push(b);
            at = b;
        }
        if l.len() >= 3 {
            loops.push(l);
        }
    }
    if loops.is_empty() {
        return Err("the cut leaves no section to close".into());
    }
    Ok(loops)
}

/// The cap's triangles (points added for its interior), facing along the plane's normal.
fn cap_triangles(
    points: &mut Vec<Point<3>>,
    loops: &[Vec<usize>],
    plane: &Plane,
    h: f64,
) -> std::result::Result<Vec<[usize; 3]>, String> {
    let n = plane.normal;
    let u = normalize(if n[0].abs() < 0.9 {
        cross(n, [1.0, 0.0, 0.0])
    } else {
        cross(n, [0.0, 1.0, 0.0])
    });
    let v = cross(n, u);
    let uv = |p: Point<3>| [dot(sub(p, plane.point), u), dot(sub(p, plane.point), v)];
    let rings: Vec<Vec<[f64; 2]>> = loops
        .iter()
        .map(|l| l.iter().map(|&i| uv(points[i])).collect())
        .collect();
    let bad = |e: spade::InsertionError| format!("the section cannot be triangulated ({e:?})");
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let mut global: HashMap<usize, usize> = HashMap::new();
    let mut handles = Vec::new();
    for (l, ring) in loops.iter().zip(&rings) {
        let hs: Vec<_> = ring
            .iter()
            .map(|q| cdt.insert(Point2::new(q[0], q[1])))
            .collect::<std::result::Result<_, _>>()
            .map_err(bad)?;
        for (&hd, &i) in hs.iter().zip(l) {
            if global.insert(hd.index(), i).is_some() {
                return Err("the section touches itself: move the cut plane".into());
            }
        }
        handles.push(hs);
    }
    for hs in &handles {
        for k in 0..hs.len() {
            let (a, b) = (hs[k], hs[(k + 1) % hs.len()]);
            if cdt.try_add_constraint(a, b).len() != 1 {
                return Err("the section crosses itself: move the cut plane".into());
            }
        }
    }
    // Interior points on a grid of the edge length, kept half an edge from the section.
    let (lo, hi) = rings
        .iter()
        .flatten()
        .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), q| {
            (
                [lo[0].min(q[0]), lo[1].min(q[1])],
                [hi[0].max(q[0]), hi[1].max(q[1])],
            )
        });
    let steps = |k: usize| ((hi[k] - lo[k]) / h).floor() as usize;
    if (steps(0) + 1).saturating_mul(steps(1) + 1) > 4_000_000 {
        return Err("the section is too large for its edge length".into());
    }
    for iy in 1..steps(1).max(1) {
        for ix in 1..steps(0).max(1) {
            let q = [lo[0] + ix as f64 * h, lo[1] + iy as f64 * h];
            if inside(&rings, q) && distance_to_rings(&rings, q) > 0.5 * h {
                let hd = cdt.insert(Point2::new(q[0], q[1])).map_err(bad)?;
                points.push(add(plane.point, add(scale(u, q[0]), scale(v, q[1]))));
                global.insert(hd.index(), points.len() - 1);
            }
        }
    }
    // Inside: the faces reached from the outside across an odd number of the section's
    // edges (a breadth-first walk that crosses those edges last, so that each face is reached
    // first across the fewest).
    let mut crossings = HashMap::new();
    let mut todo = std::collections::VecDeque::new();
    for e in cdt.convex_hull() {
        let e = e.rev();
        if e.is_constraint_edge() {
            todo.push_back((e, 1usize));
        } else {
            todo.push_front((e, 0));
        }
    }
    while let Some((e, d)) = todo.pop_front() {
        let Some(f) = e.face().as_inner() else {
            continue;
        };
        if crossings.contains_key(&f.fix()) {
            continue;
        }
        crossings.insert(f.fix(), d);
        for next in [e.prev().rev(), e.next().rev()] {
            if next.is_constraint_edge() {
                todo.push_back((next, d + 1));
            } else {
                todo.push_front((next, d));
            }
        }
    }
    let mut tris = Vec::new();
    for f in cdt.inner_faces() {
        if crossings.get(&f.fix()).is_none_or(|d| d % 2 == 0) {
            continue;
        }
        let vs = f.vertices();
        let mut t = vs.map(|v| global[&v.fix().index()]);
        let [a, b, cc] = t.map(|i| points[i]);
        if dot(cross(sub(b, a), sub(cc, a)), n) < 0.0 {
            t.swap(1, 2);
        }
        tris.push(t);
    }
    Ok(tris)
}

/// Whether `q` lies inside the rings (even-odd rule: holes are holes).
fn inside(rings: &[Vec<[f64; 2]>], q: [f64; 2]) -> bool {
    let mut odd = false;
    for r in rings {
        for k in 0..r.len() {
            let (a, b) = (r[k], r[(k + 1) % r.len()]);
            if (a[1] > q[1]) != (b[1] > q[1]) {
                let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if x > q[0] {
                    odd = !odd;
                }
            }
        }
    }
    odd
}

/// The distance from `q` to the nearest segment of the rings.
fn distance_to_rings(rings: &[Vec<[f64; 2]>], q: [f64; 2]) -> f64 {
    let mut best = f64::MAX;
    for r in rings {
        for k in 0..r.len() {
            let (a, b) = (r[k], r[(k + 1) % r.len()]);
            let ab = [b[0] - a[0], b[1] - a[1]];
            let len2 = ab[0] * ab[0] + ab[1] * ab[1];
            let t = if len2 > 0.0 {
                (((q[0] - a[0]) * ab[0] + (q[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = [q[0] - a[0] - t * ab[0], q[1] - a[1] - t * ab[1]];
            best = best.min((d[0] * d[0] + d[1] * d[1]).sqrt());
        }
    }
    best
}

/// Drops the points no facet uses, renumbering facets and landmarks (a landmark whose point
/// is no longer used is dropped).
fn compact(
    points: Vec<Point<3>>,
    facets: Vec<[usize; 3]>,
    landmarks: Vec<usize>,
) -> (Vec<Point<3>>, Vec<[usize; 3]>, Vec<usize>) {
    let mut new = vec![usize::MAX; points.len()];
    let mut kept = Vec::new();
    let facets = facets
        .into_iter()
        .map(|f| {
            f.map(|i| {
                if new[i] == usize::MAX {
                    new[i] = kept.len();
                    kept.push(points[i]);
                }
                new[i]
            })
        })
        .collect();
    let landmarks = landmarks
        .into_iter()
        .filter(|&i| new[i] != usize::MAX)
        .map(|i| new[i])
        .collect();
    (kept, facets, landmarks)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{is_closed_surface, signed_volume, uv_sphere};

    fn sphere() -> Shape<3> {
        let (points, facets) = uv_sphere(80, 40, |th, ph| {
            [
                10.0 * th.cos() * ph.cos(),
                10.0 * th.cos() * ph.sin(),
                10.0 * th.sin(),
            ]
        });
        Shape {
            name: "ball".into(),
            points,
            facets,
            landmarks: Vec::new(),
        }
    }

    /// A ring around the z axis (radii `big` and `small`), facing outwards.
    fn torus(n_small: usize, n_big: usize, big: f64, small: f64) -> Shape<3> {
        use std::f64::consts::TAU;
        let mut points = Vec::new();
        for i in 0..n_big {
            let a = TAU * i as f64 / n_big as f64;
            for j in 0..n_small {
                let b = TAU * j as f64 / n_small as f64;
                let r = big + small * b.cos();
                points.push([r * a.cos(), r * a.sin(), small * b.sin()]);
            }
        }
        let at = |i: usize, j: usize| (i % n_big) * n_small + j % n_small;
        let mut facets = Vec::new();
        for i in 0..n_big {
            for j in 0..n_small {
                facets.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                facets.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let mut s = Shape {
            name: "ring".into(),
            points,
            facets,
            landmarks: Vec::new(),
        };
        if signed_volume(&s) < 0.0 {
            for f in &mut s.facets {
                f.swap(1, 2);
            }
        }
        s
    }

    #[test]
    fn a_sphere_cut_through_its_centre_is_a_closed_half_ball() {
        let s = sphere();
        assert!(signed_volume(&s) > 0.0);
        let plane = Plane {
            point: [0.0, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
        };
        let c = cut_by_plane(&s, &plane).unwrap();
        assert!(is_closed_surface(&c.shape));
        let half_ball = 2.0 / 3.0 * std::f64::consts::PI * 1000.0;
        let v = signed_volume(&c.shape);
        assert!(
            (v - half_ball).abs() / half_ball < 0.01,
            "{v} against {half_ball}"
        );
        let disc = std::f64::consts::PI * 100.0;
        assert!((c.cap_area - disc).abs() / disc < 0.01, "{}", c.cap_area);
        assert!((c.removed_share - 0.5).abs() < 0.01, "{}", c.removed_share);
        assert!(c.shape.points.iter().all(|p| p[2] <= 1e-12));
        for f in &c.shape.facets[c.cap_start..] {
            assert!(f.iter().all(|&i| c.shape.points[i][2].abs() < 1e-12));
        }
        // The cap is sampled like the rest: interior points, no long slivers.
        let h = s.median_edge_length();
        let cap = &c.shape.facets[c.cap_start..];
        let longest = cap
            .iter()
            .flat_map(|f| (0..3).map(move |k| (f[k], f[(k + 1) % 3])))
            .map(|(a, b)| super::super::norm(sub(c.shape.points[a], c.shape.points[b])))
            .fold(0.0, f64::max);
        assert!(longest < 3.0 * h, "cap edge {longest} against {h}");
    }

    #[test]
    fn an_oblique_cut_and_a_ring_section_stay_closed() {
        // A torus-like ring (genus 1) cut across its hole: two loops, each a cap of its own.
        let ring = torus(30, 60, 10.0, 3.0);
        let plane = Plane {
            point: [0.0, 0.0, 0.0],
            normal: normalize([0.0, 0.3, 1.0]),
        };
        let c = cut_by_plane(&ring, &plane).unwrap();
        assert!(is_closed_surface(&c.shape));
        let v = signed_volume(&c.shape);
        let torus = 2.0 * std::f64::consts::PI.powi(2) * 10.0 * 9.0;
        assert!(
            (v - 0.5 * torus).abs() / torus < 0.02,
            "{v} against {torus}"
        );
        // Cut along the ring's plane: the section is an annulus (a loop with a hole).
        let flat = Plane {
            point: [0.0, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
        };
        let c = cut_by_plane(&ring, &flat).unwrap();
        assert!(is_closed_surface(&c.shape));
        let annulus = std::f64::consts::PI * (13.0f64.powi(2) - 7.0f64.powi(2));
        assert!(
            (c.cap_area - annulus).abs() / annulus < 0.02,
            "{}",
            c.cap_area
        );
    }

    #[test]
    fn an_open_surface_cut_below_its_opening_comes_out_closed() {
        let s = sphere();
        // Open the sphere at its top (as a bone cut by its image's border).
        let mut open = s.clone();
        open.facets
            .retain(|f| !f.iter().all(|&i| s.points[i][2] > 8.0));
        assert!(!is_closed_surface(&open));
        let plane = Plane {
            point: [0.0, 0.0, 5.0],
            normal: [0.0, 0.0, 1.0],
        };
        let c = cut_by_plane(&open, &plane).unwrap();
        assert!(is_closed_surface(&c.shape));
        // Above the opening's lowest point the cut cannot close it.
        let high = Plane {
            point: [0.0, 0.0, 9.5],
            normal: [0.0, 0.0, 1.0],
        };
        let e = cut_by_plane(&open, &high).unwrap_err().to_string();
        assert!(e.contains("ball") && e.contains("open"), "{e}");
    }

    #[test]
    fn a_plane_that_misses_the_shape_is_refused() {
        let s = sphere();
        for (z, what) in [(20.0, "misses"), (-20.0, "nothing")] {
            let plane = Plane {
                point: [0.0, 0.0, z],
                normal: [0.0, 0.0, 1.0],
            };
            let e = cut_by_plane(&s, &plane).unwrap_err().to_string();
            assert!(e.contains(what), "{e}");
        }
        let nan = Plane {
            point: [0.0; 3],
            normal: [f64::NAN, 0.0, 0.0],
        };
        assert!(cut_by_plane(&s, &nan).is_err());
    }
}

//! A population put on a common cut: every shape cut by a plane at the same length from its
//! far end and closed by a flat cap, so that bones the field of view cut at different heights
//! (knee MR: the femoral and tibial shafts) make one atlas of closed shapes.
//!
//! The cut of each shape is along a direction `d` (world frame, RAS for label maps): the plane
//! normal to `d` at `length` from the shape's point farthest against `d`. `auto` takes `d` from
//! where each shape is open (the normal of its opening's best-fit plane, pointing from the
//! shape to the opening: the border the image cut it at) and the length from the shortest
//! shape, less a margin of two edges (the smoothing of a label surface bends it within a voxel
//! or two of the border), so that every opening lies beyond the plane.

use crate::error::{Error, Result};
use crate::geometry::{
    Plane, Point, Shape, centroid, cut_by_plane, dot, median_edge_length, norm, normalize,
    principal_axes_of, sub,
};
use crate::report::{CutReport, InputReport};
use rayon::prelude::*;
use std::collections::HashMap;

/// How the shapes of a population are cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CutSpec {
    /// Along the direction each shape is open in, at the length the shortest reaches.
    Auto,
    /// Along `direction` (unit, world), `length` (the shapes' unit) from the far end.
    Along {
        /// Unit direction towards the removed side.
        direction: Point<3>,
        /// Length kept from each shape's far end.
        length: f64,
    },
}

impl std::str::FromStr for CutSpec {
    type Err = Error;

    /// `auto`, or `AXIS:LENGTH` with AXIS one of R, L, A, P, S, I (the world's axes, RAS: the
    /// side removed) and LENGTH in the shapes' unit: `S:60` keeps 60 mm from each shape's most
    /// inferior point.
    fn from_str(s: &str) -> Result<Self> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(CutSpec::Auto);
        }
        let bad = || {
            Error::Parameter(format!(
                "--cut {s:?}: expected `auto` or AXIS:LENGTH (AXIS one of R, L, A, P, S, I: the side removed; LENGTH kept from the far end, in the shapes' unit, e.g. S:60)"
            ))
        };
        let (axis, length) = s.split_once(':').ok_or_else(bad)?;
        let direction = match axis.trim().to_ascii_uppercase().as_str() {
            "R" => [1.0, 0.0, 0.0],
            "L" => [-1.0, 0.0, 0.0],
            "A" => [0.0, 1.0, 0.0],
            "P" => [0.0, -1.0, 0.0],
            "S" => [0.0, 0.0, 1.0],
            "I" => [0.0, 0.0, -1.0],
            _ => return Err(bad()),
        };
        let length: f64 = length.trim().parse().map_err(|_| bad())?;
        if !(length.is_finite() && length > 0.0) {
            return Err(bad());
        }
        Ok(CutSpec::Along { direction, length })
    }
}

/// Whether a surface is open (has an edge on one facet only).
pub fn is_open(shape: &Shape<3>) -> bool {
    !opening(shape).is_empty()
}

/// Whether a surface is open where a plane cut it (as an image's border cuts a bone): its
/// opening's points lie within a tenth of the opening's width of their best-fit plane, and the
/// opening is more than three edges wide. A hole of a few facets, or openings at both ends, are
/// not such a cut: those surfaces stay open (and the automatic mesher refuses them).
pub fn is_cut_by_a_plane(shape: &Shape<3>) -> bool {
    let rim: Vec<Point<3>> = opening(shape)
        .into_iter()
        .map(|i| shape.points[i])
        .collect();
    if rim.len() < 3 {
        return false;
    }
    let rc = centroid(&rim);
    let n = principal_axes_of(&rim)[2];
    let width = rim.iter().map(|&p| norm(sub(p, rc))).fold(0.0, f64::max);
    let off = rim
        .iter()
        .map(|&p| dot(sub(p, rc), n).abs())
        .fold(0.0, f64::max);
    let edge = median_edge_length(&shape.points, &shape.facets);
    off <= 0.1 * width && width > 3.0 * edge
}

/// The points on the surface's openings (edges on one facet only).
fn opening(shape: &Shape<3>) -> Vec<usize> {
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    for f in &shape.facets {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut pts: Vec<usize> = edges
        .into_iter()
        .filter(|&(_, c)| c == 1)
        .flat_map(|((a, b), _)| [a, b])
        .collect();
    pts.sort_unstable();
    pts.dedup();
    pts
}

/// The direction from `shape` to its opening (the normal of the opening's best-fit plane,
/// turned away from the shape's centroid), and the length from the far end to the opening's
/// nearest point along it.
fn open_direction(shape: &Shape<3>) -> Result<(Point<3>, f64)> {
    let rim: Vec<Point<3>> = opening(shape)
        .into_iter()
        .map(|i| shape.points[i])
        .collect();
    if rim.len() < 3 {
        return Err(Error::Population(format!(
            "{}: --cut auto cuts a shape where it is open (where its image's border cut it), and this one is closed: give the cut as --cut AXIS:LENGTH (e.g. S:60)",
            shape.name
        )));
    }
    if !is_cut_by_a_plane(shape) {
        return Err(Error::Population(format!(
            "{}: --cut auto cuts a shape where a plane cut it (its image's border), and this one is open elsewhere (a hole, or openings on several sides): close the surface, give the cut as --cut AXIS:LENGTH, or bring a --template-mesh",
            shape.name
        )));
    }
    let rc = centroid(&rim);
    let mut d = principal_axes_of(&rim)[2];
    if dot(d, sub(rc, centroid(&used_points(shape)))) < 0.0 {
        d = d.map(|x| -x);
    }
    let far = far_end(shape, d);
    let reach = rim
        .iter()
        .map(|&p| dot(p, d) - far)
        .fold(f64::INFINITY, f64::min);
    Ok((d, reach))
}

/// The points of the shape's facets.
fn used_points(shape: &Shape<3>) -> Vec<Point<3>> {
    let mut used = vec![false; shape.points.len()];
    for f in &shape.facets {
        for &i in f {
            used[i] = true;
        }
    }
    shape
        .points
        .iter()
        .zip(used)
        .filter_map(|(&p, u)| u.then_some(p))
        .collect()
}

/// The smallest projection of the shape's facets' points on `d`.
fn far_end(shape: &Shape<3>, d: Point<3>) -> f64 {
    used_points(shape)
        .iter()
        .map(|&p| dot(p, d))
        .fold(f64::INFINITY, f64::min)
}

/// Cuts every shape of `shapes` by `spec` (see the module doc), each closed by its cap; what
/// was cut goes into `inputs` (the same order), with a note among its warnings. Returns the
/// length kept.
///
/// # Errors
/// [`Error::Population`] naming the shape a cut cannot close (open on the kept side, closed
/// under `auto`, shorter than the length asked) or when `auto` finds no common length.
pub fn cut_population(
    shapes: &mut [Shape<3>],
    inputs: &mut [InputReport],
    spec: &CutSpec,
) -> Result<f64> {
    let (directions, length): (Vec<Point<3>>, f64) = match *spec {
        CutSpec::Along { direction, length } => (vec![normalize(direction); shapes.len()], length),
        CutSpec::Auto => {
            let found: Vec<(Point<3>, f64)> = shapes
                .par_iter()
                .map(open_direction)
                .collect::<Result<_>>()?;
            let margin = shapes
                .iter()
                .map(|s| 2.0 * median_edge_length(&s.points, &s.facets))
                .fold(0.0, f64::max);
            let shortest = found.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
            let length = shortest - margin;
            if length.is_nan() || length <= 0.25 * shortest {
                return Err(Error::Population(format!(
                    "--cut auto: the shapes reach {shortest:.4} along their cut direction, too short to cut at a common length; give the cut as --cut AXIS:LENGTH"
                )));
            }
            (found.into_iter().map(|f| f.0).collect(), length)
        }
    };
    let cuts: Vec<_> = shapes
        .par_iter()
        .zip(&directions)
        .map(|(s, &d)| {
            let far = far_end(s, d);
            let plane = Plane {
                point: d.map(|x| x * (far + length)),
                normal: d,
            };
            cut_by_plane(s, &plane).map(|c| (c, plane))
        })
        .collect::<Result<_>>()?;
    for ((s, input), (c, plane)) in shapes.iter_mut().zip(inputs.iter_mut()).zip(cuts) {
        if c.shape.landmarks.len() != s.landmarks.len() {
            return Err(Error::Population(format!(
                "{}: {} of its landmarks lie beyond the cut; cut farther from the far end (a longer --cut AXIS:LENGTH) or leave those landmarks out",
                s.name,
                s.landmarks.len() - c.shape.landmarks.len()
            )));
        }
        input.warnings.push(format!(
            "cut {length:.4} from its far end along ({:.3}, {:.3}, {:.3}): {:.1} % of its surface removed, the cut closed by a flat cap",
            plane.normal[0],
            plane.normal[1],
            plane.normal[2],
            100.0 * c.removed_share
        ));
        input.cut = Some(CutReport {
            point: plane.point.to_vec(),
            normal: plane.normal.to_vec(),
            length,
            removed_share: c.removed_share,
            cap_area: c.cap_area,
        });
        input.vertices = c.shape.points.len();
        *s = c.shape;
    }
    Ok(length)
}

/// The facets of a population in correspondence (one facet list; `inputs` in the same order)
/// on the cut of at least half of the shapes that were cut: all their points within half an
/// edge of the shape's cut plane. Empty when no shape was cut.
pub fn cut_facets<const D: usize>(shapes: &[Shape<D>], inputs: &[InputReport]) -> Vec<usize> {
    let Some(first) = shapes.first() else {
        return Vec::new();
    };
    let mut votes = vec![0usize; first.facets.len()];
    let mut cut = 0;
    for (s, i) in shapes.iter().zip(inputs) {
        let Some(c) = &i.cut else { continue };
        if c.point.len() != D || c.normal.len() != D || s.facets.len() != votes.len() {
            continue;
        }
        cut += 1;
        let tol = 0.5 * median_edge_length(&s.points, &s.facets);
        let off = |p: &Point<D>| {
            (0..D)
                .map(|d| (p[d] - c.point[d]) * c.normal[d])
                .sum::<f64>()
                .abs()
        };
        for (v, f) in votes.iter_mut().zip(&s.facets) {
            if f.iter().all(|&k| off(&s.points[k]) < tol) {
                *v += 1;
            }
        }
    }
    (0..votes.len())
        .filter(|&f| cut > 0 && 2 * votes[f] >= cut)
        .collect()
}

/// The plane of the cap of a fitted `instance` (subject frame) of an atlas built on a common
/// cut (the least-squares plane of the points of `cut_facets` of `facets`), its normal towards
/// the side the atlas does not have. `None` for an atlas without a cut; 3D only.
pub(crate) fn cut_plane_of<const D: usize>(
    instance: &[Point<D>],
    facets: &[[usize; D]],
    cut_facets: &[usize],
) -> Option<Plane> {
    if D != 3 {
        return None;
    }
    let (_, point, normal) = crate::geometry::cap_plane(instance, facets, cut_facets)?;
    let (point, normal) = (
        crate::geometry::in_3d(&point),
        crate::geometry::in_3d(&normal),
    );
    Some(Plane { point, normal })
}

/// `subject` cut where the fitted `instance` (subject frame) of an atlas built on a common
/// cut has its cap ([`cut_plane_of`]), closed by a flat cap: the part it shares with the
/// atlas, against which the delivered mesh is measured. `None` when the atlas has no cut, or
/// the subject does not reach beyond the plane or cannot be closed there (a subject cut below
/// the atlas's cut stays a part); 3D only. Returns the trimmed subject and the share of its
/// surface removed.
pub(crate) fn trimmed_to_cut<const D: usize>(
    instance: &[Point<D>],
    facets: &[[usize; D]],
    cut_facets: &[usize],
    subject: &Shape<D>,
) -> Option<(Shape<D>, f64)> {
    let plane = cut_plane_of(instance, facets, cut_facets)?;
    let cut = cut_by_plane(&subject.clone().into_dim::<3>(), &plane).ok()?;
    Some((cut.shape.into_dim::<D>(), cut.removed_share))
}

/// The share of the area of `instance`'s surface (`facets`, the cap's `cut_facets` left out)
/// whose facets have every point `partnered` on the subject.
pub(crate) fn covered_share<const D: usize>(
    instance: &[Point<D>],
    facets: &[[usize; D]],
    cut_facets: &[usize],
    partnered: &[bool],
) -> f64 {
    let mut on_cap = vec![false; facets.len()];
    for &f in cut_facets {
        if let Some(c) = on_cap.get_mut(f) {
            *c = true;
        }
    }
    let (mut all, mut covered) = (0.0, 0.0);
    for (f, _) in facets.iter().zip(&on_cap).filter(|(_, c)| !**c) {
        let p: Vec<Point<3>> = f
            .iter()
            .map(|&i| crate::geometry::in_3d(&instance[i]))
            .collect();
        let area = if D == 3 {
            0.5 * norm(crate::geometry::cross(sub(p[1], p[0]), sub(p[2], p[0])))
        } else {
            norm(sub(p[1], p[0]))
        };
        all += area;
        if f.iter()
            .all(|&i| partnered.get(i).copied().unwrap_or(false))
        {
            covered += area;
        }
    }
    if all > 0.0 { covered / all } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{is_closed_surface, uv_sphere};

    /// A long bone along z (an ellipsoid of radii 5, 5, 20), open above `open_at`.
    fn bone(name: &str, open_at: f64, shift: [f64; 3]) -> Shape<3> {
        let (points, facets) = uv_sphere(40, 60, |th, ph| {
            [
                5.0 * th.cos() * ph.cos() + shift[0],
                5.0 * th.cos() * ph.sin() + shift[1],
                20.0 * th.sin() + shift[2],
            ]
        });
        let facets = facets
            .into_iter()
            .filter(|f| !f.iter().all(|&i| points[i][2] - shift[2] > open_at))
            .collect();
        Shape {
            name: name.into(),
            points,
            facets,
            landmarks: Vec::new(),
        }
    }

    #[test]
    fn auto_cuts_every_shape_at_the_shortest_length_along_its_opening() {
        let mut shapes = vec![
            bone("a", 0.0, [0.0; 3]),
            bone("b", 5.0, [3.0, -2.0, 7.0]),
            bone("c", -5.0, [-1.0, 0.0, -4.0]),
        ];
        assert!(shapes.iter().all(is_cut_by_a_plane));
        let mut inputs = vec![InputReport::default(); 3];
        let length = cut_population(&mut shapes, &mut inputs, &CutSpec::Auto).unwrap();
        // The shortest reaches its opening just above 15 from its far end (z = -20): the cut a
        // margin of two edges below.
        assert!(length > 12.0 && length < 15.0, "{length}");
        for (s, i) in shapes.iter().zip(&inputs) {
            assert!(is_closed_surface(s), "{}", s.name);
            let c = i.cut.as_ref().unwrap();
            assert!((c.normal[2] - 1.0).abs() < 1e-6, "{:?}", c.normal);
            let lo = s.points.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
            let hi = s
                .points
                .iter()
                .map(|p| p[2])
                .fold(f64::NEG_INFINITY, f64::max);
            assert!((hi - lo - length).abs() < 1e-9, "{}: {}", s.name, hi - lo);
            assert!(i.warnings.iter().any(|w| w.contains("cut")));
        }
    }

    #[test]
    fn a_cut_along_an_axis_and_its_refusals() {
        let spec: CutSpec = "s:12.5".parse().unwrap();
        assert_eq!(
            spec,
            CutSpec::Along {
                direction: [0.0, 0.0, 1.0],
                length: 12.5
            }
        );
        for bad in ["", "S", "X:3", "S:-1", "S:nan", "S:inf"] {
            assert!(bad.parse::<CutSpec>().is_err(), "{bad}");
        }
        // Cut above the opening: the hole stays, refused naming the shape.
        let mut shapes = vec![bone("tall", 0.0, [0.0; 3])];
        let mut inputs = vec![InputReport::default()];
        let high: CutSpec = "S:28".parse().unwrap();
        let e = cut_population(&mut shapes, &mut inputs, &high).unwrap_err();
        assert!(e.to_string().contains("tall"), "{e}");
        // A closed shape under auto: refused with what to give instead.
        let (points, facets) = uv_sphere(20, 10, |th, ph| {
            [th.cos() * ph.cos(), th.cos() * ph.sin(), th.sin()]
        });
        let mut closed = vec![Shape {
            name: "round".into(),
            points,
            facets,
            landmarks: Vec::new(),
        }];
        let e = cut_population(&mut closed, &mut inputs, &CutSpec::Auto).unwrap_err();
        assert!(e.to_string().contains("round") && e.to_string().contains("AXIS:LENGTH"));
        // A hole of a few facets is open, but not where a plane cut it: auto refuses it.
        let mut holed = closed.clone();
        holed[0].name = "holed".into();
        holed[0].facets.retain(|f| !f.contains(&25));
        assert!(is_open(&holed[0]) && !is_cut_by_a_plane(&holed[0]));
        assert!(!is_cut_by_a_plane(&closed[0]));
        let e = cut_population(&mut holed, &mut inputs, &CutSpec::Auto).unwrap_err();
        assert!(
            e.to_string().contains("holed") && e.to_string().contains("hole"),
            "{e}"
        );
    }
}

//! Element quality by the Jacobians at element corners (section 5.3): for bilinear and
//! trilinear elements the Jacobian determinant is bounded by its corner values, so an element
//! is valid when all its corner Jacobians are positive.

use super::FeMesh;
use crate::geometry::{Point, dist2, dot, sub};

/// Corner measures of one element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementQuality {
    /// Smallest corner Jacobian determinant (area/volume units: length^D).
    pub jacobian_min: f64,
    /// Smallest scaled Jacobian: the determinant divided by the product of the corner's edge
    /// lengths, in [-1, 1]; 1 for a square or cube corner.
    pub scaled_jacobian_min: f64,
}

fn det<const D: usize>(v: &[Point<D>; D]) -> f64 {
    match D {
        2 => v[0][0] * v[1][1] - v[0][1] * v[1][0],
        3 => {
            v[0][0] * (v[1][1] * v[2][2] - v[1][2] * v[2][1])
                - v[0][1] * (v[1][0] * v[2][2] - v[1][2] * v[2][0])
                + v[0][2] * (v[1][0] * v[2][1] - v[1][1] * v[2][0])
        }
        _ => unreachable!(),
    }
}

/// Corner Jacobians of element `e`.
pub fn element_quality<const D: usize>(mesh: &FeMesh<D>, e: usize) -> ElementQuality {
    element_quality_at(mesh.kind, mesh.element(e), &mesh.nodes)
}

/// Edge ratio of an element: its longest edge over its shortest (1 for a square, a cube or
/// an equilateral simplex; unbounded for a collapsed edge). The scaled Jacobian does not see
/// a flat element whose corners stay square (a hexahedron of vanishing thickness); this
/// does. Edges are those of [`super::ElementKind::corner_frames`].
pub fn edge_ratio<const D: usize>(
    kind: super::ElementKind,
    el: &[usize],
    nodes: &[Point<D>],
) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
    // Every edge is in the frames of both its corners: taken once, from its lower one.
    for (c, frame) in kind.corner_frames().iter().enumerate() {
        for &o in frame.iter().filter(|&&o| o > c) {
            let l = crate::geometry::dist2(nodes[el[c]], nodes[el[o]]);
            lo = lo.min(l);
            hi = hi.max(l);
        }
    }
    if lo > 0.0 {
        (hi / lo).sqrt()
    } else {
        f64::INFINITY
    }
}

/// The largest [`edge_ratio`] of a mesh's elements.
pub fn edge_ratio_max<const D: usize>(mesh: &FeMesh<D>) -> f64 {
    (0..mesh.num_elements())
        .map(|e| edge_ratio(mesh.kind, mesh.element(e), &mesh.nodes))
        .fold(1.0, f64::max)
}

/// Corner Jacobians of an element given by its node indices into `nodes`.
pub fn element_quality_at<const D: usize>(
    kind: super::ElementKind,
    el: &[usize],
    nodes: &[Point<D>],
) -> ElementQuality {
    let mut jmin = f64::INFINITY;
    let mut smin = f64::INFINITY;
    for_each_corner(kind, el, nodes, |j, sj| {
        jmin = jmin.min(j);
        smin = smin.min(sj);
    });
    ElementQuality {
        jacobian_min: jmin,
        scaled_jacobian_min: smin,
    }
}

/// Calls `f(jacobian, scaled_jacobian)` for every corner of an element.
#[inline]
pub fn for_each_corner<const D: usize>(
    kind: super::ElementKind,
    el: &[usize],
    nodes: &[Point<D>],
    mut f: impl FnMut(f64, f64),
) {
    for c in 0..kind.corner_frames().len() {
        let (j, sj) = corner(kind, el, nodes, c);
        f(j, sj);
    }
}

/// The Jacobian and scaled Jacobian at corner `c` of an element.
#[inline]
pub fn corner<const D: usize>(
    kind: super::ElementKind,
    el: &[usize],
    nodes: &[Point<D>],
    c: usize,
) -> (f64, f64) {
    let (j, sj, _) = corner_with_edges(kind, el, nodes, c);
    (j, sj)
}

/// [`corner`] and the sum of the squared lengths of the corner's edges (the chords from the
/// corner node to its frame's corner nodes), which the repair's mean ratio needs: taken from
/// the same edge vectors for linear elements.
#[inline]
pub fn corner_with_edges<const D: usize>(
    kind: super::ElementKind,
    el: &[usize],
    nodes: &[Point<D>],
    c: usize,
) -> (f64, f64, f64) {
    let frame = kind.corner_frames()[c];
    let x = nodes[el[c]];
    // (A quadratic element's edges are its chords, not the tangents of its frame.)
    let (v, chords): ([Point<D>; D], Option<f64>) = match kind {
        super::ElementKind::Hex20 | super::ElementKind::Tet10 => {
            let chords = frame.iter().map(|&m| dist2(nodes[el[m]], x)).sum();
            (quadratic_frame(kind, el, nodes, c), Some(chords))
        }
        _ => (std::array::from_fn(|k| sub(nodes[el[frame[k]]], x)), None),
    };
    // Each edge vector's squared length once: its norm and, for a linear element, the edges.
    let squared: [f64; D] = std::array::from_fn(|k| dot(v[k], v[k]));
    let edges = chords.unwrap_or_else(|| squared.iter().sum());
    let j = det(&v);
    let l: f64 = squared.iter().map(|s| s.sqrt()).product();
    let sj = if l > 0.0 {
        (j / l * kind.scaled_jacobian_factor()).min(1.0)
    } else {
        -1.0
    };
    (j, sj, edges)
}

/// The edge vectors at corner `c` of a quadratic element: the tangent at the corner of the
/// quadratic edge through the corner x, the mid-edge node m and the other corner y, per unit
/// of the edge parameter: 4 m - 3 x - y (y - x when m is the midpoint). Out of line: the
/// linear kinds' corners are the hot path.
#[cold]
#[inline(never)]
fn quadratic_frame<const D: usize>(
    kind: super::ElementKind,
    el: &[usize],
    nodes: &[Point<D>],
    c: usize,
) -> [Point<D>; D] {
    let frame = kind.corner_frames()[c];
    let x = nodes[el[c]];
    std::array::from_fn(|k| {
        let y = nodes[el[frame[k]]];
        match kind.mid_node(c, frame[k]) {
            Some(m) => {
                let m = nodes[el[m]];
                std::array::from_fn(|d| 4.0 * m[d] - 3.0 * x[d] - y[d])
            }
            None => sub(y, x),
        }
    })
}

/// Per-element corner measures of a whole mesh.
pub fn mesh_quality<const D: usize>(mesh: &FeMesh<D>) -> Vec<ElementQuality> {
    (0..mesh.num_elements())
        .map(|e| element_quality(mesh, e))
        .collect()
}

/// Summary of a mesh's quality.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct QualitySummary {
    /// Smallest corner Jacobian (determinant; units of length^D).
    pub jacobian_min: f64,
    /// Smallest scaled Jacobian (1 for a perfect element, ≤ 0 inverted).
    pub scaled_jacobian_min: f64,
    /// Elements with a non-positive corner Jacobian.
    pub inverted_elements: usize,
}

/// Minimum Jacobian, minimum scaled Jacobian and the number of elements with a non-positive
/// corner Jacobian.
pub fn summarize(q: &[ElementQuality]) -> QualitySummary {
    QualitySummary {
        jacobian_min: q
            .iter()
            .map(|e| e.jacobian_min)
            .fold(f64::INFINITY, f64::min),
        scaled_jacobian_min: q
            .iter()
            .map(|e| e.scaled_jacobian_min)
            .fold(f64::INFINITY, f64::min),
        inverted_elements: q.iter().filter(|e| e.jacobian_min <= 0.0).count(),
    }
}

/// Percentiles and acceptance counts of a mesh's element quality.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct QualityDistribution {
    /// Smallest corner Jacobian.
    pub jacobian_min: f64,
    /// 1 % percentile of the elements' smallest corner Jacobians.
    pub jacobian_p01: f64,
    /// 5 % percentile of the elements' smallest corner Jacobians.
    pub jacobian_p05: f64,
    /// Smallest scaled Jacobian.
    pub scaled_jacobian_min: f64,
    /// 1 % percentile of the elements' smallest scaled Jacobians.
    pub scaled_jacobian_p01: f64,
    /// 5 % percentile of the elements' smallest scaled Jacobians.
    pub scaled_jacobian_p05: f64,
    /// The bound used ([`super::ElementKind::scaled_jacobian_bound`]).
    pub bound: f64,
    /// Elements whose smallest scaled Jacobian is below `bound`.
    pub elements_below_bound: usize,
    /// Elements with a non-positive corner Jacobian.
    pub inverted_elements: usize,
    /// Elements in the mesh.
    pub elements: usize,
    /// The largest [`edge_ratio`].
    pub edge_ratio_max: f64,
}

/// The `p`-quantile (nearest rank) of sorted values.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let k = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[k - 1]
}

/// Min, 1 % and 5 % percentiles of the corner Jacobians and scaled Jacobians, the counts of
/// elements below the acceptance bound of `mesh`'s kind and inverted, and the largest edge
/// ratio; `q` is the element quality of `mesh`.
pub fn distribution<const D: usize>(mesh: &FeMesh<D>, q: &[ElementQuality]) -> QualityDistribution {
    let kind = mesh.kind;
    let mut j: Vec<f64> = q.iter().map(|e| e.jacobian_min).collect();
    let mut s: Vec<f64> = q.iter().map(|e| e.scaled_jacobian_min).collect();
    j.sort_by(f64::total_cmp);
    s.sort_by(f64::total_cmp);
    let bound = kind.scaled_jacobian_bound();
    QualityDistribution {
        jacobian_min: quantile(&j, 0.0),
        jacobian_p01: quantile(&j, 0.01),
        jacobian_p05: quantile(&j, 0.05),
        scaled_jacobian_min: quantile(&s, 0.0),
        scaled_jacobian_p01: quantile(&s, 0.01),
        scaled_jacobian_p05: quantile(&s, 0.05),
        bound,
        elements_below_bound: s.iter().filter(|v| **v < bound).count(),
        inverted_elements: j.iter().filter(|v| **v <= 0.0).count(),
        elements: q.len(),
        edge_ratio_max: edge_ratio_max(mesh),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ElementKind;

    #[test]
    fn straight_quadratic_elements_measure_as_linear_ones_and_a_bent_edge_inverts() {
        let cube = FeMesh::<3>::block(1);
        let mut hex20 = cube.to_quadratic().unwrap();
        let q = element_quality(&hex20, 0);
        assert!((q.scaled_jacobian_min - 1.0).abs() < 1e-12, "{q:?}");
        assert!((q.jacobian_min - 1.0).abs() < 1e-12, "{q:?}");
        // The mid-edge node of edge 0-1 pulled back past corner 0: the edge's tangent at
        // corner 0 points backwards.
        let m = hex20.connectivity[ElementKind::Hex20.mid_node(0, 1).unwrap()];
        hex20.nodes[m] = [-0.2, 0.0, 0.0];
        assert!(element_quality(&hex20, 0).jacobian_min < 0.0);
        let tet = FeMesh::<3> {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            kind: ElementKind::Tet4,
            connectivity: vec![0, 1, 2, 3],
            sets: Default::default(),
        };
        let linear = element_quality(&tet, 0);
        let tet10 = tet.to_quadratic().unwrap();
        let quadratic = element_quality(&tet10, 0);
        assert!((linear.scaled_jacobian_min - quadratic.scaled_jacobian_min).abs() < 1e-12);
        assert!((linear.jacobian_min - quadratic.jacobian_min).abs() < 1e-12);
    }

    #[test]
    fn unit_square_has_scaled_jacobian_one() {
        let m = FeMesh::<2> {
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            kind: ElementKind::Quad4,
            connectivity: vec![0, 1, 2, 3],
            sets: Default::default(),
        };
        let q = element_quality(&m, 0);
        assert!((q.scaled_jacobian_min - 1.0).abs() < 1e-15);
        assert!((q.jacobian_min - 1.0).abs() < 1e-15);
    }

    #[test]
    fn unit_cube_has_scaled_jacobian_one_and_a_flipped_one_is_inverted() {
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let m = FeMesh::<3> {
            nodes,
            kind: ElementKind::Hex8,
            connectivity: (0..8).collect(),
            sets: Default::default(),
        };
        assert!((element_quality(&m, 0).scaled_jacobian_min - 1.0).abs() < 1e-15);
        let flipped = FeMesh {
            connectivity: vec![4, 5, 6, 7, 0, 1, 2, 3],
            ..m
        };
        assert!(element_quality(&flipped, 0).jacobian_min < 0.0);
    }

    #[test]
    fn regular_simplices_have_scaled_jacobian_one() {
        let h = 3f64.sqrt() / 2.0;
        let tri = FeMesh::<2> {
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [0.5, h]],
            kind: super::super::ElementKind::Tri3,
            connectivity: vec![0, 1, 2],
            sets: Default::default(),
        };
        let q = element_quality(&tri, 0);
        assert!((q.scaled_jacobian_min - 1.0).abs() < 1e-12, "{q:?}");
        let c = 1.0 / 3f64.sqrt();
        let tet = FeMesh::<3> {
            nodes: vec![[c, c, c], [c, -c, -c], [-c, c, -c], [-c, -c, c]],
            kind: super::super::ElementKind::Tet4,
            connectivity: vec![0, 2, 1, 3],
            sets: Default::default(),
        };
        let q = element_quality(&tet, 0);
        assert!(q.jacobian_min > 0.0, "{q:?}");
        assert!((q.scaled_jacobian_min - 1.0).abs() < 1e-12, "{q:?}");
        let flipped = FeMesh::<3> {
            connectivity: vec![0, 1, 2, 3],
            ..tet
        };
        assert!(element_quality(&flipped, 0).jacobian_min < 0.0);
    }

    #[test]
    fn a_clockwise_quad_is_inverted() {
        let m = FeMesh::<2> {
            nodes: vec![[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]],
            kind: ElementKind::Quad4,
            connectivity: vec![0, 1, 2, 3],
            sets: Default::default(),
        };
        let s = summarize(&mesh_quality(&m));
        assert_eq!(s.inverted_elements, 1);
    }
}

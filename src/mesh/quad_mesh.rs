//! Automatic all-quadrilateral mesh of the region bounded by a 2D outline (section 2.4).
//!
//! Method: the outline (an open outline closed by the straight segment between its ends) is
//! resampled at the element size, triangulated by a constrained Delaunay triangulation
//! refined to a minimum angle of 30° (Ruppert-style refinement, `spade`), and every triangle
//! is split into three quadrilaterals through its edge midpoints and centroid. With all
//! triangle angles in [30°, 120°] every quad corner angle lies in [30°, 150°], so the scaled
//! Jacobian is at least sin 30° = 0.5 before smoothing. Interior nodes are then smoothed
//! (Laplacian), a move being kept only where it does not lower the local minimum scaled
//! Jacobian.

use super::quality::{ElementQuality, element_quality_at};
use super::{ElementKind, FeMesh};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, add, norm, scale, sub};
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};
use std::collections::{BTreeSet, HashMap, HashSet};

/// Parameters of the quad mesher.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct QuadMeshParams {
    /// Target quad edge length (shape units).
    pub element_size: f64,
    /// Laplacian smoothing passes.
    pub smoothing_passes: usize,
}

/// The closed boundary polygon of an outline, resampled at spacing about `h`, counter-clockwise.
fn boundary_polygon(outline: &Shape<2>, h: f64) -> Vec<Point<2>> {
    let mut pts = outline.points.clone();
    pts.push(outline.points[0]); // closes an open outline by the straight segment
    let mut cum = vec![0.0];
    for w in pts.windows(2) {
        cum.push(cum.last().copied().unwrap_or(0.0) + norm(sub(w[1], w[0])));
    }
    let total = *cum.last().unwrap_or(&0.0);
    let n = ((total / h).round() as usize).max(8);
    let mut out: Vec<Point<2>> = (0..n)
        .map(|j| {
            let s = total * j as f64 / n as f64;
            let k = (cum.partition_point(|&c| c <= s).max(1) - 1).min(pts.len() - 2);
            let len = cum[k + 1] - cum[k];
            let t = if len > 0.0 { (s - cum[k]) / len } else { 0.0 };
            add(pts[k], scale(sub(pts[k + 1], pts[k]), t))
        })
        .collect();
    let area: f64 = (0..n)
        .map(|i| {
            let (a, b) = (out[i], out[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    if area < 0.0 {
        out.reverse();
    }
    out
}

/// Meshes the region bounded by `outline` with quadrilaterals of edge length about
/// `params.element_size`. Every element has positive Jacobians at its four corners, or an
/// error is returned.
///
/// Errors: a self-intersecting outline, an element size too small for the outline (more than
/// two million elements), or an invalid element after meshing.
pub fn quad_mesh(outline: &Shape<2>, params: &QuadMeshParams) -> Result<FeMesh<2>> {
    outline.validate()?;
    let q = params.element_size;
    if !(q.is_finite() && q > 0.0) {
        return Err(Error::Parameter(format!(
            "element size {q} must be positive"
        )));
    }
    let h = 2.0 * q; // triangle edge; the split halves it
    // The boundary is sampled at the quad size: chords of twice that would cut off tips of
    // narrow features (fingertips).
    let poly = boundary_polygon(outline, q);
    let area = 0.5
        * (0..poly.len())
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum::<f64>();
    let expected = area / (h * h * 0.433);
    if expected > 700_000.0 {
        return Err(Error::Parameter(format!(
            "element size {q} is too small for this outline (about {:.0} elements); choose a larger one",
            3.0 * expected
        )));
    }
    let verts: Vec<Point2<f64>> = poly.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let edges: Vec<[usize; 2]> = (0..poly.len()).map(|i| [i, (i + 1) % poly.len()]).collect();
    let mut conflicts = 0usize;
    let mut cdt =
        ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(verts, edges, |_| {
            conflicts += 1
        })
        .map_err(|e| Error::Mesh(format!("{}: triangulation failed: {e}", outline.name)))?;
    if conflicts > 0 || cdt.num_vertices() != poly.len() {
        return Err(Error::Mesh(format!(
            "{}: the outline intersects itself (or touches itself) at the element size {q}; fix the outline or use a smaller element size",
            outline.name
        )));
    }
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .with_angle_limit(AngleLimit::from_deg(30.0))
            .with_max_allowed_area(h * h * 0.433 * 1.5)
            .with_max_additional_vertices((expected as usize) * 4 + 10_000)
            .exclude_outer_faces(true),
    );
    let excluded: HashSet<usize> = result.excluded_faces.iter().map(|f| f.index()).collect();
    let nodes_tri: Vec<Point<2>> = cdt
        .vertices()
        .map(|v| [v.position().x, v.position().y])
        .collect();
    let tris: Vec<[usize; 3]> = cdt
        .inner_faces()
        .filter(|f| !excluded.contains(&f.fix().index()))
        .map(|f| f.vertices().map(|v| v.fix().index()))
        .collect();
    if tris.is_empty() {
        return Err(Error::Mesh(format!(
            "{}: the outline encloses no area",
            outline.name
        )));
    }
    // Split every triangle into three quads (midpoints shared between neighbours).
    let mut nodes = nodes_tri;
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut midpoint = |a: usize, b: usize, nodes: &mut Vec<Point<2>>| -> usize {
        let key = (a.min(b), a.max(b));
        *mid.entry(key).or_insert_with(|| {
            nodes.push(scale(add(nodes[a], nodes[b]), 0.5));
            nodes.len() - 1
        })
    };
    let mut conn = Vec::with_capacity(tris.len() * 12);
    for t in &tris {
        let [a, b, c] = *t;
        let mab = midpoint(a, b, &mut nodes);
        let mbc = midpoint(b, c, &mut nodes);
        let mca = midpoint(c, a, &mut nodes);
        let g = scale(add(add(nodes[a], nodes[b]), nodes[c]), 1.0 / 3.0);
        nodes.push(g);
        let gi = nodes.len() - 1;
        conn.extend_from_slice(&[a, mab, gi, mca, b, mbc, gi, mab, c, mca, gi, mbc]);
    }
    let mut mesh = FeMesh {
        nodes,
        kind: ElementKind::Quad4,
        connectivity: conn,
        sets: Default::default(),
    };
    // Drop unused nodes (vertices of excluded faces only).
    compact(&mut mesh);
    smooth(&mut mesh, params.smoothing_passes);
    let bad = (0..mesh.num_elements())
        .filter(|&e| {
            element_quality_at(mesh.kind, mesh.element(e), &mesh.nodes).jacobian_min <= 0.0
        })
        .count();
    if bad > 0 {
        return Err(Error::Mesh(format!(
            "{}: {bad} inverted elements after meshing",
            outline.name
        )));
    }
    Ok(mesh)
}

fn compact<const D: usize>(mesh: &mut FeMesh<D>) {
    let mut map = vec![usize::MAX; mesh.nodes.len()];
    let mut nodes = Vec::new();
    for i in mesh.connectivity.iter_mut() {
        if map[*i] == usize::MAX {
            map[*i] = nodes.len();
            nodes.push(mesh.nodes[*i]);
        }
        *i = map[*i];
    }
    mesh.nodes = nodes;
}

/// Nodes on the mesh boundary (on an edge used by one element only).
pub fn boundary_nodes(mesh: &FeMesh<2>) -> Vec<bool> {
    let mut count: HashMap<(usize, usize), u32> = HashMap::new();
    for e in 0..mesh.num_elements() {
        let el = mesh.element(e);
        for k in 0..4 {
            let (a, b) = (el[k], el[(k + 1) % 4]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut on = vec![false; mesh.nodes.len()];
    for ((a, b), c) in count {
        if c == 1 {
            on[a] = true;
            on[b] = true;
        }
    }
    on
}

/// Laplacian smoothing of interior nodes; a move is kept only where it does not lower the
/// smallest scaled Jacobian of the elements around the node.
fn smooth(mesh: &mut FeMesh<2>, passes: usize) {
    let boundary = boundary_nodes(mesh);
    let n = mesh.nodes.len();
    let mut elems_of: Vec<Vec<usize>> = vec![Vec::new(); n];
    // (ordered sets: the sum below adds the neighbours in the same order in every run, so
    // that a mesh is the same to the last bit)
    let mut nbrs: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    for e in 0..mesh.num_elements() {
        let el = mesh.element(e).to_vec();
        for k in 0..4 {
            elems_of[el[k]].push(e);
            nbrs[el[k]].insert(el[(k + 1) % 4]);
            nbrs[el[k]].insert(el[(k + 3) % 4]);
        }
    }
    let local_min = |mesh: &FeMesh<2>, i: usize| -> f64 {
        elems_of[i]
            .iter()
            .map(|&e| {
                let q: ElementQuality = element_quality_at(mesh.kind, mesh.element(e), &mesh.nodes);
                q.scaled_jacobian_min
            })
            .fold(f64::INFINITY, f64::min)
    };
    for _ in 0..passes {
        for i in 0..n {
            if boundary[i] || nbrs[i].is_empty() {
                continue;
            }
            let c = nbrs[i].iter().fold([0.0; 2], |a, &j| add(a, mesh.nodes[j]));
            let target = scale(c, 1.0 / nbrs[i].len() as f64);
            let old = mesh.nodes[i];
            let before = local_min(mesh, i);
            mesh.nodes[i] = target;
            if local_min(mesh, i) < before {
                mesh.nodes[i] = old;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::quality::{mesh_quality, summarize};

    #[test]
    fn disc_mesh_is_valid_with_good_quality() {
        let pts: Vec<Point<2>> = (0..100)
            .map(|i| {
                let t = i as f64 / 100.0 * std::f64::consts::TAU;
                [t.cos(), t.sin()]
            })
            .collect();
        let s = Shape::polyline("disc", pts, true);
        let m = quad_mesh(
            &s,
            &QuadMeshParams {
                element_size: 0.1,
                smoothing_passes: 5,
            },
        )
        .unwrap();
        let q = summarize(&mesh_quality(&m));
        assert_eq!(q.inverted_elements, 0);
        assert!(
            q.scaled_jacobian_min >= 0.3,
            "min scaled Jacobian {}",
            q.scaled_jacobian_min
        );
        // Total area close to pi (the polygon is inscribed).
        let area: f64 = (0..m.num_elements())
            .map(|e| {
                let el = m.element(e);
                0.5 * (0..4)
                    .map(|k| {
                        let (a, b) = (m.nodes[el[k]], m.nodes[el[(k + 1) % 4]]);
                        a[0] * b[1] - a[1] * b[0]
                    })
                    .sum::<f64>()
            })
            .sum();
        assert!((area - std::f64::consts::PI).abs() < 0.03, "area {area}");
    }

    #[test]
    fn self_intersecting_outline_is_an_error() {
        let s = Shape::polyline(
            "bowtie",
            vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]],
            true,
        );
        let e = quad_mesh(
            &s,
            &QuadMeshParams {
                element_size: 0.05,
                smoothing_passes: 2,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("intersects itself"), "{e}");
    }
}

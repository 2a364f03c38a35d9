//! The face where an atlas's population was cut by a common plane (anatomy the field of view
//! cut): the mean mesh's boundary faces on the plane of the mean's cap, their nodes put on
//! that plane exactly, named `CUT` (a node set and a surface: where a user fixes the shaft).
//! The morph carries the set into every subject's mesh and every solver file.
//!
//! Frame: the mean's (the atlas's reference frame); the plane is the least-squares plane of
//! the cap's points.

use super::{FeMesh, MeshSets, boundary_faces, mesh_quality, summarize};
use crate::error::{Error, Result};
use crate::geometry::{Point, cap_plane, centroid, dot, principal_axes_of, scale, sub};

/// The name of the cut's node set and surface.
pub const CUT_SET: &str = "CUT";

/// Boundary faces whose nodes lie within this share of an element of the cap's plane, and
/// whose outward normal is within 45° of the plane's, are on the cut.
const ON_PLANE: f64 = 0.3;

/// The cut face of `mesh` (the mean mesh of the shape `mean` with `facets`, of which
/// `cut_facets` are the cap): its nodes moved onto the cap's plane and named [`CUT_SET`] (node
/// set and surface) in `mesh.sets`. Returns the plane (a point and the unit normal, outwards)
/// and the number of nodes in the set.
///
/// # Errors
/// [`Error::Mesh`] when the cap has too few points, no boundary face lies on its plane, or
/// putting the face's nodes on the plane would invert an element.
pub fn mark_cut_face<const D: usize>(
    mesh: &mut FeMesh<D>,
    mean: &[Point<D>],
    facets: &[[usize; D]],
    cut_facets: &[usize],
) -> Result<(Point<D>, Point<D>, usize)> {
    let Some((_, c, n)) = cap_plane(mean, facets, cut_facets) else {
        return Err(Error::Mesh("the cut has too few points for a face".into()));
    };
    let faces = boundary_faces(mesh);
    let h = typical_edge(mesh, &faces);
    let cos45 = std::f64::consts::FRAC_1_SQRT_2;
    let on: Vec<_> = faces
        .iter()
        .filter(|f| {
            dot(f.normal, n) > cos45
                && f.nodes
                    .iter()
                    .chain(&f.mids)
                    .all(|&v| dot(sub(mesh.nodes[v], c), n).abs() < ON_PLANE * h)
        })
        .collect();
    if on.is_empty() {
        return Err(Error::Mesh(
            "no face of the mean mesh lies on the cut's plane".into(),
        ));
    }
    let mut nodes: Vec<usize> = on
        .iter()
        .flat_map(|f| f.nodes.iter().chain(&f.mids))
        .copied()
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let before = mesh.nodes.clone();
    for &v in &nodes {
        let p = mesh.nodes[v];
        mesh.nodes[v] = sub(p, scale(n, dot(sub(p, c), n)));
    }
    if summarize(&mesh_quality(mesh)).inverted_elements > 0 {
        mesh.nodes = before;
        return Err(Error::Mesh(
            "putting the cut face's nodes on its plane would invert elements".into(),
        ));
    }
    let mut surface: Vec<(usize, u8)> = on.iter().map(|f| (f.element, f.face)).collect();
    surface.sort_unstable();
    let mut sets = MeshSets::default();
    sets.node_sets.insert(CUT_SET.to_string(), nodes.clone());
    sets.surfaces.insert(CUT_SET.to_string(), surface);
    mesh.sets.merge(sets);
    Ok((c, n, nodes.len()))
}

/// A morphed mesh's [`CUT_SET`] put back on one plane (the least-squares plane of its nodes):
/// the morph and the boundary fit move the face's nodes by a little, and a user fixes the
/// shaft on a flat face. Returns the largest move (shape units); `None` when the mesh has no
/// cut, or flattening would invert an element (the nodes stay where they were).
pub fn flatten_cut_face<const D: usize>(mesh: &mut FeMesh<D>) -> Option<f64> {
    let before = mesh.nodes.clone();
    let moved = cut_face_on_its_plane(mesh)?;
    if summarize(&mesh_quality(mesh)).inverted_elements > 0 {
        mesh.nodes = before;
        return None;
    }
    Some(moved)
}

/// [`flatten_cut_face`] whatever it does to the elements (the caller repairs them): the
/// largest move, `None` when the mesh has no cut.
pub(crate) fn cut_face_on_its_plane<const D: usize>(mesh: &mut FeMesh<D>) -> Option<f64> {
    let nodes = mesh.sets.node_sets.get(CUT_SET)?;
    if nodes.len() <= D || nodes.iter().any(|&v| v >= mesh.nodes.len()) {
        return None;
    }
    let pts: Vec<Point<D>> = nodes.iter().map(|&v| mesh.nodes[v]).collect();
    let c = centroid(&pts);
    let n = principal_axes_of(&pts)[D - 1];
    let mut moved: f64 = 0.0;
    for &v in nodes {
        let off = dot(sub(mesh.nodes[v], c), n);
        moved = moved.max(off.abs());
        mesh.nodes[v] = sub(mesh.nodes[v], scale(n, off));
    }
    Some(moved)
}

/// The median distance between consecutive corners of the boundary faces.
fn typical_edge<const D: usize>(mesh: &FeMesh<D>, faces: &[super::BoundaryFace<D>]) -> f64 {
    let mut l: Vec<f64> = faces
        .iter()
        .flat_map(|f| {
            let k = f.nodes.len();
            (0..k).map(move |i| (f.nodes[i], f.nodes[(i + 1) % k]))
        })
        .map(|(a, b)| crate::geometry::norm(sub(mesh.nodes[a], mesh.nodes[b])))
        .collect();
    if l.is_empty() {
        return 0.0;
    }
    let mid = l.len() / 2;
    *l.select_nth_unstable_by(mid, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::HexMesh;

    #[test]
    fn the_cut_face_of_a_block_is_its_top_put_on_the_plane() {
        // A block of 4³ unit hexahedra; its top (z = 4) the cap of a "mean" sampled there.
        let mut mesh = HexMesh::block(4);
        let top: Vec<usize> = (0..mesh.nodes.len())
            .filter(|&v| (mesh.nodes[v][2] - 4.0).abs() < 1e-12)
            .collect();
        // Move the top nodes a little off the plane (as projections onto a mean leave them).
        for (k, &v) in top.iter().enumerate() {
            mesh.nodes[v][2] += if k % 2 == 0 { 0.1 } else { -0.1 };
        }
        let mean = vec![
            [0.0, 0.0, 4.0],
            [4.0, 0.0, 4.0],
            [4.0, 4.0, 4.0],
            [0.0, 4.0, 4.0],
            [2.0, 2.0, 0.0],
        ];
        let facets = vec![
            [0, 1, 2],
            [0, 2, 3],
            [0, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [3, 0, 4],
        ];
        let (c, n, count) = mark_cut_face(&mut mesh, &mean, &facets, &[0, 1]).unwrap();
        assert_eq!(count, 25);
        assert!((n[2] - 1.0).abs() < 1e-12 && (c[2] - 4.0).abs() < 1e-12);
        assert_eq!(mesh.sets.node_sets[CUT_SET], top);
        assert_eq!(mesh.sets.surfaces[CUT_SET].len(), 16);
        assert!(top.iter().all(|&v| (mesh.nodes[v][2] - 4.0).abs() < 1e-12));
        // A cap off the mesh: refused.
        let far: Vec<Point<3>> = mean.iter().map(|p| [p[0], p[1], p[2] + 5.0]).collect();
        let mut other = HexMesh::block(4);
        assert!(mark_cut_face(&mut other, &far, &facets, &[0, 1]).is_err());
    }
}

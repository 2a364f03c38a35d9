//! Two meshes of one model joined by a tie: a smooth mesh (a subject's bone) and the parts
//! of a voxel mesh that load it (pads, implants), their nodes kept apart and tied where they
//! meet, as solvers tie non-matching meshes (CalculiX `*TIE`, Abaqus, FEBio's tied contact).

use super::{FeMesh, boundary_faces, boundary_surface, set_name_problem};
use crate::error::{Error, Result};
use crate::geometry::ClosestPointIndex;

/// What [`join_tied`] made: the joined mesh and the names of its tie's sides.
#[derive(Clone, Debug)]
pub struct TiedMesh {
    /// `mesh`'s nodes and elements, then `parts`'s, renumbered; every set of both.
    pub mesh: FeMesh<3>,
    /// The surface of `mesh`'s boundary faces: the tie's master side (`NAME_SURFACE`).
    pub surface: String,
    /// The nodes of `parts` within the tolerance of that surface: the tie's slave side
    /// (`NAME_TIED`).
    pub tied: String,
    /// How many nodes that is.
    pub tied_nodes: usize,
}

/// Joins `parts` (a voxel mesh of the pieces that load a bone) to `mesh` (the bone), both in
/// one frame (mm): `mesh`'s elements become the element set `name` (unless it has one of that
/// name), its boundary faces the surface `NAME_SURFACE`, and the boundary nodes of `parts`
/// within `tolerance` mm of that surface the node set `NAME_TIED`, the two sides of a tie. Nodes are
/// not merged: the meshes need not match.
///
/// # Errors
/// [`Error::Mesh`] for meshes of different element kinds, a bad `name`, a set name in both
/// meshes, or no node of `parts` within `tolerance` of the surface.
pub fn join_tied(
    mesh: &FeMesh<3>,
    name: &str,
    parts: &FeMesh<3>,
    tolerance: f64,
) -> Result<TiedMesh> {
    if mesh.kind != parts.kind {
        return Err(Error::Mesh(format!(
            "a mesh of {} elements cannot be joined to one of {} (one element kind per model)",
            mesh.kind.name(),
            parts.kind.name()
        )));
    }
    if let Some(p) = set_name_problem(name) {
        return Err(Error::Mesh(format!("{name}: {p}")));
    }
    let surface = format!("{name}_SURFACE");
    let tied = format!("{name}_TIED");
    let mut sets = mesh.sets.clone();
    let shift_n = mesh.nodes.len();
    let shift_e = mesh.num_elements();
    sets.element_sets
        .entry(name.to_string())
        .or_insert_with(|| (0..shift_e).collect());
    let taken = |n: &String| {
        sets.node_sets.contains_key(n)
            || sets.element_sets.contains_key(n)
            || sets.surfaces.contains_key(n)
    };
    for n in parts
        .sets
        .node_sets
        .keys()
        .chain(parts.sets.element_sets.keys())
        .chain(parts.sets.surfaces.keys())
        .chain([&surface, &tied])
    {
        if taken(n) {
            return Err(Error::Mesh(format!(
                "the set {n} is in both meshes; rename one"
            )));
        }
    }
    sets.surfaces.insert(
        surface.clone(),
        boundary_faces(mesh)
            .iter()
            .map(|f| (f.element, f.face))
            .collect(),
    );
    let index = ClosestPointIndex::from_shape(&boundary_surface(mesh));
    // Only the parts' boundary nodes: a node inside a part is held by its elements.
    let mut outer = vec![false; parts.nodes.len()];
    for f in boundary_faces(parts) {
        for n in f.nodes.iter().chain(&f.mids) {
            outer[*n] = true;
        }
    }
    let near: Vec<usize> = (0..parts.nodes.len())
        .filter(|&n| outer[n] && index.closest(&parts.nodes[n]).dist2 <= tolerance * tolerance)
        .map(|n| n + shift_n)
        .collect();
    if near.is_empty() {
        return Err(Error::Mesh(format!(
            "no node of the parts lies within {tolerance} mm of the mesh's surface: nothing to \
             tie (are both in the same frame?)"
        )));
    }
    let tied_nodes = near.len();
    sets.node_sets.insert(tied.clone(), near);
    for (k, v) in &parts.sets.node_sets {
        sets.node_sets
            .insert(k.clone(), v.iter().map(|n| n + shift_n).collect());
    }
    for (k, v) in &parts.sets.element_sets {
        sets.element_sets
            .insert(k.clone(), v.iter().map(|e| e + shift_e).collect());
    }
    for (k, v) in &parts.sets.surfaces {
        sets.surfaces.insert(
            k.clone(),
            v.iter().map(|&(e, f)| (e + shift_e, f)).collect(),
        );
    }
    let mut nodes = mesh.nodes.clone();
    nodes.extend_from_slice(&parts.nodes);
    let mut connectivity = mesh.connectivity.clone();
    connectivity.extend(parts.connectivity.iter().map(|n| n + shift_n));
    Ok(TiedMesh {
        mesh: FeMesh {
            nodes,
            kind: mesh.kind,
            connectivity,
            sets,
        },
        surface,
        tied,
        tied_nodes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `HexMesh::block(n)` moved by `o`, its elements the set `set`.
    fn block(n: usize, o: [f64; 3], set: &str) -> FeMesh<3> {
        let mut m = crate::mesh::HexMesh::block(n);
        for p in &mut m.nodes {
            for d in 0..3 {
                p[d] += o[d];
            }
        }
        m.sets
            .element_sets
            .insert(set.into(), (0..m.num_elements()).collect());
        m
    }

    fn cube(o: [f64; 3], set: &str) -> FeMesh<3> {
        block(1, o, set)
    }

    #[test]
    fn a_pad_on_a_bone_is_tied_by_its_near_face() {
        let bone = cube([0.0, 0.0, 0.0], "B");
        // A pad 0.05 above the bone's top face.
        let pad = cube([0.0, 0.0, 1.05], "PADS");
        let j = join_tied(&bone, "BONE", &pad, 0.1).unwrap();
        assert_eq!(j.mesh.num_elements(), 2);
        assert_eq!(j.mesh.nodes.len(), 16);
        assert_eq!(j.mesh.sets.element_sets["BONE"], vec![0]);
        assert_eq!(j.mesh.sets.element_sets["PADS"], vec![1]);
        assert_eq!(j.mesh.sets.surfaces["BONE_SURFACE"].len(), 6);
        assert_eq!(j.mesh.sets.node_sets["BONE_TIED"], vec![8, 9, 10, 11]);
        assert_eq!(j.mesh.element(1)[0], 8);
        let far = cube([0.0, 0.0, 3.0], "PADS");
        assert!(join_tied(&bone, "BONE", &far, 0.1).is_err());
        let clash = cube([0.0, 0.0, 1.0], "B");
        assert!(join_tied(&bone, "BONE", &clash, 0.1).is_err());
    }

    #[test]
    fn nodes_inside_a_part_are_never_tied() {
        // A 3 x 3 x 3 block of unit cubes above the bone: 64 nodes, 8 inside.
        let block = block(3, [0.0, 0.0, 1.0], "PADS");
        let bone = cube([0.0, 0.0, 0.0], "B");
        let j = join_tied(&bone, "BONE", &block, 100.0).unwrap();
        assert_eq!(j.tied_nodes, 56);
        let inside =
            |p: &[f64; 3]| (0..3).all(|c| p[c] > [0.5, 0.5, 1.5][c] && p[c] < [2.5, 2.5, 3.5][c]);
        for &n in &j.mesh.sets.node_sets["BONE_TIED"] {
            assert!(!inside(&j.mesh.nodes[n]), "{:?}", j.mesh.nodes[n]);
        }
    }
}

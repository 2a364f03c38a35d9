//! The boundary faces of a mesh (faces shared by no other element), outward.

use super::FeMesh;
use crate::geometry::{Point, Shape};
use std::collections::HashMap;

/// A face on the boundary of a mesh (shared by no other element).
#[derive(Clone, Debug)]
pub struct BoundaryFace<const D: usize> {
    /// The element it belongs to.
    pub element: usize,
    /// Local face number ([`crate::mesh::ElementKind::faces`]).
    pub face: u8,
    /// Its corner nodes, outward order.
    pub nodes: Vec<usize>,
    /// Its mid-edge nodes (quadratic elements; empty otherwise), in the order of its edges.
    pub mids: Vec<usize>,
    /// Unit outward normal.
    pub normal: Point<D>,
    /// The centroid of its corners.
    pub centroid: Point<D>,
}

/// A face (an edge in 2D) of a mesh and the elements it belongs to: one on the boundary, two
/// inside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FacePair {
    /// The first element it belongs to (in element order).
    pub element: usize,
    /// Its local face number in `element` ([`crate::mesh::ElementKind::faces`]).
    pub face: u8,
    /// The other element it belongs to, `None` on the boundary.
    pub other: Option<usize>,
}

/// The face slots (`element * faces + face`) of `mesh` grouped by face: the slots of one
/// face are consecutive in `slots`, each group ending at its entry of `ends`.
///
/// Face slots are bucketed by their smallest node (a counting sort), then sorted within a
/// bucket of a few. Linear, and several times faster than a hash map of the keys (75 ms for
/// the 57 000 hexahedra of a femur).
fn grouped_face_slots<const D: usize>(mesh: &FeMesh<D>) -> FaceGroups {
    let faces = mesh.kind.faces();
    // A face's key: its (at most 4) corner nodes sorted, padded; no allocation per face.
    let key_of = |el: &[usize], f: &[usize]| -> [usize; 4] {
        let mut key = [usize::MAX; 4];
        for (k, &c) in f.iter().enumerate() {
            key[k] = el[c];
        }
        key.sort_unstable();
        key
    };
    let nf = faces.len();
    let slots = mesh.num_elements() * nf;
    let key = |slot: usize| key_of(mesh.element(slot / nf), faces[slot % nf]);
    let mut start = vec![0usize; mesh.nodes.len() + 1];
    for slot in 0..slots {
        start[key(slot)[0] + 1] += 1;
    }
    for v in 0..mesh.nodes.len() {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut bucketed: Vec<([usize; 4], usize)> = vec![([0; 4], 0); slots];
    for slot in 0..slots {
        let k = key(slot);
        bucketed[fill[k[0]]] = (k, slot);
        fill[k[0]] += 1;
    }
    let mut ends = Vec::with_capacity(slots / 2 + 1);
    for v in 0..mesh.nodes.len() {
        let bucket = &mut bucketed[start[v]..start[v + 1]];
        bucket.sort_unstable();
        let mut at = start[v];
        for group in bucket.chunk_by(|a, b| a.0 == b.0) {
            at += group.len();
            ends.push(at);
        }
    }
    FaceGroups {
        slots: bucketed.into_iter().map(|b| b.1).collect(),
        ends,
    }
}

/// Face slots grouped by face (see [`grouped_face_slots`]).
struct FaceGroups {
    slots: Vec<usize>,
    ends: Vec<usize>,
}

impl FaceGroups {
    /// The slots of each face, in turn.
    fn iter(&self) -> impl Iterator<Item = &[usize]> {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts.zip(&self.ends).map(|(a, &b)| &self.slots[a..b])
    }
}

/// Every distinct face (edge in 2D) of `mesh` with the one or two elements it belongs to, in
/// the order of its first element's slot: what a view clipped through the volume draws (the
/// faces between kept and removed elements). A face of more than two elements (a
/// non-manifold mesh) lists its first two.
pub fn face_pairs<const D: usize>(mesh: &FeMesh<D>) -> Vec<FacePair> {
    let nf = mesh.kind.faces().len();
    let mut pairs: Vec<FacePair> = grouped_face_slots(mesh)
        .iter()
        .map(|g| FacePair {
            element: g[0] / nf,
            face: (g[0] % nf) as u8,
            other: g.get(1).map(|s| s / nf),
        })
        .collect();
    pairs.sort_unstable_by_key(|p| (p.element, p.face));
    pairs
}

/// The faces (edges in 2D) of `mesh` that belong to one element only.
pub fn boundary_faces<const D: usize>(mesh: &FeMesh<D>) -> Vec<BoundaryFace<D>> {
    let faces = mesh.kind.faces();
    let nf = faces.len();
    let mut once = vec![false; mesh.num_elements() * nf];
    for g in grouped_face_slots(mesh).iter() {
        if let [slot] = g {
            once[*slot] = true;
        }
    }
    let mut out = Vec::new();
    for e in 0..mesh.num_elements() {
        let el = mesh.element(e);
        for (fi, f) in faces.iter().enumerate() {
            if !once[e * nf + fi] {
                continue;
            }
            let nodes: Vec<usize> = f.iter().map(|&k| el[k]).collect();
            let p: Vec<Point<D>> = nodes.iter().map(|&n| mesh.nodes[n]).collect();
            let centroid: Point<D> =
                std::array::from_fn(|d| p.iter().map(|q| q[d]).sum::<f64>() / p.len() as f64);
            let mut normal = [0.0; D];
            if D == 2 {
                // Edge a -> b of a counter-clockwise element: outward is its right side.
                normal[0] = p[1][1] - p[0][1];
                normal[1] = -(p[1][0] - p[0][0]);
            } else {
                // Newell's normal of the (possibly non-planar) polygon.
                for k in 0..p.len() {
                    let (a, b) = (p[k], p[(k + 1) % p.len()]);
                    normal[0] += (a[1] - b[1]) * (a[2] + b[2]);
                    normal[1] += (a[2] - b[2]) * (a[0] + b[0]);
                    normal[2] += (a[0] - b[0]) * (a[1] + b[1]);
                }
            }
            let n = normal.iter().map(|v| v * v).sum::<f64>().sqrt();
            if n > 0.0 {
                normal = normal.map(|v| v / n);
            }
            let mids = if mesh.kind.linear() == mesh.kind {
                Vec::new()
            } else {
                mesh.kind.face_nodes(fi)[nodes.len()..]
                    .iter()
                    .map(|&k| el[k])
                    .collect()
            };
            out.push(BoundaryFace {
                element: e,
                face: fi as u8,
                nodes,
                mids,
                normal,
                centroid,
            });
        }
    }
    out
}

/// The boundary of `mesh` as a surface (3D: its faces split into triangles) or an outline
/// (2D: its edges), over the boundary's corner nodes only, numbered anew; the mesh's frame
/// and units. The shape the mesh delivers, to be measured against a subject.
pub fn boundary_surface<const D: usize>(mesh: &FeMesh<D>) -> Shape<D> {
    let faces = boundary_faces(mesh);
    let mut renumber: HashMap<usize, usize> = HashMap::new();
    let mut points = Vec::new();
    let mut local = |n: usize, points: &mut Vec<Point<D>>| {
        *renumber.entry(n).or_insert_with(|| {
            points.push(mesh.nodes[n]);
            points.len() - 1
        })
    };
    let mut facets = Vec::new();
    for f in &faces {
        let v: Vec<usize> = f.nodes.iter().map(|&n| local(n, &mut points)).collect();
        if D == 2 {
            facets.push(std::array::from_fn(|k| v[k]));
        } else {
            for k in 1..v.len().saturating_sub(1) {
                let tri = [v[0], v[k], v[k + 1]];
                facets.push(std::array::from_fn(|j| tri[j]));
            }
        }
    }
    Shape {
        name: "mesh boundary".into(),
        points,
        facets,
        landmarks: Vec::new(),
    }
}

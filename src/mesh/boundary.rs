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

/// The faces (edges in 2D) of `mesh` that belong to one element only.
pub fn boundary_faces<const D: usize>(mesh: &FeMesh<D>) -> Vec<BoundaryFace<D>> {
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
    // Face slots `e * faces + f` bucketed by their smallest node (a counting sort), then
    // sorted within a bucket of a few: a face is on the boundary when its key is there once.
    // Linear, and several times faster than a hash map of the keys (75 ms for the 57 000
    // hexahedra of a femur).
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
    let mut once = vec![false; slots];
    for v in 0..mesh.nodes.len() {
        let bucket = &mut bucketed[start[v]..start[v + 1]];
        bucket.sort_unstable();
        for group in bucket.chunk_by(|a, b| a.0 == b.0) {
            if let [(_, slot)] = group {
                once[*slot] = true;
            }
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

//! The boundary fit after the morph (after section 4; the paper has none): the morph of eq. 9
//! is a smooth global field and cannot put every boundary node on the subject, so the mesh's
//! boundary nodes are then projected onto the subject along their normals (the fit's last
//! step, with its rule of compatible normals: never across a thin part to the other side), the
//! subject's points still left far behind (the tips of processes, which no node's normal
//! reaches) pulling their nearest boundary node onto them, the displacement carried into the
//! interior by harmonic relaxation, and the elements made poor on the way raised by the repair
//! with the boundary sliding on the subject (after the mesh-matching of Bucki et al. 2010 and
//! Baldwin et al. 2010).
//!
//! Units: the mesh's and the subject's (one frame); reach in those units.

use super::{FeMesh, boundary_faces};
use crate::geometry::{
    COMPATIBLE_NORMALS_COS, ClosestPointIndex, Point, Shape, dist2, dot, project_along_normals,
    vertex_normals,
};
use std::collections::HashMap;

/// Harmonic relaxation sweeps (Jacobi) carrying the boundary's displacement inwards: enough
/// to reach about this many rings of elements.
const RELAXATION_SWEEPS: usize = 40;

/// What a boundary fit did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BoundaryFit {
    /// Boundary nodes moved onto the subject.
    pub moved: usize,
    /// Boundary nodes left where they were (no compatible crossing within reach: a part the
    /// subject does not have).
    pub left: usize,
    /// The largest move of a boundary node (mesh units).
    pub largest_move: f64,
    /// Boundary nodes pulled to a subject point the projection left far behind.
    pub pulled: usize,
}

/// Rounds of pulls of the subject's far points.
const PULL_ROUNDS: usize = 3;

/// A subject point farther than this many median boundary edges from the projected boundary
/// pulls the boundary node nearest to it.
const PULL_FROM_EDGES: f64 = 1.0;

/// The pulls of the subject's far points on a boundary (`points`, `facets`, its vertex
/// `normals`) already projected onto the subject: every subject point farther than
/// [`PULL_FROM_EDGES`] median edges from it claims the boundary point nearest to it, where
/// the two face the same way (compatible normals: never a point of the far side of a thin
/// part); a point claimed several times goes to its farthest claimant (the tip). Returns
/// (boundary point, subject point) pairs.
fn far_pulls<const D: usize>(
    points: &[Point<D>],
    facets: &[[usize; D]],
    normals: &[Point<D>],
    subject: &ClosestPointIndex<D>,
) -> Vec<(usize, Point<D>)> {
    let from = PULL_FROM_EDGES * crate::geometry::median_edge_length(points, facets);
    if from.is_nan() || from <= 0.0 || facets.is_empty() {
        return Vec::new();
    }
    let on_boundary = ClosestPointIndex::new(points, facets);
    let mut subject_normals = Vec::new();
    subject.vertex_normals_into(&mut subject_normals);
    let mut claims: HashMap<usize, (f64, Point<D>)> = HashMap::new();
    for (q, m) in subject.points().iter().zip(&subject_normals) {
        let c = on_boundary.closest(q);
        let d = c.dist2.sqrt();
        if d.is_nan() || d <= from {
            continue;
        }
        let Some(corners) = on_boundary.facet_vertices(&c) else {
            continue;
        };
        let nearest = (0..D)
            .max_by(|&a, &b| c.weights[a].total_cmp(&c.weights[b]))
            .map_or(corners[0], |j| corners[j]);
        if dot(*m, normals[nearest]) < COMPATIBLE_NORMALS_COS {
            continue;
        }
        let e = claims.entry(nearest).or_insert((0.0, *q));
        if d > e.0 {
            *e = (d, *q);
        }
    }
    let mut pulls: Vec<(usize, Point<D>)> = claims.into_iter().map(|(k, (_, q))| (k, q)).collect();
    pulls.sort_unstable_by_key(|&(k, _)| k);
    pulls
}

/// The mesh's boundary as a shape over its corner nodes, and the mesh node of each of its
/// points.
fn boundary_with_nodes<const D: usize>(mesh: &FeMesh<D>) -> (Shape<D>, Vec<usize>) {
    let faces = boundary_faces(mesh);
    let mut renumber: HashMap<usize, usize> = HashMap::new();
    let mut nodes = Vec::new();
    let mut facets = Vec::new();
    for f in &faces {
        let v: Vec<usize> = f
            .nodes
            .iter()
            .map(|&n| {
                *renumber.entry(n).or_insert_with(|| {
                    nodes.push(n);
                    nodes.len() - 1
                })
            })
            .collect();
        for k in 1..v.len() + 2 - D {
            let tri: Vec<usize> = if D == 2 {
                vec![v[0], v[1]]
            } else {
                vec![v[0], v[k], v[k + 1]]
            };
            facets.push(std::array::from_fn(|j| tri[j]));
        }
    }
    let shape = Shape {
        name: "mesh boundary".into(),
        points: nodes.iter().map(|&n| mesh.nodes[n]).collect(),
        facets,
        landmarks: Vec::new(),
    };
    (shape, nodes)
}

/// Moves the boundary nodes of `mesh` onto the subject (indexed by `subject`) along their
/// normals, each by at most `reach` (a node with no compatible crossing within it stays:
/// where the subject is partial, only the part it has is fitted; so does a node `keep`
/// marks, such as the face on an atlas's common cut), lets the subject's far points pull
/// their nearest boundary node onto them (`far_pulls`, three rounds, within the same reach),
/// and carries the moves into the interior by harmonic relaxation (each interior node moved
/// by the mean of its neighbours' moves, 40 sweeps: `RELAXATION_SWEEPS`). Every node then
/// moves `step` (in [0, 1]; clamped, NaN taken as 1) of its move: a share of the way, for a fit in stages. Linear
/// elements only: a quadratic mesh is left as it is (its mid-edge nodes follow their corners
/// when it is made quadratic).
///
/// The caller repairs the mesh afterwards (the elements the moves made poor) with the
/// boundary sliding on the subject, and keeps the result only when it is valid and no farther
/// from the subject.
pub fn fit_boundary<const D: usize>(
    mesh: &mut FeMesh<D>,
    subject: &ClosestPointIndex<D>,
    reach: f64,
    keep: &[bool],
    step: f64,
) -> BoundaryFit {
    let mut report = BoundaryFit::default();
    let share = if step.is_nan() {
        1.0
    } else {
        step.clamp(0.0, 1.0)
    };
    if mesh.kind.linear() != mesh.kind || mesh.num_elements() == 0 {
        return report;
    }
    let (boundary, nodes) = boundary_with_nodes(mesh);
    let targets = project_along_normals(&boundary.points, &boundary.facets, subject, false, None);
    let normals = vertex_normals(&boundary.points, &boundary.facets);
    let nn = mesh.nodes.len();
    let mut disp = vec![[0.0; D]; nn];
    let mut fixed = vec![false; nn];
    let mut projected = vec![false; nn];
    for (((&n, p), t), normal) in nodes
        .iter()
        .zip(&boundary.points)
        .zip(&targets)
        .zip(&normals)
    {
        fixed[n] = true;
        let d2 = dist2(*p, t.point);
        // Where no crossing was found the projection is the closest point: taken only where
        // the subject faces the same way there (not the far side of a thin part).
        let compatible = subject
            .normal_at(t)
            .is_some_and(|m| dot(m, *normal) >= COMPATIBLE_NORMALS_COS);
        let kept = keep.get(n).copied().unwrap_or(false);
        if !kept && d2.sqrt() <= reach && compatible && t.point.iter().all(|v| v.is_finite()) {
            disp[n] = std::array::from_fn(|d| t.point[d] - p[d]);
            projected[n] = true;
            report.moved += 1;
            report.largest_move = report.largest_move.max(d2.sqrt());
        } else {
            report.left += 1;
        }
    }
    // Subject points the projected boundary leaves far behind (the tips of processes a
    // smooth morph leaves short): each pulls the boundary node nearest to it, in rounds (a
    // node pulled to a tip brings the next far points within reach of its neighbours).
    let mut pulled = vec![false; nn];
    for _ in 0..PULL_ROUNDS {
        let moved_to: Vec<Point<D>> = nodes
            .iter()
            .zip(&boundary.points)
            .map(|(&n, p)| std::array::from_fn(|d| p[d] + disp[n][d]))
            .collect();
        let mut any = false;
        for (k, q) in far_pulls(&moved_to, &boundary.facets, &normals, subject) {
            let n = nodes[k];
            let p = boundary.points[k];
            let d = dist2(p, q).sqrt();
            if pulled[n] || keep.get(n).copied().unwrap_or(false) || d > reach {
                continue;
            }
            if !projected[n] {
                report.moved += 1;
                report.left -= 1;
            }
            disp[n] = std::array::from_fn(|j| q[j] - p[j]);
            pulled[n] = true;
            any = true;
            report.pulled += 1;
            report.largest_move = report.largest_move.max(d);
        }
        if !any {
            break;
        }
    }
    // Each node's neighbours along element edges.
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); nn];
    for e in 0..mesh.num_elements() {
        let el = mesh.element(e);
        for (c, frame) in mesh.kind.corner_frames().iter().enumerate() {
            for &m in frame.iter() {
                neighbours[el[c]].push(el[m]);
            }
        }
    }
    for v in &mut neighbours {
        v.sort_unstable();
        v.dedup();
    }
    let interior: Vec<usize> = (0..nn)
        .filter(|&n| !fixed[n] && !neighbours[n].is_empty())
        .collect();
    for _ in 0..RELAXATION_SWEEPS {
        let next: Vec<Point<D>> = interior
            .iter()
            .map(|&n| {
                let k = neighbours[n].len() as f64;
                std::array::from_fn(|d| neighbours[n].iter().map(|&m| disp[m][d]).sum::<f64>() / k)
            })
            .collect();
        for (&n, v) in interior.iter().zip(next) {
            disp[n] = v;
        }
    }
    for (p, d) in mesh.nodes.iter_mut().zip(&disp) {
        for k in 0..D {
            p[k] += share * d[k];
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::boundary_surface;

    /// A 5 × 5 grid of unit squares at height `z`, split into triangles facing +z (or -z
    /// when `flip`), with its vertex (2, 2) raised by `spike`.
    fn grid(spike: f64, flip: bool) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
        let mut points = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                let up = if (i, j) == (2, 2) { spike } else { 0.0 };
                points.push([i as f64, j as f64, up]);
            }
        }
        let mut facets = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let v = j * 5 + i;
                for t in [[v, v + 1, v + 6], [v, v + 6, v + 5]] {
                    facets.push(if flip { [t[0], t[2], t[1]] } else { t });
                }
            }
        }
        (points, facets)
    }

    #[test]
    fn a_far_subject_point_pulls_the_nearest_boundary_node_unless_it_faces_away() {
        let (boundary, facets) = grid(0.0, false);
        let normals = vertex_normals(&boundary, &facets);
        // The subject: the same grid with a tip 3 edges up at (2, 2): it pulls node 12.
        let (tip, tip_facets) = grid(3.0, false);
        let subject = ClosestPointIndex::new(&tip, &tip_facets);
        assert_eq!(
            far_pulls(&boundary, &facets, &normals, &subject),
            vec![(12, [2.0, 2.0, 3.0])]
        );
        // A tip 0.5 edges up is within reach of the boundary as it is: no pull.
        let (low, low_facets) = grid(0.5, false);
        let subject = ClosestPointIndex::new(&low, &low_facets);
        assert!(far_pulls(&boundary, &facets, &normals, &subject).is_empty());
        // The far side of a thin part (its facets face the other way): no pull.
        let (back, back_facets) = grid(3.0, true);
        let subject = ClosestPointIndex::new(&back, &back_facets);
        assert!(far_pulls(&boundary, &facets, &normals, &subject).is_empty());
    }

    #[test]
    fn a_blocks_boundary_is_moved_onto_a_larger_box_and_its_interior_follows() {
        // A 4 × 4 × 4 block, and a subject: the same block's boundary scaled by 1.1 about
        // its centre.
        let mut m = FeMesh::block(4);
        let mut subject = boundary_surface(&m);
        for p in &mut subject.points {
            *p = std::array::from_fn(|d| 2.0 + 1.1 * (p[d] - 2.0));
        }
        let index = ClosestPointIndex::from_shape(&subject);
        let keep = vec![false; m.nodes.len()];
        // Half the way: the faces' nodes halfway between the block and the subject.
        let mut half = m.clone();
        let r = fit_boundary(&mut half, &index, 1.0, &keep, 0.5);
        assert_eq!(r.moved, 98);
        // Node 12: (2, 2, 0), the middle of the bottom face, whose subject is at z = -0.2.
        let d = index.closest(&half.nodes[12]).dist2.sqrt();
        assert!((d - 0.1).abs() < 1e-9, "{d}");
        let r = fit_boundary(&mut m, &index, 1.0, &keep, 1.0);
        assert_eq!(r.left, 0, "{r:?}");
        assert_eq!(r.moved, 98);
        // Faces move 0.2 out; corners and edges along their normals, a little more.
        assert!(
            r.largest_move > 0.2 && r.largest_move <= 0.2 * 3f64.sqrt() + 1e-9,
            "{r:?}"
        );
        for f in boundary_faces(&m) {
            for &n in &f.nodes {
                assert!(index.closest(&m.nodes[n]).dist2.sqrt() < 1e-9);
            }
        }
        // The interior followed: the centre stays, the interior node next to the corner
        // (0, 0, 0) moved outwards, and the mesh is valid.
        assert!(dist2(m.nodes[62], [2.0; 3]).sqrt() < 1e-9);
        let inner = 1 + 5 * (1 + 5);
        assert!(
            m.nodes[inner].iter().all(|&c| c < 1.0 - 0.01),
            "{:?}",
            m.nodes[inner]
        );
        let q = crate::mesh::quality::summarize(&crate::mesh::quality::mesh_quality(&m));
        assert!(
            q.inverted_elements == 0 && q.scaled_jacobian_min > 0.8,
            "{q:?}"
        );
        // A kept node stays; a reach too short moves nothing.
        let mut m2 = FeMesh::block(4);
        let mut keep = vec![false; m2.nodes.len()];
        keep[0] = true;
        let r = fit_boundary(&mut m2, &index, 1.0, &keep, 1.0);
        assert_eq!((r.moved, r.left), (97, 1));
        assert_eq!(m2.nodes[0], [0.0; 3]);
        let r = fit_boundary(&mut FeMesh::block(4), &index, 0.1, &[false; 125], 1.0);
        assert_eq!(r.moved, 0);
    }
}

//! Automatic all-hexahedral mesh of a closed surface (section 2.4, in 3D): a grid of cubes
//! inside the surface, made manifold, wrapped in one pillow layer whose outer nodes lie on the
//! surface, then smoothed node by node without ever lowering the worst element touched.
//!
//! Steps:
//! 1. Cubes of edge `h` whose centres are inside the surface (ray parity along `x`) and at
//!    least `0.75 h` from it.
//! 2. The largest face-connected set of them, with cubes removed until every grid edge and
//!    vertex on its boundary is manifold (no two cubes meeting only along an edge or at a
//!    corner), so that the boundary is a closed quad surface.
//! 3. Pillow: every boundary node gets a partner at its closest point on the surface, and
//!    every boundary quad becomes a hexahedron between the quad and its partners. No
//!    hexahedron has two faces on the surface. A boundary node nearer the surface than
//!    `PILLOW_MIN` cube edges along the staircase's normal first moves inwards to that
//!    depth, so that no pillow hexahedron is a sliver.
//! 4. Smoothing: surface nodes move toward the average of their surface neighbours and back
//!    onto the surface; inner nodes toward the average of their neighbours. A move is kept
//!    only when the worst quality of the hexahedra around the node does not drop: the
//!    smaller of the scaled Jacobian and `EDGE_RATIO_WEIGHT` over the edge ratio (a flat
//!    hexahedron can have square corners).
//!
//! Lengths in the surface's units; the surface must be closed and oriented outwards.

use super::quality::{edge_ratio, element_quality_at};
use super::{ElementKind, FeMesh};
use crate::error::{Error, Result};
use crate::geometry::{
    ClosestPointIndex, Point, Shape, add, bounding_box, cross, dot, normalize, scale, sub,
};
use std::collections::HashMap;

/// Parameters of the hexahedral mesher.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HexMeshParams {
    /// Cube edge, as a share of the surface's largest extent.
    pub element_size: f64,
    /// Smoothing sweeps over all nodes.
    pub smoothing_passes: usize,
}

/// A hexahedral mesh and how well it matches the surface.
#[derive(Clone, Debug)]
pub struct HexMesh {
    /// The mesh (surface units and frame).
    pub mesh: FeMesh<3>,
    /// Largest distance from a boundary face centre of the mesh to the surface (surface
    /// units).
    pub boundary_distance_max: f64,
    /// Mean of the same distances.
    pub boundary_distance_mean: f64,
}

/// Meshes the inside of the closed, outward-oriented surface `surface` with hexahedra.
///
/// Where a grid leaves an inverted element after smoothing (a thin place where two boundary
/// nodes reach the same spot of the surface), the grid is shifted by a third of a cube, or
/// its cubes made 5 % smaller or larger, and the mesh made again: the first valid one is
/// returned.
pub fn hex_mesh(surface: &Shape<3>, params: &HexMeshParams) -> Result<HexMesh> {
    crate::clear_simd_upper_state();
    let mut last = None;
    for (shift, factor) in [
        (0.0, 1.0),
        (1.0 / 3.0, 1.0),
        (2.0 / 3.0, 1.0),
        (0.0, 0.95),
        (0.5, 1.05),
    ] {
        match hex_mesh_once(surface, params, shift, factor) {
            Ok(m) => return Ok(m),
            Err(Error::Mesh(e)) if e.contains("inverted") => last = Some(Error::Mesh(e)),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| Error::Mesh("hexahedral meshing failed".into())))
}

fn hex_mesh_once(
    surface: &Shape<3>,
    params: &HexMeshParams,
    shift: f64,
    factor: f64,
) -> Result<HexMesh> {
    if !(params.element_size > 0.0 && params.element_size < 0.5) {
        return Err(Error::Parameter(format!(
            "element size {} must be in (0, 0.5) of the shape's extent",
            params.element_size
        )));
    }
    if !crate::geometry::is_closed_surface(surface) {
        return Err(Error::Mesh(format!(
            "{}: the surface is open; automatic hexahedral meshing needs a closed surface \
             (bring a template volume mesh instead: --template-mesh)",
            surface.name
        )));
    }
    let (lo, hi) = bounding_box(&surface.points);
    let ext = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let h = params.element_size * ext * factor;
    let origin: Point<3> = std::array::from_fn(|d| lo[d] - h - shift * h);
    let n: [usize; 3] = std::array::from_fn(|d| ((hi[d] - lo[d]) / h).ceil() as usize + 3);
    let cells = n[0] * n[1] * n[2];
    if cells > 50_000_000 {
        return Err(Error::Parameter(format!(
            "element size {} gives {cells} grid cells; use a larger one",
            params.element_size
        )));
    }
    let index = ClosestPointIndex::from_shape(surface);
    // 1. Inside cubes, 2. the largest face-connected component, made manifold.
    let grid = Grid { origin, h, n };
    let mut keep = inside_cubes(surface, &index, &grid);
    make_manifold(&mut keep, &index, &grid);
    if !keep.iter().any(|&b| b) {
        return Err(Error::Mesh(format!(
            "{}: no grid cube fits inside the surface at element size {}; use a smaller one",
            surface.name, params.element_size
        )));
    }

    // Grid nodes and hexahedra (VTK order), and the boundary faces of the cubes.
    let (mut nodes, mut hexes, boundary) = cube_hexahedra(&keep, &grid);

    // 3. Pillow layer.
    let on_surface = pillow(&mut nodes, &mut hexes, &boundary, &index, h);
    let mut mesh = FeMesh {
        nodes,
        kind: ElementKind::Hex8,
        connectivity: hexes,
        sets: Default::default(),
    };

    // 4. Smoothing that never lowers the worst incident element.
    smooth(&mut mesh, &on_surface, &index, params.smoothing_passes, h);
    let q = super::quality::summarize(&super::quality::mesh_quality(&mesh));
    if q.inverted_elements > 0 {
        return Err(Error::Mesh(format!(
            "{}: the hexahedral mesh has {} inverted elements at element size {}; try another size",
            surface.name, q.inverted_elements, params.element_size
        )));
    }
    let (dmax, dmean) = pillow_distance(&mesh, boundary.len(), &index);
    Ok(HexMesh {
        mesh,
        boundary_distance_max: dmax,
        boundary_distance_mean: dmean,
    })
}

/// The pillow layer (step 3): each boundary face of the cubes gets a hexahedron out to the
/// surface, its outer corners at the closest surface points of the grid nodes. (Casting along
/// the staircase's normals crosses over in concave places and folds the pillow there.)
/// Appends the nodes and hexahedra; returns which nodes lie on the surface.
fn pillow(
    nodes: &mut Vec<Point<3>>,
    hexes: &mut Vec<usize>,
    boundary: &[[usize; 4]],
    index: &ClosestPointIndex<3>,
    h: f64,
) -> Vec<bool> {
    let mut normal_sum: HashMap<usize, Point<3>> = HashMap::new();
    for f in boundary {
        let nrm = normalize(cross(
            sub(nodes[f[1]], nodes[f[0]]),
            sub(nodes[f[3]], nodes[f[0]]),
        ));
        for &v in f {
            let e = normal_sum.entry(v).or_insert([0.0; 3]);
            *e = add(*e, nrm);
        }
    }
    let mut outer: HashMap<usize, usize> = HashMap::new();
    let mut bnodes: Vec<usize> = normal_sum.keys().copied().collect();
    bnodes.sort_unstable();
    for &v in &bnodes {
        let q = index.closest(&nodes[v]).point;
        // A grid node nearer the surface than `PILLOW_MIN h` along the staircase's outward
        // normal (a cube corner may even poke out of it) moves inwards, so that its pillow
        // hexahedron is not a sliver: the scaled Jacobian does not see a hexahedron of
        // vanishing thickness, a solver does.
        let ns = normalize(normal_sum[&v]);
        let along = dot(sub(q, nodes[v]), ns);
        if along < PILLOW_MIN * h {
            nodes[v] = sub(nodes[v], scale(ns, PILLOW_MIN * h - along));
        }
        nodes.push(q);
        outer.insert(v, nodes.len() - 1);
    }
    for f in boundary {
        hexes.extend_from_slice(&[
            f[0],
            f[1],
            f[2],
            f[3],
            outer[&f[0]],
            outer[&f[1]],
            outer[&f[2]],
            outer[&f[3]],
        ]);
    }
    let mut on_surface = vec![false; nodes.len()];
    for &o in outer.values() {
        on_surface[o] = true;
    }
    on_surface
}

/// The largest and mean distance to the surface of the centres of the outer faces of the
/// pillow hexahedra (the mesh's last `pillows` elements).
fn pillow_distance(mesh: &FeMesh<3>, pillows: usize, index: &ClosestPointIndex<3>) -> (f64, f64) {
    let mut dmax: f64 = 0.0;
    let mut dsum = 0.0;
    for e in mesh.num_elements() - pillows..mesh.num_elements() {
        let el = mesh.element(e);
        let c = scale(
            add(
                add(mesh.nodes[el[4]], mesh.nodes[el[5]]),
                add(mesh.nodes[el[6]], mesh.nodes[el[7]]),
            ),
            0.25,
        );
        let d = index.closest(&c).dist2.sqrt();
        dmax = dmax.max(d);
        dsum += d;
    }
    (dmax, dsum / pillows.max(1) as f64)
}

/// The mesher's grid of cubes: `n` per axis, of edge `h`, from the corner `origin`.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: Point<3>,
    h: f64,
    n: [usize; 3],
}

impl Grid {
    /// Index of the cube `(i, j, k)`.
    #[inline]
    fn cell(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n[0] * (j + self.n[1] * k)
    }

    /// Centre of the cube `(i, j, k)`.
    #[inline]
    fn centre(&self, i: usize, j: usize, k: usize) -> Point<3> {
        [
            self.origin[0] + (i as f64 + 0.5) * self.h,
            self.origin[1] + (j as f64 + 0.5) * self.h,
            self.origin[2] + (k as f64 + 0.5) * self.h,
        ]
    }
}

/// The cubes of the grid `g` whose centres lie inside the
/// surface, by the parity of its crossings along x through each row of centres, and at least
/// [`INSET`] cube edges from it.
fn inside_cubes(surface: &Shape<3>, index: &ClosestPointIndex<3>, g: &Grid) -> Vec<bool> {
    let Grid { origin, h, n } = *g;
    let mut rows: Vec<Vec<f64>> = vec![Vec::new(); n[1] * n[2]];
    // A tiny offset keeps the rows off the surface's vertices and edges.
    let (oy, oz) = (1.234_567e-7 * h, 2.345_678e-7 * h);
    for f in &surface.facets {
        let (a, b, c) = (
            surface.points[f[0]],
            surface.points[f[1]],
            surface.points[f[2]],
        );
        let ylo = a[1].min(b[1]).min(c[1]);
        let yhi = a[1].max(b[1]).max(c[1]);
        let zlo = a[2].min(b[2]).min(c[2]);
        let zhi = a[2].max(b[2]).max(c[2]);
        let j0 = (((ylo - origin[1]) / h - 0.5).ceil().max(0.0)) as usize;
        let j1 = (((yhi - origin[1]) / h - 0.5).floor() as i64).min(n[1] as i64 - 1);
        let k0 = (((zlo - origin[2]) / h - 0.5).ceil().max(0.0)) as usize;
        let k1 = (((zhi - origin[2]) / h - 0.5).floor() as i64).min(n[2] as i64 - 1);
        for k in k0 as i64..=k1 {
            for j in j0 as i64..=j1 {
                let (y, z) = (
                    origin[1] + (j as f64 + 0.5) * h + oy,
                    origin[2] + (k as f64 + 0.5) * h + oz,
                );
                // Barycentric coordinates of (y, z) in the triangle's yz projection.
                let d = (b[1] - a[1]) * (c[2] - a[2]) - (c[1] - a[1]) * (b[2] - a[2]);
                if d.abs() < 1e-300 {
                    continue;
                }
                let u = ((y - a[1]) * (c[2] - a[2]) - (c[1] - a[1]) * (z - a[2])) / d;
                let v = ((b[1] - a[1]) * (z - a[2]) - (y - a[1]) * (b[2] - a[2])) / d;
                if u < 0.0 || v < 0.0 || u + v > 1.0 {
                    continue;
                }
                let x = a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]);
                rows[j as usize + n[1] * k as usize].push(x);
            }
        }
    }
    let mut keep = vec![false; n[0] * n[1] * n[2]];
    for k in 0..n[2] {
        for j in 0..n[1] {
            let xs = &mut rows[j + n[1] * k];
            xs.sort_by(f64::total_cmp);
            let mut c = 0;
            for i in 0..n[0] {
                let x = origin[0] + (i as f64 + 0.5) * h;
                while c < xs.len() && xs[c] < x {
                    c += 1;
                }
                if c % 2 == 1 {
                    let p = g.centre(i, j, k);
                    keep[g.cell(i, j, k)] = index.closest(&p).dist2 >= (INSET * h).powi(2);
                }
            }
        }
    }
    keep
}

/// Keeps the largest face-connected set of the cubes `keep` and removes cubes until its
/// boundary is manifold: no two cubes meeting only along an edge (the one nearer the surface
/// goes) or at a vertex (all but the largest group around it go).
fn make_manifold(keep: &mut [bool], index: &ClosestPointIndex<3>, g: &Grid) {
    let n = g.n;
    let dist_of = |i: usize, j: usize, k: usize| index.closest(&g.centre(i, j, k)).dist2;
    for _ in 0..50 {
        largest_component(keep, n);
        let mut changed = false;
        // Non-manifold edges: around a grid edge, two cubes that touch only along it.
        for axis in 0..3 {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let ijk = [i, j, k];
                        if ijk[a1] == 0 || ijk[a2] == 0 {
                            continue;
                        }
                        // The four cubes around the edge from vertex ijk along `axis`.
                        let mut quad = [[0usize; 3]; 4];
                        for (q, (d1, d2)) in [(0, 0), (1, 0), (1, 1), (0, 1)].iter().enumerate() {
                            let mut c = ijk;
                            c[a1] -= d1;
                            c[a2] -= d2;
                            quad[q] = c;
                        }
                        let on: Vec<bool> = quad
                            .iter()
                            .map(|c| keep[g.cell(c[0], c[1], c[2])])
                            .collect();
                        let count = on.iter().filter(|&&b| b).count();
                        if count == 2 && on[0] == on[2] {
                            // Diagonal pair: drop the one nearer the surface.
                            let pair: Vec<[usize; 3]> = quad
                                .iter()
                                .zip(&on)
                                .filter(|(_, b)| **b)
                                .map(|(c, _)| *c)
                                .collect();
                            let drop = if dist_of(pair[0][0], pair[0][1], pair[0][2])
                                < dist_of(pair[1][0], pair[1][1], pair[1][2])
                            {
                                pair[0]
                            } else {
                                pair[1]
                            };
                            keep[g.cell(drop[0], drop[1], drop[2])] = false;
                            changed = true;
                        }
                    }
                }
            }
        }
        // Non-manifold vertices: the cubes around a grid vertex must form one face-connected
        // group.
        for k in 1..n[2] {
            for j in 1..n[1] {
                for i in 1..n[0] {
                    let mut on = [false; 8];
                    for (b, o) in on.iter_mut().enumerate() {
                        let (di, dj, dk) = (b & 1, (b >> 1) & 1, (b >> 2) & 1);
                        *o = keep[g.cell(i - 1 + di, j - 1 + dj, k - 1 + dk)];
                    }
                    let groups = octant_groups(&on);
                    if groups.len() > 1 {
                        // Keep the largest group.
                        let best = groups
                            .iter()
                            .enumerate()
                            .max_by_key(|(_, g)| g.len())
                            .map(|(gi, _)| gi)
                            .unwrap_or(0);
                        for (gi, group) in groups.iter().enumerate() {
                            if gi == best {
                                continue;
                            }
                            for &b in group {
                                let (di, dj, dk) = (b & 1, (b >> 1) & 1, (b >> 2) & 1);
                                keep[g.cell(i - 1 + di, j - 1 + dj, k - 1 + dk)] = false;
                            }
                        }
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
}

/// The hexahedra of the cubes `keep` of the grid `g`:
/// their nodes, their connectivity (VTK order) and their boundary faces (quadrilaterals
/// with outward normals `(b - a) × (d - a)`).
#[allow(clippy::type_complexity)]
fn cube_hexahedra(keep: &[bool], g: &Grid) -> (Vec<Point<3>>, Vec<usize>, Vec<[usize; 4]>) {
    let Grid { origin, h, n } = *g;
    let vid = |i: usize, j: usize, k: usize| i + (n[0] + 1) * (j + (n[1] + 1) * k);
    let mut node_of: HashMap<usize, usize> = HashMap::new();
    let mut nodes: Vec<Point<3>> = Vec::new();
    let mut hexes: Vec<usize> = Vec::new();
    let mut node = |i: usize, j: usize, k: usize, nodes: &mut Vec<Point<3>>| -> usize {
        *node_of.entry(vid(i, j, k)).or_insert_with(|| {
            nodes.push([
                origin[0] + i as f64 * h,
                origin[1] + j as f64 * h,
                origin[2] + k as f64 * h,
            ]);
            nodes.len() - 1
        })
    };
    let mut boundary: Vec<[usize; 4]> = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                if !keep[g.cell(i, j, k)] {
                    continue;
                }
                let c = [
                    node(i, j, k, &mut nodes),
                    node(i + 1, j, k, &mut nodes),
                    node(i + 1, j + 1, k, &mut nodes),
                    node(i, j + 1, k, &mut nodes),
                    node(i, j, k + 1, &mut nodes),
                    node(i + 1, j, k + 1, &mut nodes),
                    node(i + 1, j + 1, k + 1, &mut nodes),
                    node(i, j + 1, k + 1, &mut nodes),
                ];
                hexes.extend_from_slice(&c);
                // Faces with outward normals (b - a) × (d - a), and their neighbour cubes.
                let faces: [([usize; 4], Option<usize>); 6] = [
                    (
                        [c[0], c[3], c[2], c[1]],
                        (k > 0).then(|| g.cell(i, j, k - 1)),
                    ),
                    (
                        [c[4], c[5], c[6], c[7]],
                        (k + 1 < n[2]).then(|| g.cell(i, j, k + 1)),
                    ),
                    (
                        [c[0], c[1], c[5], c[4]],
                        (j > 0).then(|| g.cell(i, j - 1, k)),
                    ),
                    (
                        [c[3], c[7], c[6], c[2]],
                        (j + 1 < n[1]).then(|| g.cell(i, j + 1, k)),
                    ),
                    (
                        [c[0], c[4], c[7], c[3]],
                        (i > 0).then(|| g.cell(i - 1, j, k)),
                    ),
                    (
                        [c[1], c[2], c[6], c[5]],
                        (i + 1 < n[0]).then(|| g.cell(i + 1, j, k)),
                    ),
                ];
                for (f, nb) in faces {
                    if nb.is_none_or(|nb| !keep[nb]) {
                        boundary.push(f);
                    }
                }
            }
        }
    }
    (nodes, hexes, boundary)
}

/// Face-connected groups among the (up to 8) present cubes around a grid vertex; cube `b` is
/// at offsets `(b & 1, b >> 1 & 1, b >> 2 & 1)`, and two cubes share a face when their
/// offsets differ in one bit.
fn octant_groups(on: &[bool; 8]) -> Vec<Vec<usize>> {
    let mut seen = [false; 8];
    let mut groups = Vec::new();
    for s in 0..8 {
        if !on[s] || seen[s] {
            continue;
        }
        let mut g = vec![s];
        seen[s] = true;
        let mut stack = vec![s];
        while let Some(b) = stack.pop() {
            for bit in [1, 2, 4] {
                let c = b ^ bit;
                if on[c] && !seen[c] {
                    seen[c] = true;
                    g.push(c);
                    stack.push(c);
                }
            }
        }
        groups.push(g);
    }
    groups
}

/// Keeps only the largest face-connected set of cubes.
fn largest_component(keep: &mut [bool], n: [usize; 3]) {
    let mut label = vec![usize::MAX; keep.len()];
    let mut sizes = Vec::new();
    for s in 0..keep.len() {
        if !keep[s] || label[s] != usize::MAX {
            continue;
        }
        let l = sizes.len();
        let mut size = 0;
        let mut stack = vec![s];
        label[s] = l;
        while let Some(c) = stack.pop() {
            size += 1;
            let (i, j, k) = (c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1]));
            let mut nb = Vec::with_capacity(6);
            if i > 0 {
                nb.push(c - 1);
            }
            if i + 1 < n[0] {
                nb.push(c + 1);
            }
            if j > 0 {
                nb.push(c - n[0]);
            }
            if j + 1 < n[1] {
                nb.push(c + n[0]);
            }
            if k > 0 {
                nb.push(c - n[0] * n[1]);
            }
            if k + 1 < n[2] {
                nb.push(c + n[0] * n[1]);
            }
            for d in nb {
                if keep[d] && label[d] == usize::MAX {
                    label[d] = l;
                    stack.push(d);
                }
            }
        }
        sizes.push(size);
    }
    if let Some(best) = (0..sizes.len()).max_by_key(|&l| sizes[l]) {
        for (k, l) in keep.iter_mut().zip(&label) {
            *k = *k && *l == best;
        }
    }
}

/// The 12 edges of a hexahedron in VTK node order.
const HEX_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// Laplacian smoothing with a guard: a node moves to the mean of its edge neighbours (surface
/// nodes: of their surface neighbours, then back onto the surface) only if the worst quality
/// of its hexahedra (scaled Jacobian, or `EDGE_RATIO_WEIGHT` over the edge ratio when less)
/// does not drop.
fn smooth(
    mesh: &mut FeMesh<3>,
    on_surface: &[bool],
    surface: &ClosestPointIndex<3>,
    passes: usize,
    h: f64,
) {
    let nn = mesh.nodes.len();
    let ne = mesh.num_elements();
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); nn];
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); nn];
    for e in 0..ne {
        let el = mesh.element(e).to_vec();
        for &v in &el {
            incident[v].push(e);
        }
        for (a, b) in HEX_EDGES {
            let (a, b) = (el[a], el[b]);
            // Surface nodes average over surface neighbours only.
            if on_surface[a] == on_surface[b] || !on_surface[a] {
                neighbours[a].push(b);
            }
            if on_surface[a] == on_surface[b] || !on_surface[b] {
                neighbours[b].push(a);
            }
        }
    }
    for l in &mut neighbours {
        l.sort_unstable();
        l.dedup();
    }
    let FeMesh {
        nodes,
        connectivity,
        ..
    } = mesh;
    let mut q = SmoothingQuality::new(connectivity, &incident, nodes);
    for _ in 0..passes {
        for v in 0..nn {
            if neighbours[v].is_empty() {
                continue;
            }
            let mut target = [0.0; 3];
            for &u in &neighbours[v] {
                target = add(target, nodes[u]);
            }
            target = scale(target, 1.0 / neighbours[v].len() as f64);
            if on_surface[v] {
                target = surface.closest(&target).point;
            }
            let before = q.worst(v);
            let old = nodes[v];
            nodes[v] = target;
            if q.worst_at(nodes, v) < before {
                nodes[v] = old;
            } else {
                q.keep(v);
            }
        }
        // Nodes around poor elements: a pattern search on the worst incident scaled Jacobian
        // (steps along the axes, shrinking), surface nodes kept on the surface.
        for v in 0..nn {
            if q.worst(v) < POOR && !neighbours[v].is_empty() {
                pattern_search(v, nodes, &mut q, on_surface[v].then_some(surface), h);
            }
        }
    }
}

/// The pattern search of [`smooth`] at node `v`: steps of shrinking length along the axes and
/// diagonals, each kept when it raises the worst quality of the node's elements; on the
/// surface (when given) each trial goes to its closest point.
fn pattern_search(
    v: usize,
    nodes: &mut [Point<3>],
    q: &mut SmoothingQuality<'_>,
    surface: Option<&ClosestPointIndex<3>>,
    h: f64,
) {
    let mut best = q.worst(v);
    for step in [0.5 * h, 0.25 * h, 0.12 * h, 0.06 * h, 0.03 * h] {
        let mut improved = true;
        let mut rounds = 0;
        while improved && rounds < 20 {
            improved = false;
            rounds += 1;
            let start = nodes[v];
            for dir in 0..27 {
                if dir == 13 {
                    continue;
                }
                let o = [
                    (dir % 3) as f64 - 1.0,
                    ((dir / 3) % 3) as f64 - 1.0,
                    (dir / 9) as f64 - 1.0,
                ];
                let mut p = start;
                for d in 0..3 {
                    p[d] += o[d] * step;
                }
                if let Some(surface) = surface {
                    p = surface.closest(&p).point;
                }
                let old = nodes[v];
                nodes[v] = p;
                let w = q.worst_at(nodes, v);
                if w > best + 1e-9 {
                    best = w;
                    improved = true;
                    q.keep(v);
                } else {
                    nodes[v] = old;
                }
            }
        }
    }
}

/// Every hexahedron's quality for [`smooth`] (the smaller of its scaled Jacobian and
/// [`EDGE_RATIO_WEIGHT`] over its edge ratio), kept up to date as nodes move: a node's worst
/// before a move is read, and only a trial position's elements are computed (kept when the
/// move is). The same moves as computing both, with a third of the corner evaluations.
struct SmoothingQuality<'a> {
    connectivity: &'a [usize],
    incident: &'a [Vec<usize>],
    cached: Vec<f64>,
    /// The qualities of the last trial's elements, in the order of `incident[v]`.
    trial: Vec<f64>,
}

impl<'a> SmoothingQuality<'a> {
    fn new(connectivity: &'a [usize], incident: &'a [Vec<usize>], nodes: &[Point<3>]) -> Self {
        let mut q = SmoothingQuality {
            connectivity,
            incident,
            cached: Vec::new(),
            trial: Vec::new(),
        };
        q.cached = (0..connectivity.len() / 8)
            .map(|e| q.of(nodes, e))
            .collect();
        q
    }

    fn of(&self, nodes: &[Point<3>], e: usize) -> f64 {
        let el = &self.connectivity[e * 8..e * 8 + 8];
        let sj = element_quality_at(ElementKind::Hex8, el, nodes).scaled_jacobian_min;
        sj.min(EDGE_RATIO_WEIGHT / edge_ratio(ElementKind::Hex8, el, nodes))
    }

    /// The worst quality of node `v`'s elements as kept.
    fn worst(&self, v: usize) -> f64 {
        self.incident[v]
            .iter()
            .map(|&e| self.cached[e])
            .fold(f64::INFINITY, f64::min)
    }

    /// The worst quality of node `v`'s elements at `nodes` (a trial position of `v`).
    fn worst_at(&mut self, nodes: &[Point<3>], v: usize) -> f64 {
        let mut trial = std::mem::take(&mut self.trial);
        trial.clear();
        trial.extend(self.incident[v].iter().map(|&e| self.of(nodes, e)));
        let worst = trial.iter().copied().fold(f64::INFINITY, f64::min);
        self.trial = trial;
        worst
    }

    /// Keeps the last trial of node `v` (its elements' qualities as [`Self::worst_at`] found).
    fn keep(&mut self, v: usize) {
        for (&e, &q) in self.incident[v].iter().zip(&self.trial) {
            self.cached[e] = q;
        }
    }
}

/// Cubes kept have their centre at least this many cube edges inside the surface.
const INSET: f64 = 0.75;

/// The smoothing's quality of a hexahedron is the smaller of its scaled Jacobian and this
/// over its edge ratio: an edge ratio above 5 counts as poor, like a scaled Jacobian below
/// 0.3.
const EDGE_RATIO_WEIGHT: f64 = 1.5;

/// Least thickness of the pillow layer along the staircase's normals, in cube edges.
const PILLOW_MIN: f64 = 0.3;

/// Elements below this scaled Jacobian get the pattern search of [`smooth`].
const POOR: f64 = 0.3;

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangulated sphere (UV) of radius `r`.
    fn sphere(r: f64, nu: usize, nv: usize) -> Shape<3> {
        let (points, facets) = crate::geometry::uv_sphere(nu, nv, |th, ph| {
            [
                r * th.cos() * ph.cos(),
                r * th.cos() * ph.sin(),
                r * th.sin(),
            ]
        });
        crate::geometry::prepare_surface(Shape {
            name: "sphere".into(),
            points,
            facets,
            landmarks: Vec::new(),
        })
        .unwrap()
    }

    use crate::geometry::dot;

    #[test]
    fn a_sphere_gets_a_valid_hex_mesh_on_its_surface() {
        let s = sphere(1.0, 48, 24);
        let m = hex_mesh(
            &s,
            &HexMeshParams {
                element_size: 0.1,
                smoothing_passes: 5,
            },
        )
        .unwrap();
        let q = super::super::quality::summarize(&super::super::quality::mesh_quality(&m.mesh));
        assert_eq!(q.inverted_elements, 0);
        assert!(
            q.scaled_jacobian_min > 0.2,
            "min scaled Jacobian {}",
            q.scaled_jacobian_min
        );
        assert!(
            m.boundary_distance_max < 0.05,
            "boundary {}",
            m.boundary_distance_max
        );
        // No sliver in the pillow layer (a flat hexahedron can have square corners).
        let ratio = super::super::quality::edge_ratio_max(&m.mesh);
        assert!(ratio < 5.0, "largest edge ratio {ratio}");
        // The volume of the mesh is close to the ball's.
        let vol: f64 = (0..m.mesh.num_elements())
            .map(|e| hex_volume(&m.mesh, e))
            .sum();
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!((vol - ball).abs() < 0.05 * ball, "volume {vol} vs {ball}");
    }

    fn hex_volume(m: &FeMesh<3>, e: usize) -> f64 {
        // Six tetrahedra of the hexahedron's diagonal split (exact for planar faces; close
        // otherwise).
        let el = m.element(e);
        let p = |i: usize| m.nodes[el[i]];
        let tets = [
            [0, 1, 2, 6],
            [0, 2, 3, 6],
            [0, 3, 7, 6],
            [0, 7, 4, 6],
            [0, 4, 5, 6],
            [0, 5, 1, 6],
        ];
        tets.iter()
            .map(|t| {
                let (a, b, c, d) = (p(t[0]), p(t[1]), p(t[2]), p(t[3]));
                dot(sub(b, a), cross(sub(c, a), sub(d, a))) / 6.0
            })
            .sum()
    }

    #[test]
    fn an_open_surface_is_refused() {
        let mut s = sphere(1.0, 12, 6);
        s.facets.pop();
        let e = hex_mesh(
            &s,
            &HexMeshParams {
                element_size: 0.2,
                smoothing_passes: 1,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("open"), "{e}");
    }
}

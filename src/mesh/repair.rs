//! Repair of a morphed mesh (after section 4; the paper has none): where an element is
//! inverted or its scaled Jacobian is below a bound, nodes are moved to untangle it and then
//! to raise the worst scaled Jacobian, locally around the bad elements first.
//!
//! Interior nodes move freely; boundary nodes that lie on the subject's surface (outline)
//! slide on it (each trial position is projected to its closest point on the surface), so
//! the surface fit is kept; other boundary nodes (an open outline's closing chord, the cut
//! ends of a tube, a crease the fit did not reach) slide on the mesh's own boundary as it
//! was, which keeps its shape. Without a surface (a mesh repaired on its own) every boundary
//! node stays where it is. Each node in turn maximizes the worst scaled Jacobian of the
//! elements around it (ties broken by their mean), by a compass search that also tries the
//! centroid of its neighbours: derivative-free, so inverted elements (negative scaled
//! Jacobians) are handled like bad ones. Sweeps run over the nodes of the elements still
//! below the bound and their neighbours, and widen to two and three rings of neighbours when
//! a sweep gains nothing.
//!
//! Units: positions in the mesh's units; the bound is on the scaled Jacobian (unitless).

use super::boundary_faces;
use crate::error::Result;
use crate::geometry::{ClosestPointIndex, Point, dist2};
use crate::mesh::quality::{
    ElementQuality, corner_with_edges, element_quality_at, mesh_quality, summarize,
};
use crate::mesh::{ElementKind, FeMesh};

/// Parameters of the repair.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RepairParams {
    /// Scaled Jacobian below which an element is repaired; `None`: the default of its kind
    /// ([`default_bound`]).
    pub bound: Option<f64>,
    /// Largest number of sweeps over the active nodes.
    pub max_sweeps: usize,
    /// A boundary node within this share of the median edge length of the surface slides
    /// on it; farther ones stay.
    pub on_surface: f64,
    /// When set, no move makes an element's edge ratio (longest edge over shortest) exceed
    /// this, or its value before the move when that was already larger: the scaled Jacobian
    /// alone would let a boundary node slide until an edge is tiny.
    pub edge_ratio_max: Option<f64>,
    /// A node's compass search stops when its step falls below this share of its first step
    /// (a third of the median distance to its neighbours). The default, 0.01, places
    /// boundary nodes sliding on the subject finely; the mean mesh's optimization, where only
    /// the quality counts, uses 0.1 (see [`crate::mesh::mesh_mean_shape`]).
    #[serde(default = "default_step_tolerance")]
    pub step_tolerance: f64,
}

fn default_step_tolerance() -> f64 {
    0.01
}

impl Default for RepairParams {
    fn default() -> Self {
        RepairParams {
            bound: None,
            max_sweeps: 60,
            on_surface: 0.25,
            edge_ratio_max: None,
            step_tolerance: default_step_tolerance(),
        }
    }
}

/// The default bounds: 0.2 for hexahedra (and simplices), 0.3 for quadrilaterals.
pub fn default_bound(kind: ElementKind) -> f64 {
    match kind {
        ElementKind::Quad4 => 0.3,
        _ => 0.2,
    }
}

/// What a repair did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RepairReport {
    /// Elements with a non-positive corner Jacobian before.
    pub inverted_before: usize,
    /// Smallest scaled Jacobian before.
    pub scaled_jacobian_min_before: f64,
    /// Elements below the bound before.
    pub below_bound_before: usize,
    /// The same after.
    pub inverted_after: usize,
    /// Smallest scaled Jacobian after.
    pub scaled_jacobian_min: f64,
    /// Elements below the bound after.
    pub below_bound_after: usize,
    /// The bound used.
    pub bound: f64,
    /// Nodes moved.
    pub moved_nodes: usize,
    /// The largest increase of a boundary node's distance to the surface (mesh units; 0 when
    /// nothing moved off it, negative never: sliding nodes end on the surface).
    pub surface_distance_change: f64,
    /// Sweeps run.
    pub sweeps: usize,
    /// The median edge length of the mesh (mesh units), the scale of the steps and of
    /// `surface_distance_change`.
    pub median_edge: f64,
}

/// Sharpness of the soft minimum: a corner 0.1 below another weighs `e^2` times more.
const KAPPA: f64 = 20.0;

/// Mean ratio of a corner below which a collapsing edge is penalized.
const MEAN_RATIO_BOUND: f64 = 0.05;

/// The penalty of one corner: `exp(-KAPPA (sj - bound))` on the scaled Jacobian `sj`, plus
/// the same on its mean ratio `D j^(2/D) / Σ|e_k|²` (`j` the corner Jacobian, `edges` the sum
/// of its edges' squared lengths `Σ|e_k|²`) against [`MEAN_RATIO_BOUND`]: the scaled Jacobian
/// of a corner whose edge collapses stays fine (it sees only the angles), and a repair that
/// traded angles for a collapsed edge would leave an element of near-zero volume.
fn corner_penalty<const D: usize>(j: f64, sj: f64, edges: f64, bound: f64) -> f64 {
    let mean_ratio = if j > 0.0 && edges > 0.0 {
        // j^(2/D): the cube root squared in 3D, j itself in 2D.
        let j_2_d = if D == 3 { cube_root(j).powi(2) } else { j };
        D as f64 * j_2_d / edges
    } else {
        0.0
    };
    (-KAPPA * (sj - bound)).exp() + (-KAPPA * (mean_ratio - MEAN_RATIO_BOUND)).exp()
}

/// The cube root of a positive, finite `x` to a relative 1e-14: a first guess from the bits
/// of `x` (a third of its exponent), then two Halley steps. Hand-written because the repair
/// takes one per corner and trial, and `f64::cbrt` (correctly rounded, from the compiler's
/// own math library) was the hottest call of a mean mesh's optimization: 26 ns against 4 ns a
/// call (20 million calls, `rustc -O`); in the build of an atlas of 10 femurs (24 800
/// hexahedra, one thread, `perf record`) it took 17 % of the samples, and the build 14 %
/// fewer samples with this one.
fn cube_root(x: f64) -> f64 {
    let mut y = f64::from_bits(x.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y
}

/// The objective of a node's elements: (worst scaled Jacobian, soft-min penalty
/// `Σ_corners exp(-KAPPA (sj - bound))`, inverted corners) over the corners that depend on
/// the node (`corners`: element and corner), plus `fixed`, the same over the corners of its
/// elements that do not.
///
/// With `against`, the score of the best position so far: `None` as soon as the corners
/// summed show that the position cannot be [`better`] (the penalty, a sum of positive terms,
/// only grows as corners are added, the worst only falls and the inverted corners only
/// rise), without the remaining corners; otherwise the whole score, the same as without.
fn score<const D: usize>(
    kind: ElementKind,
    conn: &[usize],
    corners: &[(usize, usize)],
    nodes: &[Point<D>],
    bound: f64,
    fixed: (f64, f64, usize),
    against: Option<(f64, f64, usize)>,
) -> Option<(f64, f64, usize)> {
    let k = kind.nodes();
    let (mut worst, mut penalty, mut inverted) = fixed;
    // The penalty at or above which a position is not better (see `better`).
    let (limit, inverted_max, worst_min) = match against {
        Some(b) => (b.1 * (1.0 - 1e-6), b.2, b.0),
        None => (f64::INFINITY, usize::MAX, f64::NEG_INFINITY),
    };
    for &(e, c) in corners {
        let el = &conn[e * k..(e + 1) * k];
        let (j, sj, edges) = corner_with_edges(kind, el, nodes, c);
        worst = worst.min(sj);
        penalty += corner_penalty::<D>(j, sj, edges, bound);
        if j <= 0.0 {
            inverted += 1;
        }
        if penalty >= limit || inverted > inverted_max || (worst <= 0.0 && worst < worst_min) {
            return None;
        }
    }
    Some((worst, penalty, inverted))
}

/// Whether `a` improves on `b`: a lower penalty (the sum over all corners of the mesh falls
/// with it), by a meaningful amount (smaller gains are rounding, or a node creeping along a
/// curved surface), with no more inverted corners and never inverting one where none was.
fn better(a: (f64, f64, usize), b: (f64, f64, usize)) -> bool {
    a.2 <= b.2 && (a.0 > 0.0 || a.0 >= b.0) && a.1 < b.1 * (1.0 - 1e-6)
}

/// Trial positions per node and sweep at most.
const MAX_TRIALS: usize = 600;

/// Repairs `mesh` in place (see the module doc). `surface` is the subject's shape (its
/// closest-point index): boundary nodes on it slide on it. Returns what was done; the mesh
/// may still hold elements below the bound when no node move raises them (then
/// `below_bound_after > 0`).
pub fn repair<const D: usize>(
    mesh: &mut FeMesh<D>,
    surface: Option<&ClosestPointIndex<D>>,
    params: &RepairParams,
) -> Result<RepairReport> {
    let quality = mesh_quality(mesh);
    repair_with_quality(mesh, surface, params, &quality).map(|(r, _)| r)
}

/// [`repair`] with the mesh's element quality at hand; also returns the quality after.
pub fn repair_with_quality<const D: usize>(
    mesh: &mut FeMesh<D>,
    surface: Option<&ClosestPointIndex<D>>,
    params: &RepairParams,
    quality: &[ElementQuality],
) -> Result<(RepairReport, Vec<ElementQuality>)> {
    crate::clear_simd_upper_state();
    let bound = params.bound.unwrap_or_else(|| default_bound(mesh.kind));
    let before = summarize(quality);
    let below = |q: &[ElementQuality]| q.iter().filter(|e| e.scaled_jacobian_min < bound).count();
    let mut report = RepairReport {
        inverted_before: before.inverted_elements,
        scaled_jacobian_min_before: before.scaled_jacobian_min,
        below_bound_before: below(quality),
        bound,
        ..Default::default()
    };
    if report.below_bound_before == 0 {
        report.inverted_after = before.inverted_elements;
        report.scaled_jacobian_min = before.scaled_jacobian_min;
        return Ok((report, quality.to_vec()));
    }
    let nn = mesh.nodes.len();
    let repairer = Repairer::new(mesh, surface, params, bound);
    report.median_edge = repairer.boundary.median_edge;
    let original = mesh.nodes.clone();
    let mut q: Vec<f64> = quality.iter().map(|e| e.scaled_jacobian_min).collect();
    let mut moved = vec![false; nn];
    report.sweeps = repairer.sweeps(&mut mesh.nodes, &mut q, &mut moved, params.max_sweeps);
    let mut after = mesh_quality(mesh);
    let mut s = summarize(&after);
    // Never worse than before: the penalty descent may trade the worst element for many
    // better ones; then the mesh goes back as it was.
    if s.inverted_elements > before.inverted_elements
        || s.scaled_jacobian_min < before.scaled_jacobian_min
    {
        mesh.nodes = original;
        moved.iter_mut().for_each(|m| *m = false);
        after = quality.to_vec();
        s = before;
    }
    report.inverted_after = s.inverted_elements;
    report.scaled_jacobian_min = s.scaled_jacobian_min;
    report.below_bound_after = below(&after);
    report.moved_nodes = moved.iter().filter(|m| **m).count();
    if let Some(surf) = surface {
        let role = &repairer.boundary.role;
        let distance_before = &repairer.boundary.distance_before;
        report.surface_distance_change = (0..nn)
            .filter(|&n| moved[n] && role[n] == 1)
            .map(|n| surf.closest(&mesh.nodes[n]).dist2.sqrt() - distance_before[n])
            .fold(0.0, f64::max);
    }
    Ok((report, after))
}

/// What the sweeps of a repair share: the mesh's connectivity, incidence and boundary, the
/// subject's surface and the bound.
struct Repairer<'a, const D: usize> {
    kind: ElementKind,
    conn: Vec<usize>,
    /// Each node's elements.
    incident: Vec<Vec<usize>>,
    boundary: Boundary<D>,
    surface: Option<&'a ClosestPointIndex<D>>,
    bound: f64,
    edge_ratio_max: Option<f64>,
    step_tolerance: f64,
}

impl<'a, const D: usize> Repairer<'a, D> {
    fn new(
        mesh: &FeMesh<D>,
        surface: Option<&'a ClosestPointIndex<D>>,
        params: &RepairParams,
        bound: f64,
    ) -> Self {
        let mut incident: Vec<Vec<usize>> = vec![Vec::new(); mesh.nodes.len()];
        for e in 0..mesh.num_elements() {
            for &n in mesh.element(e) {
                incident[n].push(e);
            }
        }
        Repairer {
            kind: mesh.kind,
            conn: mesh.connectivity.clone(),
            incident,
            boundary: Boundary::of(mesh, surface, params),
            surface,
            bound,
            edge_ratio_max: params.edge_ratio_max,
            step_tolerance: params.step_tolerance,
        }
    }

    /// The largest edge ratio of node `n`'s elements.
    fn edge_ratio_around(&self, n: usize, nodes: &[Point<D>]) -> f64 {
        self.incident[n]
            .iter()
            .map(|&e| super::quality::edge_ratio(self.kind, self.element(e), nodes))
            .fold(1.0, f64::max)
    }

    fn element(&self, e: usize) -> &[usize] {
        let k = self.kind.nodes();
        &self.conn[e * k..(e + 1) * k]
    }

    /// The nodes sharing an element with `n`, sorted.
    fn neighbours(&self, n: usize) -> Vec<usize> {
        let mut v: Vec<usize> = self.incident[n]
            .iter()
            .flat_map(|&e| self.element(e).iter().copied())
            .filter(|&m| m != n)
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Runs up to `max_sweeps` sweeps over the nodes around the elements below the bound
    /// (`q`: each element's scaled Jacobian, kept up to date), widening to two and three rings
    /// of neighbours when a sweep gains nothing. Returns the sweeps run.
    fn sweeps(
        &self,
        nodes: &mut [Point<D>],
        q: &mut [f64],
        moved: &mut [bool],
        max_sweeps: usize,
    ) -> usize {
        let mut ring = 1;
        let mut sweeps = 0;
        // A node's relaxation depends only on the nodes of its elements: one that stayed put
        // stays put again until one of them moves, and is skipped (the same result, without
        // its trials). `stamp[m]`: the clock when node m last moved; `settled[n]`: the clock
        // when node n's relaxation last left it in place (0: never).
        let mut clock = 1u64;
        let mut stamp = vec![0u64; nodes.len()];
        let mut settled = vec![0u64; nodes.len()];
        for sweep in 0..max_sweeps {
            sweeps = sweep + 1;
            let bad: Vec<usize> = (0..q.len()).filter(|&e| q[e] < self.bound).collect();
            if bad.is_empty() {
                break;
            }
            let worst_before = bad.iter().map(|&e| q[e]).fold(f64::INFINITY, f64::min);
            let mut gained = false;
            for n in self.active_nodes(&bad, ring, q) {
                if settled[n] != 0
                    && self.incident[n]
                        .iter()
                        .all(|&e| self.element(e).iter().all(|&m| stamp[m] <= settled[n]))
                {
                    continue;
                }
                let x0 = nodes[n];
                let bx = self.relax(n, nodes);
                nodes[n] = bx;
                if bx == x0 {
                    settled[n] = clock;
                } else {
                    clock += 1;
                    stamp[n] = clock;
                    moved[n] = true;
                    gained = true;
                    for &e in &self.incident[n] {
                        q[e] = element_quality_at(self.kind, self.element(e), nodes)
                            .scaled_jacobian_min;
                    }
                }
            }
            let worst_after = q
                .iter()
                .filter(|&&v| v < self.bound)
                .fold(f64::INFINITY, |a, &v| a.min(v));
            if !gained || worst_after <= worst_before + 1e-9 {
                if ring >= 3 && !gained {
                    break;
                }
                ring = (ring + 1).min(3);
            }
        }
        sweeps
    }

    /// The nodes of the `bad` elements widened by `ring - 1` rings of neighbours, those of the
    /// worst elements first.
    fn active_nodes(&self, bad: &[usize], ring: usize, q: &[f64]) -> Vec<usize> {
        let mut active: Vec<usize> = bad
            .iter()
            .flat_map(|&e| self.element(e).iter().copied())
            .collect();
        for _ in 1..ring {
            let more: Vec<usize> = active.iter().flat_map(|&n| self.neighbours(n)).collect();
            active.extend(more);
        }
        active.retain(|&n| self.boundary.role[n] != FIXED);
        active.sort_unstable();
        active.dedup();
        let worst = |n: usize| {
            self.incident[n]
                .iter()
                .map(|&e| q[e])
                .fold(f64::INFINITY, f64::min)
        };
        active.sort_by(|&a, &b| worst(a).total_cmp(&worst(b)));
        active
    }

    /// The corners that move with node `n` (element and corner; a quadratic element's corner
    /// moves with the mid-edge nodes of its frame's edges too), and the score of the rest of
    /// its elements' corners.
    fn corners_of(&self, n: usize, nodes: &[Point<D>]) -> (Vec<(usize, usize)>, (f64, f64, usize)) {
        let kind = self.kind;
        let mut moving = Vec::new();
        let mut fixed = (f64::INFINITY, 0.0, 0usize);
        for &e in &self.incident[n] {
            let el = self.element(e);
            for (c, frame) in kind.corner_frames().iter().enumerate() {
                if el[c] == n
                    || frame
                        .iter()
                        .any(|&m| el[m] == n || kind.mid_node(c, m).is_some_and(|mid| el[mid] == n))
                {
                    moving.push((e, c));
                } else {
                    let (j, sj, edges) = corner_with_edges(kind, el, nodes, c);
                    fixed.0 = f64::min(fixed.0, sj);
                    fixed.1 += corner_penalty::<D>(j, sj, edges, self.bound);
                    fixed.2 += usize::from(j <= 0.0);
                }
            }
        }
        (moving, fixed)
    }

    /// Where node `n` goes: the best of the centroid of its neighbours (which untangles folded
    /// stars) and a compass search over the axes and diagonals, each trial placed on the
    /// surface it slides on. `nodes[n]` is left at the best position found.
    fn relax(&self, n: usize, nodes: &mut [Point<D>]) -> Point<D> {
        let x0 = nodes[n];
        let (moving, fixed) = self.corners_of(n, nodes);
        let score_at = |nodes: &[Point<D>], against| {
            score(
                self.kind, &self.conn, &moving, nodes, self.bound, fixed, against,
            )
        };
        let Some(mut best) = score_at(nodes, None) else {
            return x0;
        };
        let mut bx = x0;
        let nb = self.neighbours(n);
        let median_edge = self.boundary.median_edge;
        // The first step: a third of the median distance to the neighbours (not the
        // least: a node next to a collapsed edge must be able to move far).
        let h0 = {
            let mut d: Vec<f64> = nb.iter().map(|&m| dist2(nodes[m], x0).sqrt()).collect();
            d.sort_by(f64::total_cmp);
            d.get(d.len() / 2)
                .copied()
                .unwrap_or(median_edge)
                .min(median_edge)
                * 0.3
        };
        // The edge ratio a move may reach around the node, when bounded.
        let ratio_cap = self
            .edge_ratio_max
            .map(|m| m.max(self.edge_ratio_around(n, nodes)));
        let mut trial = |p: Point<D>, nodes: &mut [Point<D>]| {
            let p = self.place(n, p);
            nodes[n] = p;
            let s = score_at(nodes, Some(best)).filter(|&s| better(s, best));
            if let Some(s) = s
                && ratio_cap.is_none_or(|c| self.edge_ratio_around(n, nodes) <= c)
            {
                best = s;
                bx = p;
                true
            } else {
                nodes[n] = bx;
                false
            }
        };
        let c: Point<D> = std::array::from_fn(|d| {
            nb.iter().map(|&m| nodes[m][d]).sum::<f64>() / nb.len().max(1) as f64
        });
        trial(c, nodes);
        let mut h = h0;
        let mut trials = 0;
        while h > self.step_tolerance * h0 && h > 0.0 && trials < MAX_TRIALS {
            trials += 3usize.pow(D as u32) - 1;
            let mut improved = false;
            // The axes and the diagonals (3^D - 1 directions), normalized to length h.
            for code in 0..3usize.pow(D as u32) {
                let dir: [f64; D] =
                    std::array::from_fn(|d| (code / 3usize.pow(d as u32) % 3) as f64 - 1.0);
                let len = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
                if len == 0.0 {
                    continue;
                }
                // (nodes[n] is the best position so far.)
                let p: Point<D> = std::array::from_fn(|d| nodes[n][d] + h * dir[d] / len);
                if trial(p, nodes) {
                    improved = true;
                }
            }
            if !improved {
                h *= 0.5;
            }
        }
        nodes[n]
    }

    /// A trial position of node `n` on what it slides on: the subject's surface, the mesh's
    /// own boundary, or nowhere (free).
    fn place(&self, n: usize, p: Point<D>) -> Point<D> {
        match (self.boundary.role[n], self.surface) {
            (1, Some(s)) => s.closest(&p).point,
            (2, _) => self.boundary.own_index.closest(&p).point,
            _ => p,
        }
    }
}

/// The role of a boundary node that does not move (a mesh repaired without a surface).
const FIXED: u8 = 3;

/// The boundary of a mesh as the repair sees it.
struct Boundary<const D: usize> {
    /// Every node's role: 0 free, 1 sliding on the subject's surface, 2 sliding on the
    /// mesh's own boundary, [`FIXED`] not moving.
    role: Vec<u8>,
    /// Every boundary node's distance to the subject's surface before the repair.
    distance_before: Vec<f64>,
    /// The median edge length of the mesh.
    median_edge: f64,
    /// The mesh's own boundary as it was (segments in 2D, triangles in 3D): boundary nodes
    /// off the subject's surface slide on it, so that the boundary keeps its shape.
    own_index: ClosestPointIndex<D>,
}

impl<const D: usize> Boundary<D> {
    /// The boundary of `mesh`: its nodes within `params.on_surface` median edges of
    /// `surface` slide on it, the other boundary nodes on the mesh's own boundary; without a
    /// surface, every boundary node is fixed.
    fn of(mesh: &FeMesh<D>, surface: Option<&ClosestPointIndex<D>>, params: &RepairParams) -> Self {
        let kind = mesh.kind;
        let nn = mesh.nodes.len();
        let ne = mesh.num_elements();
        let mut role = vec![0u8; nn];
        let faces = boundary_faces(mesh);
        let median_edge = {
            let mut l: Vec<f64> = (0..ne.min(2000))
                .flat_map(|e| {
                    let el = mesh.element(e);
                    kind.corner_frames()
                        .iter()
                        .enumerate()
                        .map(move |(c, f)| (el[c], el[f[0]]))
                })
                .map(|(a, b)| dist2(mesh.nodes[a], mesh.nodes[b]).sqrt())
                .collect();
            l.sort_by(f64::total_cmp);
            l.get(l.len() / 2).copied().unwrap_or(1.0)
        };
        let mut distance_before = vec![0.0; nn];
        for f in &faces {
            for &n in f.nodes.iter().chain(&f.mids) {
                if role[n] != 0 {
                    continue;
                }
                role[n] = match surface {
                    Some(s) => {
                        let d = s.closest(&mesh.nodes[n]).dist2.sqrt();
                        distance_before[n] = d;
                        if d <= params.on_surface * median_edge {
                            1
                        } else {
                            2
                        }
                    }
                    None => FIXED,
                };
            }
        }
        // The mesh's own boundary as it was (segments in 2D, triangles in 3D): boundary nodes off
        // the subject's surface slide on it, so that the boundary keeps its shape.
        let own: Vec<[usize; D]> = faces
            .iter()
            .flat_map(|f| {
                (1..f.nodes.len() + 2 - D)
                    .map(|t| {
                        std::array::from_fn(|k| {
                            if k == 0 {
                                f.nodes[0]
                            } else {
                                f.nodes[t + k - 1]
                            }
                        })
                    })
                    .collect::<Vec<[usize; D]>>()
            })
            .collect();
        let own_index = ClosestPointIndex::new(&mesh.nodes, &own);
        Boundary {
            role,
            distance_before,
            median_edge,
            own_index,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folded_quadratic_mesh_is_repaired() {
        // (The mid-edge nodes around the pushed corner stay: its edges fold back.)
        let m = folded_and_repaired(FeMesh::block(4).to_quadratic().unwrap());
        assert_eq!(summarize(&mesh_quality(&m)).inverted_elements, 0);
    }

    /// `m` (a 4 × 4 × 4 block) with its interior node (2, 2, 2) pushed down through the face
    /// below it, repaired: untangled and at or above the bound.
    fn folded_and_repaired(mut m: FeMesh<3>) -> FeMesh<3> {
        let n = 2 + 5 * (2 + 5 * 2);
        m.nodes[n][2] -= 1.6;
        let q = mesh_quality(&m);
        assert!(summarize(&q).inverted_elements > 0);
        let r = repair(&mut m, None, &RepairParams::default()).unwrap();
        assert!(r.inverted_before > 0, "{r:?}");
        assert_eq!(r.inverted_after, 0, "{r:?}");
        assert!(r.scaled_jacobian_min >= 0.2, "{r:?}");
        assert_eq!(r.below_bound_after, 0);
        m
    }

    #[test]
    fn a_node_pushed_through_its_opposite_face_is_repaired() {
        let m = folded_and_repaired(FeMesh::block(4));
        // The boundary did not move (no surface given: boundary nodes are fixed).
        let fresh = FeMesh::block(4);
        for f in boundary_faces(&fresh) {
            for &b in &f.nodes {
                assert_eq!(m.nodes[b], fresh.nodes[b]);
            }
        }
    }

    #[test]
    fn without_a_surface_the_boundary_stays_even_where_sliding_would_help() {
        // Interior node (1, 1, 1) pushed near the corner: the elements around it are poor, and
        // sliding the boundary nodes nearby would help them; without a surface they stay.
        let mut m = FeMesh::block(4);
        let n = 1 + 5 * (1 + 5);
        m.nodes[n] = [0.15, 0.15, 0.15];
        let r = repair(&mut m, None, &RepairParams::default()).unwrap();
        assert!(r.moved_nodes > 0, "{r:?}");
        let fresh = FeMesh::block(4);
        for f in boundary_faces(&fresh) {
            for &b in &f.nodes {
                assert_eq!(m.nodes[b], fresh.nodes[b], "boundary node {b} moved");
            }
        }
    }

    #[test]
    fn the_cube_root_is_that_of_std_to_1e_14() {
        for e in -300..300 {
            for m in [1.0, 1.2345, 2.0, 3.0, 7.77, 9.99] {
                let x = m * 10f64.powi(e);
                let (a, b) = (x.cbrt(), cube_root(x));
                assert!(((a - b) / a).abs() < 1e-14, "{x}: {a} {b}");
            }
        }
    }

    #[test]
    fn a_valid_mesh_is_left_alone() {
        let mut m = FeMesh::block(2);
        let r = repair(&mut m, None, &RepairParams::default()).unwrap();
        assert_eq!(r.moved_nodes, 0);
        assert_eq!(m.nodes, FeMesh::block(2).nodes);
    }
}

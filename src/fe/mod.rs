//! Finite element meshes: types, automatic meshing of the mean shape (section 2.4), and
//! element quality by corner Jacobians (section 5.3).

pub mod hexmesh;
pub mod quadmesh;
pub mod quality;
pub mod sets;

use crate::geometry::Point;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Element types. Node numbering follows VTK, which Abaqus/CalculiX and FEBio share for all
/// of these and Gmsh for the linear ones (0-based here, 1-based in their files; Gmsh numbers
/// the mid-edge nodes of its quadratic elements otherwise, and its reader and writer
/// reorder them).
///
/// ```text
/// Quad4 (counter-clockwise)     Hex8 (bottom 0-3 counter-clockwise seen from +z, top 4-7 above)
///   3 ------- 2                      7 ------- 6
///   |         |                     /|        /|
///   |         |                    4 ------- 5 |
///   |         |                    | 3 ------|- 2
///   0 ------- 1                    |/        |/
///                                  0 ------- 1
///
/// Tri3 (counter-clockwise)      Tet4 (0-1-2 counter-clockwise seen from 3)
///   2                                3
///   | \                             /|\
///   |   \                          / | \
///   |     \                       0 -|-- 2
///   0 ----- 1                      \ | /
///                                    1
/// ```
///
/// The quadratic elements have the corners of their linear kind first, then a node at the
/// middle of every edge, in this order of edges:
///
/// ```text
/// Hex20: 8 (0,1)  9 (1,2)  10 (2,3)  11 (3,0)       Tet10: 4 (0,1)  5 (1,2)  6 (2,0)
///        12 (4,5) 13 (5,6) 14 (6,7)  15 (7,4)              7 (0,3)  8 (1,3)  9 (2,3)
///        16 (0,4) 17 (1,5) 18 (2,6)  19 (3,7)
/// ```
///
/// Faces (edges in 2D) are numbered as Abaqus numbers them (`S1` is face 0), each listed
/// with its nodes ordered so that its normal points out of the element:
/// Quad4 `S1..S4` = (0,1) (1,2) (2,3) (3,0); Tri3 `S1..S3` = (0,1) (1,2) (2,0);
/// Hex8 `S1..S6` = (0,3,2,1) (4,5,6,7) (0,1,5,4) (1,2,6,5) (2,3,7,6) (3,0,4,7);
/// Tet4 `S1..S4` = (0,2,1) (0,1,3) (1,2,3) (2,0,3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElementKind {
    /// Bilinear quadrilateral (2D).
    Quad4,
    /// Trilinear hexahedron (3D).
    Hex8,
    /// Linear triangle (2D).
    Tri3,
    /// Linear tetrahedron (3D).
    Tet4,
    /// Quadratic (serendipity) hexahedron, 20 nodes (3D).
    Hex20,
    /// Quadratic tetrahedron, 10 nodes (3D).
    Tet10,
}

/// Mid-edge nodes of a Hex20 by edge (corner, corner, mid).
const HEX20_EDGES: [[usize; 3]; 12] = [
    [0, 1, 8],
    [1, 2, 9],
    [2, 3, 10],
    [3, 0, 11],
    [4, 5, 12],
    [5, 6, 13],
    [6, 7, 14],
    [7, 4, 15],
    [0, 4, 16],
    [1, 5, 17],
    [2, 6, 18],
    [3, 7, 19],
];

/// Mid-edge nodes of a Tet10 by edge (corner, corner, mid).
const TET10_EDGES: [[usize; 3]; 6] = [
    [0, 1, 4],
    [1, 2, 5],
    [2, 0, 6],
    [0, 3, 7],
    [1, 3, 8],
    [2, 3, 9],
];

/// Every kind.
const ALL_KINDS: [ElementKind; 6] = [
    ElementKind::Quad4,
    ElementKind::Hex8,
    ElementKind::Tri3,
    ElementKind::Tet4,
    ElementKind::Hex20,
    ElementKind::Tet10,
];

impl ElementKind {
    /// Nodes per element.
    pub fn nodes(self) -> usize {
        match self {
            ElementKind::Quad4 => 4,
            ElementKind::Hex8 => 8,
            ElementKind::Tri3 => 3,
            ElementKind::Tet4 => 4,
            ElementKind::Hex20 => 20,
            ElementKind::Tet10 => 10,
        }
    }
    /// The linear kind of the same shape (itself for a linear kind): its nodes are the first
    /// nodes of this kind's.
    pub fn linear(self) -> Self {
        match self {
            ElementKind::Hex20 => ElementKind::Hex8,
            ElementKind::Tet10 => ElementKind::Tet4,
            k => k,
        }
    }
    /// The mid-edge node of the edge between corners `a` and `b` of a quadratic kind.
    pub fn mid_node(self, a: usize, b: usize) -> Option<usize> {
        let edges: &[[usize; 3]] = match self {
            ElementKind::Hex20 => &HEX20_EDGES,
            ElementKind::Tet10 => &TET10_EDGES,
            _ => return None,
        };
        edges
            .iter()
            .find(|e| (e[0] == a && e[1] == b) || (e[0] == b && e[1] == a))
            .map(|e| e[2])
    }
    /// The nodes of face `f` ([`ElementKind::faces`]) with, for a quadratic kind, the
    /// mid-edge nodes after the corners (in the order of the face's edges).
    pub fn face_nodes(self, f: usize) -> Vec<usize> {
        let corners = self.faces()[f];
        let mut v = corners.to_vec();
        if self.linear() != self {
            for (i, &a) in corners.iter().enumerate() {
                let b = corners[(i + 1) % corners.len()];
                v.extend(self.mid_node(a, b));
            }
        }
        v
    }
    /// Spatial dimension of the element.
    pub fn dimension(self) -> usize {
        match self {
            ElementKind::Quad4 | ElementKind::Tri3 => 2,
            ElementKind::Hex8 | ElementKind::Tet4 | ElementKind::Hex20 | ElementKind::Tet10 => 3,
        }
    }
    /// VTK cell type id.
    pub fn vtk_type(self) -> u8 {
        match self {
            ElementKind::Quad4 => 9,
            ElementKind::Hex8 => 12,
            ElementKind::Tri3 => 5,
            ElementKind::Tet4 => 10,
            ElementKind::Hex20 => 25,
            ElementKind::Tet10 => 24,
        }
    }
    /// The kind of VTK cell type `t`.
    pub fn from_vtk_type(t: u8) -> Option<Self> {
        ALL_KINDS.into_iter().find(|k| k.vtk_type() == t)
    }
    /// Gmsh element type number.
    pub fn gmsh_type(self) -> u32 {
        match self {
            ElementKind::Tri3 => 2,
            ElementKind::Quad4 => 3,
            ElementKind::Tet4 => 4,
            ElementKind::Hex8 => 5,
            ElementKind::Tet10 => 11,
            ElementKind::Hex20 => 17,
        }
    }
    /// The kind of Gmsh element type `t`.
    pub fn from_gmsh_type(t: u32) -> Option<Self> {
        ALL_KINDS.into_iter().find(|k| k.gmsh_type() == t)
    }
    /// For each node in this crate's (VTK) order, its place in Gmsh's order of the element's
    /// nodes (the identity for the linear kinds).
    pub fn gmsh_order(self) -> &'static [usize] {
        match self {
            // Gmsh's hexahedron 20: edges (0,1) (0,3) (0,4) (1,2) (1,5) (2,3) (2,6) (3,7)
            // (4,5) (4,7) (5,6) (6,7).
            ElementKind::Hex20 => &[
                0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
            ],
            // Gmsh's tetrahedron 10: edges (0,1) (1,2) (2,0) (0,3) (2,3) (1,3).
            ElementKind::Tet10 => &[0, 1, 2, 3, 4, 5, 6, 7, 9, 8],
            ElementKind::Quad4 => &[0, 1, 2, 3],
            ElementKind::Tri3 => &[0, 1, 2],
            ElementKind::Tet4 => &[0, 1, 2, 3],
            ElementKind::Hex8 => &[0, 1, 2, 3, 4, 5, 6, 7],
        }
    }
    /// Abaqus/CalculiX element type written (plane stress in 2D).
    pub fn abaqus_type(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "CPS4",
            ElementKind::Tri3 => "CPS3",
            ElementKind::Hex8 => "C3D8",
            ElementKind::Tet4 => "C3D4",
            ElementKind::Hex20 => "C3D20",
            ElementKind::Tet10 => "C3D10",
        }
    }
    /// The kind of an Abaqus/CalculiX element type (continuum elements of these node counts:
    /// plane stress/strain, axisymmetric, 3D, with their reduced/hybrid/incompatible-mode
    /// variants).
    pub fn from_abaqus_type(t: &str) -> Option<Self> {
        let t = t.trim().to_ascii_uppercase();
        let base: String = t
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect();
        let stem = base.trim_end_matches(['R', 'H', 'I', 'T', 'M']);
        match stem {
            "C3D8" => Some(ElementKind::Hex8),
            "C3D4" => Some(ElementKind::Tet4),
            "C3D20" => Some(ElementKind::Hex20),
            "C3D10" => Some(ElementKind::Tet10),
            "CPS4" | "CPE4" | "CAX4" => Some(ElementKind::Quad4),
            "CPS3" | "CPE3" | "CAX3" => Some(ElementKind::Tri3),
            _ => None,
        }
    }
    /// FEBio element type name.
    pub fn febio_type(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "quad4",
            ElementKind::Tri3 => "tri3",
            ElementKind::Hex8 => "hex8",
            ElementKind::Tet4 => "tet4",
            ElementKind::Hex20 => "hex20",
            ElementKind::Tet10 => "tet10",
        }
    }
    /// The faces (edges in 2D) of the element, by local corner node, outward (see the type's
    /// doc); a quadratic kind has those of its linear kind ([`ElementKind::face_nodes`] adds
    /// the mid-edge nodes).
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self.linear() {
            ElementKind::Quad4 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
            ElementKind::Tri3 => &[&[0, 1], &[1, 2], &[2, 0]],
            ElementKind::Hex8 => &[
                &[0, 3, 2, 1],
                &[4, 5, 6, 7],
                &[0, 1, 5, 4],
                &[1, 2, 6, 5],
                &[2, 3, 7, 6],
                &[3, 0, 4, 7],
            ],
            _ => &[&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[2, 0, 3]],
        }
    }
    /// Scale of the scaled Jacobian: 1 for the ideal element's corners (square, cube,
    /// equilateral triangle and tetrahedron).
    pub fn scaled_jacobian_factor(self) -> f64 {
        match self {
            ElementKind::Quad4 | ElementKind::Hex8 | ElementKind::Hex20 => 1.0,
            ElementKind::Tri3 => 2.0 / 3f64.sqrt(),
            ElementKind::Tet4 | ElementKind::Tet10 => std::f64::consts::SQRT_2,
        }
    }
    /// The usual acceptance bound on the scaled Jacobian (hexahedra 0.5, quadrilaterals 0.3,
    /// simplices 0.2).
    pub fn scaled_jacobian_bound(self) -> f64 {
        match self.linear() {
            ElementKind::Hex8 => 0.5,
            ElementKind::Quad4 => 0.3,
            _ => 0.2,
        }
    }
    /// For each corner, the `D` neighbouring corners whose edge vectors span the corner's
    /// Jacobian matrix (right-handed for a valid element); a quadratic kind has those of its
    /// linear kind, the edge vectors then being the edges' tangents at the corner
    /// (`4 mid - 3 corner - other corner`, see [`crate::fe::quality`]).
    pub fn corner_frames(self) -> &'static [&'static [usize]] {
        match self {
            ElementKind::Quad4 => &[&[1, 3], &[2, 0], &[3, 1], &[0, 2]],
            ElementKind::Hex8 | ElementKind::Hex20 => &[
                &[1, 3, 4],
                &[2, 0, 5],
                &[3, 1, 6],
                &[0, 2, 7],
                &[7, 5, 0],
                &[4, 6, 1],
                &[5, 7, 2],
                &[6, 4, 3],
            ],
            ElementKind::Tri3 => &[&[1, 2], &[2, 0], &[0, 1]],
            ElementKind::Tet4 | ElementKind::Tet10 => {
                &[&[1, 2, 3], &[2, 0, 3], &[0, 1, 3], &[0, 2, 1]]
            }
        }
    }
    /// Name used in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "quad4",
            ElementKind::Hex8 => "hex8",
            ElementKind::Tri3 => "tri3",
            ElementKind::Tet4 => "tet4",
            ElementKind::Hex20 => "hex20",
            ElementKind::Tet10 => "tet10",
        }
    }
    /// The kind named `name` (as written by [`ElementKind::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        ALL_KINDS.into_iter().find(|k| k.name() == name)
    }
}

/// A finite element mesh of one element kind.
#[derive(Clone, Debug, PartialEq)]
pub struct FeMesh<const D: usize> {
    /// `#nodes` node positions (shape units).
    pub nodes: Vec<Point<D>>,
    /// Element kind.
    pub kind: ElementKind,
    /// Connectivity, `kind.nodes()` node indices per element, concatenated.
    pub connectivity: Vec<usize>,
    /// Named node sets, element sets and surfaces (carried by every morph: it moves nodes).
    pub sets: MeshSets,
}

/// Named sets of a mesh, 0-based and sorted: node sets, element sets, and surfaces as
/// `(element, face)` pairs with faces numbered as in [`ElementKind::faces`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshSets {
    pub node_sets: BTreeMap<String, Vec<usize>>,
    pub element_sets: BTreeMap<String, Vec<usize>>,
    pub surfaces: BTreeMap<String, Vec<(usize, u8)>>,
}

impl MeshSets {
    /// Adds the sets of `other`; a set of the same name is replaced.
    pub fn merge(&mut self, other: MeshSets) {
        self.node_sets.extend(other.node_sets);
        self.element_sets.extend(other.element_sets);
        self.surfaces.extend(other.surfaces);
    }

    /// Whether there is no set at all.
    pub fn is_empty(&self) -> bool {
        self.node_sets.is_empty() && self.element_sets.is_empty() && self.surfaces.is_empty()
    }

    /// Checks every member against a mesh of `nodes` nodes and `elements` elements of
    /// `kind`; the message names the set and the member.
    pub fn check(&self, kind: ElementKind, nodes: usize, elements: usize) -> Result<(), String> {
        for (name, s) in &self.node_sets {
            if let Some(n) = s.iter().find(|&&n| n >= nodes) {
                return Err(format!(
                    "node set {name} names node {} but the mesh has {nodes} nodes",
                    n + 1
                ));
            }
        }
        for (name, s) in &self.element_sets {
            if let Some(e) = s.iter().find(|&&e| e >= elements) {
                return Err(format!(
                    "element set {name} names element {} but the mesh has {elements} elements",
                    e + 1
                ));
            }
        }
        for (name, s) in &self.surfaces {
            if let Some((e, f)) = s
                .iter()
                .find(|(e, f)| *e >= elements || *f as usize >= kind.faces().len())
            {
                return Err(format!(
                    "surface {name} names face S{} of element {}, which does not exist",
                    f + 1,
                    e + 1
                ));
            }
        }
        Ok(())
    }
}

/// A quadrilateral mesh.
pub type QuadMesh = FeMesh<2>;
/// A hexahedral mesh.
pub type HexMesh = FeMesh<3>;

impl HexMesh {
    /// A block of `n × n × n` unit hexahedra from the origin, node `x + (n+1)(y + (n+1)z)` at
    /// `(x, y, z)`, elements in the [`ElementKind::Hex8`] node order (a reference mesh for
    /// checks and tests).
    pub fn block(n: usize) -> Self {
        let id = |x: usize, y: usize, z: usize| x + (n + 1) * (y + (n + 1) * z);
        let mut nodes = Vec::with_capacity((n + 1).pow(3));
        for z in 0..=n {
            for y in 0..=n {
                for x in 0..=n {
                    nodes.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let mut connectivity = Vec::with_capacity(8 * n.pow(3));
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    connectivity.extend([
                        id(x, y, z),
                        id(x + 1, y, z),
                        id(x + 1, y + 1, z),
                        id(x, y + 1, z),
                        id(x, y, z + 1),
                        id(x + 1, y, z + 1),
                        id(x + 1, y + 1, z + 1),
                        id(x, y + 1, z + 1),
                    ]);
                }
            }
        }
        FeMesh {
            nodes,
            kind: ElementKind::Hex8,
            connectivity,
            sets: Default::default(),
        }
    }
}

impl<const D: usize> FeMesh<D> {
    /// Number of elements.
    pub fn num_elements(&self) -> usize {
        self.connectivity.len() / self.kind.nodes()
    }
    /// Node indices of element `e`.
    pub fn element(&self, e: usize) -> &[usize] {
        let k = self.kind.nodes();
        &self.connectivity[e * k..(e + 1) * k]
    }
    /// The same connectivity with new node positions.
    #[track_caller]
    pub fn with_nodes(&self, nodes: Vec<Point<D>>) -> Self {
        assert_eq!(
            nodes.len(),
            self.nodes.len(),
            "with_nodes: one position per node"
        );
        FeMesh {
            nodes,
            kind: self.kind,
            connectivity: self.connectivity.clone(),
            sets: self.sets.clone(),
        }
    }

    /// The quadratic mesh of a linear 3D one (Hex8 to Hex20, Tet4 to Tet10): a node at the
    /// middle of every edge, shared by the elements around it, numbered after the linear
    /// mesh's nodes (which keep their numbers). Element sets and surfaces are kept; a node
    /// set gains the mid-edge nodes of the edges whose two ends it holds. `None` for a mesh
    /// that is already quadratic or two-dimensional.
    pub fn to_quadratic(&self) -> Option<Self> {
        let kind = match self.kind {
            ElementKind::Hex8 => ElementKind::Hex20,
            ElementKind::Tet4 => ElementKind::Tet10,
            _ => return None,
        };
        let edges: &[[usize; 3]] = match kind {
            ElementKind::Hex20 => &HEX20_EDGES,
            _ => &TET10_EDGES,
        };
        let mut nodes = self.nodes.clone();
        let mut mid: std::collections::HashMap<(usize, usize), usize> = Default::default();
        let mut connectivity = Vec::with_capacity(self.num_elements() * kind.nodes());
        for e in 0..self.num_elements() {
            let el = self.element(e);
            connectivity.extend_from_slice(el);
            for &[a, b, _] in edges {
                let key = (el[a].min(el[b]), el[a].max(el[b]));
                let m = *mid.entry(key).or_insert_with(|| {
                    let (p, q) = (self.nodes[key.0], self.nodes[key.1]);
                    nodes.push(std::array::from_fn(|d| 0.5 * (p[d] + q[d])));
                    nodes.len() - 1
                });
                connectivity.push(m);
            }
        }
        let mut sets = self.sets.clone();
        for members in sets.node_sets.values_mut() {
            let has: std::collections::HashSet<usize> = members.iter().copied().collect();
            members.extend(
                mid.iter()
                    .filter(|((a, b), _)| has.contains(a) && has.contains(b))
                    .map(|(_, &m)| m),
            );
            members.sort_unstable();
        }
        Some(FeMesh {
            nodes,
            kind,
            connectivity,
            sets,
        })
    }
}

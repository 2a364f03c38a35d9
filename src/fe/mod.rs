//! Finite element meshes: types, automatic meshing of the mean shape (section 2.4), and
//! element quality by corner Jacobians (section 5.3).

pub mod hexmesh;
pub mod quadmesh;
pub mod quality;
pub mod sets;

use crate::geometry::Point;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Element types. Node numbering follows VTK, which Gmsh, Abaqus/CalculiX and FEBio share for
/// these linear elements (0-based here, 1-based in their files).
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
}

impl ElementKind {
    /// Nodes per element.
    pub fn nodes(self) -> usize {
        match self {
            ElementKind::Quad4 => 4,
            ElementKind::Hex8 => 8,
            ElementKind::Tri3 => 3,
            ElementKind::Tet4 => 4,
        }
    }
    /// Spatial dimension of the element.
    pub fn dimension(self) -> usize {
        match self {
            ElementKind::Quad4 | ElementKind::Tri3 => 2,
            ElementKind::Hex8 | ElementKind::Tet4 => 3,
        }
    }
    /// VTK cell type id.
    pub fn vtk_type(self) -> u8 {
        match self {
            ElementKind::Quad4 => 9,
            ElementKind::Hex8 => 12,
            ElementKind::Tri3 => 5,
            ElementKind::Tet4 => 10,
        }
    }
    /// The kind of VTK cell type `t`.
    pub fn from_vtk_type(t: u8) -> Option<Self> {
        [Self::Quad4, Self::Hex8, Self::Tri3, Self::Tet4]
            .into_iter()
            .find(|k| k.vtk_type() == t)
    }
    /// Gmsh element type number.
    pub fn gmsh_type(self) -> u32 {
        match self {
            ElementKind::Tri3 => 2,
            ElementKind::Quad4 => 3,
            ElementKind::Tet4 => 4,
            ElementKind::Hex8 => 5,
        }
    }
    /// The kind of Gmsh element type `t`.
    pub fn from_gmsh_type(t: u32) -> Option<Self> {
        [Self::Quad4, Self::Hex8, Self::Tri3, Self::Tet4]
            .into_iter()
            .find(|k| k.gmsh_type() == t)
    }
    /// Abaqus/CalculiX element type written (plane stress in 2D).
    pub fn abaqus_type(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "CPS4",
            ElementKind::Tri3 => "CPS3",
            ElementKind::Hex8 => "C3D8",
            ElementKind::Tet4 => "C3D4",
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
        let stem = base.trim_end_matches(['R', 'H', 'I', 'T']);
        match stem {
            "C3D8" => Some(ElementKind::Hex8),
            "C3D4" => Some(ElementKind::Tet4),
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
        }
    }
    /// The faces (edges in 2D) of the element, by local node, outward (see the type's doc).
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self {
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
            ElementKind::Tet4 => &[&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[2, 0, 3]],
        }
    }
    /// Scale of the scaled Jacobian: 1 for the ideal element's corners (square, cube,
    /// equilateral triangle and tetrahedron).
    pub fn scaled_jacobian_factor(self) -> f64 {
        match self {
            ElementKind::Quad4 | ElementKind::Hex8 => 1.0,
            ElementKind::Tri3 => 2.0 / 3f64.sqrt(),
            ElementKind::Tet4 => std::f64::consts::SQRT_2,
        }
    }
    /// The usual acceptance bound on the scaled Jacobian (hexahedra 0.5, quadrilaterals 0.3,
    /// simplices 0.2).
    pub fn scaled_jacobian_bound(self) -> f64 {
        match self {
            ElementKind::Hex8 => 0.5,
            ElementKind::Quad4 => 0.3,
            ElementKind::Tri3 | ElementKind::Tet4 => 0.2,
        }
    }
    /// For each corner, the `D` neighbouring corners whose edge vectors span the corner's
    /// Jacobian matrix (right-handed for a valid element).
    pub fn corner_frames(self) -> &'static [&'static [usize]] {
        match self {
            ElementKind::Quad4 => &[&[1, 3], &[2, 0], &[3, 1], &[0, 2]],
            ElementKind::Hex8 => &[
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
            ElementKind::Tet4 => &[&[1, 2, 3], &[2, 0, 3], &[0, 1, 3], &[0, 2, 1]],
        }
    }
    /// Name used in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "quad4",
            ElementKind::Hex8 => "hex8",
            ElementKind::Tri3 => "tri3",
            ElementKind::Tet4 => "tet4",
        }
    }
    /// The kind named `name` (as written by [`ElementKind::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::Quad4, Self::Hex8, Self::Tri3, Self::Tet4]
            .into_iter()
            .find(|k| k.name() == name)
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
}

//! Finite element meshes: types, automatic meshing of the mean shape (section 2.4), and
//! element quality by corner Jacobians (section 5.3).

pub mod hexmesh;
pub mod quadmesh;
pub mod quality;

use crate::geometry::Point;
use serde::{Deserialize, Serialize};

/// Element types. Node numbering follows VTK.
///
/// ```text
/// Quad4 (counter-clockwise)     Hex8 (bottom 0-3 counter-clockwise seen from +z, top 4-7 above)
///   3 ------- 2                      7 ------- 6
///   |         |                     /|        /|
///   |         |                    4 ------- 5 |
///   |         |                    | 3 ------|- 2
///   0 ------- 1                    |/        |/
///                                  0 ------- 1
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElementKind {
    /// Bilinear quadrilateral (2D).
    Quad4,
    /// Trilinear hexahedron (3D).
    Hex8,
}

impl ElementKind {
    /// Nodes per element.
    pub fn nodes(self) -> usize {
        match self {
            ElementKind::Quad4 => 4,
            ElementKind::Hex8 => 8,
        }
    }
    /// VTK cell type id.
    pub fn vtk_type(self) -> u8 {
        match self {
            ElementKind::Quad4 => 9,
            ElementKind::Hex8 => 12,
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
        }
    }
    /// Name used in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "quad4",
            ElementKind::Hex8 => "hex8",
        }
    }
    /// The kind named `name` (as written by [`ElementKind::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "quad4" => Some(ElementKind::Quad4),
            "hex8" => Some(ElementKind::Hex8),
            _ => None,
        }
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
}

/// A quadrilateral mesh.
pub type QuadMesh = FeMesh<2>;
/// A hexahedral mesh.
pub type HexMesh = FeMesh<3>;

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
        }
    }
}

//! Element kinds: node counts and numbering, faces, corner frames of the Jacobians.

use serde::{Deserialize, Serialize};

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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
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
pub(crate) const HEX20_EDGES: [[usize; 3]; 12] = [
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
pub(crate) const TET10_EDGES: [[usize; 3]; 6] = [
    [0, 1, 4],
    [1, 2, 5],
    [2, 0, 6],
    [0, 3, 7],
    [1, 3, 8],
    [2, 3, 9],
];

/// Every kind.
pub(crate) const ALL_KINDS: [ElementKind; 6] = [
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
    /// (`4 mid - 3 corner - other corner`, see [`crate::mesh::quality`]).
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

//! Finite element meshes: element kinds, the mesh type and its sets, automatic meshing of the
//! mean shape (section 2.4), the morph by a B-spline FFD (eq. 9), element quality by corner
//! Jacobians (section 5.3), and the repair of poor elements.
//!
//! | file | what it computes |
//! |---|---|
//! | `element` | [`ElementKind`]: node numbering (diagrams), faces, corner frames |
//! | `element_size` | [`ElementSize`]: the mean mesh's element size from a length, a share or the thickness |
//! | `fe_mesh` | [`FeMesh`] and [`MeshSets`] |
//! | `boundary` | the boundary faces of a mesh, outward |
//! | `cut_face` | the mean mesh's face on a population's common cut: the `CUT` node set and surface |
//! | `boundary_fit` | the boundary nodes moved onto the subject after the morph, the interior relaxed |
//! | `quad_mesh` | quadrilateral mesh of a 2D outline |
//! | `hex_mesh` | hexahedral mesh of a closed surface |
//! | `mean_mesh` | the mesh of the mean shape, by dimension |
//! | `quality` | corner Jacobians, scaled Jacobians, edge ratios (section 5.3) |
//! | `sets` | node sets, element sets and surfaces from a TOML description |
//! | `load_case` | a load case: node sets by geometry, displacements, forces, the rigid-body holds |
//! | `morph` | [`Morpher`]: the mesh carried by boundary correspondences (eq. 9) |
//! | `repair` | untangling and improving poor elements |
//! | `join` | a voxel mesh's parts joined to a mesh by a tie (a surface and the nodes near it) |
//! | `voxel_mesh` | one hexahedron per voxel of a label map's parts (voxel FE models) |

mod boundary;
mod boundary_fit;
mod cut_face;
mod element;
pub mod element_size;
mod fe_mesh;
pub mod hex_mesh;
mod join;
mod load_case;
mod mean_mesh;
mod morph;
pub mod quad_mesh;
pub mod quality;
pub mod repair;
pub mod sets;
mod voxel_mesh;

pub use boundary::{BoundaryFace, FacePair, boundary_faces, boundary_surface, face_pairs};
pub use boundary_fit::{BoundaryFit, fit_boundary};
pub(crate) use cut_face::cut_face_on_its_plane;
pub use cut_face::{CUT_SET, flatten_cut_face, mark_cut_face};
pub use element::ElementKind;
pub(crate) use element::{ALL_KINDS, HEX20_EDGES, TET10_EDGES};
pub use element_size::{ElementSize, resolve_element_size};
pub use fe_mesh::{FeMesh, HexMesh, MAX_SET_NAME, MeshSets, QuadMesh, set_name_problem};
pub use hex_mesh::{HexMeshParams, hex_mesh};
pub use join::{TiedMesh, join_tied};
pub use load_case::{AXES, AppliedLoadCase, Condition, LoadCase, NodeSelector, PlaneSelector};
pub use mean_mesh::{
    MEAN_MESH_COVERAGE, MEAN_MESH_EDGE_RATIO_MAX, MEAN_MESH_SCALED_JACOBIAN_MIN,
    MEAN_MESH_SCALED_JACOBIAN_TARGET, mesh_mean_shape,
};
pub use morph::{Correspondence, MAX_STIFFENINGS, Morph, Morpher, STIFFEN_FACTOR};
pub use quad_mesh::{QuadMeshParams, quad_mesh};
pub use quality::{ElementQuality, QualityDistribution, QualitySummary, mesh_quality, summarize};
pub use repair::{RepairParams, RepairReport, repair, repair_with_quality};
pub use sets::SetsConfig;
pub use voxel_mesh::{MAX_VOXEL_ELEMENTS, VoxelPart, voxel_mesh};

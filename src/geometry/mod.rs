//! Shapes as points plus connectivity; normals, closest points, rays and similarities.
//!
//! A shape in `D` dimensions is a list of points and a list of boundary facets, each facet a
//! `(D-1)`-simplex given by `D` point indices: segments `[a, b]` for outlines (`D = 2`),
//! triangles `[a, b, c]` for surfaces (`D = 3`). Coordinates are in the shape's own units and
//! frame; nothing here changes them.
//!
//! | file | what it computes |
//! |---|---|
//! | `point` | vector operations, bounding boxes, centroids |
//! | `shape` | [`Shape`], its checks, sizes, and test shapes ([`uv_sphere`]) |
//! | `normals` | facet and vertex normals (section 2.1) |
//! | `closest_point` | [`ClosestPointIndex`]: exact closest points through a BVH |
//! | `query_memo` | [`QueryMemo`]: what a search remembers for the next query |
//! | `ray` | ray casts against the facets |
//! | `normal_projection` | projection along normals onto a subject |
//! | `principal_axes` | principal axes and the starting rotations of an alignment |
//! | `orientation` | closed surfaces oriented outwards, signed volume |
//! | `plane_cut` | [`cut_by_plane`]: a surface cut by a plane and closed by a flat cap |
//! | `similarity` | [`Similarity`] `t_{R,T,s}` and rotations from generators |
//! | `decimate` | vertex-clustering decimation |
//! | `surface_distance` | [`surface_distances`]: a delivered shape's distances to its subject |
//! | `thickness` | local thickness across a closed shape |
//! | `topology` | connected components, genus, floating islands dropped |

mod closest_point;
mod decimate;
mod edge_collapse;
mod normal_projection;
mod normals;
mod orientation;
mod plane_cut;
mod point;
mod principal_axes;
mod query_memo;
mod ray;
mod shape;
mod similarity;
mod surface_distance;
mod thickness;
mod topology;

pub use closest_point::{ClosestPointIndex, LEAF_FACETS, SurfacePoint};
pub use edge_collapse::collapse_short_edges;
pub use normal_projection::{COMPATIBLE_NORMALS_COS, project_along_normals};
pub use normals::{facet_normal, vertex_normals};
pub use orientation::{is_closed_surface, prepare_surface, signed_volume};
pub use plane_cut::{Plane, PlaneCut, cap_plane, cut_by_plane};
pub use point::{
    MAX_COORDINATE, Point, add, bounding_box, centroid, centroid_size, coordinate_problem, cross,
    dist2, dot, in_3d, norm, normalize, same_dim, scale, sub,
};
pub use principal_axes::{principal_axes_of, start_rotations};
pub use query_memo::QueryMemo;
pub use shape::{
    Contour2, MAX_NAME_CHARS, REFERENCE_POINTS, Shape, Surface3, display_name, hidden_char,
    median_edge_length, uv_sphere,
};
pub use similarity::{Similarity, rotation_exp};
pub use surface_distance::{SurfaceDistances, surface_distances};
pub use thickness::{local_thickness, thickness_quantile};
pub use topology::{Component, components, drop_small_components};

#[cfg(test)]
mod tests;

//! The FE mesh of the mean shape (section 2.4): quadrilaterals in 2D, hexahedra in 3D.

use crate::error::{Error, Result};
use crate::geometry::surface_distances;
use crate::geometry::{ClosestPointIndex, Shape, bounding_box, same_dim};
use crate::mesh::quality::{edge_ratio_max, mesh_quality, summarize};
use crate::mesh::repair::default_bound;
use crate::mesh::{FeMesh, QuadMeshParams, boundary_surface, quad_mesh};

/// The largest element edge ratio (longest edge over shortest) a mean mesh may have.
pub const MEAN_MESH_EDGE_RATIO_MAX: f64 = 10.0;

/// How far (in element sizes) the mean mesh's boundary and the mean shape may lie from each
/// other, at most, both ways.
pub const MEAN_MESH_COVERAGE: f64 = 1.5;

/// Meshes the mean shape (section 2.4): quadrilaterals in 2D
/// ([`quad_mesh`](fn@super::quad_mesh)), hexahedra in 3D ([`hex_mesh`](fn@super::hex_mesh),
/// closed surfaces only); `element_size` is a share of the mean's largest extent.
///
/// The mesh meets a bar or is refused: every element's scaled Jacobian at or above the
/// repair bound of its kind, edge ratios at most [`MEAN_MESH_EDGE_RATIO_MAX`], and its
/// boundary and the mean within [`MEAN_MESH_COVERAGE`] element sizes of each other both ways
/// (the mean's points to the mesh only, for an open outline). A mesh that misses it is made
/// again 10 % finer, 12 % coarser and 20 % finer; the first that meets it is returned.
///
/// # Errors
/// [`Error::Mesh`] naming what every size tried failed.
pub fn mesh_mean_shape<const D: usize>(
    mean: &Shape<D>,
    element_size: f64,
    smoothing_passes: usize,
) -> Result<FeMesh<D>> {
    let mut failures = Vec::new();
    for factor in [1.0, 0.9, 1.12, 0.8] {
        let size = element_size * factor;
        match mesh_once(mean, size, smoothing_passes) {
            Ok(m) => match meets_the_bar(&m, mean, size) {
                Ok(()) => return Ok(m),
                Err(why) => failures.push(format!("size {size:.4}: {why}")),
            },
            Err(Error::Mesh(why)) => failures.push(format!("size {size:.4}: {why}")),
            Err(e) => return Err(e),
        }
    }
    Err(Error::Mesh(format!(
        "the mesh of the mean shape misses its bar at every element size tried ({}); give          another --element-size or a template mesh (--template-mesh)",
        failures.join("; ")
    )))
}

/// Whether `mesh` of `mean` (element size `size`, a share of the mean's largest extent)
/// meets the bar of [`mesh_mean_shape`]; the reason when not.
fn meets_the_bar<const D: usize>(
    mesh: &FeMesh<D>,
    mean: &Shape<D>,
    size: f64,
) -> std::result::Result<(), String> {
    let q = summarize(&mesh_quality(mesh));
    let bound = default_bound(mesh.kind);
    if q.scaled_jacobian_min.is_nan() || q.scaled_jacobian_min < bound {
        return Err(format!(
            "smallest scaled Jacobian {:.3} below {bound}",
            q.scaled_jacobian_min
        ));
    }
    let ratio = edge_ratio_max(mesh);
    if ratio.is_nan() || ratio > MEAN_MESH_EDGE_RATIO_MAX {
        return Err(format!(
            "edge ratio {ratio:.1} above {MEAN_MESH_EDGE_RATIO_MAX}"
        ));
    }
    let (lo, hi) = bounding_box(&mean.points);
    let h = size * (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let boundary = boundary_surface(mesh);
    let index = ClosestPointIndex::from_shape(mean);
    let open = D == 2 && mean.facets.len() < mean.points.len();
    let d = surface_distances(&boundary, mean, &index, !open, h);
    if d.max.is_nan() || d.max > MEAN_MESH_COVERAGE * h {
        return Err(format!(
            "its boundary and the mean lie up to {:.2} element sizes apart ({:.1} % of the \
             mean farther than one)",
            d.max / h,
            100.0 * d.share_beyond
        ));
    }
    Ok(())
}

fn mesh_once<const D: usize>(
    mean: &Shape<D>,
    element_size: f64,
    smoothing_passes: usize,
) -> Result<FeMesh<D>> {
    match D {
        2 => {
            let s2 = Shape::<2> {
                name: mean.name.clone(),
                points: mean.points.iter().map(same_dim::<D, 2>).collect(),
                facets: mean.facets.iter().map(|f| [f[0], f[1]]).collect(),
                landmarks: Vec::new(),
            };
            let m = quad_mesh(
                &s2,
                &QuadMeshParams {
                    element_size,
                    smoothing_passes,
                },
            )?;
            Ok(FeMesh {
                nodes: m.nodes.iter().map(same_dim::<2, D>).collect(),
                kind: m.kind,
                connectivity: m.connectivity,
                sets: Default::default(),
            })
        }
        _ => {
            let s3 = Shape::<3> {
                name: mean.name.clone(),
                points: mean.points.iter().map(same_dim::<D, 3>).collect(),
                facets: mean.facets.iter().map(|f| [f[0], f[1], f[2 % D]]).collect(),
                landmarks: Vec::new(),
            };
            let m = crate::mesh::hex_mesh::hex_mesh(
                &s3,
                &crate::mesh::hex_mesh::HexMeshParams {
                    element_size,
                    smoothing_passes,
                },
            )?;
            Ok(FeMesh {
                nodes: m.mesh.nodes.iter().map(same_dim::<3, D>).collect(),
                kind: m.mesh.kind,
                connectivity: m.mesh.connectivity,
                sets: Default::default(),
            })
        }
    }
}

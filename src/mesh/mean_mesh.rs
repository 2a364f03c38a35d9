//! The FE mesh of the mean shape (section 2.4): quadrilaterals in 2D, hexahedra in 3D.

use crate::error::Result;
use crate::geometry::{Shape, same_dim};
use crate::mesh::{FeMesh, QuadMeshParams, quad_mesh};

/// Meshes the mean shape: quadrilaterals in 2D ([`quad_mesh`](fn@super::quad_mesh)), hexahedra in 3D
/// ([`hex_mesh`](fn@super::hex_mesh), closed surfaces only).
pub fn mesh_mean_shape<const D: usize>(
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

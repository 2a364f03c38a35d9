//! A label map's voxel mesh of several parts ([`crate::mesh::voxel_mesh`]), written: the
//! direct route of voxel FE pipelines, beside the atlas's smooth one.

use crate::error::{Error, Result};
use crate::formats::{MeshFormat, read_image};
use crate::mesh::{FeMesh, VoxelPart, voxel_mesh};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What `atlasmesh voxel-mesh` wrote.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VoxelMeshReport {
    /// The label map.
    pub label_map: String,
    /// Voxel spacing (mm).
    pub spacing: [f64; 3],
    /// Elements and nodes.
    pub elements: usize,
    /// See `elements`.
    pub nodes: usize,
    /// Per part: its name, labels and elements.
    pub parts: Vec<(String, Vec<i64>, usize)>,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
    /// The mesh the parts were joined to by a tie, when one was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joined: Option<JoinReport>,
}

/// A mesh the voxel parts were joined to ([`crate::mesh::join_tied`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct JoinReport {
    /// The mesh file.
    pub mesh: String,
    /// Its element set in the joined mesh.
    pub name: String,
    /// Its boundary faces: the tie's surface.
    pub surface: String,
    /// The parts' nodes within the tolerance of that surface: the tie's node set.
    pub tied: String,
    /// How many nodes that is.
    pub tied_nodes: usize,
    /// mm.
    pub tolerance: f64,
}

/// A mesh to join the voxel parts to by a tie: its file, the element set its elements
/// become, the tie's tolerance (mm).
#[derive(Clone, Debug)]
pub struct JoinRequest<'a> {
    /// The mesh (`.inp`, `.vtu`, `.vtk`, `.msh`; hexahedra, world RAS mm as the label map).
    pub mesh: &'a Path,
    /// The element set of its elements (e.g. `BONE`).
    pub name: &'a str,
    /// mm: the parts' nodes within this distance of the mesh's surface are tied to it.
    pub tolerance: f64,
}

/// The voxel mesh of `parts` of the label map `image_file` ([`voxel_mesh`]; world RAS, mm),
/// written to `out` as `NAME_voxels.EXT` in every format of `formats`, each part an element
/// set. With `join`, the parts are joined to that mesh instead of written alone
/// ([`crate::mesh::join_tied`]): its elements first, then the parts', the tie's surface and
/// node set named in the report, the file `NAME_joined.EXT`.
///
/// # Errors
/// Those of reading the image and of [`voxel_mesh`] (the image named), of reading and joining
/// the mesh (the mesh named), and of the writes.
pub fn write_voxel_mesh(
    image_file: &Path,
    parts: &[VoxelPart],
    formats: &[MeshFormat],
    join: Option<&JoinRequest>,
    out: &Path,
) -> Result<(FeMesh<3>, VoxelMeshReport)> {
    let file = read_image(image_file)?;
    let source = image_file.display().to_string();
    let mesh = voxel_mesh(&file.image, parts, &source).map_err(|e| match e {
        Error::Parameter(m) if !m.starts_with(&source) => {
            Error::Parameter(format!("{source}: {m}"))
        }
        e => e,
    })?;
    let part_elements: Vec<usize> = parts
        .iter()
        .map(|p| mesh.sets.element_sets[&p.name].len())
        .collect();
    let (mesh, joined) = match join {
        None => (mesh, None),
        Some(j) => {
            let bone = crate::formats::read_fe_mesh::<3>(j.mesh)?;
            let named = |e: Error| match e {
                Error::Mesh(m) => Error::Mesh(format!("{}: {m}", j.mesh.display())),
                e => e,
            };
            let tied = crate::mesh::join_tied(&bone, j.name, &mesh, j.tolerance).map_err(named)?;
            let report = JoinReport {
                mesh: j.mesh.display().to_string(),
                name: j.name.to_string(),
                surface: tied.surface,
                tied: tied.tied,
                tied_nodes: tied.tied_nodes,
                tolerance: j.tolerance,
            };
            (tied.mesh, Some(report))
        }
    };
    let name = super::write_subject::file_name(&super::shape_name(image_file));
    let suffix = if joined.is_some() { "joined" } else { "voxels" };
    let quality = crate::mesh::mesh_quality(&mesh);
    let mut files = Vec::new();
    for f in formats {
        let path = format!("{name}_{suffix}.{}", f.extension());
        crate::formats::write_mesh(&out.join(&path), &mesh, None, &quality)?;
        files.push(path);
    }
    let report = VoxelMeshReport {
        label_map: source,
        spacing: file.image.spacing(),
        elements: mesh.num_elements(),
        nodes: mesh.nodes.len(),
        parts: parts
            .iter()
            .zip(part_elements)
            .map(|(p, e)| (p.name.clone(), p.labels.clone(), e))
            .collect(),
        files,
        joined,
    };
    Ok((mesh, report))
}

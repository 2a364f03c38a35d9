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
}

/// The voxel mesh of `parts` of the label map `image_file` ([`voxel_mesh`]; world RAS, mm),
/// written to `out` as `NAME_voxels.EXT` in every format of `formats`, each part an element
/// set.
///
/// # Errors
/// Those of reading the image and of [`voxel_mesh`] (the image named), and of the writes.
pub fn write_voxel_mesh(
    image_file: &Path,
    parts: &[VoxelPart],
    formats: &[MeshFormat],
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
    let name = super::write_subject::file_name(&super::shape_name(image_file));
    let quality = crate::mesh::mesh_quality(&mesh);
    let mut files = Vec::new();
    for f in formats {
        let path = format!("{name}_voxels.{}", f.extension());
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
            .map(|p| {
                (
                    p.name.clone(),
                    p.labels.clone(),
                    mesh.sets.element_sets[&p.name].len(),
                )
            })
            .collect(),
        files,
    };
    Ok((mesh, report))
}

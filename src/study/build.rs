//! Building an atlas from a population and writing it.

use super::params::RunParams;
use super::sets::apply_sets;
use crate::error::Result;
use crate::formats::{create_dir, write_vtp, write_vtu};
use crate::geometry::Shape;
use crate::mesh::FeMesh;
use crate::mesh::quality::{mesh_quality, summarize};
use crate::model::Atlas;
use crate::report::MeanMeshReport;
use std::path::{Path, PathBuf};

pub(crate) fn mean_mesh_report<const D: usize>(atlas: &Atlas<D>) -> MeanMeshReport {
    let q = summarize(&mesh_quality(&atlas.mesh));
    MeanMeshReport {
        nodes: atlas.mesh.nodes.len(),
        elements: atlas.mesh.num_elements(),
        element_kind: atlas.mesh.kind.name().into(),
        scaled_jacobian_min: q.scaled_jacobian_min,
        jacobian_min: q.jacobian_min,
        edge_ratio_max: crate::mesh::quality::edge_ratio_max(&atlas.mesh),
    }
}

/// The atlas of `shapes`: with `meshes` (one template volume mesh per shape, or one for the
/// first) their mean as the FE mesh (`Atlas::build_with_meshes`), else the automatic mesh.
pub(crate) fn atlas_of<const D: usize>(
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
) -> Result<Atlas<D>> {
    let mut atlas = match meshes {
        Some(m) => Atlas::build_with_meshes(shapes, &params.atlas, m)?,
        None => Atlas::build(shapes, &params.atlas)?,
    };
    if let Some(c) = &params.sets {
        apply_sets(&mut atlas, c)?;
    }
    Ok(atlas)
}

/// Builds an atlas from a population and writes it, with the mean mesh as VTU and the mean
/// outline as VTP beside it.
pub fn build<const D: usize>(
    shapes: &[Shape<D>],
    params: &RunParams,
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    build_with_meshes(shapes, None, params, atlas_path)
}

/// [`build`] with template volume meshes (one per shape, or one for the first shape).
pub fn build_with_meshes<const D: usize>(
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    let atlas = atlas_of(shapes, meshes, params)?;
    if let Some(dir) = atlas_path.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_dir(dir)?;
    }
    atlas.save(atlas_path)?;
    let stem = atlas_path.with_extension("");
    write_vtu(
        &PathBuf::from(format!("{}_mean_mesh.vtu", stem.display())),
        &atlas.mesh,
        None,
    )?;
    write_vtp(
        &PathBuf::from(format!("{}_mean.vtp", stem.display())),
        &atlas.mean_shape(),
    )?;
    Ok(atlas)
}

/// Compactness, generalization and specificity of the model of `shapes` (in correspondence;
/// up to 30 modes, 1000 random instances per mode count, seed 0), written beside the atlas
/// file `atlas_path`: `ATLAS.measures.json` and, with `plots`, `ATLAS.measures.png`. Returns
/// the measures and the JSON file's path.
pub fn write_model_measures<const D: usize>(
    shapes: &[Shape<D>],
    atlas_path: &Path,
    plots: bool,
) -> Result<(crate::eval::ShapeModelMeasures, PathBuf)> {
    let m = crate::eval::shape_model_measures(shapes, 30, 1000, 0)?;
    let json = atlas_path.with_extension("measures.json");
    m.write(&json)?;
    if plots {
        crate::report::plot_shape_model_measures(
            &atlas_path.with_extension("measures.png"),
            &m,
            "shape units",
        )?;
    }
    Ok((m, json))
}

//! Building an atlas from a population and writing it.

use super::params::RunParams;
use super::sets::apply_sets;
use crate::error::{Error, Result};
use crate::formats::{create_dir, write_vtp, write_vtu};
use crate::geometry::Shape;
use crate::mesh::quality::{mesh_quality, summarize};
use crate::mesh::{FeMesh, mesh_mean_shape, resolve_element_size};
use crate::model::Atlas;
use crate::report::MeanMeshReport;
use std::path::{Path, PathBuf};

/// The mean mesh's figures; `data_per_mean`: data units per reference unit (NaN when not
/// known).
pub(crate) fn mean_mesh_report<const D: usize>(
    atlas: &Atlas<D>,
    data_per_mean: f64,
) -> MeanMeshReport {
    let q = summarize(&mesh_quality(&atlas.mesh));
    MeanMeshReport {
        nodes: atlas.mesh.nodes.len(),
        elements: atlas.mesh.num_elements(),
        element_kind: atlas.mesh.kind.name().into(),
        scaled_jacobian_min: q.scaled_jacobian_min,
        jacobian_min: q.jacobian_min,
        edge_ratio_max: crate::mesh::quality::edge_ratio_max(&atlas.mesh),
        element_size_share: atlas.params.element_size,
        element_size: atlas.params.element_size * data_per_mean,
    }
}

/// How many units of the data one unit of the reference-frame `mean` is: the shapes' mean
/// centroid size over the mean's (the scale GPA removed).
pub fn data_per_mean<const D: usize>(shapes: &[Shape<D>], mean: &Shape<D>) -> f64 {
    let size = crate::geometry::centroid_size;
    let data = shapes.iter().map(|s| size(&s.points)).sum::<f64>() / shapes.len().max(1) as f64;
    data / size(&mean.points)
}

/// The atlas of `shapes`: with `meshes` (one template volume mesh per shape, or one for the
/// first) their mean as the FE mesh (`Atlas::build_with_meshes`), else the automatic mesh at
/// `params.element_size` (a length in the shapes' unit, a share, or from the thickness); the
/// atlas's `params.element_size` is then the share used.
pub fn atlas_of<const D: usize>(
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
) -> Result<Atlas<D>> {
    refuse_point_sets(shapes, "a mesh of the mean")?;
    let mut atlas = match meshes {
        Some(m) => Atlas::build_with_meshes(shapes, &params.atlas, m)?,
        None => {
            let mut used = params.atlas.element_size;
            let mut atlas = Atlas::build_meshed(shapes, &params.atlas, |mean| {
                used =
                    resolve_element_size(params.element_size, mean, data_per_mean(shapes, mean))?;
                mesh_mean_shape(mean, used, params.atlas.smoothing_passes)
            })?;
            atlas.params.element_size = used;
            atlas
        }
    };
    if let Some(c) = &params.sets {
        apply_sets(&mut atlas, c)?;
    }
    Ok(atlas)
}

/// An atlas of a population put on a common cut: the facets of the mean's cap
/// ([`super::cut_facets`]; empty for none) kept, and the mean mesh's face on the cut made the
/// `CUT` node set and surface ([`crate::mesh::mark_cut_face`]).
pub fn put_on_cut<const D: usize>(atlas: &mut Atlas<D>, cut_facets: &[usize]) -> Result<()> {
    if !cut_facets.is_empty() {
        atlas.cut_facets = cut_facets.to_vec();
        if atlas.has_mesh() {
            crate::mesh::mark_cut_face(&mut atlas.mesh, &atlas.mean, &atlas.facets, cut_facets)
                .map_err(|e| Error::Mesh(format!("the face of the common cut: {e}")))?;
        }
    }
    Ok(())
}

/// Builds an atlas from a population and writes it, with the mean mesh as VTU and the mean
/// outline as VTP beside it.
pub fn build<const D: usize>(
    shapes: &[Shape<D>],
    params: &RunParams,
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    build_with_meshes(shapes, None, params, &[], &[], atlas_path)
}

/// Names the atlas's landmarks by `ids` (the ids of the population's landmark files, one per
/// landmark; otherwise they stay unnamed and are paired by order).
pub(super) fn name_landmarks<const D: usize>(atlas: &mut Atlas<D>, ids: &[String]) {
    if ids.len() == atlas.landmarks.len() {
        atlas.landmark_ids = ids.to_vec();
    }
}

/// [`build`] with template volume meshes (one per shape, or one for the first shape), the
/// ids of the landmarks (see [`Atlas::landmark_ids`]) and the facets of a common cut
/// ([`super::cut_facets`]; empty for none): the mean mesh's face on the cut is the `CUT` node
/// set and surface ([`crate::mesh::mark_cut_face`]).
pub fn build_with_meshes<const D: usize>(
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
    landmark_ids: &[String],
    cut_facets: &[usize],
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    let mut atlas = atlas_of(shapes, meshes, params)?;
    name_landmarks(&mut atlas, landmark_ids);
    put_on_cut(&mut atlas, cut_facets)?;
    save_with_mean(&atlas, atlas_path)?;
    Ok(atlas)
}

/// The shape model of `shapes` alone ([`Atlas::build_model`]: no mean mesh) written to
/// `atlas_path`, with the mean shape beside it in the data's frame and unit
/// (`ATLAS_mean.vtp`; points only for point sets).
pub fn build_model<const D: usize>(
    shapes: &[Shape<D>],
    params: &RunParams,
    landmark_ids: &[String],
    atlas_path: &Path,
) -> Result<Atlas<D>> {
    let mut atlas = Atlas::build_model(shapes, &params.atlas)?;
    name_landmarks(&mut atlas, landmark_ids);
    save_with_mean(&atlas, atlas_path)?;
    Ok(atlas)
}

/// Saves `atlas` to `atlas_path` with, beside it in the data's frame and unit, its mean mesh
/// (`ATLAS_mean_mesh.vtu`, when it has one) and mean shape (`ATLAS_mean.vtp`).
pub(super) fn save_with_mean<const D: usize>(atlas: &Atlas<D>, atlas_path: &Path) -> Result<()> {
    if let Some(dir) = atlas_path.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_dir(dir)?;
    }
    atlas.save(atlas_path)?;
    if atlas.has_mesh() {
        let stem = atlas_path.with_extension("");
        write_vtu(
            &PathBuf::from(format!("{}_mean_mesh.vtu", stem.display())),
            &atlas
                .mesh
                .with_nodes(atlas.to_data_frame(&atlas.mesh.nodes)),
            None,
        )?;
    }
    write_mean_shape(atlas, atlas_path)
}

/// `ATLAS_mean.vtp` beside the atlas file: the mean shape in the data's frame and unit.
fn write_mean_shape<const D: usize>(atlas: &Atlas<D>, atlas_path: &Path) -> Result<()> {
    let mut mean = atlas.mean_shape();
    mean.points = atlas.to_data_frame(&mean.points);
    let stem = atlas_path.with_extension("");
    write_vtp(
        &PathBuf::from(format!("{}_mean.vtp", stem.display())),
        &mean,
    )
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

/// Writes `ATLAS.inputs.json` beside the atlas file `atlas_path`: the population's shapes as
/// read (topology, islands dropped, registration residuals and warnings), the registration's
/// template and the mean mesh (its element size in the data's unit with `data_per_mean`).
/// Returns its path.
pub fn write_build_facts<const D: usize>(
    atlas_path: &Path,
    inputs: &[crate::report::InputReport],
    template: Option<&str>,
    atlas: &Atlas<D>,
    data_per_mean: f64,
) -> Result<PathBuf> {
    let path = atlas_path.with_extension("inputs.json");
    let json = serde_json::json!({
        "inputs": inputs,
        "template": template,
        "mean_mesh": atlas.has_mesh().then(|| mean_mesh_report(atlas, data_per_mean)),
    });
    let text = serde_json::to_vec_pretty(&json)
        .map_err(|e| crate::error::Error::Numerical(format!("inputs.json: {e}")))?;
    crate::formats::write_atomic(&path, &text)?;
    Ok(path)
}

/// Refuses shapes without facets (point sets) for `what`, which needs surfaces or outlines:
/// they make a shape model alone.
///
/// # Errors
/// [`Error::Population`] naming the first point set.
pub(crate) fn refuse_point_sets<const D: usize>(shapes: &[Shape<D>], what: &str) -> Result<()> {
    match shapes.iter().find(|s| s.facets.is_empty()) {
        Some(s) => Err(Error::Population(format!(
            "{}: points without facets make a shape model alone (build --no-mesh, or mesh=False \
             in Python); {what} needs surfaces or outlines",
            s.name
        ))),
        None => Ok(()),
    }
}

//! Shapes the model allows, as FE models: an instance of the model for given weights (eq. 4),
//! carried to the data's frame and unit ([`Atlas::data_frame`]), the mean mesh morphed onto it
//! (eq. 9), repaired, checked and written like a fitted subject's.

use super::params::RunParams;
use super::subject::{check_valid, delivered_distances};
use super::write_subject::file_name;
use crate::error::{Error, Result};
use crate::formats::{write_mesh, write_shape};
use crate::geometry::{ClosestPointIndex, Shape, Similarity};
use crate::mesh::quality::summarize;
use crate::mesh::{Correspondence, Morpher, repair_with_quality};
use crate::model::Atlas;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One instance asked for: its name and its weights in standard deviations of each mode
/// (`w_k = sd_k sqrt(lambda_k)`; modes not given are 0).
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceSpec {
    /// The instance's name (its files' and folder's).
    pub name: String,
    /// Weights in standard deviations, one per mode from the first (shorter: the rest 0).
    pub sd: Vec<f64>,
}

/// What was made of one instance.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct InstanceReport {
    /// The instance's name.
    pub name: String,
    /// Its weights in standard deviations of each mode.
    pub sd: Vec<f64>,
    /// Smallest scaled Jacobian of the mesh written.
    pub scaled_jacobian_min: f64,
    /// Inverted elements of the mesh written (0: an invalid mesh is not written).
    pub inverted_elements: usize,
    /// Elements below the repair bound.
    pub elements_below_bound: usize,
    /// Two-way RMS distance between the mesh's boundary and the instance's surface (data's
    /// unit).
    pub mesh_rms_distance: f64,
    /// The largest of the two 95th percentiles of those distances (data's unit).
    pub mesh_p95_distance: f64,
    /// The mesh's median boundary edge (data's unit).
    pub element_size: f64,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

/// Makes and writes every instance of `specs` into `out/NAME/`: the surface (`NAME.EXT` in
/// every `params.surface_formats`) and the FE mesh (`NAME_mesh.EXT` in every
/// `params.formats`), in the data's frame and unit (the reference frame for an atlas of
/// format version 2), with the atlas's sets.
///
/// # Errors
/// [`Error::Parameter`] for more weights than modes or a weight that is not finite; the
/// errors of the morph and the repair; [`Error::Mesh`] when a mesh stays invalid (nothing is
/// written for it).
pub fn write_instances<const D: usize>(
    atlas: &Atlas<D>,
    morpher: &Morpher<D>,
    specs: &[InstanceSpec],
    params: &RunParams,
    out: &Path,
) -> Result<Vec<InstanceReport>> {
    let m = atlas.num_modes();
    if let Some(spec) = specs
        .iter()
        .find(|s| s.sd.len() > m || s.sd.iter().any(|v| !v.is_finite()))
    {
        return Err(Error::Parameter(format!(
            "instance {}: {} weights for a model of {m} modes (finite numbers of standard deviations)",
            spec.name,
            spec.sd.len()
        )));
    }
    crate::formats::create_dir(out)?;
    let _lock = crate::formats::lock_dir(out)?;
    specs
        .iter()
        .map(|spec| write_instance(atlas, morpher, spec, params, out))
        .collect()
}

/// One instance of [`write_instances`].
fn write_instance<const D: usize>(
    atlas: &Atlas<D>,
    morpher: &Morpher<D>,
    spec: &InstanceSpec,
    params: &RunParams,
    out: &Path,
) -> Result<InstanceReport> {
    let m = atlas.num_modes();
    let w: Vec<f64> = (0..m)
        .map(|k| spec.sd.get(k).copied().unwrap_or(0.0) * atlas.eigenvalues[k].sqrt())
        .collect();
    let frame = atlas.data_frame.unwrap_or_else(Similarity::identity);
    let surface = Shape {
        name: spec.name.clone(),
        points: atlas.to_data_frame(&atlas.instance(&w)),
        facets: atlas.facets.clone(),
        landmarks: atlas.landmarks.clone(),
    };
    let morph = morpher.morph(&Correspondence {
        targets: surface.points.clone(),
        partnered: Vec::new(),
        frame,
    })?;
    let mut mesh = morph.mesh;
    let mut quality = morph.quality;
    let index = ClosestPointIndex::from_shape(&surface);
    if let Some(rp) = &params.repair {
        quality = repair_with_quality(&mut mesh, Some(&index), rp, &quality)?.1;
    }
    let q = summarize(&quality);
    check_valid(&surface, &mesh, &q, params)?;
    let delivered = delivered_distances(&mesh, &surface, &index, params);
    let dist = crate::mesh::quality::distribution(&mesh, &quality);
    let base = file_name(&spec.name);
    let dir = out.join(&base);
    crate::formats::create_dir(&dir)?;
    let mut files = Vec::new();
    for f in &params.formats {
        let name = format!("{base}_mesh.{}", f.extension());
        write_mesh(&dir.join(&name), &mesh, None, &quality)?;
        files.push(format!("{base}/{name}"));
    }
    for &f in &params.surface_formats {
        let name = format!("{base}.{}", f.extension());
        write_shape(&dir.join(&name), &surface, f)?;
        files.push(format!("{base}/{name}"));
    }
    Ok(InstanceReport {
        name: spec.name.clone(),
        sd: spec.sd.clone(),
        scaled_jacobian_min: q.scaled_jacobian_min,
        inverted_elements: q.inverted_elements,
        elements_below_bound: dist.elements_below_bound,
        mesh_rms_distance: delivered.distances.rms,
        mesh_p95_distance: delivered.distances.p95,
        element_size: delivered.element_size,
        files,
    })
}

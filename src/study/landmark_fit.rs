//! A subject known by a few landmark positions only (`fit --landmarks-only`): the posterior
//! of the model given them ([`crate::fit::fit_landmarks`]), its mean shape with the per-point
//! standard deviation, and the mean mesh morphed onto it (eq. 9), repaired, checked and
//! written with the standard deviation at every node.

use super::params::RunParams;
use super::subject::check_valid;
use super::write_subject::file_name;
use crate::error::{Error, Result};
use crate::fit::fit_landmarks;
use crate::formats::landmarks::{Landmark, NamedLandmark};
use crate::formats::{ShapeFormat, write_mesh, write_shape};
use crate::geometry::{ClosestPointIndex, Point, Shape};
use crate::mesh::quality::summarize;
use crate::mesh::{Correspondence, Morpher, repair_with_quality};
use crate::model::Atlas;
use crate::report::PosteriorReport;
use std::path::Path;

/// A subject's landmarks paired with the atlas's: `(model point, position)`, the ids used,
/// and warnings for those left out.
pub type LandmarkPairs<const D: usize> = (Vec<(usize, Point<D>)>, Vec<String>, Vec<String>);

/// The model points and positions of a subject's landmarks `given` (read from `file`): by id
/// when the atlas names its landmarks (an id it lacks is left out with a warning), else by
/// rank (as many as the atlas has). Positions only: an index names a point of a shape the
/// subject does not have.
///
/// # Errors
/// [`Error::Population`] for a landmark given as an index, no landmark in common, or
/// another count than the atlas's unnamed landmarks.
pub fn pair_with_atlas<const D: usize>(
    atlas: &Atlas<D>,
    given: &[NamedLandmark<D>],
    file: &Path,
) -> Result<LandmarkPairs<D>> {
    let position = |(id, l): &NamedLandmark<D>| match l {
        Landmark::At(p) => Ok(*p),
        Landmark::Index(_) => Err(Error::Population(format!(
            "{}: landmark {id} is a point index; --landmarks-only needs positions",
            file.display()
        ))),
    };
    let mut pairs = Vec::new();
    let mut used = Vec::new();
    let mut warnings = Vec::new();
    if atlas.landmark_ids.is_empty() {
        if given.len() != atlas.landmarks.len() {
            return Err(Error::Population(format!(
                "{}: {} landmarks, the atlas has {} (unnamed, so paired by rank)",
                file.display(),
                given.len(),
                atlas.landmarks.len()
            )));
        }
        for (k, l) in given.iter().enumerate() {
            pairs.push((atlas.landmarks[k], position(l)?));
            used.push(l.0.clone());
        }
    } else {
        for l in given {
            match atlas.landmark_ids.iter().position(|id| *id == l.0) {
                Some(k) => {
                    pairs.push((atlas.landmarks[k], position(l)?));
                    used.push(l.0.clone());
                }
                None => warnings.push(format!(
                    "landmark {} is not one of the atlas's ({}): left out",
                    l.0,
                    atlas.landmark_ids.join(", ")
                )),
            }
        }
        if pairs.is_empty() {
            return Err(Error::Population(format!(
                "{}: no landmark the atlas has ({})",
                file.display(),
                atlas.landmark_ids.join(", ")
            )));
        }
    }
    Ok((pairs, used, warnings))
}

/// Fits `atlas` to the landmarks `observed` of the subject `name` (standard deviation `sd`,
/// subject units) and writes into `out`: the posterior mean surface `NAME_fit.vtp` with the
/// point data `posterior_sd` (and the other `params.surface_formats` without it), the mesh
/// `NAME_mesh.EXT` in every `params.formats` (VTU with `posterior_sd` at every node, the
/// standard deviation of the mean shape's nearest point) and the deck; subject frame and
/// units. Without a `morpher` (an atlas without a mesh), the surface alone.
///
/// # Errors
/// The errors of [`fit_landmarks`], of the morph and repair, [`Error::Mesh`] for a mesh that
/// stays invalid (nothing of it written), and those of the writes.
#[allow(clippy::too_many_arguments)]
pub fn write_landmark_fit<const D: usize>(
    atlas: &Atlas<D>,
    morpher: Option<&Morpher<D>>,
    name: &str,
    observed: &[(usize, Point<D>)],
    sd: f64,
    params: &RunParams,
    out: &Path,
) -> Result<PosteriorReport> {
    let fit = fit_landmarks(atlas, observed, sd)?;
    let surface = Shape {
        name: name.to_string(),
        points: fit.mean.clone(),
        facets: atlas.facets.clone(),
        landmarks: atlas.landmarks.clone(),
    };
    let base = file_name(name);
    crate::formats::create_dir(out)?;
    let mut files = Vec::new();
    let (mut elements, mut sj, mut inverted) = (0, f64::NAN, 0);
    if let Some(morpher) = morpher {
        let morph = morpher.morph(&Correspondence {
            targets: surface.points.clone(),
            partnered: Vec::new(),
            frame: fit.similarity,
        })?;
        let mut mesh = morph.mesh;
        let mut quality = morph.quality;
        let index = ClosestPointIndex::from_shape(&surface);
        if let Some(rp) = &params.repair {
            quality = repair_with_quality(&mut mesh, Some(&index), rp, &quality)?.1;
        }
        let q = summarize(&quality);
        check_valid(&surface, &mesh, &q, params)?;
        // Each node: the spread at the mean shape's closest point (reference frame).
        let on_mean = ClosestPointIndex::from_shape(&atlas.mean_shape());
        let node_sd: Vec<f64> = atlas
            .mesh
            .nodes
            .iter()
            .map(|p| {
                let c = on_mean.closest(p);
                let f = atlas.facets[c.facet];
                (0..D).map(|k| c.weights[k] * fit.point_sd[f[k]]).sum()
            })
            .collect();
        let mean_mesh = atlas.mesh.moved(&fit.similarity);
        for f in &params.formats {
            let file = format!("{base}_mesh.{}", f.extension());
            if *f == crate::formats::MeshFormat::Vtu {
                crate::formats::write_vtu_with_point_data(
                    &out.join(&file),
                    &mesh,
                    Some(&mean_mesh),
                    &quality,
                    &[("posterior_sd", &node_sd)],
                )?;
            } else {
                write_mesh(&out.join(&file), &mesh, Some(&mean_mesh), &quality)?;
            }
            files.push(file);
        }
        if let Some(deck) = &params.deck {
            files.push(deck.write_with_nodes(&mesh.nodes, out, &base)?);
        }
        (elements, sj, inverted) = (
            mesh.num_elements(),
            q.scaled_jacobian_min,
            q.inverted_elements,
        );
    }
    let file = format!("{base}_fit.vtp");
    crate::formats::write_vtp_with_point_data(
        &out.join(&file),
        &surface,
        &[("posterior_sd", &fit.point_sd)],
    )?;
    files.push(file);
    for &f in params
        .surface_formats
        .iter()
        .filter(|f| **f != ShapeFormat::Vtp && !surface.facets.is_empty())
    {
        let file = format!("{base}_fit.{}", f.extension());
        write_shape(&out.join(&file), &surface, f)?;
        files.push(file);
    }
    let mut sorted = fit.point_sd.clone();
    sorted.sort_by(f64::total_cmp);
    Ok(PosteriorReport {
        name: name.to_string(),
        landmarks: Vec::new(),
        landmark_sd: sd,
        landmark_rms: fit.landmark_rms,
        scale: fit.similarity.s,
        sd: fit
            .posterior
            .weights
            .iter()
            .zip(&atlas.eigenvalues)
            .map(|(w, l)| w / l.sqrt())
            .collect(),
        point_sd_median: sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN),
        point_sd_max: sorted.last().copied().unwrap_or(f64::NAN),
        elements,
        scaled_jacobian_min: sj,
        inverted_elements: inverted,
        files,
        warnings: Vec::new(),
    })
}

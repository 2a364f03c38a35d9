//! One registration of a template to a target (section 2.1, eq. 2), written out: the deformed
//! template, the target resampled at the template's points, and `registration.json`.

use super::attach_landmarks;
use crate::error::{Error, Result};
use crate::formats::{create_dir, write_atomic, write_vtp};
use crate::geometry::{ClosestPointIndex, Shape};
use crate::register::{RegisterParams, register};
use std::path::{Path, PathBuf};

/// What [`register_pair`] did.
#[derive(Clone, Debug)]
pub struct PairRegistration {
    /// The template's name.
    pub template: String,
    /// The target's name.
    pub target: String,
    /// RMS distance of the deformed template's points to the target at the last update
    /// (target units).
    pub final_rms: f64,
    /// The deformed template against the target, both ways (target units).
    pub residuals: crate::register::RegistrationResiduals,
}

/// Registers `shapes[0]` (the template) to `shapes[1]` (the target), with the landmarks of
/// `landmarks` (one file per shape, or none) and `grid` control points along the longest axis
/// (default by dimension). Writes `deformed_template.vtp`, `correspondence.vtp` (the target
/// resampled at the template's points) and `registration.json` (pre-alignment, mean squared
/// distance per update, alignment misfit, residuals both ways) into `out`.
pub fn register_pair<const D: usize>(
    mut shapes: Vec<Shape<D>>,
    landmarks: &[PathBuf],
    grid: Option<usize>,
    out: &Path,
) -> Result<PairRegistration> {
    if shapes.len() != 2 {
        return Err(Error::Population(
            "register: the template and target files must hold one shape each".into(),
        ));
    }
    attach_landmarks(&mut shapes, landmarks)?;
    let (template, target) = (&shapes[0], &shapes[1]);
    let index = ClosestPointIndex::from_shape(target);
    let defaults = RegisterParams::for_dimension(D);
    let r = register(
        template,
        target,
        &index,
        &RegisterParams {
            grid: grid.unwrap_or(defaults.grid),
            ..defaults
        },
    )?;
    create_dir(out)?;
    let deformed = Shape {
        name: template.name.clone(),
        points: r.deformed.clone(),
        facets: template.facets.clone(),
        landmarks: template.landmarks.clone(),
    };
    write_vtp(&out.join("deformed_template.vtp"), &deformed)?;
    write_vtp(
        &out.join("correspondence.vtp"),
        &r.resampled(template, target),
    )?;
    let residuals = r.residuals(template, target, &index);
    let json = serde_json::json!({
        "template": template.name,
        "target": target.name,
        "points": template.points.len(),
        "landmarks": template.landmarks.len(),
        "pre_alignment": {
            "scale": r.similarity.s,
            "rotation": r.similarity.r.iter().map(|row| row.to_vec()).collect::<Vec<_>>(),
            "translation": r.similarity.t.to_vec(),
        },
        "mean_squared_distance": r.history,
        "alignment_misfit": r.misfit,
        "residuals": residuals,
    });
    let text = serde_json::to_string_pretty(&json)
        .map_err(|e| Error::Numerical(format!("registration.json: {e}")))?;
    write_atomic(&out.join("registration.json"), text.as_bytes())?;
    Ok(PairRegistration {
        template: template.name.clone(),
        target: target.name.clone(),
        final_rms: r.history.last().copied().unwrap_or(0.0).sqrt(),
        residuals,
    })
}

//! The schema of `posterior.json`, the report of `atlasmesh fit --landmarks-only`: each
//! subject's model given its landmarks, its spread and its mesh.

use super::FailedSubject;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

use super::schema::f64_or_nan;

/// One subject fitted to its landmarks alone.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PosteriorReport {
    /// The subject's name.
    pub name: String,
    /// The landmarks used (ids, or ranks when the atlas's landmarks are unnamed).
    pub landmarks: Vec<String>,
    /// The landmarks' standard deviation assumed (subject units).
    #[serde(deserialize_with = "f64_or_nan")]
    pub landmark_sd: f64,
    /// RMS distance between the given landmarks and the posterior mean's (subject units).
    #[serde(deserialize_with = "f64_or_nan")]
    pub landmark_rms: f64,
    /// The scale of the similarity from the reference frame to the subject.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scale: f64,
    /// The posterior mean's weights in standard deviations of each mode.
    pub sd: Vec<f64>,
    /// The median over the model's points of the posterior standard deviation of a point's
    /// position (subject units): how much the landmarks leave open.
    #[serde(deserialize_with = "f64_or_nan")]
    pub point_sd_median: f64,
    /// The largest posterior standard deviation of a point's position (subject units).
    #[serde(deserialize_with = "f64_or_nan")]
    pub point_sd_max: f64,
    /// Elements of the mesh written (0 for an atlas without a mesh).
    pub elements: usize,
    /// Smallest scaled Jacobian of the mesh written.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_min: f64,
    /// Inverted elements of the mesh written (always 0: an invalid mesh is not written).
    pub inverted_elements: usize,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
    /// What a user should know (landmarks the atlas does not have, left out).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// `posterior.json`: every subject of a `fit --landmarks-only` run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PosteriorRunReport {
    /// The atlas file.
    pub atlas: String,
    /// 2 or 3.
    pub dimension: usize,
    /// Modes of the model.
    pub modes: usize,
    /// Subjects fitted.
    pub subjects: Vec<PosteriorReport>,
    /// Subjects that failed, with the reason.
    #[serde(default)]
    pub failed: Vec<FailedSubject>,
    /// Subjects skipped because their outputs were complete.
    #[serde(default)]
    pub resumed: usize,
    /// The shard (`I/N`) this report covers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// The version of atlasmesh that made it.
    pub atlasmesh_version: String,
}

impl PosteriorRunReport {
    /// Writes the report as pretty JSON (through a temporary file and a rename).
    pub fn write(&self, path: &Path) -> Result<()> {
        super::schema::write_pretty(path, self, "posterior report")
    }
}

//! The schema of `instances.json`, the report of `atlasmesh instance` and `atlasmesh sample`:
//! the shapes of the model made, their weights and their meshes' quality.

use super::FailedSubject;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

use super::schema::f64_or_nan;

/// What was made of one instance of the model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct InstanceReport {
    /// The instance's name (its folder's and files').
    pub name: String,
    /// Its weights in standard deviations of each mode (`w_k / sqrt(lambda_k)`; modes not
    /// listed are 0).
    pub sd: Vec<f64>,
    /// Its Mahalanobis distance to the mean, `sqrt(sum sd_k^2)`.
    #[serde(deserialize_with = "f64_or_nan")]
    pub mahalanobis: f64,
    /// Elements of the mesh written.
    pub elements: usize,
    /// Smallest scaled Jacobian of the mesh written.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_min: f64,
    /// Smallest scaled Jacobian of the morph, before the repair.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_min_before_repair: f64,
    /// Inverted elements of the mesh written (always 0: an invalid mesh is not written).
    pub inverted_elements: usize,
    /// The scaled-Jacobian bound of the repair (0 without repair).
    #[serde(deserialize_with = "f64_or_nan")]
    pub repair_bound: f64,
    /// Elements below the repair bound after the repair (0 when the repair reached it).
    pub elements_below_repair_bound: usize,
    /// Elements below the usual acceptance bound of their kind (hexahedra 0.5,
    /// quadrilaterals 0.3, simplices 0.2).
    pub elements_below_bound: usize,
    /// Two-way RMS distance between the mesh's boundary and the instance's surface (data's
    /// unit, e.g. mm).
    #[serde(deserialize_with = "f64_or_nan")]
    pub mesh_rms_distance: f64,
    /// The larger of the two directions' 95th-percentile distances (data's unit).
    #[serde(deserialize_with = "f64_or_nan")]
    pub mesh_p95_distance: f64,
    /// The largest distance either way (data's unit).
    #[serde(deserialize_with = "f64_or_nan")]
    pub mesh_max_distance: f64,
    /// RMS distance of the mesh's boundary nodes to the instance's surface: how closely the
    /// morph put them on it (data's unit; the RMS distance above adds the faces' chordal
    /// error between the nodes).
    #[serde(deserialize_with = "f64_or_nan")]
    pub boundary_node_rms_distance: f64,
    /// The largest distance of a boundary node to the instance's surface (data's unit).
    #[serde(deserialize_with = "f64_or_nan")]
    pub boundary_node_max_distance: f64,
    /// The mesh's element size, the median edge of its boundary (data's unit).
    #[serde(deserialize_with = "f64_or_nan")]
    pub element_size: f64,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

/// How the weights of `atlasmesh sample` were drawn.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sampling {
    /// Samples drawn (over every shard).
    pub n: usize,
    /// The seed of the random stream (ChaCha8).
    pub seed: u64,
    /// The bound of every weight in standard deviations (a normal truncated there), if any.
    pub max_sd: Option<f64>,
}

/// Figures over the instances of a run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct InstancesSummary {
    /// Instances written.
    pub written: usize,
    /// Instances that failed (see `failed`).
    pub failed: usize,
    /// Instances skipped because their outputs were complete (resume).
    pub resumed: usize,
    /// Instances whose mesh has an element below the repair bound.
    pub below_repair_bound: usize,
    /// The smallest scaled Jacobian over every mesh written.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_min: f64,
    /// The largest ratio of a mesh's boundary RMS distance to its element size.
    #[serde(deserialize_with = "f64_or_nan")]
    pub mesh_rms_distance_per_element_max: f64,
    /// The largest ratio of a mesh's boundary nodes' RMS distance to its element size.
    #[serde(deserialize_with = "f64_or_nan")]
    pub boundary_node_rms_distance_per_element_max: f64,
}

impl InstancesSummary {
    /// The summary of `instances` and `failed` failures.
    pub fn of(instances: &[InstanceReport], failed: usize) -> Self {
        let min = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::NAN, f64::min);
        let max = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::NAN, f64::max);
        InstancesSummary {
            written: instances.len(),
            failed,
            resumed: 0,
            below_repair_bound: instances
                .iter()
                .filter(|r| r.elements_below_repair_bound > 0)
                .count(),
            scaled_jacobian_min: min(&mut instances.iter().map(|r| r.scaled_jacobian_min)),
            mesh_rms_distance_per_element_max: max(&mut instances
                .iter()
                .map(|r| r.mesh_rms_distance / r.element_size)),
            boundary_node_rms_distance_per_element_max: max(&mut instances
                .iter()
                .map(|r| r.boundary_node_rms_distance / r.element_size)),
        }
    }
}

/// `instances.json`: the instances of one run of `atlasmesh instance` or `atlasmesh sample`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct InstancesReport {
    /// The atlas file.
    pub atlas: String,
    /// 2 or 3.
    pub dimension: usize,
    /// Modes of the model.
    pub modes: usize,
    /// The eigenvalues of the modes (reference frame, largest side 1, squared).
    pub eigenvalues: Vec<f64>,
    /// Whether the instances are in the data's unit (an atlas of format 3); else in the
    /// atlas's reference frame.
    pub data_unit: bool,
    /// How the weights were drawn (`atlasmesh sample`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sampling: Option<Sampling>,
    /// The shard (`I/N`) of a sampled population.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// The run's parameters (morph, repair, formats).
    pub parameters: serde_json::Value,
    /// Figures over every instance.
    pub summary: InstancesSummary,
    /// Instances that failed, with the reason.
    #[serde(default)]
    pub failed: Vec<FailedSubject>,
    /// Every instance written.
    pub instances: Vec<InstanceReport>,
    /// The version of atlasmesh that made it.
    pub atlasmesh_version: String,
}

impl InstancesReport {
    /// Writes the report as pretty JSON (through a temporary file and a rename).
    pub fn write(&self, path: &Path) -> Result<()> {
        super::schema::write_pretty(path, self, "instances report")
    }
}

//! The `report.json` schema of `atlasmesh materials`: the map's summary, the load case, and
//! the solve (the solver's run, the reaction forces, the stiffness).

use crate::materials::MaterialSummary;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What `atlasmesh materials` wrote: the map's summary and the files.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MaterialsReport {
    /// atlasmesh's version.
    pub version: String,
    /// The mesh file mapped.
    pub mesh: String,
    /// Its element kind and count.
    pub element_kind: String,
    /// The map.
    pub materials: MaterialSummary,
    /// The load case applied (as read), when one was given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_case: Option<crate::mesh::LoadCase>,
    /// The node counts of the load case's sets.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub load_sets: std::collections::BTreeMap<String, usize>,
    /// The solve, when CalculiX ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solve: Option<SolveReport>,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

/// What a solve gave: the solver's run and the reaction forces (N) of the load case's sets.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// The solver run (`ccx` and where it was found).
    pub solver: String,
    /// The deck solved, relative to the output folder.
    pub deck: String,
    /// Wall time of the solver (s).
    pub seconds: f64,
    /// The solver's peak resident memory (MB), as the system reports it for the child.
    pub peak_memory_mb: f64,
    /// The total reaction force (N; x, y, z, world) of each displacement set and rigid-body
    /// anchor.
    pub reactions: BTreeMap<String, [f64; 3]>,
    /// The loaded set: the first with a non-zero displacement.
    pub loaded_set: String,
    /// Its axis (`x`, `y` or `z`).
    pub axis: String,
    /// Its displacement (mm).
    pub displacement_mm: f64,
    /// Its reaction along the axis (N).
    pub reaction_n: f64,
    /// The stiffness: `|reaction / displacement|` (N/mm).
    pub stiffness_n_per_mm: f64,
    /// The nodes of the load case's ties that CalculiX found no face for (they stay free),
    /// as it lists them in `NAME_WarnNodeMissTiedContact.nam`.
    #[serde(default)]
    pub untied_nodes: usize,
    /// The largest nodal displacement's magnitude (mm), from the `.frd` results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub largest_displacement_mm: Option<f64>,
}

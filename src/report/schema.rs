//! The schema of `report.json` (fixed field names, for scripts) and of the shape-model
//! measures file, and their writing.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Per-subject figures.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SubjectReport {
    /// The subject's name (its file stem; FILE.SHAPE for a file of several shapes).
    pub name: String,
    /// Correspondence updates of Algorithm 1.
    pub iterations: usize,
    /// Wall time of the fit (seconds).
    #[serde(deserialize_with = "f64_or_nan")]
    pub fit_seconds: f64,
    /// Wall time of the subject's whole processing in a run: its fit, morph, repair, checks
    /// and files (seconds; the reading of its file not included). NaN where not measured.
    #[serde(default = "nan", deserialize_with = "f64_or_nan")]
    pub seconds: f64,
    /// The process's heap at its peak while the subject was processed (MB, 10⁶ bytes; what
    /// the run holds, the atlas included): measured by the command line when it makes one
    /// subject at a time (`--jobs 1`), absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heap_peak_mb: Option<f64>,
    /// `E_d` (eq. 6) at the end of the fit, subject units squared.
    #[serde(deserialize_with = "f64_or_nan")]
    pub e_d: f64,
    /// Two-way RMS distance between the fitted instance and the subject (subject units).
    #[serde(deserialize_with = "f64_or_nan")]
    pub rms_distance: f64,
    /// `rms_distance` / the subject's bounding-box diagonal.
    #[serde(deserialize_with = "f64_or_nan")]
    pub rms_distance_relative: f64,
    /// Correlation of normals between mean and subject at corresponding points (eq. 13).
    #[serde(deserialize_with = "f64_or_nan")]
    pub normal_correlation: f64,
    /// Baseline (with `--baselines`): normal correlation of the similarity-ICP correspondence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_correlation_icp: Option<f64>,
    /// Baseline (with `--baselines`): normal correlation of the FFD-registration
    /// correspondence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_correlation_ffd: Option<f64>,
    /// Smallest corner Jacobian of the mesh written (subject units^D).
    #[serde(deserialize_with = "f64_or_nan")]
    pub jacobian_min: f64,
    /// Smallest scaled Jacobian of the mesh written.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_min: f64,
    /// Elements of the mesh written with a non-positive corner Jacobian.
    pub inverted_elements: usize,
    /// Inverted elements before the repair.
    pub inverted_before_repair: usize,
    /// Smallest scaled Jacobian before the repair.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_min_before_repair: f64,
    /// How far the repair moved boundary nodes off the subject's surface: the largest
    /// increase of a node's distance to it (subject units; 0 without repair).
    #[serde(deserialize_with = "f64_or_nan")]
    pub surface_distance_change: f64,
    /// `surface_distance_change` over the mesh's median edge length.
    #[serde(default)]
    #[serde(deserialize_with = "f64_or_nan")]
    pub surface_distance_change_edges: f64,
    /// The scaled Jacobian bound of the repair (0 without repair).
    #[serde(default)]
    #[serde(deserialize_with = "f64_or_nan")]
    pub repair_bound: f64,
    /// Whether any element was below the bound before the repair (then nodes were moved).
    #[serde(default)]
    pub repaired: bool,
    /// The `alpha` of eq. 9 the morph used (the requested one unless that inverted an
    /// element; see `Morpher::morph`).
    #[serde(deserialize_with = "f64_or_nan")]
    pub morph_alpha: f64,
    /// Whether the morph had to stiffen (`morph_alpha` above the requested `alpha`).
    #[serde(default)]
    pub morph_escalated: bool,
    /// Counts of the elements' smallest corner scaled Jacobians in 40 bins of width 0.05
    /// from -1 to 1 (bin `k` covers `[-1 + 0.05 k, -1 + 0.05 (k + 1))`, the last includes 1).
    #[serde(default)]
    pub scaled_jacobian_histogram: Vec<u32>,
    /// 1st percentile of the elements' smallest scaled Jacobians.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_p01: f64,
    /// 5th percentile of the elements' smallest scaled Jacobians.
    #[serde(deserialize_with = "f64_or_nan")]
    pub scaled_jacobian_p05: f64,
    /// The largest element edge ratio (longest edge over shortest) of the mesh written.
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub edge_ratio_max: f64,
    /// Elements below the usual acceptance bound of their kind (hexahedra 0.5,
    /// quadrilaterals 0.3, simplices 0.2).
    pub elements_below_bound: usize,
    /// The delivered mesh against the subject: two-way RMS distance between the boundary of
    /// the mesh written and the subject's surface (subject units; subject → mesh only for a
    /// partial subject or an open outline).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub mesh_rms_distance: f64,
    /// `mesh_rms_distance` / the subject's bounding-box diagonal.
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub mesh_rms_distance_relative: f64,
    /// The larger of the two directions' 95th-percentile distances between the mesh's
    /// boundary and the subject (subject units).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub mesh_p95_distance: f64,
    /// The largest distance either way between the mesh's boundary and the subject (subject
    /// units).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub mesh_max_distance: f64,
    /// The share of the subject's points farther from the mesh than one element size.
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub mesh_share_beyond_element: f64,
    /// The element size of the mesh written: the median edge length of its boundary (subject
    /// units).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub element_size: f64,
    /// Which of the checks of `success` failed: `fit` (the instance farther than its bound,
    /// `max_instance_distance` of the diagonal, two-way RMS), `mesh_distance` (the mesh
    /// farther than `max_mesh_distance`), `mesh_farther_than_fit` (the delivered mesh
    /// farther from the subject than the fitted instance, two-way RMS, by more than a tenth of
    /// an element size), `mesh_quality` (inverted elements, non-finite nodes, or elements
    /// below the repair bound).
    #[serde(default)]
    pub failed_checks: Vec<String>,
    /// Every check passed: the delivered mesh is within its distance bound of the subject and
    /// of valid quality (see `failed_checks`).
    pub success: bool,
    /// When the fit was not close (above 0.75 % of the diagonal): the two-way RMS distance of
    /// a fit of the subject's mirror image (subject units).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mirrored_rms_distance: Option<f64>,
    /// What a user should know about this subject (a subject that may be mirrored).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// For a subject read from a label map: its smallest voxel spacing (mm), the unit of the
    /// distances in voxels its page shows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub voxel_size: Option<f64>,
    /// With an atlas built on a common cut: where the subject's mesh ends and how much of the
    /// atlas the subject covers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atlas_cut: Option<SubjectCut>,
    /// The mesh's materials from the subject's CT: the recipe, the figures and the checks
    /// (whose findings are among `warnings` too).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub materials: Option<crate::materials::MaterialSummary>,
    /// Whether the last inner loop of Algorithm 1 met its tolerance.
    pub converged: bool,
    /// `E_d` at every iteration.
    pub e_d_history: Vec<f64>,
    /// The fit's shape weights in standard deviations of each mode (`w_k / sqrt(lambda_k)`,
    /// eq. 4): the subject's coordinates in the shape space.
    #[serde(default)]
    pub sd: Vec<f64>,
    /// The fit's pose (eq. 5): the atlas's reference frame to the subject's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<Pose>,
    /// The fold that held the subject out in a k-fold cross-validation (1 to the number of
    /// folds; absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fold: Option<usize>,
    /// Output files of this subject, relative to the report.
    pub files: Vec<String>,
}

/// A fit's pose `t_{R,T,s}` (eq. 5): `x_subject = s R x + T` takes a point `x` of the atlas's
/// reference frame (the mean shape's coordinates) to the subject's frame and unit (its file's:
/// mm, world RAS for a label map). Instances of the model's shape space are posed by it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// `s` (subject unit per reference unit).
    pub scale: f64,
    /// `R`, row-major, D × D, `det R = +1`.
    pub rotation: Vec<Vec<f64>>,
    /// `T` (subject unit).
    pub translation: Vec<f64>,
    /// The homogeneous (D + 1) × (D + 1) matrix `[[s R, T], [0, 1]]`, row-major, as VTK,
    /// PyVista and ITK apply transforms.
    pub matrix: Vec<Vec<f64>>,
}

impl Pose {
    /// The pose of the similarity `t` (reference frame to subject frame).
    pub fn of<const D: usize>(t: &crate::geometry::Similarity<D>) -> Self {
        let rotation: Vec<Vec<f64>> = t.r.iter().map(|row| row.to_vec()).collect();
        let mut matrix: Vec<Vec<f64>> =
            t.r.iter()
                .zip(&t.t)
                .map(|(row, ti)| row.iter().map(|v| t.s * v).chain([*ti]).collect())
                .collect();
        matrix.push((0..=D).map(|k| if k == D { 1.0 } else { 0.0 }).collect());
        Pose {
            scale: t.s,
            rotation,
            translation: t.t.to_vec(),
            matrix,
        }
    }
}

/// The fitted subjects' shape scores as CSV: a header `name,mode_1,...,mode_M`, then one
/// row per subject with its weights in standard deviations ([`SubjectReport::sd`]); `M` is
/// the most modes any subject has, a subject with fewer leaves the rest empty. Names are
/// quoted when they hold a comma, a quote or a line break (RFC 4180).
pub fn scores_csv(subjects: &[SubjectReport]) -> String {
    scores_table(subjects.iter().map(|s| (s.name.as_str(), s.sd.as_slice())))
}

/// [`scores_csv`] of `(name, scores)` rows.
fn scores_table<'a>(rows: impl Iterator<Item = (&'a str, &'a [f64])> + Clone) -> String {
    use std::fmt::Write as _;
    let m = rows.clone().map(|(_, sd)| sd.len()).max().unwrap_or(0);
    let mut out = String::from("name");
    for k in 1..=m {
        let _ = write!(out, ",mode_{k}");
    }
    out.push('\n');
    for (name, sd) in rows {
        if name.contains([',', '"', '\n', '\r']) {
            let _ = write!(out, "\"{}\"", name.replace('"', "\"\""));
        } else {
            out.push_str(name);
        }
        for k in 0..m {
            out.push(',');
            if let Some(v) = sd.get(k) {
                let _ = write!(out, "{v}");
            }
        }
        out.push('\n');
    }
    out
}

/// Figures over all subjects.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// Subjects reported.
    pub subjects: usize,
    /// Subjects whose every check passed (see `failed_checks` of each subject).
    pub succeeded: usize,
    /// Subjects whose mesh has no inverted element.
    pub meshes_valid: usize,
    /// Subjects that failed (batch fit: see `failed` in the report).
    #[serde(default)]
    pub failed: usize,
    /// Subjects skipped because their outputs were complete (resume).
    #[serde(default)]
    pub resumed: usize,
    /// Subjects whose mesh needed repair.
    #[serde(default)]
    pub repaired: usize,
    /// Subjects still below the repair bound after the repair.
    #[serde(default)]
    pub below_repair_bound: usize,
    /// Subjects whose fitted instance is farther than its bound (`fit` in `failed_checks`).
    #[serde(default)]
    pub failed_fit: usize,
    /// Subjects whose delivered mesh is farther than one of its bounds (`mesh_distance` or
    /// `mesh_farther_than_fit`).
    #[serde(default)]
    pub failed_mesh_distance: usize,
    /// Subjects whose delivered mesh is not of valid quality (`mesh_quality`).
    #[serde(default)]
    pub failed_mesh_quality: usize,
    /// Subjects whose morph had to stiffen (`morph_escalated`).
    #[serde(default)]
    pub morph_escalations: usize,
    /// Subjects whose last inner loop of Algorithm 1 did not meet its tolerance.
    #[serde(default)]
    pub not_converged: usize,
    /// Median fit time (seconds).
    #[serde(deserialize_with = "f64_or_nan")]
    pub median_fit_seconds: f64,
    /// The subjects' [`SubjectReport::seconds`] added up: the run's work (seconds; NaN
    /// where one was not measured).
    #[serde(default = "nan", deserialize_with = "f64_or_nan")]
    pub subject_seconds: f64,
    /// The largest [`SubjectReport::heap_peak_mb`] (MB), when every subject has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heap_peak_mb: Option<f64>,
    /// Median two-way RMS distance of the fitted instance over the subject's diagonal.
    #[serde(deserialize_with = "f64_or_nan")]
    pub median_rms_distance_relative: f64,
    /// Median two-way RMS distance of the delivered mesh to its subject (subject units).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub median_mesh_rms_distance: f64,
    /// Median of `mesh_rms_distance_relative`.
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub median_mesh_rms_distance_relative: f64,
    /// Median of `mesh_p95_distance` (subject units).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub median_mesh_p95_distance: f64,
    /// Median normal correlation (eq. 13).
    #[serde(deserialize_with = "f64_or_nan")]
    pub median_normal_correlation: f64,
}

/// The mean mesh's figures.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MeanMeshReport {
    /// Nodes of the mean mesh.
    pub nodes: usize,
    /// Elements of the mean mesh.
    pub elements: usize,
    /// Element kind (`hex8`, `quad4`, ...).
    pub element_kind: String,
    /// Smallest scaled Jacobian of the mean mesh.
    pub scaled_jacobian_min: f64,
    /// Smallest corner Jacobian of the mean mesh (reference units^D).
    pub jacobian_min: f64,
    /// The largest element edge ratio (longest edge over shortest).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub edge_ratio_max: f64,
    /// The element size the mesher used, as a share of the mean's largest extent.
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub element_size_share: f64,
    /// The same in the unit of the population's data (mm for mm data).
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub element_size: f64,
}

/// One input shape of a population: its topology, what was dropped from it, and how well the
/// registration template reached it.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct InputReport {
    /// The shape's name.
    pub name: String,
    /// Its vertices (after dropping islands).
    pub vertices: usize,
    /// Its connected components as read.
    pub components: usize,
    /// The genus of its largest component (closed surfaces; `None` otherwise).
    pub genus: Option<usize>,
    /// Floating components dropped (each under the share of the area in `warnings`).
    pub dropped_components: usize,
    /// The share of the shape's area (length in 2D) dropped with them.
    pub dropped_share: f64,
    /// With `--register`: the template's residuals against it, both ways (shape units;
    /// `None` for the template itself).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub registration: Option<crate::register::RegistrationResiduals>,
    /// Where it was cut (`--cut`: a population put on a common cut), if it was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cut: Option<CutReport>,
    /// What a user should know about it (islands dropped, a registration that did not
    /// reach).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Where a shape was cut: the plane (its point and unit normal towards the removed side, the
/// shape's frame: world, RAS for label maps) and what the cut removed.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct CutReport {
    /// A point of the cut plane.
    pub point: Vec<f64>,
    /// The plane's unit normal, towards the removed side.
    pub normal: Vec<f64>,
    /// The length kept from the shape's far end (the shapes' unit).
    pub length: f64,
    /// The share of the surface's area removed.
    pub removed_share: f64,
    /// The cap's area (the section; the unit squared).
    pub cap_area: f64,
}

/// A subject fitted with an atlas built on a common cut: the atlas's cut plane in the subject's
/// frame (its point, and its unit normal towards the side the atlas does not have), where the
/// delivered mesh ends; the share of the subject's surface beyond it (left out of the fit's
/// measures), and the share of the atlas's surface (the cap excluded) the subject covers (below
/// 1 when the field of view cut the subject below the atlas's cut).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SubjectCut {
    /// A point of the atlas's cut plane, subject frame.
    pub point: Vec<f64>,
    /// The plane's unit normal, towards the side beyond the atlas's cut.
    pub normal: Vec<f64>,
    /// The share of the subject's surface area beyond the plane.
    pub beyond_share: f64,
    /// The share of the atlas's surface area (the cap excluded) with a partner on the subject.
    pub atlas_covered_share: f64,
}

/// `report.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// The data the run was made from (files or folder).
    pub dataset: String,
    /// 2 (outlines) or 3 (surfaces).
    pub dimension: usize,
    /// Modes of the model used.
    pub modes: usize,
    /// Cumulative variance share, one value per kept mode.
    pub variance_explained: Vec<f64>,
    /// Every parameter of the run (enough to repeat it).
    pub parameters: serde_json::Value,
    /// The atlas's mean mesh.
    pub mean_mesh: Option<MeanMeshReport>,
    /// The population's shapes as read (leave-one-out): topology, islands dropped,
    /// registration residuals.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<InputReport>,
    /// The registration's template (with `--register`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub template: Option<String>,
    /// Every subject written (those that failed are in `failed`).
    pub subjects: Vec<SubjectReport>,
    /// Figures over all subjects.
    pub summary: Summary,
    /// The subjects that failed, with the reason (a batch fit, a leave-one-out); always
    /// written, empty when none failed.
    #[serde(default)]
    pub failed: Vec<FailedSubject>,
    /// Batch fit: the shard (`I/N`) this report covers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// The atlasmesh version that wrote the report.
    pub atlasmesh_version: String,
    /// The atlas file a fit used (a leave-one-out builds its own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atlas: Option<AtlasSource>,
    /// The number of folds of a k-fold cross-validation (absent for a leave-one-out and a
    /// fit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    /// The peak of the process's resident memory when the report was written (MB, 10⁶
    /// bytes): what a scheduler must give the run (of merged reports, the largest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resident_peak_mb: Option<f64>,
}

/// An atlas file as a run used it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AtlasSource {
    /// The file, as given.
    pub file: String,
    /// The CRC-32 of the file's bytes (8 hexadecimal digits, as `crc32 FILE` or Python's
    /// `zlib.crc32` give it): the run's atlas, whatever its name.
    pub checksum_crc32: String,
}

/// JSON has no NaN: serde_json writes it as `null`; read `null` back as NaN (a median of no
/// subjects, a measure that could not be taken).
/// Writes `value` as pretty JSON to `path` (through a temporary file and a rename); `what`
/// names it in an error.
pub(super) fn write_pretty<T: Serialize>(path: &Path, value: &T, what: &str) -> Result<()> {
    let s = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Numerical(format!("{what}: {e}")))?;
    crate::formats::write_atomic(path, s.as_bytes())
}

fn nan() -> f64 {
    f64::NAN
}

/// A number that `report.json` may hold as `null` (NaN and infinities are written so).
pub(super) fn f64_or_nan<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Subjects that failed any of `checks`.
fn failed_any(subjects: &[SubjectReport], checks: &[&str]) -> usize {
    subjects
        .iter()
        .filter(|s| s.failed_checks.iter().any(|c| checks.contains(&c.as_str())))
        .count()
}

impl Summary {
    /// Summary of the subjects' figures; `failed` subjects that have no report.
    pub fn of(subjects: &[SubjectReport], failed: usize) -> Self {
        Summary {
            subjects: subjects.len() + failed,
            failed,
            resumed: 0,
            succeeded: subjects.iter().filter(|s| s.success).count(),
            meshes_valid: subjects.iter().filter(|s| s.inverted_elements == 0).count(),
            repaired: subjects.iter().filter(|s| s.repaired).count(),
            below_repair_bound: subjects
                .iter()
                .filter(|s| s.scaled_jacobian_min < s.repair_bound)
                .count(),
            failed_fit: failed_any(subjects, &["fit"]),
            failed_mesh_distance: failed_any(subjects, &["mesh_distance", "mesh_farther_than_fit"]),
            failed_mesh_quality: failed_any(subjects, &["mesh_quality"]),
            morph_escalations: subjects.iter().filter(|s| s.morph_escalated).count(),
            not_converged: subjects.iter().filter(|s| !s.converged).count(),
            median_mesh_rms_distance: median(
                subjects.iter().map(|s| s.mesh_rms_distance).collect(),
            ),
            median_mesh_rms_distance_relative: median(
                subjects
                    .iter()
                    .map(|s| s.mesh_rms_distance_relative)
                    .collect(),
            ),
            median_mesh_p95_distance: median(
                subjects.iter().map(|s| s.mesh_p95_distance).collect(),
            ),
            median_fit_seconds: median(subjects.iter().map(|s| s.fit_seconds).collect()),
            subject_seconds: subjects.iter().map(|s| s.seconds).sum(),
            heap_peak_mb: subjects
                .iter()
                .map(|s| s.heap_peak_mb)
                .collect::<Option<Vec<f64>>>()
                .and_then(|v| v.into_iter().reduce(f64::max)),
            median_rms_distance_relative: median(
                subjects.iter().map(|s| s.rms_distance_relative).collect(),
            ),
            median_normal_correlation: median(
                subjects.iter().map(|s| s.normal_correlation).collect(),
            ),
        }
    }
}

impl Report {
    /// Writes the report as pretty JSON (atomically). NaN becomes null.
    pub fn write(&self, path: &Path) -> Result<()> {
        write_pretty(path, self, "report")
    }
}

/// A subject that failed: its name, its input file and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FailedSubject {
    /// The subject's name.
    pub name: String,
    /// Its input file.
    pub input: String,
    /// Why it failed.
    pub error: String,
    /// The exit code of the error's class (2 bad input, 3 I/O, 4 numerics or invalid mesh).
    pub exit_code: u8,
}

impl FailedSubject {
    /// The subject `name` (from the file `input`; empty for a shape held in memory) that
    /// failed with `error`.
    pub fn new(name: &str, input: &str, error: &crate::error::Error) -> Self {
        FailedSubject {
            name: name.to_string(),
            input: input.to_string(),
            error: error.to_string(),
            exit_code: error.exit_code(),
        }
    }
}

use crate::eval::ShapeModelMeasures;

impl ShapeModelMeasures {
    /// Writes the measures as JSON (temporary name, then rename).
    pub fn write(&self, path: &std::path::Path) -> crate::error::Result<()> {
        let bytes = serde_json::to_vec_pretty(self)
            .map_err(|e| crate::error::Error::io(path, std::io::Error::other(e.to_string())))?;
        crate::formats::write_atomic(path, &bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scores_quote_names_and_leave_missing_modes_empty() {
        let rows = [("a", &[0.5, -1.0][..]), ("b, \"c\"", &[2.0][..])];
        assert_eq!(
            scores_table(rows.iter().copied()),
            "name,mode_1,mode_2\na,0.5,-1\n\"b, \"\"c\"\"\",2,\n"
        );
    }

    #[test]
    fn a_pose_matrix_applies_the_similarity() {
        let t = crate::geometry::Similarity::<2> {
            s: 2.0,
            r: [[0.0, -1.0], [1.0, 0.0]],
            t: [3.0, 4.0],
        };
        let p = Pose::of(&t);
        assert_eq!(
            p.matrix,
            vec![
                vec![0.0, -2.0, 3.0],
                vec![2.0, 0.0, 4.0],
                vec![0.0, 0.0, 1.0]
            ]
        );
        let x = [1.0, 2.0];
        let y = t.apply(&x);
        for r in 0..2 {
            assert_eq!(
                p.matrix[r][0] * x[0] + p.matrix[r][1] * x[1] + p.matrix[r][2],
                y[r]
            );
        }
    }
}

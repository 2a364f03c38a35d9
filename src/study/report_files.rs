//! The population-level plots, `report.json` and `report.html` of a run.

use super::params::RunParams;
use crate::error::Result;
use crate::model::Atlas;
use crate::report::{
    JACOBIAN_BINS, Report, SubjectReport, Summary, plot_cumulative_variance, plot_e_d,
    plot_jacobian_histogram,
};
use std::path::Path;

/// What a run adds to a report beside the subjects: the data set's name, the mean mesh, a
/// batch's failures, its shard and the subjects it skipped; the shape-model measures of the
/// population (the HTML report plots them).
#[derive(Clone, Debug, Default)]
pub struct BatchFacts {
    /// The data the run was made from (files or folder).
    pub dataset: String,
    /// The atlas's mean mesh.
    pub mean_mesh: Option<crate::report::MeanMeshReport>,
    /// Subjects that failed, with the reason.
    pub failed: Vec<crate::report::FailedSubject>,
    /// The shard (`I/N`) of a batch.
    pub shard: Option<String>,
    /// Subjects skipped because their outputs were complete.
    pub resumed: usize,
    /// The population model's measures (the HTML report plots them).
    pub measures: Option<crate::eval::ShapeModelMeasures>,
    /// The population's shapes as read (leave-one-out).
    pub inputs: Vec<crate::report::InputReport>,
    /// The registration's template (leave-one-out with registration).
    pub template: Option<String>,
    /// The atlas file of a fit.
    pub atlas: Option<crate::report::AtlasSource>,
    /// The number of folds of a k-fold cross-validation (`None`: a leave-one-out, or a fit).
    pub folds: Option<usize>,
}

/// Writes `report.json`, `scores.csv` and the overview `report.html`; with plots, the
/// population-level pictures and the model's page too (by `morpher`, the atlas's; one is made
/// when `None` and the atlas has a mesh).
pub(crate) fn finish_report<const D: usize>(
    out: &Path,
    atlas_for_variance: &Atlas<D>,
    morpher: Option<&crate::mesh::Morpher<D>>,
    subjects: Vec<SubjectReport>,
    params: &RunParams,
    batch: BatchFacts,
) -> Result<Report> {
    let BatchFacts {
        dataset,
        mean_mesh,
        failed,
        shard,
        resumed,
        measures,
        inputs,
        template,
        atlas,
        folds,
    } = batch;
    let m = atlas_for_variance.num_modes();
    if params.plots {
        plot_cumulative_variance(
            &out.join("cumulative_variance.png"),
            &atlas_for_variance.cumulative_variance,
            m,
        )?;
        let hist: Vec<(String, Vec<f64>)> = subjects
            .iter()
            .map(|s| (s.name.clone(), s.e_d_history.clone()))
            .collect();
        plot_e_d(&out.join("e_d.png"), &hist)?;
        let mut counts = vec![0u32; JACOBIAN_BINS];
        for s in &subjects {
            for (c, v) in counts.iter_mut().zip(&s.scaled_jacobian_histogram) {
                *c += v;
            }
        }
        plot_jacobian_histogram(&out.join("scaled_jacobians.png"), &counts)?;
    }
    let report = Report {
        dataset,
        dimension: D,
        modes: m,
        variance_explained: atlas_for_variance.cumulative_variance[..m].to_vec(),
        parameters: serde_json::to_value(params).unwrap_or_default(),
        mean_mesh,
        inputs,
        template,
        summary: Summary {
            resumed,
            ..Summary::of(&subjects, failed.len())
        },
        failed,
        shard,
        subjects,
        atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
        atlas,
        folds,
        resident_peak_mb: super::run::resident_peak_mb(),
    };
    report.write(&out.join("report.json"))?;
    crate::formats::write_atomic(
        &out.join("scores.csv"),
        crate::report::scores_csv(&report.subjects).as_bytes(),
    )?;
    // The overview stays without pictures (a cohort's run): its tables, every file linked.
    let mut pictures = crate::report::html::Pictures::default();
    if params.plots {
        if let Some(m) = &measures {
            crate::report::plot_shape_model_measures(&out.join("measures.png"), m, "")?;
            pictures.measures = Some("measures.png".into());
        }
        if report
            .subjects
            .iter()
            .any(|s| s.normal_correlation_icp.is_some())
        {
            crate::report::plot_baselines(&out.join("baselines.png"), &report.subjects)?;
        }
        if atlas_for_variance.num_modes() > 0 {
            crate::report::plot_modes(&out.join("modes.png"), atlas_for_variance)?;
            pictures.modes = Some("modes.png".into());
        }
        if atlas_for_variance.has_mesh() && atlas_for_variance.num_modes() > 0 {
            let own;
            let morpher = match morpher {
                Some(m) => Ok(m),
                None => {
                    own = atlas_for_variance.morpher(&params.morph);
                    own.as_ref().map_err(|e| e.to_string())
                }
            };
            pictures.model_page = Some(morpher.and_then(|m| {
                super::model_page::write_model_page(
                    atlas_for_variance,
                    m,
                    out,
                    &["modes.png", "cumulative_variance.png"],
                )
                .map_err(|e| e.to_string())
            }));
        }
    }
    crate::report::html::write(&out.join("report.html"), &report, out, &pictures)?;
    Ok(report)
}

//! `atlasmesh merge-reports`: the reports of several shards joined into one (`report.json`
//! of `fit`, with the run's `scores.csv` beside it; `instances.json` of `sample`, or
//! `posterior.json` of `fit --landmarks-only`).

use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh merge-reports`.
#[derive(Args)]
pub struct MergeArgs {
    /// The reports to join (all report.json, or all instances.json).
    #[arg(num_args = 1.., required = true)]
    reports: Vec<PathBuf>,
    /// The joined report to write (a fit's shape scores beside it: `scores.csv` for
    /// `report.json`, `NAME.scores.csv` for `NAME.json`).
    #[arg(long)]
    out: PathBuf,
}

/// Which kind of run's report `path` holds: `instances` (of `instance` or `sample`),
/// `posterior` (`fit --landmarks-only`) or a fit's.
fn kind(path: &std::path::Path) -> &'static str {
    let v = atlasmesh::formats::read_input(path)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok());
    match v {
        Some(v) if v.get("instances").is_some() => "instances",
        Some(v) if v.get("subjects").is_some() && v.get("summary").is_none() => "posterior",
        _ => "fit",
    }
}

/// Runs `atlasmesh merge-reports`.
pub fn run(a: MergeArgs) -> anyhow::Result<()> {
    if kind(&a.reports[0]) == "posterior" {
        let r: atlasmesh::report::PosteriorRunReport = atlasmesh::study::run::merge(&a.reports)?;
        r.write(&a.out)?;
        println!(
            "{} subjects ({} failed) from {} reports: {}",
            r.subjects.len(),
            r.failed.len(),
            a.reports.len(),
            a.out.display()
        );
        return Ok(());
    }
    if kind(&a.reports[0]) == "instances" {
        let r = atlasmesh::study::merge_instances(&a.reports)?;
        r.write(&a.out)?;
        println!(
            "{} instances ({} failed) from {} reports: {}",
            r.summary.written,
            r.summary.failed,
            a.reports.len(),
            a.out.display()
        );
        return Ok(());
    }
    let r = atlasmesh::study::batch::merge_reports(&a.reports)?;
    r.write(&a.out)?;
    let scores = scores_path(&a.out);
    atlasmesh::formats::write_atomic(
        &scores,
        atlasmesh::report::scores_csv(&r.subjects).as_bytes(),
    )?;
    println!(
        "{} subjects ({} failed) from {} reports: {} (shape scores: {})",
        r.summary.subjects,
        r.summary.failed,
        a.reports.len(),
        a.out.display(),
        scores.display()
    );
    Ok(())
}

/// The merged run's shape scores beside its report: `scores.csv` beside a `report.json`,
/// `NAME.scores.csv` beside any other `NAME.json`.
fn scores_path(report: &std::path::Path) -> PathBuf {
    match report.file_stem().and_then(|s| s.to_str()) {
        Some("report") | None => report.with_file_name("scores.csv"),
        Some(stem) => report.with_file_name(format!("{stem}.scores.csv")),
    }
}

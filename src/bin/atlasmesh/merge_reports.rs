//! `atlasmesh merge-reports`: the reports of several shards joined into one (`report.json`
//! of `fit`, or `instances.json` of `sample`).

use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh merge-reports`.
#[derive(Args)]
pub struct MergeArgs {
    /// The reports to join (all report.json, or all instances.json).
    #[arg(num_args = 1.., required = true)]
    reports: Vec<PathBuf>,
    /// The joined report to write.
    #[arg(long)]
    out: PathBuf,
}

/// Whether `path` holds an `instances.json` (of `instance` or `sample`).
fn is_instances(path: &std::path::Path) -> bool {
    atlasmesh::formats::read_input(path)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .is_some_and(|v| v.get("instances").is_some())
}

/// Runs `atlasmesh merge-reports`.
pub fn run(a: MergeArgs) -> anyhow::Result<()> {
    if is_instances(&a.reports[0]) {
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
    println!(
        "{} subjects ({} failed) from {} reports: {}",
        r.summary.subjects,
        r.summary.failed,
        a.reports.len(),
        a.out.display()
    );
    Ok(())
}

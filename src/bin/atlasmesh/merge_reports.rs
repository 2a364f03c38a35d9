//! `atlasmesh merge-reports`: the reports of several shards joined into one.

use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh merge-reports`.
#[derive(Args)]
pub struct MergeArgs {
    /// The reports to join.
    #[arg(num_args = 1.., required = true)]
    reports: Vec<PathBuf>,
    /// The joined report to write.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `atlasmesh merge-reports`.
pub fn run(a: MergeArgs) -> anyhow::Result<()> {
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

//! What the commands print when they end, and the error of a batch with failures.

use atlasmesh::report::Report;
use std::path::Path;

/// Prints a run's summary and where its reports are.
pub fn print_summary(r: &Report, out: &Path) {
    let s = &r.summary;
    println!(
        "{} subjects: {} succeeded, {} meshes valid; median fit {:.1} ms, median relative RMS distance {:.4}, median normal correlation {:.3}",
        s.subjects,
        s.succeeded,
        s.meshes_valid,
        s.median_fit_seconds * 1e3,
        s.median_rms_distance_relative,
        s.median_normal_correlation
    );
    println!("report: {}", out.join("report.json").display());
    if out.join("report.html").is_file() {
        println!("report: {}", out.join("report.html").display());
    }
}

/// Some subjects of a batch failed (the others were written): exit code 6.
#[derive(Debug)]
pub struct BatchFailed {
    /// Subjects that failed.
    pub failed: usize,
    /// Subjects in the batch.
    pub total: usize,
}

impl std::fmt::Display for BatchFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} subjects failed (see `failed` in report.json); the others were written",
            self.failed, self.total
        )
    }
}

impl std::error::Error for BatchFailed {}

//! What the commands print when they end, and the error of a batch with failures.

use atlasmesh::report::Report;
use std::path::Path;

/// Prints a run's summary and where its reports are.
pub fn print_summary(r: &Report, out: &Path) {
    let s = &r.summary;
    if let Some(m) = &r.mean_mesh {
        // (A saved atlas does not know the shapes' unit: then the size is a share only.)
        let size = if m.element_size.is_finite() {
            format!(
                "{:.3} in the shapes' unit ({:.2} % of the largest extent)",
                m.element_size,
                100.0 * m.element_size_share
            )
        } else {
            format!(
                "{:.2} % of the largest extent",
                100.0 * m.element_size_share
            )
        };
        println!(
            "mean mesh: {} {} elements of size {size}, smallest scaled Jacobian {:.3}",
            m.elements, m.element_kind, m.scaled_jacobian_min
        );
    }
    if r.subjects.is_empty() {
        // No fitted subject: no medians to print (they would read NaN).
        println!(
            "{} subjects: none fitted{}",
            s.subjects,
            if s.subjects == 0 {
                " (nothing to do: an empty list or shard)"
            } else {
                ""
            }
        );
    } else {
        println!(
            "{} subjects: {} succeeded, {} meshes valid; median fit {:.1} ms; delivered meshes: median RMS distance {:.3} ({:.4} of the diagonal), median 95th percentile {:.3}; median normal correlation {:.3}",
            s.subjects,
            s.succeeded,
            s.meshes_valid,
            s.median_fit_seconds * 1e3,
            s.median_mesh_rms_distance,
            s.median_mesh_rms_distance_relative,
            s.median_mesh_p95_distance,
            s.median_normal_correlation
        );
    }
    let unsuccessful = s.subjects.saturating_sub(s.succeeded + s.failed);
    if unsuccessful > 0 || s.failed > 0 {
        println!(
            "not successful: {unsuccessful} ({} fit farther than its bound, {} mesh farther than its bound, {} mesh quality){}",
            s.failed_fit,
            s.failed_mesh_distance,
            s.failed_mesh_quality,
            if s.failed > 0 {
                format!("; {} failed (no mesh)", s.failed)
            } else {
                String::new()
            }
        );
    }
    if s.below_repair_bound + s.morph_escalations + s.not_converged > 0 {
        println!(
            "{} below the repair bound, {} morphs stiffened, {} fits not converged",
            s.below_repair_bound, s.morph_escalations, s.not_converged
        );
    }
    for x in &r.subjects {
        for w in &x.warnings {
            eprintln!("warning: {}: {w}", x.name);
        }
    }
    println!("report: {}", out.join("report.json").display());
    if out.join("report.html").is_file() {
        println!("report: {}", out.join("report.html").display());
    }
}

/// Lists the subjects of `r` that failed on stderr: [`BatchFailed`] when there are any.
pub fn failures(r: &Report) -> anyhow::Result<()> {
    if r.failed.is_empty() {
        return Ok(());
    }
    for f in &r.failed {
        if f.input.is_empty() {
            eprintln!("failed: {}: {}", f.name, f.error);
        } else {
            eprintln!("failed: {} ({}): {}", f.name, f.input, f.error);
        }
    }
    Err(BatchFailed {
        failed: r.failed.len(),
        total: r.summary.subjects,
        items: "subjects",
        report: "report.json",
    }
    .into())
}

/// Some subjects of a batch failed (the others were written): exit code 6.
#[derive(Debug)]
pub struct BatchFailed {
    /// Subjects that failed.
    pub failed: usize,
    /// Subjects in the batch.
    pub total: usize,
    /// What the items are (`subjects`, `instances`).
    pub items: &'static str,
    /// The report that lists the failures.
    pub report: &'static str,
}

impl std::fmt::Display for BatchFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let rest = if self.failed >= self.total {
            "none was written"
        } else {
            "the others were written"
        };
        write!(
            f,
            "{} of {} {} failed (see `failed` in {}); {rest}",
            self.failed, self.total, self.items, self.report
        )
    }
}

impl std::error::Error for BatchFailed {}

//! `atlasmesh register`: one template registered to one target (section 2.1, eq. 2).

use atlasmesh::study::{self, PairRegistration, PopulationOptions};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh register`.
#[derive(Args)]
pub struct RegisterArgs {
    /// Template shape (outline or surface file).
    #[arg(long)]
    template: PathBuf,
    /// Target shape.
    #[arg(long)]
    target: PathBuf,
    /// Landmark files of the template and the target (Scalismo JSON or .pts), in that order.
    #[arg(long, num_args = 2)]
    landmarks: Vec<PathBuf>,
    /// Outlines in CSV/text files are open.
    #[arg(long)]
    open: bool,
    #[command(flatten)]
    labels: crate::args::LabelArgs,
    /// FFD control points along the template's longest axis (default: 20 in 2D, 16 in 3D).
    #[arg(long, value_name = "N", value_parser = crate::args::count::<4, 32>)]
    grid: Option<usize>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `atlasmesh register`.
pub fn run(a: RegisterArgs) -> anyhow::Result<()> {
    let files = [a.template.clone(), a.target.clone()];
    let r: PairRegistration = if study::inputs_are_surfaces(&files)? {
        let shapes = study::load_surfaces(&files, &a.labels.reading()?)?;
        study::register_pair(shapes, &a.landmarks, a.grid, &a.out)?
    } else {
        let shapes = study::load_outlines_raw(
            &files,
            &PopulationOptions {
                closed: !a.open,
                ..Default::default()
            },
        )?;
        study::register_pair(shapes, &a.landmarks, a.grid, &a.out)?
    };
    let x = &r.residuals;
    println!(
        "registered {} to {}: two-way RMS distance {:.4}, 95th percentile {:.4} ({:.2} % of the target's diagonal), max {:.4}; template to target RMS {:.4}; outputs in {}",
        r.template,
        r.target,
        x.rms,
        x.p95,
        100.0 * x.p95_relative,
        x.max,
        x.template_to_target_rms,
        a.out.display()
    );
    if x.p95_relative > atlasmesh::register::REGISTRATION_WARNING_P95 {
        eprintln!(
            "warning: the registered template stays up to {:.4} (95th percentile) from {}: check the registration",
            x.p95, r.target
        );
    }
    Ok(())
}

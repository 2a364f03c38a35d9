//! `atlasmesh register`: one template registered to one target (section 2.1, eq. 2), or to
//! every shape of a population in stages (`--shapes`: resumable, shardable).

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
    #[arg(long, required_unless_present = "shapes", conflicts_with = "shapes")]
    target: Option<PathBuf>,
    /// Register the template to every shape of a population instead (files, folders of them,
    /// or `.list` files), each into its own folder OUT/NAME (the shape in correspondence,
    /// `NAME_registered.vtp`, and its record), resumable and shardable like `fit`; then
    /// `atlasmesh build --shapes OUT/registered.list` (the lists of every shard) makes the
    /// atlas that `build --register --template TEMPLATE` makes.
    #[arg(long, num_args = 1.., value_name = "SHAPES")]
    shapes: Vec<PathBuf>,
    /// With --shapes: only the I-th of N parts of the shape list (sorted by path, shape k to
    /// part k mod N).
    #[arg(long, value_name = "I/N", requires = "shapes")]
    shard: Option<String>,
    /// With --shapes: register every shape again, even those whose outputs are complete.
    #[arg(long, requires = "shapes")]
    no_resume: bool,
    /// With --shapes: worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = crate::args::count::<0, 1024>)]
    jobs: usize,
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
pub fn run(a: RegisterArgs, term: &crate::terminal::Terminal) -> anyhow::Result<()> {
    let Some(target) = a.target.clone() else {
        return population(&a, term);
    };
    let files = [a.template.clone(), target];
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

/// `atlasmesh register --shapes`: the template registered to every shape, in stages.
fn population(a: &RegisterArgs, term: &crate::terminal::Terminal) -> anyhow::Result<()> {
    if !a.landmarks.is_empty() {
        anyhow::bail!(
            "--landmarks with --shapes: a population registered in stages takes no landmarks; \
             build --register --landmarks registers it in one run"
        );
    }
    let files = study::batch::subject_files(&a.shapes)?;
    let place = study::RunPlace {
        out: a.out.clone(),
        resume: !a.no_resume,
        shard: a.shard.as_deref().map(study::Shard::parse).transpose()?,
    };
    let spec = study::PopulationSpec {
        labels: a.labels.reading()?,
        outlines: PopulationOptions {
            closed: !a.open,
            ..Default::default()
        },
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    let r = if study::inputs_are_surfaces(std::slice::from_ref(&a.template))? {
        pool.install(|| {
            study::register_files::<3>(&a.template, &files, &spec, a.grid, &place, term)
        })?
    } else {
        pool.install(|| {
            study::register_files::<2>(&a.template, &files, &spec, a.grid, &place, term)
        })?
    };
    if !term.is_quiet() {
        for s in &r.shapes {
            for w in &s.warnings {
                eprintln!("warning: {}: {w}", s.name);
            }
        }
    }
    println!(
        "registered {} shapes to {} ({} resumed, {} failed): {}",
        r.shapes.len(),
        r.template,
        r.resumed,
        r.failed.len(),
        a.out.join("registration.json").display()
    );
    for f in &r.failed {
        eprintln!("failed: {} ({}): {}", f.name, f.input, f.error);
    }
    if r.failed.is_empty() {
        Ok(())
    } else {
        Err(crate::summary::BatchFailed {
            failed: r.failed.len(),
            total: r.shapes.len() + r.failed.len(),
            items: "shapes",
            report: "registration.json",
        }
        .into())
    }
}

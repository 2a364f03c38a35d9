//! `atlasmesh loo`: the leave-one-out experiment (section 6.1), or a k-fold cross-validation.

use crate::args::{PopArgs, RunArgs, dataset_name};
use crate::population::{Read, corresponded, read};
use crate::summary::{failures, print_summary};
use crate::terminal::Terminal;
use atlasmesh::report::Report;
use atlasmesh::study;
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `atlasmesh loo`.
#[derive(Args)]
pub struct LooArgs {
    #[command(flatten)]
    pop: PopArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Output folder (report.json, meshes, plots).
    #[arg(long)]
    out: PathBuf,
    /// K-fold cross-validation instead of the leave-one-out: the shapes split into K
    /// consecutive groups in the order given, each group fitted with the atlas of the others.
    #[arg(long, value_name = "K", value_parser = crate::args::count::<2, 1_000_000>)]
    folds: Option<usize>,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = crate::args::count::<0, 1024>)]
    jobs: usize,
}

/// Runs `atlasmesh loo`.
pub fn run(mut a: LooArgs, term: &Terminal) -> anyhow::Result<()> {
    a.pop.expand()?;
    let r = if study::inputs_are_surfaces(&a.pop.shapes)? {
        loo(&a, read::<3>(&a.pop, &a.run, false, term)?, term)?
    } else {
        loo(&a, read::<2>(&a.pop, &a.run, false, term)?, term)?
    };
    print_summary(&r, &a.out);
    failures(&r)
}

/// Leave-one-out on shapes of either dimension.
fn loo<const D: usize>(a: &LooArgs, mut pop: Read<D>, term: &Terminal) -> anyhow::Result<Report> {
    let (corresponded, template) = corresponded(&mut pop, a.jobs, term)?;
    let Read {
        population:
            study::Population {
                shapes,
                inputs,
                meshes,
                as_read,
                ..
            },
        params,
        ..
    } = pop;
    let facts = study::PopulationFacts { inputs, template };
    let folds = study::Folds {
        corresponded: &corresponded,
        // Shapes put on a common cut are fitted as read (a bone the field of view cut).
        subjects: as_read.as_deref().unwrap_or(&shapes),
        meshes: meshes.as_deref(),
        population: &facts,
    };
    let (dataset, out) = (dataset_name(&a.pop.shapes), Path::new(&a.out));
    Ok(match a.folds {
        Some(k) => study::cross_validation(folds, k, &dataset, &params, out, a.jobs, term)?,
        None => study::leave_one_out_of(folds, &dataset, &params, out, a.jobs, term)?,
    })
}

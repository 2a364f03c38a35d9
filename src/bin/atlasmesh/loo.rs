//! `atlasmesh loo`: the leave-one-out experiment (section 6.1).

use crate::args::{PopArgs, RunArgs, dataset_name};
use crate::population::{Population, corresponded, outlines_and_params, surfaces_and_params};
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
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = crate::args::count::<0, 1024>)]
    jobs: usize,
}

/// Runs `atlasmesh loo`.
pub fn run(mut a: LooArgs, term: &Terminal) -> anyhow::Result<()> {
    a.pop.expand()?;
    let r = if study::inputs_are_surfaces(&a.pop.shapes)? {
        loo(&a, surfaces_and_params(&a.pop, &a.run, false, term)?, term)?
    } else {
        loo(&a, outlines_and_params(&a.pop, &a.run, term)?, term)?
    };
    print_summary(&r, &a.out);
    failures(&r)
}

/// Leave-one-out on shapes of either dimension.
fn loo<const D: usize>(a: &LooArgs, pop: Population<D>, term: &Terminal) -> anyhow::Result<Report> {
    let Population {
        shapes,
        mut inputs,
        params,
        meshes,
        landmark_ids,
        as_read,
    } = pop;
    let (corresponded, template) =
        corresponded(&a.pop, &shapes, &landmark_ids, &mut inputs, a.jobs, term)?;
    Ok(study::leave_one_out_of(
        study::Folds {
            corresponded: &corresponded,
            // Shapes put on a common cut are fitted as read (a bone the field of view cut).
            subjects: as_read.as_deref().unwrap_or(&shapes),
            meshes: meshes.as_deref(),
            population: &study::PopulationFacts { inputs, template },
        },
        &dataset_name(&a.pop.shapes),
        &params,
        Path::new(&a.out),
        a.jobs,
        term,
    )?)
}

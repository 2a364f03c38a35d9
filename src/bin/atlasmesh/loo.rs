//! `atlasmesh loo`: the leave-one-out experiment (section 6.1).

use crate::args::{PopArgs, RunArgs, dataset_name};
use crate::population::{corresponded, outlines_and_params, surfaces_and_params};
use crate::summary::{failures, print_summary};
use crate::terminal::Terminal;
use atlasmesh::geometry::Shape;
use atlasmesh::mesh::FeMesh;
use atlasmesh::report::Report;
use atlasmesh::study::{self, RunParams};
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
    #[arg(long, default_value_t = 0)]
    jobs: usize,
}

/// Runs `atlasmesh loo`.
pub fn run(a: LooArgs, term: &Terminal) -> anyhow::Result<()> {
    let r = if study::inputs_are_surfaces(&a.pop.shapes)? {
        let (shapes, params, meshes) = surfaces_and_params(&a.pop, &a.run)?;
        loo(&a, &shapes, meshes.as_deref(), &params, term)?
    } else {
        let (shapes, params) = outlines_and_params(&a.pop, &a.run)?;
        loo(&a, &shapes, None, &params, term)?
    };
    print_summary(&r, &a.out);
    failures(&r)
}

/// Leave-one-out on shapes of either dimension.
fn loo<const D: usize>(
    a: &LooArgs,
    shapes: &[Shape<D>],
    meshes: Option<&[FeMesh<D>]>,
    params: &RunParams,
    term: &Terminal,
) -> anyhow::Result<Report> {
    let corresponded = corresponded(&a.pop, shapes, a.jobs, term)?;
    Ok(study::leave_one_out_of(
        &corresponded,
        shapes,
        meshes,
        &dataset_name(&a.pop.shapes),
        params,
        Path::new(&a.out),
        a.jobs,
        term,
    )?)
}

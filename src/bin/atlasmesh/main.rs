//! The `atlasmesh` command-line tool: one file per command, each parsing its arguments and
//! calling the library's study layer ([`atlasmesh::study`]); progress is drawn here.

#![warn(clippy::too_many_lines)]

mod args;
mod build;
mod convert;
mod demo;
mod fit;
mod instance;
mod loo;
mod materials;
mod merge_reports;
mod population;
mod quality;
mod register;
mod repair;
mod summary;
mod terminal;
mod voxel_mesh;

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use summary::BatchFailed;
use terminal::Terminal;

/// Subject-specific finite element meshes from a statistical shape atlas.
#[derive(Parser)]
#[command(name = "atlasmesh", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// No progress output.
    #[arg(long, global = true)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Leave-one-out experiment (or k-fold with --folds): for each shape, atlas from the others, fit, morph, measure
    Loo(loo::LooArgs),
    /// Build an atlas (shape model + mean mesh) and save it.
    Build(build::BuildArgs),
    /// Fit subjects with a saved atlas, morph the mean mesh onto them, and measure.
    Fit(fit::FitArgs),
    /// Shapes of the model for given weights (in standard deviations), each with its FE mesh
    /// (the mean mesh morphed onto it, repaired, checked), in the data's unit.
    Instance(instance::InstanceArgs),
    /// A population of shapes drawn from the model (weights ~ N(0, Λ), optionally within
    /// ±K sd), each with its FE mesh, in parallel, resumable and shardable like `fit`.
    Sample(instance::SampleArgs),
    /// Joins the report.json files of several `fit --shard` runs (or batches of one atlas)
    /// into one.
    MergeReports(merge_reports::MergeArgs),
    /// Register one template shape to one target by the FFD of eq. 2 (section 2.1); writes
    /// the deformed template and the target resampled at the template's points (VTP), and
    /// registration.json (pre-alignment, mean squared distance per update).
    Register(register::RegisterArgs),
    /// Element quality of an FE mesh (.inp, .msh, .vtu, .vtk): min and 1 %/5 % percentiles of
    /// the corner Jacobian and scaled Jacobian, elements below the acceptance bound (hexahedra
    /// 0.5, quadrilaterals 0.3, simplices 0.2). Exits with 4 when an element is inverted.
    Quality(quality::QualityArgs),
    /// Converts an FE mesh between .inp, .msh, .vtu, .vtk and .feb, with its sets; an atlas
    /// file (.safetensors) as input gives its mean mesh (in the data's frame and unit).
    Convert(convert::ConvertArgs),
    /// Repairs an FE mesh: untangles inverted elements and raises scaled Jacobians below the
    /// bound by moving nodes; boundary nodes on SURFACE slide on it, other boundary nodes stay.
    Repair(repair::RepairArgs),
    /// Bone materials of any FE mesh from a CT (Bonemat's method): each element's HU
    /// integrated over its volume, its density and Young's modulus by a recipe, written as a
    /// material per group of E (.inp, .feb) and per-element values (.vtu, .vtk, .msh).
    Materials(materials::MaterialsArgs),
    /// One hexahedron per voxel of a label map's parts (voxel FE models, the direct route),
    /// each part an element set, parts that touch sharing their nodes.
    VoxelMesh(voxel_mesh::VoxelMeshArgs),
    /// Run the whole method on built-in synthetic data (no files needed).
    Demo(demo::DemoArgs),
}

fn run(cli: Cli) -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let term = Terminal::new(cli.quiet);
    match cli.command {
        Command::Loo(a) => loo::run(a, &term),
        Command::Build(a) => build::run(a, &term),
        Command::Fit(a) => fit::run(a, &term),
        Command::Instance(a) => instance::run(a, &term),
        Command::Sample(a) => instance::run_sample(a, &term),
        Command::MergeReports(a) => merge_reports::run(a),
        Command::Register(a) => register::run(a, &term),
        Command::Quality(a) => quality::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Repair(a) => repair::run(a, &term),
        Command::Materials(a) => materials::run(a),
        Command::VoxelMesh(a) => voxel_mesh::run(a),
        Command::Demo(a) => demo::run(a, &term),
    }
}

/// The heap counted, so that a run's report gives each subject's peak (`--jobs 1`).
#[global_allocator]
static ALLOCATOR: atlasmesh::study::run::CountingAllocator =
    atlasmesh::study::run::CountingAllocator;

fn main() -> ExitCode {
    // A file-size limit (`ulimit -f`) makes writes fail with an error, which removes the
    // temporary and names the file, instead of killing the process mid-write.
    // SAFETY: setting a signal's disposition to "ignore" before any thread starts.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", terminal::safe(&format!("{e:#}")));
            let code = e
                .downcast_ref::<atlasmesh::Error>()
                .map(|e| e.exit_code())
                .or_else(|| e.downcast_ref::<BatchFailed>().map(|_| 6))
                .unwrap_or(1);
            ExitCode::from(code)
        }
    }
}

//! `atlasmesh fit`: subjects fitted with a saved atlas, the mean mesh morphed onto each.

use crate::args::{RunArgs, dataset_name};
use crate::summary::{failures, print_summary};
use crate::terminal::Terminal;
use atlasmesh::study::{self, RunContext, RunPlace, Shard, batch};
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `atlasmesh fit`.
#[derive(Args)]
pub struct FitArgs {
    /// Atlas file written by `atlasmesh build`.
    #[arg(long)]
    atlas: PathBuf,
    /// Subject files (surfaces: PLY, STL, OBJ, VTK, VTP; outlines: CSV, text, VTK), folders
    /// of them, or `.list` files naming one path per line. Each subject gets its own
    /// folder OUT/NAME with its outputs and its record subject.json.
    #[arg(
        long,
        visible_alias = "subjects",
        num_args = 1..,
        required_unless_present = "landmarks_only"
    )]
    subject: Vec<PathBuf>,
    /// Subjects known by a few landmark positions only (Scalismo JSON or .pts, one subject
    /// per file; or CSV shape,landmark,x,y[,z] of several): the model's posterior given them,
    /// its mean shape with the per-point standard deviation (point data `posterior_sd`) and
    /// its FE mesh, in OUT/NAME/, and OUT/posterior.json.
    #[arg(
        long,
        value_name = "FILE",
        num_args = 1..,
        conflicts_with_all = ["subject", "one_way", "partial", "baselines", "max_misfit"]
    )]
    landmarks_only: Vec<PathBuf>,
    /// The landmarks' standard deviation (their uncertainty), in their unit.
    #[arg(
        long,
        value_name = "SD",
        default_value_t = 1.0,
        requires = "landmarks_only",
        value_parser = crate::args::positive
    )]
    landmark_sd: f64,
    /// Outlines in CSV/text files are open.
    #[arg(long)]
    open: bool,
    /// Columns of CSV subject files whose names are not the usual ones (shape, point, x, y),
    /// as ROLE=COLUMN pairs: `shape=specimen,x=X,y=Y`.
    #[arg(long, value_name = "MAP")]
    columns: Option<atlasmesh::formats::CsvColumns>,
    #[command(flatten)]
    labels: crate::args::LabelArgs,
    /// The subjects' CT, for per-element bone materials in every mesh file: one image
    /// (NIfTI, NRRD, MetaImage, or a DICOM series' folder) for one subject file; for several,
    /// a folder with a CT named like each subject (NAME.nii.gz, ..., or a DICOM folder NAME),
    /// or a CSV table with columns subject,ct. In the subjects' frame (mm).
    #[arg(long, value_name = "PATH", conflicts_with = "landmarks_only")]
    ct: Option<PathBuf>,
    /// The material recipe (TOML: calibration, density chain, law, integration, materials;
    /// see docs/materials.md); without it, the documented defaults.
    #[arg(long, value_name = "FILE", requires = "ct")]
    recipe: Option<PathBuf>,
    #[command(flatten)]
    run: RunArgs,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = crate::args::count::<0, 1024>)]
    jobs: usize,
    /// Only the I-th of N parts of the subject list (sorted by path, subject k to part
    /// k mod N), e.g. `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`; join the
    /// parts' reports with `atlasmesh merge-reports`.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Fit every subject again, even those whose outputs are complete.
    #[arg(long)]
    no_resume: bool,
}

/// Runs `atlasmesh fit`: the dimension is the atlas's, chosen once here.
pub fn run(a: FitArgs, term: &Terminal) -> anyhow::Result<()> {
    if atlasmesh::formats::atlas_dimension(&a.atlas)? == 3 {
        run_in::<3>(&a, term)
    } else {
        run_in::<2>(&a, term)
    }
}

/// `atlasmesh fit` with an atlas of dimension `D`.
fn run_in<const D: usize>(a: &FitArgs, term: &Terminal) -> anyhow::Result<()> {
    let place = RunPlace {
        out: a.out.clone(),
        resume: !a.no_resume,
        shard: a.shard.as_deref().map(Shard::parse).transpose()?,
    };
    // Every subject file listed (and its folder name checked) before the atlas is read.
    let files = if a.landmarks_only.is_empty() {
        let files = batch::subject_files(&a.subject)?;
        batch::check_folder_names(&files)?;
        files
    } else {
        Vec::new()
    };
    let ct = match &a.ct {
        Some(p) => study::CtSource::parse(p)?,
        None => study::CtSource::None,
    };
    ct.check_subjects(&files)?;
    let mut params = a.run.params()?;
    if ct.is_some() {
        params.materials = Some(match &a.recipe {
            Some(r) => study::read_recipe(r)?,
            None => Default::default(),
        });
    }
    let ctx = RunContext::<D>::open(&a.atlas, params, a.run.deck.as_deref(), place)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    if !a.landmarks_only.is_empty() {
        let subjects = study::read_landmark_subjects::<D>(&a.landmarks_only)?;
        let r =
            pool.install(|| study::fit_landmark_subjects(&ctx, &subjects, a.landmark_sd, term))?;
        return print_posterior(&r, &a.out, term);
    }
    let reading = study::SubjectReading {
        open: a.open,
        columns: a.columns.clone().unwrap_or_default(),
        labels: a.labels.reading()?,
        ct,
    };
    let r =
        pool.install(|| batch::fit_batch(&ctx, &files, &reading, &dataset_name(&files), term))?;
    if !term.is_quiet() {
        for s in &r.subjects {
            for w in &s.warnings {
                eprintln!("warning: {}: {w}", s.name);
            }
        }
    }
    print_summary(&r, &a.out);
    failures(&r)
}

/// What `fit --landmarks-only` prints of its report (see
/// [`atlasmesh::study::fit_landmark_subjects`]).
fn print_posterior(
    report: &atlasmesh::report::PosteriorRunReport,
    out: &Path,
    term: &Terminal,
) -> anyhow::Result<()> {
    for s in &report.subjects {
        for w in s.warnings.iter().filter(|_| !term.is_quiet()) {
            eprintln!("warning: {}: {w}", s.name);
        }
        println!(
            "{}: {} landmarks, matched within {:.3} (RMS); the posterior leaves {:.3} (median) to {:.3} (largest) standard deviation per point; mesh scaled Jacobian min {:.3}",
            s.name,
            s.landmarks.len(),
            s.landmark_rms,
            s.point_sd_median,
            s.point_sd_max,
            s.scaled_jacobian_min
        );
    }
    println!("posterior: {}", out.join("posterior.json").display());
    for f in &report.failed {
        eprintln!("failed: {} ({}): {}", f.name, f.input, f.error);
    }
    if !report.failed.is_empty() {
        return Err(crate::summary::BatchFailed {
            failed: report.failed.len(),
            total: report.failed.len() + report.subjects.len(),
            items: "subjects",
            report: "posterior.json",
        }
        .into());
    }
    Ok(())
}

//! `atlasmesh fit`: subjects fitted with a saved atlas, the mean mesh morphed onto each.

use crate::args::{RunArgs, dataset_name};
use crate::summary::{failures, print_summary};
use crate::terminal::Terminal;
use atlasmesh::geometry::Shape;
use atlasmesh::model::Atlas;
use atlasmesh::study::{self, batch};
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
    #[arg(long, visible_alias = "subjects", num_args = 1.., required = true)]
    subject: Vec<PathBuf>,
    /// Outlines in CSV/text files are open.
    #[arg(long)]
    open: bool,
    /// Columns of CSV subject files whose names are not the usual ones (shape, point, x, y),
    /// as ROLE=COLUMN pairs: `shape=specimen,x=X,y=Y`.
    #[arg(long, value_name = "MAP")]
    columns: Option<atlasmesh::formats::CsvColumns>,
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

/// Runs `atlasmesh fit`.
pub fn run(a: FitArgs, term: &Terminal) -> anyhow::Result<()> {
    let files = batch::subject_files(&a.subject)?;
    batch::check_folder_names(&files)?;
    let shard = a.shard.as_deref().map(batch::parse_shard).transpose()?;
    // A subject of the other dimension than the atlas is named as such.
    let other = |p: &Path, it: &str, dim: usize| {
        atlasmesh::Error::Population(format!(
            "{}: {it}, but the atlas {} is {dim}D",
            p.display(),
            a.atlas.display()
        ))
    };
    if atlasmesh::formats::atlas_dimension(&a.atlas)? == 3 {
        let load = |p: &Path| -> atlasmesh::Result<Vec<_>> {
            if !study::is_surface_file(p)? {
                return Err(other(p, "a 2D outline", 3));
            }
            // Floating islands (under 1 % of the area) dropped, as in a population.
            let mut s = vec![atlasmesh::formats::read_surface(p)?];
            for i in study::clean_shapes(&mut s, study::ISLAND_SHARE) {
                for w in i.warnings.iter().filter(|_| !term.is_quiet()) {
                    eprintln!("warning: {}: {w}", i.name);
                }
            }
            Ok(s)
        };
        fit::<3>(&a, &files, shard, &load, term)
    } else {
        let load = |p: &Path| -> atlasmesh::Result<Vec<_>> {
            if study::is_surface_file(p)? {
                return Err(other(p, "a 3D surface", 2));
            }
            let columns = a.columns.clone().unwrap_or_default();
            let shapes = atlasmesh::formats::read_outlines_with(p, !a.open, &columns)?;
            for s in &shapes {
                s.validate()
                    .map_err(|e| atlasmesh::Error::parse(p, 0, e.to_string()))?;
            }
            Ok(shapes)
        };
        fit::<2>(&a, &files, shard, &load, term)
    }
}

/// The batch of `files` with an atlas of dimension `D` (see [`atlasmesh::study::batch`]).
fn fit<const D: usize>(
    a: &FitArgs,
    files: &[PathBuf],
    shard: Option<(usize, usize)>,
    load: &(dyn Fn(&Path) -> atlasmesh::Result<Vec<Shape<D>>> + Sync),
    term: &Terminal,
) -> anyhow::Result<()> {
    let mut atlas = Atlas::<D>::load(&a.atlas)?;
    let atlas_crc = batch::file_crc32(&a.atlas)?;
    let mut params = a.run.params_for(D)?;
    params.atlas = atlas.params;
    if let Some(c) = &params.sets {
        study::apply_sets(&mut atlas, c)?;
    }
    if let (Some(deck), Some(path)) = (&params.deck, &a.run.deck) {
        study::check_deck(&atlas, deck, path)?;
    }
    let files = match shard {
        Some((i, n)) => batch::shard(files, i, n),
        None => files.to_vec(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    let opts = batch::BatchOptions {
        resume: !a.no_resume,
        shard: shard.map(|(i, n)| format!("{i}/{n}")),
    };
    let r = pool.install(|| {
        batch::fit_batch(
            &atlas,
            &files,
            load,
            &dataset_name(&files),
            &params,
            atlas_crc,
            &a.out,
            &opts,
            term,
        )
    })?;
    print_summary(&r, &a.out);
    failures(&r)
}

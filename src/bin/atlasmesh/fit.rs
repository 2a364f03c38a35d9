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
    #[arg(long, value_name = "FILE", num_args = 1.., conflicts_with = "subject")]
    landmarks_only: Vec<PathBuf>,
    /// The landmarks' standard deviation (their uncertainty), in their unit.
    #[arg(
        long,
        value_name = "SD",
        default_value_t = 1.0,
        requires = "landmarks_only"
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
    if !a.landmarks_only.is_empty() {
        return if atlasmesh::formats::atlas_dimension(&a.atlas)? == 3 {
            landmarks_only::<3>(&a, term)
        } else {
            landmarks_only::<2>(&a, term)
        };
    }
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

/// `fit --landmarks-only`: each subject's posterior given its landmarks (see
/// [`atlasmesh::study::write_landmark_fit`]).
fn landmarks_only<const D: usize>(a: &FitArgs, term: &Terminal) -> anyhow::Result<()> {
    use atlasmesh::formats::landmarks;
    use atlasmesh::study::Progress;
    use rayon::prelude::*;
    let mut atlas = Atlas::<D>::load(&a.atlas)?;
    let params = a.run.params_for(D)?;
    if let Some(c) = &params.sets {
        study::apply_sets(&mut atlas, c)?;
    }
    if let (Some(deck), Some(path)) = (&params.deck, &a.run.deck) {
        study::check_deck(&atlas, deck, path)?;
    }
    // Every subject's landmarks, read before anything is written.
    let mut subjects: Vec<(String, PathBuf, Vec<landmarks::NamedLandmark<D>>)> = Vec::new();
    for f in &a.landmarks_only {
        let csv = f.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        if csv {
            for (name, l) in landmarks::read_landmarks_csv::<D>(f)? {
                subjects.push((name, f.clone(), l));
            }
        } else {
            let name = f
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            subjects.push((name, f.clone(), landmarks::read_landmarks::<D>(f)?));
        }
    }
    let mut folders: Vec<String> = subjects.iter().map(|s| batch::folder_name(&s.0)).collect();
    folders.sort();
    if let Some(w) = folders.windows(2).find(|w| w[0] == w[1]) {
        return Err(atlasmesh::Error::Population(format!(
            "two subjects would share the output folder {}/; rename one",
            w[0]
        ))
        .into());
    }
    let morpher = atlas
        .has_mesh()
        .then(|| atlas.morpher(&params.morph))
        .transpose()?;
    atlasmesh::formats::create_dir(&a.out)?;
    let _lock = atlasmesh::formats::lock_dir(&a.out)?;
    term.items_started("posterior", subjects.len());
    let results: Vec<Result<atlasmesh::report::PosteriorReport, atlasmesh::report::FailedSubject>> =
        subjects
            .par_iter()
            .map(|(name, file, given)| {
                let folder = batch::folder_name(name);
                let r = study::pair_with_atlas(&atlas, given, file).and_then(
                    |(pairs, used, warnings)| {
                        let mut r = study::write_landmark_fit(
                            &atlas,
                            morpher.as_ref(),
                            name,
                            &pairs,
                            a.landmark_sd,
                            &params,
                            &a.out.join(&folder),
                        )?;
                        r.landmarks = used;
                        r.warnings = warnings;
                        for f in &mut r.files {
                            *f = format!("{folder}/{f}");
                        }
                        Ok(r)
                    },
                );
                term.item_done("posterior", name);
                r.map_err(|e| {
                    atlasmesh::report::FailedSubject::new(name, &file.display().to_string(), &e)
                })
            })
            .collect();
    term.items_finished("posterior");
    let mut report = atlasmesh::report::PosteriorRunReport {
        atlas: a.atlas.display().to_string(),
        dimension: D,
        modes: atlas.num_modes(),
        subjects: Vec::new(),
        failed: Vec::new(),
        atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
    };
    for r in results {
        match r {
            Ok(r) => report.subjects.push(r),
            Err(f) => report.failed.push(f),
        }
    }
    let path = a.out.join("posterior.json");
    report.write(&path)?;
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
    println!("posterior: {}", path.display());
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

//! Batch fitting of a population of subjects with one atlas (the stages of sections 3-5 for
//! each subject): a [`Job`] of the run engine ([`super::run`]), so streamed, parallel,
//! resumable and split into shards for a cluster like every run.
//!
//! Every subject file is read ([`read_subjects`]), fitted (Algorithm 1), morphed (eq. 9),
//! repaired, checked and written by one worker, then dropped: memory stays flat in the
//! number of subjects (only the small per-subject figures are kept for the summary). Each
//! subject gets its own folder `OUT/NAME/` with its record `OUT/NAME/subject.json` written
//! last (see [`super::run::run_items`]). A subject that fails is reported with its reason
//! and the batch goes on.

use super::build::mean_mesh_report;
use super::progress::Progress;
use super::report_files::{BatchFacts, finish_report};
use super::run::{Job, Origin, RunContext, RunOutcome, Units, check_folders, run_items};
use super::subject_file::{Subject, SubjectReading, read_subjects};
use super::write_subject::write_subject;
use crate::error::{Error, Result};
use crate::mesh::Morpher;
use crate::report::{FailedSubject, Report, SubjectReport};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// File name of a subject's record in its folder.
pub const RECORD: &str = "subject.json";

/// A subject's record `NAME/subject.json`: its report (files relative to the batch folder)
/// and what it was made from.
pub type SubjectRecord = super::run::Record<SubjectReport>;

impl super::run::UnitReport for SubjectReport {
    fn files(&self) -> &[String] {
        &self.files
    }
    fn files_mut(&mut self) -> &mut Vec<String> {
        &mut self.files
    }
    fn set_cost(&mut self, seconds: f64, heap_peak_mb: Option<f64>) {
        self.seconds = seconds;
        self.heap_peak_mb = heap_peak_mb;
    }
}

/// The subject files named by `specs`: a folder gives every shape file in it (by extension:
/// `.ply .stl .obj .vtk .vtp .csv .txt .xy`, and label maps `.nii .nii.gz .nrrd .nhdr .mha
/// .mhd`), sorted by name; a `.list` file gives the paths
/// on its lines (relative to the list's folder; blank lines and `#` comments skipped; a
/// `.list` there is an error); any other file is itself a subject. In a folder, anything with
/// a shape extension but a folder is a subject, so a broken link or a FIFO fails with its
/// reason instead of being skipped.
pub fn subject_files(specs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    const SHAPES: [&str; 8] = ["ply", "stl", "obj", "vtk", "vtp", "csv", "txt", "xy"];
    let ext = |p: &Path| {
        p.extension()
            .map(|e| e.to_string_lossy().to_lowercase())
            .unwrap_or_default()
    };
    let mut files = Vec::new();
    for spec in specs {
        if spec.is_dir() {
            let mut in_dir: Vec<PathBuf> = std::fs::read_dir(spec)
                .map_err(|e| Error::io(spec, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                // Anything but a folder: a link that loops or leads nowhere, a FIFO, is a
                // subject that fails with its reason, never skipped without a word.
                .filter(|p| {
                    !p.is_dir()
                        && (SHAPES.contains(&ext(p).as_str()) || crate::formats::is_image_file(p))
                })
                .collect();
            if in_dir.is_empty() {
                return Err(Error::Population(format!(
                    "{}: no shape file (.ply .stl .obj .vtk .vtp .csv .txt .xy) or label map (.nii .nii.gz .nrrd .nhdr .mha .mhd) in this folder",
                    spec.display()
                )));
            }
            in_dir.sort();
            files.extend(in_dir);
        } else if ext(spec) == "list" {
            let text = crate::formats::read_input_text(spec)?;
            let base = spec.parent().unwrap_or(Path::new("."));
            for (n, l) in text.lines().enumerate() {
                let l = l.trim();
                if l.is_empty() || l.starts_with('#') {
                    continue;
                }
                let p = base.join(l);
                if ext(&p) == "list" {
                    return Err(Error::parse(
                        spec,
                        n + 1,
                        format!(
                            "{l}: a list inside a list is not read; name the subject files (or a folder of them)"
                        ),
                    ));
                }
                files.push(p);
            }
        } else {
            files.push(spec.clone());
        }
    }
    if files.is_empty() {
        return Err(Error::Population("no subject file given".into()));
    }
    Ok(files)
}

/// CRC-32 of a file's bytes.
pub fn file_crc32(path: &Path) -> Result<u32> {
    let bytes = crate::formats::read_input(path)?;
    Ok(crc32fast::hash(&bytes))
}

/// The data set's name in reports: the files, or for more than three their folder and count.
pub fn dataset_name(paths: &[PathBuf]) -> String {
    if paths.len() <= 3 {
        return paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" ");
    }
    let parent = |p: &PathBuf| p.parent().map(|d| d.to_path_buf()).unwrap_or_default();
    let first = parent(&paths[0]);
    if paths.iter().all(|p| parent(p) == first) {
        format!("{} ({} files)", first.display(), paths.len())
    } else {
        format!("{} files ({} ...)", paths.len(), paths[0].display())
    }
}

/// The folder name of a subject (its name with path-unsafe characters replaced).
pub fn folder_name(name: &str) -> String {
    crate::study::file_name(name)
}

/// Checks that no two of `files` would share an output folder (their stems as
/// [`folder_name`]s: `S 1.ply` and `S_1.ply` both make `S_1/`). Run it on the whole list
/// before sharding, so that every shard of a batch agrees.
///
/// # Errors
/// [`Error::Population`] naming the two files and their folder.
pub fn check_folder_names(files: &[PathBuf]) -> Result<()> {
    let shown: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    check_folders(files.iter().zip(&shown).map(|(f, d)| (stem(f), d.as_str())))
}

/// Fits every subject in `files` with the atlas of `ctx` (see the module doc), reading
/// each as `reading` says, and writes `report.json` over all of them into the run's folder
/// (`dataset` names the data in it). Errors only where the batch as a whole cannot run
/// (unwritable output folder, duplicate subject names); a subject's failure is in the
/// report's `failed`.
pub fn fit_batch<const D: usize>(
    ctx: &RunContext<D>,
    files: &[PathBuf],
    reading: &SubjectReading,
    dataset: &str,
    progress: &dyn Progress,
) -> Result<Report> {
    check_folder_names(files)?;
    // (The morpher first: it refuses an atlas without a mesh, which has nothing to fit.)
    let job = FitFiles {
        ctx,
        morpher: ctx.morpher()?,
        reading,
        dataset,
        run_crc: ctx.run_crc(),
    };
    ctx.fitter()?;
    run_items(&job, files, ctx.looping(RECORD), progress)
}

/// Fits shapes held in memory with the atlas of `ctx`, in parallel, each subject's files
/// written flat into the run's folder (`NAME_mesh.vtu`, ...) with `report.json` over all of
/// them; a subject that fails is in the report's `failed`, as in [`fit_batch`].
pub fn fit_shapes<const D: usize>(
    ctx: &RunContext<D>,
    subjects: &[Subject<D>],
    dataset: &str,
    progress: &dyn Progress,
) -> Result<Report> {
    let job = FitShapes {
        ctx,
        morpher: ctx.morpher()?,
        dataset,
    };
    ctx.fitter()?;
    run_items(&job, subjects, ctx.looping(RECORD), progress)
}

/// One subject fitted and written into `dir` (its page linking the run's report at
/// `index_href`), its input's warnings in its report.
fn fit_and_write<const D: usize>(
    ctx: &RunContext<D>,
    subject: &Subject<D>,
    dir: &Path,
    index_href: &str,
) -> Result<SubjectReport> {
    let outcome = ctx.fit(subject, &ctx.params)?;
    write_subject(
        &ctx.atlas,
        &subject.shape,
        outcome,
        dir,
        &ctx.params,
        index_href,
    )
}

/// The batch fit of subject files.
struct FitFiles<'a, const D: usize> {
    ctx: &'a RunContext<D>,
    morpher: Arc<Morpher<D>>,
    reading: &'a SubjectReading,
    dataset: &'a str,
    run_crc: u32,
}

impl<const D: usize> Job for FitFiles<'_, D> {
    type Item = PathBuf;
    type Key = PathBuf;
    type Report = SubjectReport;
    type Output = Report;
    const LABEL: &'static str = "fit";
    const REPORT: &'static str = "report.json";

    fn name(&self, file: &PathBuf) -> String {
        stem(file)
    }

    fn key(&self, _: usize, file: &PathBuf) -> PathBuf {
        file.clone()
    }

    fn run(
        &self,
        file: &PathBuf,
        units: &Units<'_>,
    ) -> Vec<std::result::Result<SubjectReport, FailedSubject>> {
        let input = file.display().to_string();
        let fail = |name: &str, e: &Error| Err(FailedSubject::new(name, &input, e));
        let name = stem(file);
        let input_crc32 = match file_crc32(file) {
            Ok(c) => c,
            Err(e) => return vec![fail(&name, &e)],
        };
        let origin = Origin {
            input: &input,
            input_crc32,
            run_crc32: self.run_crc,
        };
        // A one-shape file's subject is named after the file (its folder is known before
        // reading it); a file of several outlines names its subjects FILE.SHAPE.
        if let Some(r) = units.resumed(&folder_name(&name), origin) {
            return vec![Ok(r)];
        }
        let subjects = match read_subjects::<D>(file, self.reading) {
            Ok(s) if s.is_empty() => {
                let e = Error::Population(format!("{}: no shape in this file", file.display()));
                return vec![fail(&name, &e)];
            }
            Ok(s) => s,
            Err(e) => return vec![fail(&name, &e)],
        };
        let several = subjects.len() > 1;
        let mut folders = std::collections::HashSet::new();
        subjects
            .into_iter()
            .map(|mut subject| {
                let label = if several {
                    format!("{name}.{}", subject.shape.name)
                } else {
                    name.clone()
                };
                let folder = folder_name(&label);
                if !folders.insert(folder.clone()) {
                    let e = Error::Population(format!(
                        "{}: another shape of this file already has the output folder {folder}/; rename one",
                        file.display()
                    ));
                    return fail(&label, &e);
                }
                subject.shape.name = label.clone();
                units
                    .make(&folder, origin, |dir| {
                        fit_and_write(self.ctx, &subject, dir, "../report.html")
                    })
                    .or_else(|e| fail(&label, &e))
            })
            .collect()
    }

    fn finish(&self, outcome: RunOutcome<SubjectReport>) -> Result<Report> {
        finish_fit(self.ctx, &self.morpher, self.dataset, outcome)
    }
}

/// The fit of subjects held in memory, written flat into the run's folder.
struct FitShapes<'a, const D: usize> {
    ctx: &'a RunContext<D>,
    morpher: Arc<Morpher<D>>,
    dataset: &'a str,
}

impl<const D: usize> Job for FitShapes<'_, D> {
    type Item = Subject<D>;
    type Key = usize;
    type Report = SubjectReport;
    type Output = Report;
    const LABEL: &'static str = "fit";
    const REPORT: &'static str = "report.json";

    fn name(&self, s: &Subject<D>) -> String {
        s.shape.name.clone()
    }

    fn key(&self, k: usize, _: &Subject<D>) -> usize {
        k
    }

    fn run(
        &self,
        s: &Subject<D>,
        units: &Units<'_>,
    ) -> Vec<std::result::Result<SubjectReport, FailedSubject>> {
        vec![
            fit_and_write(self.ctx, s, units.out(), "report.html")
                .map_err(|e| FailedSubject::new(&s.shape.name, "", &e)),
        ]
    }

    fn finish(&self, outcome: RunOutcome<SubjectReport>) -> Result<Report> {
        finish_fit(self.ctx, &self.morpher, self.dataset, outcome)
    }
}

/// The report of a batch from its subjects' results (see [`finish_report`]).
fn finish_fit<const D: usize>(
    ctx: &RunContext<D>,
    morpher: &Morpher<D>,
    dataset: &str,
    outcome: RunOutcome<SubjectReport>,
) -> Result<Report> {
    let atlas = &ctx.atlas;
    finish_report(
        &ctx.place.out,
        atlas,
        Some(morpher),
        outcome.reports,
        &ctx.params,
        BatchFacts {
            dataset: dataset.to_string(),
            // (An atlas of format version 2 does not know the data's unit: a share only.)
            mean_mesh: Some(mean_mesh_report(
                atlas,
                atlas.data_frame.map_or(f64::NAN, |t| t.s),
            )),
            failed: outcome.failed,
            shard: ctx.place.shard.map(|s| s.label()),
            resumed: outcome.resumed,
            atlas: (!ctx.atlas_file.is_empty()).then(|| crate::report::AtlasSource {
                file: ctx.atlas_file.clone(),
                checksum_crc32: format!("{:08x}", ctx.atlas_crc),
            }),
            ..Default::default()
        },
    )
}

/// Joins the `report.json` of several shards (or batches) of one atlas and run into one
/// report ([`super::run::merge`]): subjects and failures concatenated (sorted by name),
/// summary recomputed. Refuses reports of another dimension, atlas or parameters, and a
/// subject that is in two of them.
pub fn merge_reports(paths: &[PathBuf]) -> Result<Report> {
    super::run::merge(paths)
}

/// A file's stem: the name of its subject (`.nii.gz` and `.seg.nrrd` whole).
fn stem(p: &Path) -> String {
    super::label_map::shape_name(p)
}

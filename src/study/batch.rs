//! Batch fitting of a population of subjects with one atlas (the stages of sections 3-5 for
//! each subject): streamed, parallel, resumable, and split into shards for a cluster.
//!
//! Every subject file is read, fitted (Algorithm 1), morphed (eq. 9), repaired, checked and
//! written by one worker, then dropped: memory stays flat in the number of subjects (only the
//! small per-subject figures are kept for the summary). Each subject gets its own folder
//! `OUT/NAME/`; its record `OUT/NAME/subject.json` is written last, through a temporary name
//! and a rename like every other output, so a subject is complete exactly when its record is
//! there, its files exist and it was made from the same input (CRC-32 of the file) with the
//! same atlas and parameters. A re-run skips complete subjects (resume); an interrupted run
//! leaves no half-written file. A subject that fails is reported with its reason and the
//! batch goes on.
//!
//! Shards: [`shard`] takes the `i`-th of `n` parts of the subject list sorted by path
//! (subject `k` of the sorted list goes to part `k mod n`): disjoint, covering, balanced to
//! one subject, and the same on every machine that sees the same list.

use super::build::mean_mesh_report;
use super::params::RunParams;
use super::progress::Progress;
use super::report_files::finish_report;
use super::write_subject::process_subject;
use crate::error::{Error, Result};
use crate::fit::Fitter;
use crate::geometry::Shape;
use crate::mesh::Morpher;
use crate::model::Atlas;
use crate::report::{FailedSubject, Report, SubjectReport};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// File name of a subject's record in its folder.
pub const RECORD: &str = "subject.json";

/// Options of a batch run.
#[derive(Clone, Debug, Default)]
pub struct BatchOptions {
    /// Skip subjects whose outputs are complete (see the module doc).
    pub resume: bool,
    /// A label for the report (e.g. `"shard 2/8"`).
    pub shard: Option<String>,
}

/// What a run adds to a report beside the subjects: a batch's failures, its shard and the
/// subjects it skipped; the shape-model measures of the population (the HTML report plots
/// them).
#[derive(Clone, Debug, Default)]
pub struct BatchFacts {
    /// Subjects that failed, with the reason.
    pub failed: Vec<FailedSubject>,
    /// The shard (`I/N`) of a batch.
    pub shard: Option<String>,
    /// Subjects skipped because their outputs were complete.
    pub resumed: usize,
    /// The population model's measures (the HTML report plots them).
    pub measures: Option<crate::eval::ShapeModelMeasures>,
    /// The population's shapes as read (leave-one-out).
    pub inputs: Vec<crate::report::InputReport>,
    /// The registration's template (leave-one-out with registration).
    pub template: Option<String>,
}

/// A subject's record `NAME/subject.json`: its report (files relative to the batch folder)
/// and what it was made from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SubjectRecord {
    /// The input file.
    pub input: String,
    /// CRC-32 of the input file's bytes.
    pub input_crc32: u32,
    /// CRC-32 of the atlas file and of the run parameters (JSON).
    pub run_crc32: u32,
    /// The subject's report (files relative to the batch folder).
    pub report: SubjectReport,
}

/// The subject files named by `specs`: a folder gives every shape file in it (by extension:
/// `.ply .stl .obj .vtk .vtp .csv .txt .xy`), sorted by name; a `.list` file gives the paths
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
                .filter(|p| !p.is_dir() && SHAPES.contains(&ext(p).as_str()))
                .collect();
            if in_dir.is_empty() {
                return Err(Error::Population(format!(
                    "{}: no shape file (.ply .stl .obj .vtk .vtp .csv .txt .xy) in this folder",
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

/// Parses `I/N` (`0 <= I < N`).
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || {
        Error::Parameter(format!(
            "--shard {s}: expected I/N with 0 <= I < N, e.g. 0/8 (Slurm: $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT)"
        ))
    };
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// The `i`-th of `n` parts of `files` (see the module doc).
pub fn shard(files: &[PathBuf], i: usize, n: usize) -> Vec<PathBuf> {
    let mut sorted = files.to_vec();
    sorted.sort();
    sorted.dedup();
    sorted
        .into_iter()
        .enumerate()
        .filter(|(k, _)| k % n.max(1) == i)
        .map(|(_, p)| p)
        .collect()
}

/// CRC-32 of a file's bytes.
pub fn file_crc32(path: &Path) -> Result<u32> {
    let bytes = crate::formats::read_input(path)?;
    Ok(crc32fast::hash(&bytes))
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
    let mut folders: Vec<(String, &PathBuf)> =
        files.iter().map(|f| (folder_name(&stem(f)), f)).collect();
    folders.sort();
    if let Some(w) = folders.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(Error::Population(format!(
            "{} and {} would share the output folder {}/; rename one",
            w[0].1.display(),
            w[1].1.display(),
            w[0].0
        )));
    }
    Ok(())
}

/// The record of a complete subject in `out`, if there is one made from `input` (its CRC)
/// with the same run (`run_crc`) and with every file it lists present.
fn complete(out: &Path, folder: &str, input_crc: u32, run_crc: u32) -> Option<SubjectReport> {
    let text = std::fs::read(out.join(folder).join(RECORD)).ok()?;
    let rec: SubjectRecord = serde_json::from_slice(&text).ok()?;
    (rec.input_crc32 == input_crc
        && rec.run_crc32 == run_crc
        && rec.report.files.iter().all(|f| out.join(f).is_file()))
    .then_some(rec.report)
}

/// Fits every subject in `files` with `atlas` (see the module doc) and writes `out/report.json`
/// over all of them. `load` reads one file's shapes (one or more); `atlas_crc` is the CRC-32
/// of the atlas file (part of a subject's completeness). Errors only where the batch as a
/// whole cannot run (unwritable output folder, duplicate subject names); a subject's failure
/// is in the report's `failed`.
#[allow(clippy::too_many_arguments)]
pub fn fit_batch<const D: usize>(
    atlas: &Atlas<D>,
    files: &[PathBuf],
    load: &(dyn Fn(&Path) -> Result<Vec<Shape<D>>> + Sync),
    dataset: &str,
    params: &RunParams,
    atlas_crc: u32,
    out: &Path,
    opts: &BatchOptions,
    progress: &dyn Progress,
) -> Result<Report> {
    check_folder_names(files)?;
    crate::formats::create_dir(out)?;
    let _lock = crate::formats::lock_dir(out)?;
    check_report_shard(&out.join("report.json"), opts.shard.as_deref())?;
    let run_crc = {
        let mut h = crc32fast::Hasher::new();
        h.update(&atlas_crc.to_le_bytes());
        h.update(serde_json::to_string(params).unwrap_or_default().as_bytes());
        h.finalize()
    };
    // (The morpher first: it refuses an atlas without a mesh, which has nothing to fit.)
    let morpher = atlas.morpher(&params.morph)?;
    let fitter = Fitter::new(atlas);
    let label = "fit";
    progress.items_started(label, files.len());
    let skipped = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<(Vec<SubjectReport>, Vec<FailedSubject>)> = files
        .par_iter()
        .map(|file| {
            let r = fit_file(
                atlas, &fitter, &morpher, file, load, params, run_crc, out, opts, &skipped,
            );
            progress.item_done(label, &stem(file));
            r
        })
        .collect();
    progress.items_finished(label);
    finish_batch(
        out,
        dataset,
        atlas,
        &morpher,
        params,
        results,
        opts.shard.clone(),
        skipped.into_inner(),
    )
}

/// Fits shapes held in memory with `atlas`, in parallel, each subject's files written flat
/// into `out` (`NAME_mesh.vtu`, ...) with `out/report.json` over all of them; a subject that
/// fails is in the report's `failed`, as in [`fit_batch`].
pub fn fit_shapes<const D: usize>(
    atlas: &Atlas<D>,
    subjects: &[Shape<D>],
    dataset: &str,
    params: &RunParams,
    out: &Path,
    progress: &dyn Progress,
) -> Result<Report> {
    crate::formats::create_dir(out)?;
    let _lock = crate::formats::lock_dir(out)?;
    // (The morpher first: it refuses an atlas without a mesh, which has nothing to fit.)
    let morpher = atlas.morpher(&params.morph)?;
    let fitter = Fitter::new(atlas);
    let label = "fit";
    progress.items_started(label, subjects.len());
    let results: Vec<(Vec<SubjectReport>, Vec<FailedSubject>)> = subjects
        .par_iter()
        .map(|s| {
            let r = match process_subject(atlas, &fitter, &morpher, s, out, params, "report.html") {
                Ok(r) => (vec![r], Vec::new()),
                Err(e) => (Vec::new(), vec![FailedSubject::new(&s.name, "", &e)]),
            };
            progress.item_done(label, &s.name);
            r
        })
        .collect();
    progress.items_finished(label);
    finish_batch(out, dataset, atlas, &morpher, params, results, None, 0)
}

/// The report of a batch from its subjects' results (see [`finish_report`]).
#[allow(clippy::too_many_arguments)]
fn finish_batch<const D: usize>(
    out: &Path,
    dataset: &str,
    atlas: &Atlas<D>,
    morpher: &crate::mesh::Morpher<D>,
    params: &RunParams,
    results: Vec<(Vec<SubjectReport>, Vec<FailedSubject>)>,
    shard: Option<String>,
    resumed: usize,
) -> Result<Report> {
    let mut subjects = Vec::new();
    let mut failed = Vec::new();
    for (s, f) in results {
        subjects.extend(s);
        failed.extend(f);
    }
    finish_report(
        out,
        dataset,
        atlas,
        Some(morpher),
        subjects,
        params,
        // (An atlas of format version 2 does not know the data's unit: a share only.)
        Some(mean_mesh_report(
            atlas,
            atlas.data_frame.map_or(f64::NAN, |t| t.s),
        )),
        BatchFacts {
            failed,
            shard,
            resumed,
            ..Default::default()
        },
    )
}

/// Refuses to run a batch into a folder whose report (`path`) is another shard's (or of a run
/// without shards, or with shards when this one has none): the report would be replaced.
pub(crate) fn check_report_shard(path: &Path, shard: Option<&str>) -> Result<()> {
    let Ok(bytes) = std::fs::read(path) else {
        return Ok(());
    };
    let before: Option<String> = serde_json::from_slice::<serde_json::Value>(&bytes)
        .ok()
        .and_then(|v| v.get("shard").and_then(|s| s.as_str().map(str::to_string)));
    if before.as_deref() == shard {
        return Ok(());
    }
    let label = |s: Option<&str>| {
        s.map_or("a run without --shard".to_string(), |s| {
            format!("shard {s}")
        })
    };
    Err(Error::Parameter(format!(
        "{}: is the report of {}; {} would replace it: give each shard its own --out (e.g. OUT/shard-1) and join them with merge-reports",
        path.display(),
        label(before.as_deref()),
        label(shard)
    )))
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Removes the temporary files (`.NAME.tmp-PID...`) an interrupted run left in `dir`.
fn remove_temporaries(dir: &Path) {
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') && name.contains(".tmp-") {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// One file of a batch: its subjects' reports and failures.
#[allow(clippy::too_many_arguments)]
fn fit_file<const D: usize>(
    atlas: &Atlas<D>,
    fitter: &Fitter<D>,
    morpher: &Morpher<D>,
    file: &Path,
    load: &(dyn Fn(&Path) -> Result<Vec<Shape<D>>> + Sync),
    params: &RunParams,
    run_crc: u32,
    out: &Path,
    opts: &BatchOptions,
    skipped: &std::sync::atomic::AtomicUsize,
) -> (Vec<SubjectReport>, Vec<FailedSubject>) {
    let input = file.display().to_string();
    let fail = |name: &str, e: &Error| FailedSubject::new(name, &input, e);
    let name = stem(file);
    let input_crc = match file_crc32(file) {
        Ok(c) => c,
        Err(e) => return (Vec::new(), vec![fail(&name, &e)]),
    };
    // A one-shape file's subject is named after the file (its folder is known before
    // reading it); a file of several outlines names its subjects FILE.SHAPE.
    if opts.resume
        && let Some(r) = complete(out, &folder_name(&name), input_crc, run_crc)
    {
        skipped.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        return (vec![r], Vec::new());
    }
    let shapes = match load(file) {
        Ok(s) if s.is_empty() => {
            let e = Error::Population(format!("{}: no shape in this file", file.display()));
            return (Vec::new(), vec![fail(&name, &e)]);
        }
        Ok(s) => s,
        Err(e) => return (Vec::new(), vec![fail(&name, &e)]),
    };
    let several = shapes.len() > 1;
    let mut reports = Vec::new();
    let mut failed = Vec::new();
    let mut folders = std::collections::HashSet::new();
    for mut shape in shapes {
        let subject = if several {
            format!("{name}.{}", shape.name)
        } else {
            name.clone()
        };
        let folder = folder_name(&subject);
        if !folders.insert(folder.clone()) {
            let e = Error::Population(format!(
                "{}: another shape of this file already has the output folder {folder}/; rename one",
                file.display()
            ));
            failed.push(fail(&subject, &e));
            continue;
        }
        if several
            && opts.resume
            && let Some(r) = complete(out, &folder, input_crc, run_crc)
        {
            skipped.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            reports.push(r);
            continue;
        }
        shape.name = subject.clone();
        let dir = out.join(&folder);
        let done = std::fs::create_dir_all(&dir)
            .map_err(|e| Error::io(&dir, e))
            .and_then(|_| {
                // The record goes first (the subject is incomplete until it is back), and
                // the temporary files of an interrupted run with it.
                let _ = std::fs::remove_file(dir.join(RECORD));
                remove_temporaries(&dir);
                process_subject(
                    atlas,
                    fitter,
                    morpher,
                    &shape,
                    &dir,
                    params,
                    "../report.html",
                )
            })
            .and_then(|mut r| {
                for f in &mut r.files {
                    *f = format!("{folder}/{f}");
                }
                let rec = SubjectRecord {
                    input: file.display().to_string(),
                    input_crc32: input_crc,
                    run_crc32: run_crc,
                    report: r,
                };
                let text = serde_json::to_vec_pretty(&rec)
                    .map_err(|e| Error::Numerical(format!("subject record: {e}")))?;
                crate::formats::write_atomic(&dir.join(RECORD), &text)?;
                Ok(rec.report)
            });
        match done {
            Ok(r) => reports.push(r),
            Err(e) => failed.push(fail(&subject, &e)),
        }
    }
    (reports, failed)
}

/// Joins the `report.json` of several shards (or batches) of one atlas and run into one
/// report: subjects and failures concatenated (sorted by name), summary recomputed. Refuses
/// reports of another dimension, atlas or parameters, and a subject that is in two of them.
pub fn merge_reports(paths: &[PathBuf]) -> Result<Report> {
    let mut merged: Option<Report> = None;
    for p in paths {
        let text = crate::formats::read_input(p)?;
        let r: Report = serde_json::from_slice(&text)
            .map_err(|e| Error::parse(p, e.line(), format!("not an atlasmesh report: {e}")))?;
        match &mut merged {
            None => merged = Some(r),
            Some(m) => {
                if m.dimension != r.dimension || m.modes != r.modes || m.parameters != r.parameters
                {
                    return Err(Error::Population(format!(
                        "{}: made with another atlas or other parameters than {}",
                        p.display(),
                        paths[0].display()
                    )));
                }
                m.subjects.extend(r.subjects);
                m.failed.extend(r.failed);
                m.summary.resumed += r.summary.resumed;
            }
        }
    }
    let mut m = merged.ok_or_else(|| Error::Population("no report to merge".into()))?;
    m.subjects.sort_by(|a, b| a.name.cmp(&b.name));
    if let Some(w) = m.subjects.windows(2).find(|w| w[0].name == w[1].name) {
        return Err(Error::Population(format!(
            "subject {} is in two of the reports (overlapping shards?)",
            w[0].name
        )));
    }
    m.failed.sort_by(|a, b| a.name.cmp(&b.name));
    let resumed = m.summary.resumed;
    m.summary = crate::report::Summary::of(&m.subjects, m.failed.len());
    m.summary.resumed = resumed;
    m.shard = None;
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_are_disjoint_and_cover_the_list() {
        let files: Vec<PathBuf> = (0..23)
            .rev()
            .map(|k| PathBuf::from(format!("s{k:03}.ply")))
            .collect();
        for n in [1, 2, 5, 8, 30] {
            let mut all: Vec<PathBuf> = (0..n).flat_map(|i| shard(&files, i, n)).collect();
            assert_eq!(
                all.len(),
                files.len(),
                "{n} shards cover every subject once"
            );
            all.sort();
            all.dedup();
            assert_eq!(all.len(), files.len());
            let sizes: Vec<usize> = (0..n).map(|i| shard(&files, i, n).len()).collect();
            assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1);
            // Stable: the same list in another order gives the same parts.
            let mut shuffled = files.clone();
            shuffled.rotate_left(7);
            for i in 0..n {
                assert_eq!(shard(&files, i, n), shard(&shuffled, i, n));
            }
        }
    }

    #[test]
    fn shard_specs_are_checked() {
        assert_eq!(parse_shard("2/8").unwrap(), (2, 8));
        for bad in ["8/8", "1", "a/2", "0/0", "-1/3"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }
}

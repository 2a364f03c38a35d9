//! The item loop of every run: its items (subject files, instances' weights, subjects'
//! landmarks) taken in parallel, each into its own folder whose record is written last,
//! resumed, sharded, with progress, then the run's report.
//!
//! A unit (one subject, one instance) lives in `OUT/NAME/`; its record `NAME/RECORD` is
//! written last, through a temporary name and a rename like every other output, so a unit is
//! complete exactly when its record is there, every file it lists exists and it was made from
//! the same input (CRC-32 of the input file) with the same run (CRC-32 of the atlas and the
//! parameters). A re-run skips complete units (resume); an interrupted run leaves no
//! half-written file. A unit that fails is reported with its reason and the run goes on.

use super::shard::Shard;
use crate::error::{Error, Result};
use crate::report::FailedSubject;
use crate::study::progress::Progress;
use rayon::prelude::*;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The report of one unit of a run, which lists its files (relative to the run's folder).
pub trait UnitReport: Serialize + DeserializeOwned + Send {
    /// The unit's files.
    fn files(&self) -> &[String];
    /// The unit's files, to prefix with its folder.
    fn files_mut(&mut self) -> &mut Vec<String>;
    /// Records what the unit cost: its wall time (seconds) and, when the run makes one unit
    /// at a time and the program counts its heap, the heap's peak meanwhile (MB).
    fn set_cost(&mut self, _seconds: f64, _heap_peak_mb: Option<f64>) {}
}

/// A kind of run: what one item makes and what the run's report is.
pub trait Job: Sync {
    /// One item of the run.
    type Item: Sync + Clone;
    /// What orders the items for sharding.
    type Key: Ord;
    /// The report of one unit.
    type Report: UnitReport;
    /// What the run returns (its report).
    type Output;
    /// The progress label.
    const LABEL: &'static str;
    /// The run's report file in the output folder (a shard refuses another shard's).
    const REPORT: &'static str;
    /// The item's name, for progress.
    fn name(&self, item: &Self::Item) -> String;
    /// The item's sort key for sharding (its position `k` in the list, or its path).
    fn key(&self, k: usize, item: &Self::Item) -> Self::Key;
    /// Makes one item's units (one or more), through `units`.
    fn run(
        &self,
        item: &Self::Item,
        units: &Units<'_>,
    ) -> Vec<std::result::Result<Self::Report, FailedSubject>>;
    /// The run's report from its units' reports, failures and resumed count, written.
    fn finish(&self, outcome: RunOutcome<Self::Report>) -> Result<Self::Output>;
}

/// What the item loop gathered: the units' reports, the failures, how many were resumed.
#[derive(Debug)]
pub struct RunOutcome<R> {
    /// Reports of the units made or resumed.
    pub reports: Vec<R>,
    /// Units that failed, with the reason.
    pub failed: Vec<FailedSubject>,
    /// Units skipped because their outputs were complete.
    pub resumed: usize,
}

/// How the loop runs: the output folder, resume and shard.
#[derive(Clone, Copy, Debug)]
pub struct Looping<'a> {
    /// The output folder.
    pub out: &'a Path,
    /// Skip complete units.
    pub resume: bool,
    /// Only this part of the items.
    pub shard: Option<Shard>,
    /// The record file's name in a unit's folder.
    pub record: &'static str,
}

/// A unit's record `NAME/RECORD`: its report (files relative to the run's folder) and what
/// it was made from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Record<R> {
    /// The input file (empty when the unit has none).
    #[serde(default)]
    pub input: String,
    /// CRC-32 of the input file's bytes (0 without one).
    #[serde(default)]
    pub input_crc32: u32,
    /// CRC-32 of the atlas file and of the run parameters (and of what else the unit is
    /// made from).
    pub run_crc32: u32,
    /// The unit's report.
    pub report: R,
}

/// What a unit is made from: its input file and the run.
#[derive(Clone, Copy, Debug)]
pub struct Origin<'a> {
    /// The input file (empty when there is none).
    pub input: &'a str,
    /// CRC-32 of the input file.
    pub input_crc32: u32,
    /// CRC-32 of the run.
    pub run_crc32: u32,
}

/// The units of one item: resumed or made into their folders, with their records.
pub struct Units<'a> {
    looping: Looping<'a>,
    resumed: &'a AtomicUsize,
}

impl Units<'_> {
    /// The run's output folder.
    pub fn out(&self) -> &Path {
        self.looping.out
    }

    /// The report of the unit in `folder` when resuming and it is complete (made from
    /// `origin`, with every file it lists present); counted as resumed.
    pub fn resumed<R: UnitReport>(&self, folder: &str, origin: Origin<'_>) -> Option<R> {
        if !self.looping.resume {
            return None;
        }
        let out = self.looping.out;
        let text = std::fs::read(out.join(folder).join(self.looping.record)).ok()?;
        let rec: Record<R> = serde_json::from_slice(&text).ok()?;
        let done = rec.input_crc32 == origin.input_crc32
            && rec.run_crc32 == origin.run_crc32
            && rec.report.files().iter().all(|f| out.join(f).is_file());
        done.then(|| {
            self.resumed.fetch_add(1, Ordering::Relaxed);
            rec.report
        })
    }

    /// Makes the unit in `folder` (resumed when complete): its old record and the temporary
    /// files of an interrupted run removed, `make` run in `OUT/folder`, its files prefixed
    /// with `folder/`, its record written last.
    pub fn make<R: UnitReport>(
        &self,
        folder: &str,
        origin: Origin<'_>,
        make: impl FnOnce(&Path) -> Result<R>,
    ) -> Result<R> {
        if let Some(r) = self.resumed(folder, origin) {
            return Ok(r);
        }
        let dir = self.looping.out.join(folder);
        crate::formats::create_dir(&dir)?;
        // The record goes first (the unit is incomplete until it is back), and the temporary
        // files of an interrupted run with it.
        let _ = std::fs::remove_file(dir.join(self.looping.record));
        remove_temporaries(&dir);
        // One unit at a time: the heap's peak from here on is this unit's.
        let alone = rayon::current_num_threads() == 1;
        if alone {
            super::memory::reset_heap_peak();
        }
        let t0 = std::time::Instant::now();
        let mut report = make(&dir).inspect_err(|_| {
            // A unit refused before it wrote anything leaves no empty folder behind (one that
            // holds files is left as it is).
            let _ = std::fs::remove_dir(&dir);
        })?;
        let heap = if alone {
            super::memory::heap_peak_mb()
        } else {
            None
        };
        report.set_cost(t0.elapsed().as_secs_f64(), heap);
        for f in report.files_mut() {
            *f = format!("{folder}/{f}");
        }
        let rec = Record {
            input: origin.input.to_string(),
            input_crc32: origin.input_crc32,
            run_crc32: origin.run_crc32,
            report,
        };
        let text = serde_json::to_vec_pretty(&rec)
            .map_err(|e| Error::Numerical(format!("record of {folder}: {e}")))?;
        crate::formats::write_atomic(&dir.join(self.looping.record), &text)?;
        Ok(rec.report)
    }
}

/// Runs `job` over `items` (see the module doc): the output folder made and locked, the
/// shard's part of the items made in parallel (on the current rayon pool) with progress,
/// then [`Job::finish`] while the folder is still locked.
///
/// # Errors
/// Only where the run as a whole cannot go: an output folder that cannot be made or is
/// locked by another run, a report of another shard in it, and the errors of
/// [`Job::finish`].
pub fn run_items<J: Job>(
    job: &J,
    items: &[J::Item],
    looping: Looping<'_>,
    progress: &dyn Progress,
) -> Result<J::Output> {
    crate::formats::create_dir(looping.out)?;
    let _lock = crate::formats::lock_dir(looping.out)?;
    let label = looping.shard.map(|s| s.label());
    check_report_shard(&looping.out.join(J::REPORT), label.as_deref())?;
    let mine: Vec<J::Item> = match looping.shard {
        Some(s) => {
            let keyed: Vec<(usize, J::Item)> = items.iter().cloned().enumerate().collect();
            s.select(&keyed, |(k, it)| job.key(*k, it))
                .into_iter()
                .map(|(_, it)| it)
                .collect()
        }
        None => items.to_vec(),
    };
    let resumed = AtomicUsize::new(0);
    let units = Units {
        looping,
        resumed: &resumed,
    };
    progress.items_started(J::LABEL, mine.len());
    let results: Vec<_> = mine
        .par_iter()
        .map(|item| {
            let r = job.run(item, &units);
            progress.item_done(J::LABEL, &job.name(item));
            r
        })
        .collect();
    progress.items_finished(J::LABEL);
    let mut outcome = RunOutcome {
        reports: Vec::new(),
        failed: Vec::new(),
        resumed: resumed.into_inner(),
    };
    for r in results.into_iter().flatten() {
        match r {
            Ok(r) => outcome.reports.push(r),
            Err(f) => outcome.failed.push(f),
        }
    }
    job.finish(outcome)
}

/// Refuses to run into a folder whose report (`path`) is another shard's (or of a run
/// without shards, or with shards when this one has none): the report would be replaced.
fn check_report_shard(path: &Path, shard: Option<&str>) -> Result<()> {
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

/// Checks that no two of `names` would share an output folder (as
/// file names: `S 1` and `S_1` both make `S_1/`); `what` says
/// where each comes from in the error.
///
/// # Errors
/// [`Error::Population`] naming the two and their folder.
pub fn check_folders<'a>(names: impl IntoIterator<Item = (String, &'a str)>) -> Result<()> {
    let mut folders: Vec<(String, &str)> = names
        .into_iter()
        .map(|(n, what)| (crate::study::file_name(&n), what))
        .collect();
    folders.sort();
    if let Some(w) = folders.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(Error::Population(format!(
            "{} and {} would share the output folder {}/; rename one",
            w[0].1, w[1].1, w[0].0
        )));
    }
    Ok(())
}

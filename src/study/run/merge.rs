//! One merge for the reports of every kind of run: the reports of several shards (or runs)
//! of one atlas and parameters joined into one.

use crate::error::{Error, Result};
use crate::report::{InstancesReport, InstancesSummary, PosteriorRunReport, Report, Summary};
use serde::de::DeserializeOwned;

/// A run's report that shards of the run can be joined into.
pub trait RunReport: DeserializeOwned {
    /// What the report is, for errors ("report", "instances report").
    const WHAT: &'static str;
    /// Whether `other` was made with the same atlas and parameters.
    fn same_run(&self, other: &Self) -> bool;
    /// Adds `other`'s units, failures and resumed count.
    fn join(&mut self, other: Self);
    /// Sorts the units and failures by name; the names of the units, sorted.
    fn sort(&mut self) -> Vec<&str>;
    /// The summary recomputed over the units, the shard removed.
    fn summarize(&mut self);
}

/// Joins the reports in `paths` into one (see [`RunReport`]): units and failures
/// concatenated, sorted by name, summary recomputed.
///
/// # Errors
/// [`Error::Parse`] for a file that is not such a report; [`Error::Population`] for
/// reports of another dimension, atlas or parameters, and a unit that is in two of them.
pub fn merge<R: RunReport>(paths: &[std::path::PathBuf]) -> Result<R> {
    let mut merged: Option<R> = None;
    for p in paths {
        let text = crate::formats::read_input(p)?;
        let r: R = serde_json::from_slice(&text)
            .map_err(|e| Error::parse(p, e.line(), format!("not an atlasmesh {}: {e}", R::WHAT)))?;
        match &mut merged {
            None => merged = Some(r),
            Some(m) if m.same_run(&r) => m.join(r),
            Some(_) => {
                return Err(Error::Population(format!(
                    "{}: made with another atlas or other parameters than {}",
                    p.display(),
                    paths[0].display()
                )));
            }
        }
    }
    let mut m = merged.ok_or_else(|| Error::Population("no report to merge".into()))?;
    if let Some(w) = m.sort().windows(2).find(|w| w[0] == w[1]) {
        return Err(Error::Population(format!(
            "{} is in two of the reports (overlapping shards?)",
            w[0]
        )));
    }
    m.summarize();
    Ok(m)
}

impl RunReport for Report {
    const WHAT: &'static str = "report";
    fn same_run(&self, o: &Self) -> bool {
        let crc = |r: &Self| r.atlas.as_ref().map(|a| a.checksum_crc32.clone());
        self.dimension == o.dimension
            && self.modes == o.modes
            && self.parameters == o.parameters
            && crc(self) == crc(o)
    }
    fn join(&mut self, o: Self) {
        self.subjects.extend(o.subjects);
        self.failed.extend(o.failed);
        self.summary.resumed += o.summary.resumed;
        self.resident_peak_mb = match (self.resident_peak_mb, o.resident_peak_mb) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
    fn sort(&mut self) -> Vec<&str> {
        self.subjects.sort_by(|a, b| a.name.cmp(&b.name));
        self.failed.sort_by(|a, b| a.name.cmp(&b.name));
        self.subjects.iter().map(|s| s.name.as_str()).collect()
    }
    fn summarize(&mut self) {
        let resumed = self.summary.resumed;
        self.summary = Summary::of(&self.subjects, self.failed.len());
        self.summary.resumed = resumed;
        self.shard = None;
    }
}

impl RunReport for InstancesReport {
    const WHAT: &'static str = "instances report";
    fn same_run(&self, o: &Self) -> bool {
        self.dimension == o.dimension
            && self.eigenvalues == o.eigenvalues
            && self.parameters == o.parameters
            && self.sampling == o.sampling
    }
    fn join(&mut self, o: Self) {
        self.instances.extend(o.instances);
        self.failed.extend(o.failed);
        self.summary.resumed += o.summary.resumed;
    }
    fn sort(&mut self) -> Vec<&str> {
        self.instances.sort_by(|a, b| a.name.cmp(&b.name));
        self.failed.sort_by(|a, b| a.name.cmp(&b.name));
        self.instances.iter().map(|s| s.name.as_str()).collect()
    }
    fn summarize(&mut self) {
        let resumed = self.summary.resumed;
        self.summary = InstancesSummary::of(&self.instances, self.failed.len());
        self.summary.resumed = resumed;
        self.shard = None;
    }
}

impl RunReport for PosteriorRunReport {
    const WHAT: &'static str = "posterior report";
    fn same_run(&self, o: &Self) -> bool {
        self.dimension == o.dimension && self.modes == o.modes && self.atlas == o.atlas
    }
    fn join(&mut self, o: Self) {
        self.subjects.extend(o.subjects);
        self.failed.extend(o.failed);
        self.resumed += o.resumed;
    }
    fn sort(&mut self) -> Vec<&str> {
        self.subjects.sort_by(|a, b| a.name.cmp(&b.name));
        self.failed.sort_by(|a, b| a.name.cmp(&b.name));
        self.subjects.iter().map(|s| s.name.as_str()).collect()
    }
    fn summarize(&mut self) {
        self.shard = None;
    }
}

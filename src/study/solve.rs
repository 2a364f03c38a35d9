//! Solving a written deck with CalculiX: `ccx` run in the output folder, bounded in time,
//! its reaction forces read back from its `.dat` file, the stiffness of the loaded set.

use crate::error::{Error, Result};
use crate::mesh::{AXES, AppliedLoadCase};
pub use crate::report::SolveReport;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The longest a solve may run (s), unless `ATLASMESH_SOLVER_TIMEOUT` says otherwise.
pub const SOLVER_TIMEOUT_S: u64 = 3600;

/// CalculiX's executable: `ATLASMESH_CCX`, else `ccx` on the `PATH`; `None` when there is none.
pub fn find_calculix() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("ATLASMESH_CCX") {
        let p = PathBuf::from(p);
        return p.is_file().then_some(p);
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("ccx"))
        .find(|p| p.is_file())
}

/// How to run the deck by hand (when CalculiX is not found).
pub fn how_to_solve(deck: &Path, load: &AppliedLoadCase) -> String {
    let dir = deck.parent().unwrap_or(Path::new("."));
    let stem = deck
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let set = load.loaded.as_ref().map(|l| l.0.as_str()).unwrap_or("?");
    format!(
        "CalculiX (ccx) is not on the PATH (or ATLASMESH_CCX): the deck is written; solve it with \
         `cd {} && ccx -i {stem}` and read the total reaction force of set {set} in {stem}.dat",
        dir.display()
    )
}

/// Runs CalculiX (`ccx`, [`find_calculix`]) on `deck` (an `.inp` with the step of `load`) in
/// the deck's folder, with `threads` threads, its output in `NAME_ccx.log` there; reads the
/// reaction force totals of `load`'s sets from `NAME.dat` and gives the stiffness of the
/// loaded set: `k = |RF_axis / u_axis|` (N/mm).
///
/// # Errors
/// [`Error::Parameter`] when CalculiX is not found, fails (its log's last lines), runs past
/// the timeout (killed), or its `.dat` lacks a set's totals; [`Error::Io`] naming the file.
pub fn solve_calculix(deck: &Path, load: &AppliedLoadCase, threads: usize) -> Result<SolveReport> {
    let ccx = find_calculix().ok_or_else(|| Error::Parameter(how_to_solve(deck, load)))?;
    let dir = deck.parent().unwrap_or(Path::new("."));
    let stem = deck
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let log_path = dir.join(format!("{stem}_ccx.log"));
    let log = std::fs::File::create(&log_path).map_err(|e| Error::io(&log_path, e))?;
    let err = log.try_clone().map_err(|e| Error::io(&log_path, e))?;
    let timeout = std::env::var("ATLASMESH_SOLVER_TIMEOUT")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .unwrap_or(SOLVER_TIMEOUT_S);
    // CalculiX writes this list only when a tie misses nodes: one from an earlier run goes.
    let untied_path = dir.join(format!("{stem}_WarnNodeMissTiedContact.nam"));
    if untied_path.is_file() {
        std::fs::remove_file(&untied_path).map_err(|e| Error::io(&untied_path, e))?;
    }
    let start = Instant::now();
    let mut child = std::process::Command::new(&ccx)
        .arg("-i")
        .arg(&stem)
        .current_dir(dir)
        .env("OMP_NUM_THREADS", threads.max(1).to_string())
        .env("CCX_NPROC_EQUATION_SOLVER", threads.max(1).to_string())
        .stdin(std::process::Stdio::null())
        .stdout(log)
        .stderr(err)
        .spawn()
        .map_err(|e| Error::io(&ccx, e))?;
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| Error::io(&ccx, e))? {
            break s;
        }
        if start.elapsed() > Duration::from_secs(timeout) {
            let _ = child.kill();
            let _ = child.wait();
            return Err(Error::Parameter(format!(
                "CalculiX ran past {timeout} s on {} and was stopped (ATLASMESH_SOLVER_TIMEOUT \
                 sets the limit)",
                deck.display()
            )));
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let seconds = start.elapsed().as_secs_f64();
    let log_text = std::fs::read_to_string(&log_path).unwrap_or_default();
    let dat_path = dir.join(format!("{stem}.dat"));
    if !status.success() || log_text.contains("*ERROR") || !dat_path.is_file() {
        return Err(Error::Parameter(format!(
            "CalculiX failed on {} ({status}); its log {} ends: {}",
            deck.display(),
            log_path.display(),
            log_tail(&log_text)
        )));
    }
    let dat = std::fs::read_to_string(&dat_path).map_err(|e| Error::io(&dat_path, e))?;
    let totals = reaction_totals(&dat);
    let mut reactions = BTreeMap::new();
    for set in &load.reaction_sets {
        let rf = totals.get(&set.to_ascii_uppercase()).ok_or_else(|| {
            Error::parse(
                &dat_path,
                0,
                format!("no total reaction force of set {set}"),
            )
        })?;
        reactions.insert(set.clone(), *rf);
    }
    let (loaded_set, axis, u) = load.loaded.clone().ok_or_else(|| {
        Error::Parameter(format!(
            "{}: no displacement is non-zero; a stiffness needs a displaced set",
            deck.display()
        ))
    })?;
    let reaction = reactions[&loaded_set][axis];
    // CalculiX lists the tie's nodes it could not tie, one number per line after the header.
    let untied_nodes = std::fs::read_to_string(&untied_path)
        .map(|t| {
            t.lines()
                .filter(|l| l.trim().parse::<usize>().is_ok())
                .count()
        })
        .unwrap_or(0);
    Ok(SolveReport {
        solver: ccx.display().to_string(),
        deck: deck
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default(),
        seconds,
        peak_memory_mb: children_peak_rss_mb(),
        reactions,
        loaded_set,
        axis: AXES[axis].into(),
        displacement_mm: u,
        reaction_n: reaction,
        stiffness_n_per_mm: (reaction / u).abs(),
        untied_nodes,
        largest_displacement_mm: None,
    })
}

/// The last six non-empty lines of a solver's log, joined by ` / `.
fn log_tail(log: &str) -> String {
    let tail: Vec<&str> = log
        .lines()
        .filter(|l| !l.trim().is_empty())
        .rev()
        .take(6)
        .collect();
    tail.into_iter().rev().collect::<Vec<_>>().join(" / ")
}

/// The reaction force totals of a CalculiX `.dat` file by set (upper case, as CalculiX
/// names sets): the three numbers after each `total force (fx,fy,fz) for set NAME and time
/// T` line; the last time's when there are several.
pub fn reaction_totals(dat: &str) -> BTreeMap<String, [f64; 3]> {
    let mut out = BTreeMap::new();
    let mut lines = dat.lines();
    while let Some(l) = lines.next() {
        let Some(rest) = l.trim().strip_prefix("total force (fx,fy,fz) for set ") else {
            continue;
        };
        let Some(name) = rest.split_whitespace().next() else {
            continue;
        };
        let values = lines.by_ref().find(|v| !v.trim().is_empty());
        let v: Vec<f64> = values
            .unwrap_or("")
            .split_whitespace()
            .filter_map(|t| t.parse().ok())
            .collect();
        if v.len() == 3 {
            out.insert(name.to_ascii_uppercase(), [v[0], v[1], v[2]]);
        }
    }
    out
}

/// The largest resident memory of the waited-for children (MB of 2^20 bytes; 0 when the
/// system does not say).
fn children_peak_rss_mb() -> f64 {
    super::run::peak_resident_bytes(libc::RUSAGE_CHILDREN).map_or(0.0, |b| b / 1_048_576.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reaction_totals_are_read_from_a_dat_file() {
        let dat = "\n                        S T E P       1\n\n\
 total force (fx,fy,fz) for set TOP and time  0.1000000E+01\n\n\
       -2.056312E-11  3.122544E-11 -2.472035E+03\n\n\
 total force (fx,fy,fz) for set RIGID_1 and time  0.1000000E+01\n\n\
        1.0E-12 -2.0E-12  0.000000E+00\n";
        let t = reaction_totals(dat);
        assert_eq!(t.len(), 2);
        assert_eq!(t["TOP"], [-2.056312e-11, 3.122544e-11, -2.472035e3]);
        assert_eq!(t["RIGID_1"][1], -2.0e-12);
    }
}

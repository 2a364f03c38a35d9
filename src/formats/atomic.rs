//! Output folders and atomic writes (a temporary name, then a rename), and the bound on
//! counts read from headers.

use crate::error::{Error, Result};
use std::path::Path;

/// Upper bound on counts read from file headers (guards against absurd allocations).
pub(crate) const MAX_COUNT: usize = 50_000_000;

/// Creates the output folder `dir` (and its parents); a clear error when a file is in the way.
pub fn create_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::io(
            dir,
            std::io::Error::other("exists and is a file, not a folder; choose another --out"),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
}

/// Takes the output folder `dir` for this run alone: an advisory lock on the folder itself
/// (no file is made; the system releases it when the process ends, killed or not), held
/// while the returned handle lives. A second run into the same folder (two shards started
/// with one `--out`) is refused instead of overwriting the first one's report.
///
/// # Errors
/// [`Error::Io`] naming `dir` when another process holds it.
pub fn lock_dir(dir: &Path) -> Result<std::fs::File> {
    let f = std::fs::File::open(dir).map_err(|e| Error::io(dir, e))?;
    match f.try_lock() {
        Ok(()) => Ok(f),
        Err(std::fs::TryLockError::WouldBlock) => Err(Error::io(
            dir,
            std::io::Error::new(
                std::io::ErrorKind::ResourceBusy,
                "another atlasmesh run is writing into this folder (two shards with one --out?); wait for it to end, or give each run its own --out (e.g. OUT/shard-1)",
            ),
        )),
        Err(std::fs::TryLockError::Error(e)) => Err(Error::io(dir, e)),
    }
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so that
/// an interrupted run never leaves a half-written file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    // A failed write (a full disk, a file-size limit) leaves neither the temporary file nor a
    // half-written `path`; the error names `path`.
    std::fs::write(&tmp, bytes).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })?;
    remove_stale_temporaries(dir, &name);
    Ok(())
}

/// Removes the temporaries of `name` in `dir` (`.NAME.tmp-PID`) that a process no longer
/// running left (killed mid-write, say), once `name` is written whole. A temporary whose
/// process may still run (or where `/proc` cannot tell) is left alone.
fn remove_stale_temporaries(dir: &Path, name: &str) {
    let prefix = format!(".{name}.tmp-");
    let proc_fs = Path::new("/proc/self").exists();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(pid) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else {
            continue;
        };
        let gone = pid.parse::<u32>().is_ok_and(|p| {
            proc_fs && p != std::process::id() && !Path::new(&format!("/proc/{p}")).exists()
        });
        if gone {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

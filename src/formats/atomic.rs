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
    })
}

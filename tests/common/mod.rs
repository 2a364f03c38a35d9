//! Shared helpers of the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The data folder named by `ATLASMESH_DATA`, or `None` (the test prints that it was skipped).
/// When the variable is set, a missing folder is a failure.
pub fn data_dir(test: &str) -> Option<PathBuf> {
    match std::env::var_os("ATLASMESH_DATA") {
        None => {
            eprintln!("{test}: skipped (ATLASMESH_DATA is not set)");
            None
        }
        Some(d) => {
            let p = PathBuf::from(d);
            assert!(p.is_dir(), "ATLASMESH_DATA={} is not a folder", p.display());
            Some(p)
        }
    }
}

/// A fresh temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("atlasmesh-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

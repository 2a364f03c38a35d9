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

/// The 40 IMM hands of `data`, resampled in correspondence to 2001 points (`Some`) or as
/// given (56 landmarks, `None`); open outlines.
pub fn hands(
    data: &std::path::Path,
    resample: Option<usize>,
) -> Vec<atlasmesh::geometry::Shape<2>> {
    atlasmesh::pipeline::load_population(
        &[data.join("imm-hands-2d/hands_long.csv")],
        &atlasmesh::pipeline::PopulationOptions {
            closed: false,
            resample,
        },
    )
    .unwrap()
}

/// The distal femurs S001-S030 of `data`.
pub fn femurs(data: &std::path::Path) -> Vec<atlasmesh::geometry::Shape<3>> {
    let paths: Vec<_> = (1..=30)
        .map(|k| {
            data.join(format!(
                "knee-distal-femur-synthetic-3d/femur/S{k:03}_Femur.ply"
            ))
        })
        .collect();
    atlasmesh::pipeline::load_surfaces(&paths).unwrap()
}

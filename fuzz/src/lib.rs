//! Shared by the fuzz targets: the readers take paths (as users give them), so every input is
//! written to a file with the format's extension in a per-process temporary folder first.

use std::path::PathBuf;

/// Writes `data` to `input.EXT` in this process's fuzz folder and returns its path.
pub fn file(data: &[u8], ext: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("atlasmesh-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let p = dir.join(format!("input.{ext}"));
    std::fs::write(&p, data).expect("fuzz temporary file");
    p
}

/// A block of 2 × 2 × 2 unit hexahedra.
pub fn block() -> atlasmesh::mesh::FeMesh<3> {
    atlasmesh::mesh::FeMesh::block(2)
}

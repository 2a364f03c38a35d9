//! Shared by the fuzz targets: they call atlasmesh's parsers on the bytes (no file), with a
//! file name that carries the format's extension; only the atlas header reader needs a file.

use std::path::PathBuf;

/// The name `input.EXT` the parsers see (it selects the format; no such file is read).
pub fn name(ext: &str) -> PathBuf {
    PathBuf::from(format!("input.{ext}"))
}

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

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
pub fn block() -> atlasmesh::fe::FeMesh<3> {
    let id = |x: usize, y: usize, z: usize| x + 3 * (y + 3 * z);
    let mut nodes = Vec::new();
    for z in 0..3 {
        for y in 0..3 {
            for x in 0..3 {
                nodes.push([x as f64, y as f64, z as f64]);
            }
        }
    }
    let mut connectivity = Vec::new();
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..2 {
                connectivity.extend([
                    id(x, y, z),
                    id(x + 1, y, z),
                    id(x + 1, y + 1, z),
                    id(x, y + 1, z),
                    id(x, y, z + 1),
                    id(x + 1, y, z + 1),
                    id(x + 1, y + 1, z + 1),
                    id(x, y + 1, z + 1),
                ]);
            }
        }
    }
    atlasmesh::fe::FeMesh {
        nodes,
        kind: atlasmesh::fe::ElementKind::Hex8,
        connectivity,
        sets: Default::default(),
    }
}

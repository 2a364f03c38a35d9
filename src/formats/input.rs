//! Input files read whole, safely: regular files only (a device such as `/dev/zero`, a FIFO
//! or a folder is refused before it is opened, so nothing reads forever or hangs), at most
//! [`max_input_bytes`] (2 GiB unless `ATLASMESH_MAX_INPUT_BYTES` says otherwise), and shapes
//! and meshes of at most [`max_points`] points (4 million unless `ATLASMESH_MAX_POINTS` says
//! otherwise), refused as soon as a header or the parse tells, so that the memory a refused
//! input takes stays bounded.

use crate::error::{Error, Result};
use std::io::Read as _;
use std::path::Path;

/// The default largest input file, in bytes.
pub const DEFAULT_MAX_INPUT_BYTES: u64 = 2 << 30;

/// The largest input file read, in bytes: `ATLASMESH_MAX_INPUT_BYTES` when set to a number,
/// else [`DEFAULT_MAX_INPUT_BYTES`].
pub fn max_input_bytes() -> u64 {
    std::env::var("ATLASMESH_MAX_INPUT_BYTES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(DEFAULT_MAX_INPUT_BYTES)
}

/// What decoding one compressed file may take, in bytes: [`DECODE_FACTOR`] times the file's
/// size, at least [`DECODE_FLOOR`] (or `ATLASMESH_MAX_DECODED_BYTES` when set to a number:
/// label maps of large, mostly empty volumes compress beyond the factor). Real data compress
/// a few times (meshes) to some tens of times (label maps: the shared VerSe and
/// TotalSegmentator maps 11-68 times); a file announcing more is refused before anything is
/// inflated: a decompression bomb, or a header that lies.
pub fn decode_budget(compressed_bytes: usize) -> usize {
    let floor = std::env::var("ATLASMESH_MAX_DECODED_BYTES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(DECODE_FLOOR);
    compressed_bytes.saturating_mul(DECODE_FACTOR).max(floor)
}

/// See [`decode_budget`].
pub const DECODE_FACTOR: usize = 64;
/// See [`decode_budget`].
pub const DECODE_FLOOR: usize = 256 << 20;

/// The default largest number of points (vertices, nodes) of an input shape or mesh.
pub const DEFAULT_MAX_POINTS: usize = 4_000_000;

/// The largest number of points of an input shape or mesh: `ATLASMESH_MAX_POINTS` when set
/// to a number, else [`DEFAULT_MAX_POINTS`]. A fit takes about 1 kB of memory per point of
/// its subject, so the default keeps a fit under about 4 GB.
pub fn max_points() -> usize {
    std::env::var("ATLASMESH_MAX_POINTS")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(DEFAULT_MAX_POINTS)
}

/// [`Error::Parse`] of `path` when `count` points (or, for `per_point` > 1, items of which
/// each point has about `per_point`) exceed [`max_points`].
pub(crate) fn check_points(path: &Path, count: usize, per_point: usize) -> Result<()> {
    let cap = max_points();
    if count / per_point.max(1) > cap {
        let what = if per_point > 1 {
            format!("{count} triangles (about {} points)", count / per_point)
        } else {
            format!("{count} points")
        };
        return Err(Error::parse(
            path,
            0,
            format!(
                "{what}, beyond the limit of {cap} points (set ATLASMESH_MAX_POINTS to raise it; a fit takes about 1 kB per point), or decimate the surface"
            ),
        ));
    }
    Ok(())
}

/// The bytes of the input file `path`.
///
/// # Errors
/// [`Error::Parse`] for a file that is not regular or is larger than [`max_input_bytes`];
/// [`Error::Io`] when it cannot be read.
pub fn read_input(path: &Path) -> Result<Vec<u8>> {
    let meta = regular_file(path)?;
    let cap = max_input_bytes();
    let too_big = |n: u64| {
        Error::parse(
            path,
            0,
            format!(
                "{n} bytes or more, beyond the input limit of {cap} bytes (set ATLASMESH_MAX_INPUT_BYTES to raise it)"
            ),
        )
    };
    if meta.len() > cap {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(cap + 1).read_to_end(&mut bytes))
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The metadata of `path` (links followed), which must name a regular file.
///
/// # Errors
/// [`Error::Parse`] for a folder, a device, a FIFO or a socket; [`Error::Io`] when it does
/// not exist.
pub fn regular_file(path: &Path) -> Result<std::fs::Metadata> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a folder"
        } else {
            "a device, FIFO or socket"
        };
        return Err(Error::parse(
            path,
            0,
            format!("not a regular file ({what}); give a file"),
        ));
    }
    Ok(meta)
}

/// The text of the input file `path` (as [`read_input`]; invalid UTF-8 is an I/O error of
/// kind `InvalidData`, as `std::fs::read_to_string` gives it).
pub fn read_input_text(path: &Path) -> Result<String> {
    String::from_utf8(read_input(path)?).map_err(|_| {
        Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "stream did not contain valid UTF-8",
            ),
        )
    })
}

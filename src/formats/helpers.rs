//! What the format readers and writers share, below them all (the dispatchers `fe_mesh`,
//! `outline` and `surface` sit above): text of a file, numbers and names, coordinates, the
//! checks every mesh read gets.

use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::mesh::{ElementKind, MeshSets};
use std::fmt::Write as _;
use std::path::Path;

pub(crate) fn read_text(path: &Path) -> Result<String> {
    let bytes = crate::formats::read_input(path)?;
    text_of(path, &bytes).map(str::to_owned)
}

/// The text of a file's bytes, as [`read_text`] gives it.
pub(crate) fn text_of<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|_| Error::parse(path, 0, "not a text file (invalid UTF-8)"))
}

/// The text of a file's bytes, as `std::fs::read_to_string` gives it (invalid UTF-8 is an
/// I/O error of kind `InvalidData`).
pub(crate) fn utf8<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|_| {
        Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "stream did not contain valid UTF-8",
            ),
        )
    })
}

pub(crate) fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "shape".into())
}

pub(crate) fn parse_f64(path: &Path, line: usize, tok: &str) -> Result<f64> {
    let v: f64 = tok
        .trim()
        .parse()
        .map_err(|_| Error::parse(path, line, format!("{:?} is not a number", tok.trim())))?;
    if !v.is_finite() {
        return Err(Error::parse(
            path,
            line,
            format!("coordinate {:?} is NaN or infinite", tok.trim()),
        ));
    }
    Ok(v)
}

pub(crate) fn check_mesh<const D: usize>(
    path: &Path,
    nodes: &[Point<D>],
    kind: ElementKind,
    conn: &[usize],
    sets: &MeshSets,
) -> Result<()> {
    if conn.is_empty() {
        return Err(Error::parse(path, 0, "the mesh has no elements"));
    }
    super::check_points(path, nodes.len(), 1)?;
    if let Some((i, m)) = (nodes.iter().enumerate())
        .find_map(|(i, p)| crate::geometry::coordinate_problem(p).map(|m| (i, m)))
    {
        return Err(Error::parse(path, 0, format!("node {} {m}", i + 1)));
    }
    sets.check(kind, nodes.len(), conn.len() / kind.nodes())
        .map_err(|m| Error::parse(path, 0, m))
}

pub(crate) fn xyz<const D: usize>(p: &Point<D>) -> [f64; 3] {
    [p[0], p[1], if D > 2 { p[2] } else { 0.0 }]
}

/// Comma-separated 1-based ids, `per_line` per line (Abaqus allows 16 per data line).
pub(crate) fn id_lines(out: &mut String, ids: impl IntoIterator<Item = usize>, per_line: usize) {
    let mut k = 0;
    for i in ids {
        if k > 0 {
            out.push_str(if k % per_line == 0 { ",\n" } else { ", " });
        }
        let _ = write!(out, "{}", i + 1);
        k += 1;
    }
    if k > 0 {
        out.push('\n');
    }
}

pub(crate) type Parsed = (Vec<Point<3>>, Vec<Vec<usize>>);

/// The three coordinates after the keyword of a `vertex x y z` (STL) or `v x y z` (OBJ) line.
pub(crate) fn xyz_after_keyword(
    path: &Path,
    line: usize,
    text: &str,
    tokens: &[&str],
) -> Result<Point<3>> {
    let mut p = [0.0; 3];
    for (d, v) in p.iter_mut().enumerate() {
        *v = tokens
            .get(d + 1)
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| Error::parse(path, line, format!("bad vertex line '{text}'")))?;
    }
    Ok(p)
}

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
        .map(|s| crate::geometry::display_name(&s.to_string_lossy()))
        .unwrap_or_else(|| "shape".into())
}

/// A token of the input as a message quotes it: at most 40 characters (a 60 MB field is not
/// echoed whole).
pub(crate) fn shown(token: &str) -> String {
    if token.chars().count() > 40 {
        format!("{:?}...", token.chars().take(40).collect::<String>())
    } else {
        format!("{token:?}")
    }
}

pub(crate) fn parse_f64(path: &Path, line: usize, tok: &str) -> Result<f64> {
    let v: f64 = tok
        .trim()
        .parse()
        .map_err(|_| Error::parse(path, line, format!("{} is not a number", shown(tok.trim()))))?;
    if !v.is_finite() {
        return Err(Error::parse(
            path,
            line,
            format!("coordinate {:?} is NaN or infinite", tok.trim()),
        ));
    }
    Ok(v)
}

/// The whole-mesh sets that atlasmesh's writers add (`NALL` of every node, `EALL` of every
/// element, in Abaqus/CalculiX and Gmsh files) removed from sets read back: they are not the
/// user's. A set of that name holding only part of the mesh is refused: written back, it
/// would merge with the whole-mesh set of the same name and be lost.
pub(crate) fn drop_whole_mesh_sets(
    path: &Path,
    sets: &mut MeshSets,
    nodes: usize,
    elements: usize,
) -> Result<()> {
    fn whole(
        path: &Path,
        map: &mut std::collections::BTreeMap<String, Vec<usize>>,
        reserved: &str,
        what: &str,
        total: usize,
    ) -> Result<()> {
        let names: Vec<String> = map
            .keys()
            .filter(|n| n.eq_ignore_ascii_case(reserved))
            .cloned()
            .collect();
        for name in names {
            let mut m = map.remove(&name).unwrap_or_default();
            m.sort_unstable();
            m.dedup();
            if m.len() != total {
                return Err(Error::parse(
                    path,
                    0,
                    format!(
                        "{what} set {name} holds {} of the {total} {what}s; {reserved} is the name \
                         atlasmesh's solver files give the whole mesh, so a part of it would be \
                         lost when written: rename the set",
                        m.len()
                    ),
                ));
            }
        }
        Ok(())
    }
    whole(path, &mut sets.node_sets, "NALL", "node", nodes)?;
    whole(path, &mut sets.element_sets, "EALL", "element", elements)
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

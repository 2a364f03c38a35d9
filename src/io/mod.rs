//! Reading shapes and writing files safely.
//!
//! Outline formats (2D):
//! - long CSV with a header of four columns `shape,point,x,y` (also `shape,landmark,x,y` or
//!   `hand,point,x,y`): one or more shapes, points ordered by their index;
//! - plain text, one point `x y` per line (`#` comments); blank lines separate shapes;
//! - legacy VTK `POLYDATA` with `LINES`, ASCII or binary (big-endian), as written by VTK and
//!   Scalismo; the points are ordered by walking the line segments, and an outline is closed
//!   when the segments form a loop. A constant `z` is dropped; varying `z` is an error.

pub mod femesh;
pub mod landmarks;
pub mod surface;
pub mod vtkxml;

use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use std::collections::HashMap;
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

/// Reads the outlines in `path` (format from the extension: `.csv`, `.vtk`, else text).
/// `closed` applies to CSV and text files; VTK files carry their own topology.
pub fn read_outlines(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let shapes = match ext.as_str() {
        "csv" => read_long_csv(path, closed)?,
        "vtk" => vec![read_vtk_outline(path)?],
        _ => read_text_outlines(path, closed)?,
    };
    if shapes.is_empty() {
        return Err(Error::parse(path, 0, "the file holds no shape"));
    }
    for s in &shapes {
        check_finite(path, s)?;
    }
    Ok(shapes)
}

fn check_finite(path: &Path, s: &Shape<2>) -> Result<()> {
    if let Some(i) = s
        .points
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(Error::parse(
            path,
            0,
            format!(
                "shape {}: point {i} has a NaN or infinite coordinate",
                s.name
            ),
        ));
    }
    if s.points.len() < 3 {
        return Err(Error::parse(
            path,
            0,
            format!(
                "shape {} has {} point(s); an outline needs at least 3",
                s.name,
                s.points.len()
            ),
        ));
    }
    Ok(())
}

fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    String::from_utf8(bytes).map_err(|_| Error::parse(path, 0, "not a text file (invalid UTF-8)"))
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "shape".into())
}

fn parse_f64(path: &Path, line: usize, tok: &str) -> Result<f64> {
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

/// Long CSV: header `name,index,x,y`; rows grouped by name (first-appearance order), sorted by
/// index, which must run 0..n-1 without gaps or repeats.
pub fn read_long_csv(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    let text = read_text(path)?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(Error::parse(
            path,
            1,
            "empty file; expected a header like shape,point,x,y",
        ));
    };
    let cols: Vec<String> = header.split(',').map(|c| c.trim().to_lowercase()).collect();
    if cols.len() != 4
        || cols[2] != "x"
        || cols[3] != "y"
        || !["point", "landmark", "index"].contains(&cols[1].as_str())
    {
        return Err(Error::parse(
            path,
            1,
            format!("header {header:?}: expected shape,point,x,y (or shape,landmark,x,y)"),
        ));
    }
    let mut order: Vec<String> = Vec::new();
    let mut rows: HashMap<String, Vec<(usize, Point<2>, usize)>> = HashMap::new();
    for (i, l) in lines {
        let ln = i + 1;
        let f: Vec<&str> = l.split(',').collect();
        if f.len() != 4 {
            return Err(Error::parse(
                path,
                ln,
                format!("{} fields, 4 expected", f.len()),
            ));
        }
        let name = f[0].trim().to_string();
        let idx: usize = f[1].trim().parse().map_err(|_| {
            Error::parse(
                path,
                ln,
                format!(
                    "point index {:?} is not a non-negative integer",
                    f[1].trim()
                ),
            )
        })?;
        if idx > MAX_COUNT {
            return Err(Error::parse(
                path,
                ln,
                format!("point index {idx} is implausibly large"),
            ));
        }
        let p = [parse_f64(path, ln, f[2])?, parse_f64(path, ln, f[3])?];
        if !rows.contains_key(&name) {
            order.push(name.clone());
        }
        rows.entry(name).or_default().push((idx, p, ln));
    }
    order
        .into_iter()
        .map(|name| {
            let mut r = rows.remove(&name).unwrap_or_default();
            r.sort_by_key(|x| x.0);
            for (k, (idx, _, ln)) in r.iter().enumerate() {
                if *idx != k {
                    return Err(Error::parse(path, *ln, format!("shape {name}: point index {idx} where {k} was expected (indices must run 0..n-1 once each)")));
                }
            }
            Ok(Shape::polyline(name, r.into_iter().map(|x| x.1).collect(), closed))
        })
        .collect()
}

/// Plain text: one `x y` (or `x,y`) per line; `#` starts a comment. Blank lines separate
/// shapes (as in geomstats' `cells.txt`): a file of one block is one shape named after the
/// file; blocks of a file with several are named `STEM-000`, `STEM-001`, ... in file order.
pub fn read_text_outlines(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    let text = read_text(path)?;
    let mut blocks: Vec<Vec<Point<2>>> = vec![Vec::new()];
    for (i, raw) in text.lines().enumerate() {
        if raw.trim().is_empty() {
            if blocks.last().is_some_and(|b| !b.is_empty()) {
                blocks.push(Vec::new());
            }
            continue;
        }
        let l = raw.split('#').next().unwrap_or("").trim();
        if l.is_empty() {
            continue;
        }
        let f: Vec<&str> = l
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .collect();
        if f.len() != 2 {
            return Err(Error::parse(
                path,
                i + 1,
                format!("{} values, 2 expected (x y); is this a 3D file?", f.len()),
            ));
        }
        let p = [parse_f64(path, i + 1, f[0])?, parse_f64(path, i + 1, f[1])?];
        if let Some(b) = blocks.last_mut() {
            b.push(p);
        }
    }
    blocks.retain(|b| !b.is_empty());
    if blocks.is_empty() {
        return Err(Error::parse(path, 0, "the file holds no point"));
    }
    let name = stem(path);
    let many = blocks.len() > 1;
    Ok(blocks
        .into_iter()
        .enumerate()
        .map(|(k, pts)| {
            let n = if many {
                format!("{name}-{k:03}")
            } else {
                name.clone()
            };
            Shape::polyline(n, pts, closed)
        })
        .collect())
}

/// A cursor over a legacy VTK file's bytes.
struct Cursor<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Cursor<'a> {
    fn next_line(&mut self) -> Option<&'a str> {
        while self.pos < self.b.len() {
            let start = self.pos;
            let end = self.b[start..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(self.b.len(), |k| start + k);
            self.pos = (end + 1).min(self.b.len());
            self.line += 1;
            let s = std::str::from_utf8(&self.b[start..end]).ok()?.trim();
            if !s.is_empty() {
                return Some(s);
            }
        }
        None
    }
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }
    fn tokens(&mut self, n: usize) -> Option<Vec<&'a str>> {
        let mut out = Vec::with_capacity(n.min(1 << 20));
        while out.len() < n {
            let l = self.next_line()?;
            out.extend(l.split_whitespace());
        }
        (out.len() == n).then_some(out)
    }
}

/// Points and line cells of a legacy VTK POLYDATA file.
pub struct VtkPolyData {
    pub points: Vec<[f64; 3]>,
    pub lines: Vec<Vec<usize>>,
    pub polygons: Vec<Vec<usize>>,
}

/// Reads a legacy VTK POLYDATA file (ASCII or binary big-endian): `POINTS`, `LINES`,
/// `POLYGONS` (other sections are ignored).
pub fn read_vtk_polydata(path: &Path) -> Result<VtkPolyData> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let mut c = Cursor {
        b: &bytes,
        pos: 0,
        line: 0,
    };
    let err = |c: &Cursor, m: &str| Error::parse(path, c.line, m.to_string());
    let h = c.next_line().ok_or_else(|| err(&c, "empty file"))?;
    if !h.starts_with("# vtk DataFile") {
        return Err(err(
            &c,
            "not a legacy VTK file (first line must start with '# vtk DataFile')",
        ));
    }
    c.next_line().ok_or_else(|| err(&c, "truncated header"))?;
    let fmt = c
        .next_line()
        .ok_or_else(|| err(&c, "truncated header"))?
        .to_uppercase();
    let binary = match fmt.as_str() {
        "ASCII" => false,
        "BINARY" => true,
        _ => return Err(err(&c, "third line must be ASCII or BINARY")),
    };
    let ds = c.next_line().ok_or_else(|| err(&c, "truncated header"))?;
    if !ds.to_uppercase().starts_with("DATASET POLYDATA") {
        return Err(err(
            &c,
            &format!("{ds:?}: only DATASET POLYDATA is read here"),
        ));
    }
    let mut out = VtkPolyData {
        points: Vec::new(),
        lines: Vec::new(),
        polygons: Vec::new(),
    };
    while let Some(l) = c.next_line() {
        let f: Vec<&str> = l.split_whitespace().collect();
        let key = f[0].to_uppercase();
        match key.as_str() {
            "POINTS" => {
                let n: usize = f
                    .get(1)
                    .and_then(|s| s.parse().ok())
                    .filter(|&n| n <= MAX_COUNT)
                    .ok_or_else(|| err(&c, "bad POINTS count"))?;
                let ty = f.get(2).map(|s| s.to_lowercase()).unwrap_or_default();
                let size = match ty.as_str() {
                    "float" => 4,
                    "double" => 8,
                    _ => {
                        return Err(err(
                            &c,
                            &format!("POINTS type {ty:?}: float or double expected"),
                        ));
                    }
                };
                let vals: Vec<f64> = if binary {
                    let raw = c.take(n * 3 * size).ok_or_else(|| {
                        err(
                            &c,
                            &format!(
                                "truncated: POINTS announces {n} points but the file ends before"
                            ),
                        )
                    })?;
                    raw.chunks_exact(size)
                        .map(|ch| {
                            if size == 4 {
                                f32::from_be_bytes([ch[0], ch[1], ch[2], ch[3]]) as f64
                            } else {
                                f64::from_be_bytes(ch.try_into().unwrap_or([0; 8]))
                            }
                        })
                        .collect()
                } else {
                    let line = c.line;
                    let toks = c.tokens(n * 3).ok_or_else(|| {
                        err(&c, &format!("truncated: POINTS announces {n} points"))
                    })?;
                    toks.iter()
                        .map(|t| parse_f64(path, line, t))
                        .collect::<Result<_>>()?
                };
                if vals.iter().any(|v| !v.is_finite()) {
                    return Err(err(&c, "a point coordinate is NaN or infinite"));
                }
                out.points = vals.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            }
            "LINES" | "POLYGONS" | "VERTICES" | "TRIANGLE_STRIPS" => {
                if f.get(1).map(|s| s.to_uppercase()) == Some("OFFSETS".into()) {
                    return Err(err(
                        &c,
                        "VTK 5.1 cell arrays (OFFSETS/CONNECTIVITY) are not supported; save as legacy 4.2",
                    ));
                }
                let n: usize = f
                    .get(1)
                    .and_then(|s| s.parse().ok())
                    .filter(|&n| n <= MAX_COUNT)
                    .ok_or_else(|| err(&c, "bad cell count"))?;
                let size: usize = f
                    .get(2)
                    .and_then(|s| s.parse().ok())
                    .filter(|&n| n <= MAX_COUNT)
                    .ok_or_else(|| err(&c, "bad cell size"))?;
                let ints: Vec<i64> = if binary {
                    let raw = c.take(size * 4).ok_or_else(|| {
                        err(&c, &format!("truncated: {key} announces {size} integers"))
                    })?;
                    raw.chunks_exact(4)
                        .map(|ch| i32::from_be_bytes([ch[0], ch[1], ch[2], ch[3]]) as i64)
                        .collect()
                } else {
                    let toks = c.tokens(size).ok_or_else(|| {
                        err(&c, &format!("truncated: {key} announces {size} integers"))
                    })?;
                    toks.iter()
                        .map(|t| {
                            t.parse::<i64>()
                                .map_err(|_| err(&c, &format!("{t:?} is not an integer")))
                        })
                        .collect::<Result<_>>()?
                };
                let mut cells = Vec::with_capacity(n);
                let mut k = 0;
                for _ in 0..n {
                    let m = *ints
                        .get(k)
                        .ok_or_else(|| err(&c, &format!("{key}: fewer integers than announced")))?;
                    let m = usize::try_from(m).map_err(|_| err(&c, "negative cell size"))?;
                    let ids = ints
                        .get(k + 1..k + 1 + m)
                        .ok_or_else(|| err(&c, &format!("{key}: fewer integers than announced")))?;
                    let ids: Vec<usize> = ids
                        .iter()
                        .map(|&i| {
                            usize::try_from(i)
                                .ok()
                                .filter(|&i| i < out.points.len())
                                .ok_or_else(|| {
                                    err(&c, &format!("{key}: point index {i} out of range"))
                                })
                        })
                        .collect::<Result<_>>()?;
                    cells.push(ids);
                    k += 1 + m;
                }
                match key.as_str() {
                    "LINES" => out.lines = cells,
                    "POLYGONS" => out.polygons = cells,
                    _ => {}
                }
            }
            _ => {
                // POINT_DATA, CELL_DATA, FIELD ... : nothing the shape needs.
                if binary {
                    break;
                }
            }
        }
    }
    if out.points.is_empty() {
        return Err(Error::parse(path, c.line, "no POINTS section"));
    }
    Ok(out)
}

/// Reads a 2D outline from a legacy VTK POLYDATA file with LINES. Points are reordered along
/// the chain of segments; every point must have at most two neighbours and the segments must
/// form one chain or one loop.
pub fn read_vtk_outline(path: &Path) -> Result<Shape<2>> {
    let vtk = read_vtk_polydata(path)?;
    let z0 = vtk.points[0][2];
    if vtk
        .points
        .iter()
        .any(|p| (p[2] - z0).abs() > 1e-9 * (1.0 + z0.abs()))
    {
        return Err(Error::parse(
            path,
            0,
            "the points have varying z: this is a 3D shape, a 2D outline was expected",
        ));
    }
    let n = vtk.points.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut nseg = 0;
    for l in &vtk.lines {
        for w in l.windows(2) {
            if w[0] != w[1] {
                adj[w[0]].push(w[1]);
                adj[w[1]].push(w[0]);
                nseg += 1;
            }
        }
    }
    if nseg == 0 {
        return Err(Error::parse(
            path,
            0,
            "no LINES: an outline needs line segments",
        ));
    }
    if let Some(i) = adj.iter().position(|a| a.len() > 2) {
        return Err(Error::parse(
            path,
            0,
            format!(
                "point {i} has {} neighbours: the lines branch; one chain or loop is expected",
                adj[i].len()
            ),
        ));
    }
    let used: Vec<usize> = (0..n).filter(|&i| !adj[i].is_empty()).collect();
    let start = used
        .iter()
        .copied()
        .find(|&i| adj[i].len() == 1)
        .unwrap_or(used[0]);
    let closed = adj[start].len() == 2;
    let mut order = vec![start];
    let mut prev = usize::MAX;
    let mut cur = start;
    loop {
        let next = adj[cur]
            .iter()
            .copied()
            .find(|&j| j != prev && (order.len() < 2 || j != order[order.len() - 2]));
        match next {
            Some(j) if j != start => {
                order.push(j);
                prev = cur;
                cur = j;
            }
            _ => break,
        }
        if order.len() > n {
            break;
        }
    }
    if order.len() != used.len() {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the lines form several pieces ({} of {} points in the first); one outline is expected",
                order.len(),
                used.len()
            ),
        ));
    }
    let pts = order
        .iter()
        .map(|&i| [vtk.points[i][0], vtk.points[i][1]])
        .collect();
    Ok(Shape::polyline(stem(path), pts, closed))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str, content: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("atlasmesh-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, content).unwrap();
        p
    }

    #[test]
    fn ascii_vtk_loop_is_read_in_chain_order() {
        let p = tmp(
            "sq.vtk",
            b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 1 0 1 0 0 0 1 0\nLINES 4 12\n2 0 2\n2 2 1\n2 3 0\n2 1 3\n",
        );
        let s = read_vtk_outline(&p).unwrap();
        assert!(s.is_closed());
        assert_eq!(
            s.points,
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        );
    }

    #[test]
    fn binary_vtk_truncated_is_an_error() {
        let mut b =
            b"# vtk DataFile Version 3.0\nx\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n".to_vec();
        b.extend_from_slice(&[0u8; 20]);
        let p = tmp("t.vtk", &b);
        let e = read_vtk_outline(&p).unwrap_err().to_string();
        assert!(e.contains("truncated") && e.contains("t.vtk"), "{e}");
    }

    #[test]
    fn blank_lines_separate_the_shapes_of_a_text_file() {
        let p = tmp(
            "blocks.txt",
            b"# cells\n0 0\n1 0\n0 1\n\n\n2 2\n3 2\n# comment\n2 3\n3 3\n",
        );
        let s = read_outlines(&p, true).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].name.as_str(), s[0].points.len()), ("blocks-000", 3));
        assert_eq!((s[1].name.as_str(), s[1].points.len()), ("blocks-001", 4));
        let one = tmp("one.txt", b"0 0\n1 0\n0 1\n");
        assert_eq!(read_outlines(&one, true).unwrap()[0].name, "one");
    }

    #[test]
    fn csv_with_a_gap_in_indices_is_an_error() {
        let p = tmp(
            "gap.csv",
            b"shape,point,x,y\n0,0,1,2\n0,2,3,4\n0,1,5,6\n0,4,1,1\n",
        );
        let e = read_long_csv(&p, false).unwrap_err().to_string();
        assert!(e.contains("gap.csv") && e.contains("index 4"), "{e}");
    }
}

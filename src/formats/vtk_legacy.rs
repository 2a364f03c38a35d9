//! Legacy VTK (`.vtk`): POLYDATA outlines and surfaces, UNSTRUCTURED_GRID meshes with their
//! sets as point and cell data, read and written.

use super::atomic::MAX_COUNT;
use super::fe_mesh::{check_mesh, xyz};
use super::outline::{parse_f64, stem};
use crate::error::{Error, Result};
use crate::geometry::Shape;
use crate::mesh::quality::ElementQuality;
use crate::mesh::{ALL_KINDS, ElementKind, FeMesh, MeshSets};
use std::fmt::Write as _;
use std::path::Path;

/// A cursor over a legacy VTK file's bytes.
pub(crate) struct Cursor<'a> {
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
    /// The points.
    pub points: Vec<[f64; 3]>,
    /// The LINES cells (point indices).
    pub lines: Vec<Vec<usize>>,
    /// The POLYGONS cells (point indices).
    pub polygons: Vec<Vec<usize>>,
}

/// Reads a legacy VTK POLYDATA file (ASCII or binary big-endian): `POINTS`, `LINES`,
/// `POLYGONS` (other sections are ignored).
pub fn read_vtk_polydata(path: &Path) -> Result<VtkPolyData> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_vtk_polydata(path, &bytes)
}

/// [`read_vtk_polydata`] of a file's bytes (`path` only names the file in messages): no file is read.
pub fn parse_vtk_polydata(path: &Path, bytes: &[u8]) -> Result<VtkPolyData> {
    let mut c = Cursor {
        b: bytes,
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
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_vtk_outline(path, &bytes)
}

/// [`read_vtk_outline`] of a file's bytes (`path` only names the file in messages).
pub fn parse_vtk_outline(path: &Path, bytes: &[u8]) -> Result<Shape<2>> {
    let vtk = parse_vtk_polydata(path, bytes)?;
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

/// Reads a legacy VTK ASCII `UNSTRUCTURED_GRID` (one cell type), with `set_NAME` scalars as
/// sets.
pub fn read_vtk_unstructured(path: &Path) -> Result<FeMesh<3>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_vtk_unstructured(path, &text)
}

/// [`read_vtk_unstructured`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_vtk_unstructured(path: &Path, text: &str) -> Result<FeMesh<3>> {
    let lines: Vec<&str> = text.lines().collect();
    if !lines
        .first()
        .is_some_and(|l| l.starts_with("# vtk DataFile"))
    {
        return Err(Error::parse(path, 1, "not a legacy VTK file"));
    }
    if lines.get(2).map(|l| l.trim().to_ascii_uppercase()) != Some("ASCII".into()) {
        return Err(Error::parse(
            path,
            3,
            "binary legacy VTK meshes are not read; use ASCII or VTU",
        ));
    }
    if !text.contains("UNSTRUCTURED_GRID") {
        return Err(Error::parse(path, 4, "not an UNSTRUCTURED_GRID"));
    }
    // Tokens with their line numbers.
    let toks: Vec<(usize, &str)> = lines
        .iter()
        .enumerate()
        .skip(3)
        .flat_map(|(i, l)| l.split_whitespace().map(move |t| (i + 1, t)))
        .collect();
    let mut at = 0;
    let find = |kw: &str, from: usize| {
        toks[from..]
            .iter()
            .position(|t| t.1.eq_ignore_ascii_case(kw))
            .map(|p| p + from)
    };
    let count = |i: usize| -> Result<usize> {
        let (ln, t) = toks
            .get(i)
            .copied()
            .ok_or_else(|| Error::parse(path, 0, "truncated"))?;
        let n: usize = t
            .parse()
            .map_err(|_| Error::parse(path, ln, format!("{t:?} is not a count")))?;
        if n > crate::formats::MAX_COUNT {
            return Err(Error::parse(path, ln, format!("count {n} is out of range")));
        }
        Ok(n)
    };
    let p = find("POINTS", at).ok_or_else(|| Error::parse(path, 0, "no POINTS"))?;
    let n = count(p + 1)?;
    at = p + 3;
    let vals = toks
        .get(at..at + 3 * n)
        .ok_or_else(|| Error::parse(path, 0, "POINTS is short (truncated?)"))?;
    let mut nodes = Vec::with_capacity(n);
    for c in vals.chunks(3) {
        let v: Vec<f64> = c
            .iter()
            .map(|(ln, t)| {
                t.parse::<f64>()
                    .map_err(|_| Error::parse(path, *ln, format!("{t:?} is not a number")))
            })
            .collect::<Result<_>>()?;
        nodes.push([v[0], v[1], v[2]]);
    }
    at += 3 * n;
    let c = find("CELLS", at).ok_or_else(|| Error::parse(path, 0, "no CELLS"))?;
    let ne = count(c + 1)?;
    let size = count(c + 2)?;
    let body = toks
        .get(c + 3..c + 3 + size)
        .ok_or_else(|| Error::parse(path, 0, "CELLS is short (truncated?)"))?;
    let t =
        find("CELL_TYPES", c + 3 + size).ok_or_else(|| Error::parse(path, 0, "no CELL_TYPES"))?;
    let types = toks
        .get(t + 2..t + 2 + ne)
        .ok_or_else(|| Error::parse(path, 0, "CELL_TYPES is short"))?;
    let kind = types
        .first()
        .and_then(|(_, s)| s.parse::<u8>().ok())
        .and_then(ElementKind::from_vtk_type)
        .ok_or_else(|| {
            Error::parse(
                path,
                0,
                "cell type: triangles, quads, tetrahedra or hexahedra",
            )
        })?;
    if types
        .iter()
        .any(|(_, s)| s.parse::<u8>().ok() != Some(kind.vtk_type()))
    {
        return Err(Error::parse(path, 0, "one cell type per mesh"));
    }
    let mut conn = Vec::with_capacity(ne * kind.nodes());
    let mut i = 0;
    for _ in 0..ne {
        let (ln, k) = body
            .get(i)
            .copied()
            .ok_or_else(|| Error::parse(path, 0, "CELLS is short"))?;
        if k.parse::<usize>().ok() != Some(kind.nodes()) {
            return Err(Error::parse(
                path,
                ln,
                format!("a cell of {k} nodes; {} expected", kind.nodes()),
            ));
        }
        for (ln, v) in body
            .get(i + 1..i + 1 + kind.nodes())
            .ok_or_else(|| Error::parse(path, ln, "CELLS is short"))?
        {
            let v: usize = v
                .parse()
                .map_err(|_| Error::parse(path, *ln, "a bad node index"))?;
            if v >= n {
                return Err(Error::parse(
                    path,
                    *ln,
                    format!("node index {v} of {n} nodes"),
                ));
            }
            conn.push(v);
        }
        i += 1 + kind.nodes();
    }
    let mut sets = MeshSets::default();
    let mut section = 0; // 1 point data, 2 cell data
    let mut k = t + 2 + ne;
    while k < toks.len() {
        let w = toks[k].1.to_ascii_uppercase();
        if w == "POINT_DATA" {
            section = 1;
            k += 2;
            continue;
        }
        if w == "CELL_DATA" {
            section = 2;
            k += 2;
            continue;
        }
        let len = if section == 1 { n } else { ne };
        if w == "SCALARS" {
            let name = toks.get(k + 1).map(|t| t.1).unwrap_or("");
            let mut j = k + 3;
            if toks.get(j).is_some_and(|t| t.1.parse::<usize>().is_ok()) {
                j += 1;
            }
            if toks
                .get(j)
                .is_some_and(|t| t.1.eq_ignore_ascii_case("LOOKUP_TABLE"))
            {
                j += 2;
            }
            let v = toks
                .get(j..j + len)
                .ok_or_else(|| Error::parse(path, 0, format!("{name} is short")))?;
            if let Some(set) = name.strip_prefix("set_") {
                let members: Vec<usize> = (0..len).filter(|&q| v[q].1 != "0").collect();
                if section == 1 {
                    sets.node_sets.insert(set.to_string(), members);
                } else {
                    sets.element_sets.insert(set.to_string(), members);
                }
            }
            k = j + len;
            continue;
        }
        if w == "VECTORS" {
            k += 3 + 3 * len;
            continue;
        }
        k += 1;
    }
    check_mesh(path, &nodes, kind, &conn, &sets)?;
    Ok(FeMesh {
        nodes,
        kind,
        connectivity: conn,
        sets,
    })
}

/// Legacy VTK, ASCII.
pub fn vtk<const D: usize>(
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
) -> String {
    let nn = mesh.nodes.len();
    let ne = mesh.num_elements();
    let k = mesh.kind.nodes();
    let mut s = String::with_capacity(nn * 60 + ne * 40);
    let _ = writeln!(
        s,
        "# vtk DataFile Version 4.2\natlasmesh {}\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {nn} double",
        env!("CARGO_PKG_VERSION")
    );
    for p in &mesh.nodes {
        let q = xyz(p);
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", q[0], q[1], q[2]);
    }
    let _ = writeln!(s, "CELLS {ne} {}", ne * (k + 1));
    for e in 0..ne {
        let _ = write!(s, "{k}");
        for n in mesh.element(e) {
            let _ = write!(s, " {n}");
        }
        s.push('\n');
    }
    let _ = writeln!(s, "CELL_TYPES {ne}");
    for _ in 0..ne {
        let _ = writeln!(s, "{}", mesh.kind.vtk_type());
    }
    let mask = |s: &mut String, name: &str, m: &[usize], n: usize| {
        let mut v = vec![0u8; n];
        for &i in m {
            if i < n {
                v[i] = 1;
            }
        }
        let _ = writeln!(
            s,
            "SCALARS set_{name} unsigned_char 1\nLOOKUP_TABLE default"
        );
        for c in v.chunks(32) {
            let line: Vec<&str> = c.iter().map(|x| if *x == 1 { "1" } else { "0" }).collect();
            let _ = writeln!(s, "{}", line.join(" "));
        }
    };
    if quality.len() == ne || !mesh.sets.element_sets.is_empty() {
        let _ = writeln!(s, "CELL_DATA {ne}");
    }
    if quality.len() == ne {
        s.push_str("SCALARS jacobian_min double 1\nLOOKUP_TABLE default\n");
        for q in quality {
            let _ = writeln!(s, "{:.17e}", q.jacobian_min);
        }
        s.push_str("SCALARS scaled_jacobian_min double 1\nLOOKUP_TABLE default\n");
        for q in quality {
            let _ = writeln!(s, "{:.17e}", q.scaled_jacobian_min);
        }
    }
    for (name, m) in &mesh.sets.element_sets {
        mask(&mut s, name, m, ne);
    }
    let reference = reference.filter(|r| r.nodes.len() == nn);
    if reference.is_some() || !mesh.sets.node_sets.is_empty() {
        let _ = writeln!(s, "POINT_DATA {nn}");
    }
    if let Some(r) = reference {
        s.push_str("VECTORS displacement double\n");
        for (p, o) in mesh.nodes.iter().zip(&r.nodes) {
            let (a, b) = (xyz(p), xyz(o));
            let _ = writeln!(
                s,
                "{:.17e} {:.17e} {:.17e}",
                a[0] - b[0],
                a[1] - b[1],
                a[2] - b[2]
            );
        }
    }
    for (name, m) in &mesh.sets.node_sets {
        mask(&mut s, name, m, nn);
    }
    s
}

/// The element-type table of this format.
impl ElementKind {
    /// VTK cell type id.
    pub fn vtk_type(self) -> u8 {
        match self {
            ElementKind::Quad4 => 9,
            ElementKind::Hex8 => 12,
            ElementKind::Tri3 => 5,
            ElementKind::Tet4 => 10,
            ElementKind::Hex20 => 25,
            ElementKind::Tet10 => 24,
        }
    }
    /// The kind of VTK cell type `t`.
    pub fn from_vtk_type(t: u8) -> Option<Self> {
        ALL_KINDS.into_iter().find(|k| k.vtk_type() == t)
    }
}

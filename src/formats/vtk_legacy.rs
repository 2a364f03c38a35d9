//! Legacy VTK (`.vtk`), versions 2.0 to 5.1 (VTK ≥ 9.1 writes 5.1: cells as `OFFSETS` and
//! `CONNECTIVITY`), ASCII and binary (big-endian): POLYDATA outlines and surfaces,
//! UNSTRUCTURED_GRID meshes with their sets as point and cell data; field data, lookup tables,
//! `METADATA` and attributes other than `set_NAME` scalars are read past. Meshes are written
//! as 4.2 ASCII.

use super::atomic::MAX_COUNT;
use super::helpers::xyz;
use super::vtk_cells::{
    DataArrays, VtkPolyData, cell_types, mesh_from_cells, outline_from_polydata,
};
use crate::error::{Error, Result};
use crate::geometry::Shape;
use crate::mesh::quality::ElementQuality;
use crate::mesh::{ALL_KINDS, ElementKind, FeMesh};
use std::fmt::Write as _;
use std::path::Path;

/// A legacy VTK file as parsed.
#[derive(Default)]
struct Legacy {
    /// `DATASET` (upper case).
    dataset: String,
    points: Vec<[f64; 3]>,
    /// POLYDATA: lines, polygons and the triangles of strips.
    poly: VtkPolyData,
    /// UNSTRUCTURED_GRID: cells and their types.
    cells: Vec<Vec<usize>>,
    types: Vec<u8>,
    /// `set_NAME` scalars of the points and of the cells.
    point_sets: DataArrays,
    cell_sets: DataArrays,
}

/// A cursor over a legacy VTK file's bytes: keyword lines, and value blocks in ASCII or
/// big-endian binary.
struct Cursor<'a> {
    path: &'a Path,
    b: &'a [u8],
    pos: usize,
    line: usize,
    binary: bool,
}

impl<'a> Cursor<'a> {
    fn err(&self, m: impl Into<String>) -> Error {
        Error::parse(self.path, self.line, m.into())
    }

    /// The next line, empty or not (`None` at the end of the file).
    fn raw_line(&mut self) -> Result<Option<&'a str>> {
        if self.pos >= self.b.len() {
            return Ok(None);
        }
        let start = self.pos;
        let end = self.b[start..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(self.b.len(), |k| start + k);
        self.pos = (end + 1).min(self.b.len());
        self.line += 1;
        std::str::from_utf8(&self.b[start..end])
            .map(|s| Some(s.trim()))
            .map_err(|_| {
                self.err("binary bytes where a keyword line was expected (a section longer than announced?)")
            })
    }

    /// The next non-empty line.
    fn line(&mut self) -> Result<Option<&'a str>> {
        while let Some(l) = self.raw_line()? {
            if !l.is_empty() {
                return Ok(Some(l));
            }
        }
        Ok(None)
    }

    /// `n` values of VTK type `ty` (`float`, `int`, `vtktypeint64`...).
    fn values(&mut self, n: usize, ty: &str, what: &str) -> Result<Vec<f64>> {
        if n > MAX_COUNT.saturating_mul(9) {
            return Err(self.err(format!("{what}: {n} values is beyond the limit")));
        }
        let ty = ty.to_ascii_lowercase();
        let size = match ty.as_str() {
            "unsigned_char" | "char" => 1,
            "short" | "unsigned_short" => 2,
            "int" | "unsigned_int" | "float" | "vtkidtype" => 4,
            "long" | "unsigned_long" | "double" | "vtktypeint64" | "vtktypeuint64" => 8,
            _ => return Err(self.err(format!("{what}: data type {ty:?} is not read"))),
        };
        if self.binary {
            let raw = self
                .b
                .get(self.pos..self.pos.saturating_add(n * size))
                .ok_or_else(|| {
                    self.err(format!(
                        "truncated: {what} announces {n} values but the file ends before"
                    ))
                })?;
            self.pos += n * size;
            let signed = !ty.starts_with("unsigned") && ty != "vtktypeuint64";
            let v: Vec<f64> = raw
                .chunks_exact(size)
                .map(|c| {
                    let mut w = [0u8; 8];
                    w[8 - size..].copy_from_slice(c);
                    let u = u64::from_be_bytes(w);
                    match (ty.as_str(), size) {
                        ("float", _) => f32::from_bits(u as u32) as f64,
                        ("double", _) => f64::from_bits(u),
                        (_, 8) if signed => u as i64 as f64,
                        (_, 4) if signed => u as u32 as i32 as f64,
                        (_, 2) if signed => u as u16 as i16 as f64,
                        (_, 1) if signed => u as u8 as i8 as f64,
                        _ => u as f64,
                    }
                })
                .collect();
            return Ok(v);
        }
        let mut out = Vec::with_capacity(n.min(1 << 20));
        while out.len() < n {
            let l = self.line()?.ok_or_else(|| {
                self.err(format!(
                    "truncated: {what} announces {n} values, the file ends after {}",
                    out.len()
                ))
            })?;
            for t in l.split_whitespace() {
                let v: f64 = t
                    .parse()
                    .map_err(|_| self.err(format!("{what}: {t:?} is not a number")))?;
                out.push(v);
            }
        }
        if out.len() != n {
            return Err(self.err(format!(
                "{what}: {} values where {n} were announced",
                out.len()
            )));
        }
        Ok(out)
    }

    /// Skips a `METADATA` block (up to its empty line).
    fn skip_metadata(&mut self) -> Result<()> {
        while let Some(l) = self.raw_line()? {
            if l.is_empty() {
                break;
            }
        }
        Ok(())
    }
}

/// A count field of a keyword line.
fn count(c: &Cursor, f: &[&str], i: usize, what: &str) -> Result<usize> {
    f.get(i)
        .and_then(|s| s.parse::<usize>().ok())
        .filter(|&n| n <= MAX_COUNT)
        .ok_or_else(|| c.err(format!("{}: a bad {what}", f[0])))
}

/// Cells as an index list (`n` cells) or, in 5.1, offsets and connectivity.
fn read_cells(c: &mut Cursor, f: &[&str], v5: bool, points: usize) -> Result<Vec<Vec<usize>>> {
    let key = f[0].to_ascii_uppercase();
    let a = count(c, f, 1, "cell count")?;
    let b = count(c, f, 2, "cell size")?;
    let idx = |c: &Cursor, v: f64, n: usize| -> Result<usize> {
        if v >= 0.0 && v.fract() == 0.0 && v < n as f64 {
            Ok(v as usize)
        } else {
            Err(c.err(format!("{key}: index {v} is out of range (0..{n})")))
        }
    };
    if v5 {
        let mut section = |want: &str, n: usize| -> Result<Vec<f64>> {
            let l = c
                .line()?
                .ok_or_else(|| c.err(format!("truncated: {key} has no {want}")))?;
            let g: Vec<&str> = l.split_whitespace().collect();
            if !g[0].eq_ignore_ascii_case(want) {
                return Err(c.err(format!("{key}: {want} expected, found {:?}", g[0])));
            }
            let ty = g.get(1).copied().unwrap_or("vtktypeint64");
            c.values(n, ty, &format!("{key} {want}"))
        };
        let offsets = section("OFFSETS", a)?;
        let conn = section("CONNECTIVITY", b)?;
        if offsets.first().is_some_and(|&o| o != 0.0)
            || offsets.last().is_some_and(|&o| o != b as f64)
        {
            return Err(c.err(format!(
                "{key}: the offsets run from {} to {}, not from 0 to the {b} connectivity entries",
                offsets.first().copied().unwrap_or(0.0),
                offsets.last().copied().unwrap_or(0.0)
            )));
        }
        let mut cells = Vec::with_capacity(a.saturating_sub(1));
        for w in offsets.windows(2) {
            let (s, e) = (idx(c, w[0], b + 1)?, idx(c, w[1], b + 1)?);
            if e < s {
                return Err(c.err(format!("{key}: the offsets decrease")));
            }
            cells.push(
                conn[s..e]
                    .iter()
                    .map(|&v| idx(c, v, points))
                    .collect::<Result<_>>()?,
            );
        }
        return Ok(cells);
    }
    let ints = c.values(b, "int", &key)?;
    let mut cells = Vec::with_capacity(a);
    let mut k = 0;
    for _ in 0..a {
        let m = idx(c, *ints.get(k).unwrap_or(&-1.0), b)?;
        let ids = ints
            .get(k + 1..k + 1 + m)
            .ok_or_else(|| c.err(format!("{key}: fewer integers than announced")))?;
        cells.push(
            ids.iter()
                .map(|&v| idx(c, v, points))
                .collect::<Result<_>>()?,
        );
        k += 1 + m;
    }
    if k != b {
        return Err(c.err(format!("{key}: {b} integers announced, the cells use {k}")));
    }
    Ok(cells)
}

/// Parses a legacy VTK file of any version from 2.0 to 5.1.
#[allow(
    clippy::too_many_lines,
    reason = "a parser: one pass over the file's keywords, each keyword's branch beside the others"
)]
fn parse_legacy(path: &Path, bytes: &[u8]) -> Result<Legacy> {
    let mut c = Cursor {
        path,
        b: bytes,
        pos: 0,
        line: 0,
        binary: false,
    };
    let h = c.raw_line()?.ok_or_else(|| c.err("empty file"))?;
    let version = h
        .strip_prefix("# vtk DataFile Version")
        .ok_or_else(|| {
            c.err("not a legacy VTK file (first line must start with '# vtk DataFile Version')")
        })?
        .trim();
    let v5 = version
        .split('.')
        .next()
        .and_then(|m| m.parse::<u32>().ok())
        .unwrap_or(0)
        >= 5;
    c.raw_line()?.ok_or_else(|| c.err("truncated header"))?;
    c.binary = match c.line()?.map(str::to_ascii_uppercase).as_deref() {
        Some("ASCII") => false,
        Some("BINARY") => true,
        _ => return Err(c.err("the third line must be ASCII or BINARY")),
    };
    let mut out = Legacy::default();
    // Point or cell attributes, and how many values each has.
    let mut target: Option<(bool, usize)> = None;
    while let Some(l) = c.line()? {
        let f: Vec<&str> = l.split_whitespace().collect();
        let key = f[0].to_ascii_uppercase();
        match key.as_str() {
            "DATASET" => {
                out.dataset = f.get(1).map(|s| s.to_ascii_uppercase()).unwrap_or_default();
                if !matches!(out.dataset.as_str(), "POLYDATA" | "UNSTRUCTURED_GRID") {
                    return Err(c.err(format!(
                        "DATASET {}: POLYDATA and UNSTRUCTURED_GRID are read",
                        out.dataset
                    )));
                }
            }
            "POINTS" => {
                let n = count(&c, &f, 1, "point count")?;
                let ty = f.get(2).copied().unwrap_or("float");
                let v = c.values(3 * n, ty, "POINTS")?;
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(c.err("a point coordinate is NaN or infinite"));
                }
                out.points = v.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            }
            "VERTICES" | "LINES" | "POLYGONS" | "TRIANGLE_STRIPS" | "CELLS" => {
                let cells = read_cells(&mut c, &f, v5, out.points.len())?;
                match key.as_str() {
                    "LINES" => out.poly.lines.extend(cells),
                    "POLYGONS" => out.poly.polygons.extend(cells),
                    "TRIANGLE_STRIPS" => cells.iter().for_each(|s| out.poly.push_strip(s)),
                    "CELLS" => out.cells = cells,
                    _ => {}
                }
            }
            "CELL_TYPES" => {
                let n = count(&c, &f, 1, "count")?;
                out.types = cell_types(c.values(n, "int", "CELL_TYPES")?.into_iter().map(|t| {
                    if t.fract() == 0.0 && t.abs() < 1e18 {
                        t as i64
                    } else {
                        -1
                    }
                }));
            }
            "POINT_DATA" | "CELL_DATA" => {
                target = Some((key == "POINT_DATA", count(&c, &f, 1, "count")?));
            }
            "METADATA" => c.skip_metadata()?,
            "FIELD" => {
                let arrays = count(&c, &f, 2, "array count")?;
                for _ in 0..arrays {
                    let l = c
                        .line()?
                        .ok_or_else(|| c.err("truncated: FIELD is short"))?;
                    let g: Vec<&str> = l.split_whitespace().collect();
                    if g[0] == "NULL_ARRAY" {
                        continue;
                    }
                    let comps = count(&c, &g, 1, "component count")?;
                    let tuples = count(&c, &g, 2, "tuple count")?;
                    let ty = g.get(3).copied().unwrap_or("float");
                    c.values(comps.saturating_mul(tuples), ty, "FIELD")?;
                    let next = c.pos;
                    let line = c.line;
                    match c.line()? {
                        Some("METADATA") => c.skip_metadata()?,
                        _ => (c.pos, c.line) = (next, line),
                    }
                }
            }
            "SCALARS"
            | "VECTORS"
            | "NORMALS"
            | "TENSORS"
            | "TENSORS6"
            | "TEXTURE_COORDINATES"
            | "COLOR_SCALARS"
            | "LOOKUP_TABLE" => {
                let (points, n) = target.unwrap_or((true, out.points.len()));
                let name = f.get(1).copied().unwrap_or("");
                let (width, ty) = match key.as_str() {
                    "SCALARS" => {
                        let comps = match f.get(3) {
                            Some(s) => s
                                .parse()
                                .map_err(|_| c.err("SCALARS: a bad component count"))?,
                            None => 1,
                        };
                        // Its LOOKUP_TABLE line, when there is one.
                        let next = c.pos;
                        let line = c.line;
                        match c.line()? {
                            Some(l) if l.to_ascii_uppercase().starts_with("LOOKUP_TABLE") => {}
                            _ => (c.pos, c.line) = (next, line),
                        }
                        (comps, f.get(2).copied().unwrap_or("float"))
                    }
                    "VECTORS" | "NORMALS" => (3, f.get(2).copied().unwrap_or("float")),
                    "TENSORS" => (9, f.get(2).copied().unwrap_or("float")),
                    "TENSORS6" => (6, f.get(2).copied().unwrap_or("float")),
                    "TEXTURE_COORDINATES" => (
                        count(&c, &f, 2, "dimension")?,
                        f.get(3).copied().unwrap_or("float"),
                    ),
                    "COLOR_SCALARS" => (
                        count(&c, &f, 2, "component count")?,
                        if c.binary { "unsigned_char" } else { "float" },
                    ),
                    _ => {
                        // A lookup table: its size, four colour values each.
                        let size = count(&c, &f, 2, "size")?;
                        let ty = if c.binary { "unsigned_char" } else { "float" };
                        c.values(4 * size, ty, "LOOKUP_TABLE")?;
                        continue;
                    }
                };
                let v = c.values(width.saturating_mul(n), ty, &format!("{key} {name}"))?;
                if key == "SCALARS" && width == 1 && name.starts_with("set_") {
                    let d = (name.to_string(), v);
                    if points {
                        out.point_sets.push(d);
                    } else {
                        out.cell_sets.push(d);
                    }
                }
                let next = c.pos;
                let line = c.line;
                match c.line()? {
                    Some("METADATA") => c.skip_metadata()?,
                    _ => (c.pos, c.line) = (next, line),
                }
            }
            _ => {
                return Err(c.err(format!(
                    "{:?} is not a legacy VTK keyword (or a section before it is longer than announced)",
                    f[0]
                )));
            }
        }
    }
    if out.dataset.is_empty() {
        return Err(Error::parse(path, c.line, "no DATASET line"));
    }
    if out.points.is_empty() {
        return Err(Error::parse(path, c.line, "no POINTS section"));
    }
    Ok(out)
}

/// Reads a legacy VTK POLYDATA file: its points, lines and polygons (triangle strips as
/// triangles; vertices and attributes read past). An UNSTRUCTURED_GRID of vertices, lines,
/// triangles, polygons and quadrilaterals (as meshio writes surfaces) is read as polydata.
pub fn read_vtk_polydata(path: &Path) -> Result<VtkPolyData> {
    let bytes = crate::formats::read_input(path)?;
    parse_vtk_polydata(path, &bytes)
}

/// [`read_vtk_polydata`] of a file's bytes (`path` only names the file in messages): no file is read.
pub fn parse_vtk_polydata(path: &Path, bytes: &[u8]) -> Result<VtkPolyData> {
    let l = parse_legacy(path, bytes)?;
    if l.dataset == "POLYDATA" {
        return Ok(VtkPolyData {
            points: l.points,
            ..l.poly
        });
    }
    // An unstructured grid of surface cells (meshio writes every .vtk so).
    let mut poly = VtkPolyData {
        points: l.points,
        ..Default::default()
    };
    for (cell, &t) in l.cells.iter().zip(&l.types) {
        match t {
            1 | 2 => {}
            3 | 4 => poly.lines.push(cell.clone()),
            5 | 7 | 9 => poly.polygons.push(cell.clone()),
            6 => poly.push_strip(cell),
            _ => {
                return Err(Error::parse(
                    path,
                    0,
                    format!(
                        "an UNSTRUCTURED_GRID with cells of VTK type {t}: a shape needs polygons or lines (a volume mesh is read as a mesh)"
                    ),
                ));
            }
        }
    }
    Ok(poly)
}

/// Reads a 2D outline from a legacy VTK POLYDATA file with LINES. Points are reordered along
/// the chain of segments; every point must have at most two neighbours and the segments must
/// form one chain or one loop.
pub fn read_vtk_outline(path: &Path) -> Result<Shape<2>> {
    let bytes = crate::formats::read_input(path)?;
    parse_vtk_outline(path, &bytes)
}

/// [`read_vtk_outline`] of a file's bytes (`path` only names the file in messages).
pub fn parse_vtk_outline(path: &Path, bytes: &[u8]) -> Result<Shape<2>> {
    outline_from_polydata(path, &parse_vtk_polydata(path, bytes)?)
}

/// Reads a legacy VTK UNSTRUCTURED_GRID mesh (ASCII or binary, 4.2 or 5.1): the cells of the
/// highest dimension, of one kind, with `set_NAME` scalars as sets.
pub fn read_vtk_unstructured(path: &Path) -> Result<FeMesh<3>> {
    let bytes = crate::formats::read_input(path)?;
    parse_vtk_unstructured(path, &bytes)
}

/// [`read_vtk_unstructured`] of a file's bytes (`path` only names the file in messages): no file is read.
pub fn parse_vtk_unstructured(path: &Path, bytes: &[u8]) -> Result<FeMesh<3>> {
    let l = parse_legacy(path, bytes)?;
    if l.dataset != "UNSTRUCTURED_GRID" {
        return Err(Error::parse(
            path,
            0,
            format!(
                "DATASET {}: an UNSTRUCTURED_GRID (a mesh) was expected",
                l.dataset
            ),
        ));
    }
    mesh_from_cells(
        path,
        l.points,
        &l.cells,
        &l.types,
        &l.point_sets,
        &l.cell_sets,
    )
}

/// Legacy VTK, ASCII.
pub fn vtk<const D: usize>(
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
    cell_fields: &[(&str, Vec<f64>)],
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
    if quality.len() == ne || !mesh.sets.element_sets.is_empty() || !cell_fields.is_empty() {
        let _ = writeln!(s, "CELL_DATA {ne}");
    }
    for (name, values) in cell_fields {
        let _ = writeln!(s, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for v in values {
            let _ = writeln!(s, "{v:.17e}");
        }
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

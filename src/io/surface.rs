//! Triangle surfaces (3D): PLY (ASCII, binary little- and big-endian), STL (ASCII and
//! binary), Wavefront OBJ and legacy VTK POLYDATA (POLYGONS; ASCII or binary) in; PLY (binary little-endian) and STL (binary) out. Polygons
//! are split into triangles as fans. Every surface read is checked by [`prepare_surface`].

use super::{MAX_COUNT, write_atomic};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, facet_normal, norm};
use std::collections::HashMap;
use std::path::Path;

/// Reads a triangle surface; the format comes from the extension (`.ply`, `.stl`, `.obj`,
/// legacy `.vtk` POLYDATA with POLYGONS, `.vtp` with ASCII arrays).
/// The surface is checked and oriented by [`prepare_surface`].
pub fn read_surface(path: &Path) -> Result<Shape<3>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (points, polys) = match ext.as_str() {
        "ply" => parse_ply(path, &bytes)?,
        "stl" => parse_stl(path, &bytes)?,
        "obj" => parse_obj(path, &bytes)?,
        "vtp" => super::vtkxml::read_vtp(path)?,
        "vtk" => {
            let v = super::read_vtk_polydata(path)?;
            if v.polygons.is_empty() {
                return Err(Error::parse(
                    path,
                    0,
                    "no POLYGONS: a surface needs polygons (an outline has LINES)",
                ));
            }
            (v.points, v.polygons)
        }
        _ => {
            return Err(Error::parse(
                path,
                0,
                format!("unknown surface format '.{ext}' (use .ply, .stl, .obj, .vtk or .vtp)"),
            ));
        }
    };
    let mut facets = Vec::with_capacity(polys.len());
    for (k, poly) in polys.iter().enumerate() {
        if poly.len() < 3 {
            return Err(Error::parse(
                path,
                0,
                format!("face {k} has {} vertices; at least 3 needed", poly.len()),
            ));
        }
        if let Some(&i) = poly.iter().find(|&&i| i >= points.len()) {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "face {k} refers to vertex {i}, but the file has {} vertices",
                    points.len()
                ),
            ));
        }
        for j in 1..poly.len() - 1 {
            facets.push([poly[0], poly[j], poly[j + 1]]);
        }
    }
    let shape = Shape {
        name,
        points,
        facets,
        landmarks: Vec::new(),
    };
    prepare_surface(shape).map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// Checks a triangle surface and orients it: finite coordinates, at least one facet, no
/// degenerate facet (repeated vertex or zero area: an error naming the facet; a mesh's
/// numbering is kept so that shapes stay in correspondence), every edge shared by at most
/// two facets (edge-manifold), facets oriented consistently across every edge (flipped as
/// needed; an error when impossible, as on a Möbius strip), and, where the surface is
/// closed, normals pointing outwards (positive enclosed volume). Open surfaces are allowed.
pub fn prepare_surface(mut s: Shape<3>) -> Result<Shape<3>> {
    if s.facets.is_empty() {
        return Err(Error::shape(&s.name, "has no facets (a surface is needed)"));
    }
    s.validate()?;
    let scale = norm(crate::geometry::sub(
        crate::geometry::bounding_box(&s.points).1,
        crate::geometry::bounding_box(&s.points).0,
    ));
    for (k, f) in s.facets.iter().enumerate() {
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
            return Err(Error::shape(
                &s.name,
                format!("facet {k} repeats a vertex ({f:?})"),
            ));
        }
        if norm(facet_normal(&s.points, f)) <= 1e-14 * scale * scale {
            return Err(Error::shape(
                &s.name,
                format!("facet {k} {f:?} has zero area"),
            ));
        }
    }
    // Edge -> facets using it.
    let mut edges: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (k, f) in s.facets.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(k);
        }
    }
    if let Some(((a, b), fs)) = edges.iter().find(|(_, fs)| fs.len() > 2) {
        return Err(Error::shape(
            &s.name,
            format!(
                "is not edge-manifold: the edge between vertices {a} and {b} is shared by {} facets",
                fs.len()
            ),
        ));
    }
    // Consistent orientation, component by component (breadth-first over shared edges).
    let nf = s.facets.len();
    let mut flip: Vec<Option<bool>> = vec![None; nf];
    let directed =
        |f: &[usize; 3], a: usize, b: usize| (0..3).any(|e| f[e] == a && f[(e + 1) % 3] == b);
    for seed in 0..nf {
        if flip[seed].is_some() {
            continue;
        }
        flip[seed] = Some(false);
        let mut queue = vec![seed];
        while let Some(k) = queue.pop() {
            let fk = oriented(&s.facets[k], flip[k] == Some(true));
            for e in 0..3 {
                let (a, b) = (fk[e], fk[(e + 1) % 3]);
                for &j in &edges[&(a.min(b), a.max(b))] {
                    if j == k {
                        continue;
                    }
                    // A consistent neighbour runs the shared edge from b to a.
                    let same_dir = directed(&s.facets[j], a, b);
                    let want = same_dir; // flip j if it runs a -> b too
                    match flip[j] {
                        None => {
                            flip[j] = Some(want);
                            queue.push(j);
                        }
                        Some(fj) if fj != want => {
                            return Err(Error::shape(
                                &s.name,
                                format!(
                                    "cannot be oriented consistently (facets {k} and {j} disagree \
                                     around the edge {a}-{b} whichever way they turn)"
                                ),
                            ));
                        }
                        _ => {}
                    }
                }
            }
        }
    }
    for (f, fl) in s.facets.iter_mut().zip(&flip) {
        *f = oriented(f, *fl == Some(true));
    }
    let closed = edges.values().all(|fs| fs.len() == 2);
    if closed && signed_volume(&s) < 0.0 {
        for f in &mut s.facets {
            f.swap(1, 2);
        }
    }
    Ok(s)
}

fn oriented(f: &[usize; 3], flip: bool) -> [usize; 3] {
    if flip { [f[0], f[2], f[1]] } else { *f }
}

/// Volume enclosed by a closed surface (positive when its normals point outwards).
pub fn signed_volume(s: &Shape<3>) -> f64 {
    s.facets
        .iter()
        .map(|f| {
            let (a, b, c) = (s.points[f[0]], s.points[f[1]], s.points[f[2]]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Whether every edge of the surface is shared by exactly two facets.
pub fn is_closed_surface(s: &Shape<3>) -> bool {
    let mut count: HashMap<(usize, usize), u32> = HashMap::new();
    for f in &s.facets {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count.values().all(|&c| c == 2)
}

type Parsed = (Vec<Point<3>>, Vec<Vec<usize>>);

#[derive(Clone, Copy, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn read(self, b: &[u8], big: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big {
                    <$t>::from_be_bytes(a) as f64
                } else {
                    <$t>::from_le_bytes(a) as f64
                }
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => rd!(i16, 2),
            Scalar::U16 => rd!(u16, 2),
            Scalar::I32 => rd!(i32, 4),
            Scalar::U32 => rd!(u32, 4),
            Scalar::F32 => rd!(f32, 4),
            Scalar::F64 => rd!(f64, 8),
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

/// PLY: elements `vertex` (properties `x`, `y`, `z`) and `face` (list `vertex_indices` or
/// `vertex_index`); other elements and properties are skipped.
fn parse_ply(path: &Path, bytes: &[u8]) -> Result<Parsed> {
    let err = |line: usize, m: String| Error::parse(path, line, m);
    let end = find_header_end(bytes).ok_or_else(|| {
        err(
            1,
            "no 'end_header' line: not a PLY file or truncated header".into(),
        )
    })?;
    let header = std::str::from_utf8(&bytes[..end.0])
        .map_err(|_| err(1, "the PLY header is not text".into()))?;
    let mut lines = header.lines().enumerate();
    match lines.next() {
        Some((_, l)) if l.trim() == "ply" => {}
        _ => return Err(err(1, "does not start with 'ply'".into())),
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, l) in lines {
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.first().copied() {
            Some("format") => {
                format = Some(match t.get(1).copied() {
                    Some("ascii") => 0,
                    Some("binary_little_endian") => 1,
                    Some("binary_big_endian") => 2,
                    other => return Err(err(i + 1, format!("unknown PLY format {other:?}"))),
                })
            }
            Some("element") => {
                let count: usize = t
                    .get(2)
                    .and_then(|c| c.parse().ok())
                    .ok_or_else(|| err(i + 1, format!("bad element line '{l}'")))?;
                if count > MAX_COUNT {
                    return Err(err(
                        i + 1,
                        format!("element count {count} is implausibly large"),
                    ));
                }
                elements.push(Element {
                    name: t.get(1).unwrap_or(&"").to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err(i + 1, "property before any element".into()))?;
                let bad = || err(i + 1, format!("bad property line '{l}'"));
                if t.get(1) == Some(&"list") {
                    let c = t.get(2).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?;
                    let v = t.get(3).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?;
                    el.props
                        .push(Property::List(t.get(4).unwrap_or(&"").to_string(), c, v));
                } else {
                    let v = t.get(1).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?;
                    el.props
                        .push(Property::Scalar(t.get(2).unwrap_or(&"").to_string(), v));
                }
            }
            _ => {}
        }
    }
    let format = format.ok_or_else(|| err(2, "no 'format' line".into()))?;
    let body = &bytes[end.1..];
    let mut points = Vec::new();
    let mut polys = Vec::new();
    if format == 0 {
        let text =
            std::str::from_utf8(body).map_err(|_| err(0, "the ASCII body is not text".into()))?;
        let mut tokens = text.split_whitespace();
        for el in &elements {
            for k in 0..el.count {
                let mut xyz = [f64::NAN; 3];
                let mut poly = Vec::new();
                for p in &el.props {
                    let mut next = || -> Result<f64> {
                        let tok = tokens.next().ok_or_else(|| {
                            err(
                                0,
                                format!("truncated: {} {k} of {} is incomplete", el.name, el.count),
                            )
                        })?;
                        tok.parse::<f64>().map_err(|_| {
                            err(0, format!("'{tok}' in {} {k} is not a number", el.name))
                        })
                    };
                    match p {
                        Property::Scalar(name, _) => {
                            let v = next()?;
                            set_xyz(&mut xyz, name, v);
                        }
                        Property::List(name, _, _) => {
                            let n = next()? as usize;
                            if n > 1000 {
                                return Err(err(
                                    0,
                                    format!("{} {k} has a list of {n} items", el.name),
                                ));
                            }
                            for _ in 0..n {
                                let v = next()?;
                                if name == "vertex_indices" || name == "vertex_index" {
                                    poly.push(index(v).ok_or_else(|| {
                                        err(0, format!("bad vertex index {v} in face {k}"))
                                    })?);
                                }
                            }
                        }
                    }
                }
                store(&el.name, xyz, poly, &mut points, &mut polys);
            }
        }
    } else {
        let big = format == 2;
        let mut at = 0usize;
        for el in &elements {
            for k in 0..el.count {
                let mut xyz = [f64::NAN; 3];
                let mut poly = Vec::new();
                for p in &el.props {
                    let trunc = || {
                        err(
                            0,
                            format!("truncated: {} {k} of {} is cut off", el.name, el.count),
                        )
                    };
                    match p {
                        Property::Scalar(name, s) => {
                            let b = body.get(at..at + s.size()).ok_or_else(trunc)?;
                            at += s.size();
                            set_xyz(&mut xyz, name, s.read(b, big));
                        }
                        Property::List(name, c, v) => {
                            let b = body.get(at..at + c.size()).ok_or_else(trunc)?;
                            at += c.size();
                            let n = c.read(b, big);
                            if !(0.0..=1000.0).contains(&n) {
                                return Err(err(
                                    0,
                                    format!("{} {k} has a list of {n} items", el.name),
                                ));
                            }
                            for _ in 0..n as usize {
                                let b = body.get(at..at + v.size()).ok_or_else(trunc)?;
                                at += v.size();
                                if name == "vertex_indices" || name == "vertex_index" {
                                    let x = v.read(b, big);
                                    poly.push(index(x).ok_or_else(|| {
                                        err(0, format!("bad vertex index {x} in face {k}"))
                                    })?);
                                }
                            }
                        }
                    }
                }
                store(&el.name, xyz, poly, &mut points, &mut polys);
            }
        }
    }
    if points
        .iter()
        .any(|p: &Point<3>| p.iter().any(|c| c.is_nan()))
        && !points.is_empty()
    {
        return Err(err(
            0,
            "a vertex lacks x, y or z, or has a NaN coordinate".into(),
        ));
    }
    Ok((points, polys))
}

fn index(v: f64) -> Option<usize> {
    (v >= 0.0 && v.fract() == 0.0 && v < MAX_COUNT as f64).then_some(v as usize)
}

fn set_xyz(xyz: &mut [f64; 3], name: &str, v: f64) {
    match name {
        "x" => xyz[0] = v,
        "y" => xyz[1] = v,
        "z" => xyz[2] = v,
        _ => {}
    }
}

fn store(
    el: &str,
    xyz: [f64; 3],
    poly: Vec<usize>,
    points: &mut Vec<Point<3>>,
    polys: &mut Vec<Vec<usize>>,
) {
    match el {
        "vertex" => points.push(xyz),
        "face" => polys.push(poly),
        _ => {}
    }
}

/// Byte offsets of the end of the header text and of the start of the body.
fn find_header_end(bytes: &[u8]) -> Option<(usize, usize)> {
    let pat = b"end_header";
    let limit = bytes.len().min(1 << 20);
    let pos = bytes[..limit].windows(pat.len()).position(|w| w == pat)?;
    let mut body = pos + pat.len();
    while body < bytes.len() && (bytes[body] == b'\r' || bytes[body] == b' ') {
        body += 1;
    }
    if body < bytes.len() && bytes[body] == b'\n' {
        body += 1;
    }
    Some((pos, body))
}

/// STL: binary when the size matches `84 + 50 n`, else ASCII (`facet`/`vertex` lines).
/// Triangles come as corner triples; equal corners are merged into one vertex.
fn parse_stl(path: &Path, bytes: &[u8]) -> Result<Parsed> {
    let mut corners: Vec<Point<3>> = Vec::new();
    let binary = bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        84 + 50 * n == bytes.len()
    };
    if binary {
        let n = (bytes.len() - 84) / 50;
        for t in 0..n {
            let base = 84 + 50 * t + 12;
            for c in 0..3 {
                let mut p = [0.0; 3];
                for (d, v) in p.iter_mut().enumerate() {
                    let o = base + 12 * c + 4 * d;
                    *v = f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]])
                        as f64;
                }
                corners.push(p);
            }
        }
    } else {
        let text = std::str::from_utf8(bytes).map_err(|_| {
            Error::parse(
                path,
                0,
                "neither a binary STL (size does not match its triangle count) nor ASCII text",
            )
        })?;
        if !text.trim_start().starts_with("solid") {
            return Err(Error::parse(
                path,
                1,
                "an ASCII STL starts with 'solid'; a binary one has 84 + 50 n bytes",
            ));
        }
        for (i, l) in text.lines().enumerate() {
            let t: Vec<&str> = l.split_whitespace().collect();
            if t.first() == Some(&"vertex") {
                corners.push(xyz_after_keyword(path, i + 1, l, &t)?);
            }
        }
        if !corners.len().is_multiple_of(3) {
            return Err(Error::parse(
                path,
                0,
                "truncated: the vertex count is not a multiple of 3",
            ));
        }
    }
    let mut ids: HashMap<[u64; 3], usize> = HashMap::new();
    let mut points = Vec::new();
    let mut polys = Vec::with_capacity(corners.len() / 3);
    for tri in corners.chunks(3) {
        let mut poly = Vec::with_capacity(3);
        for p in tri {
            let key = [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()];
            let id = *ids.entry(key).or_insert_with(|| {
                points.push(*p);
                points.len() - 1
            });
            poly.push(id);
        }
        polys.push(poly);
    }
    Ok((points, polys))
}

/// The three coordinates after the keyword of a `vertex x y z` (STL) or `v x y z` (OBJ) line.
fn xyz_after_keyword(path: &Path, line: usize, text: &str, tokens: &[&str]) -> Result<Point<3>> {
    let mut p = [0.0; 3];
    for (d, v) in p.iter_mut().enumerate() {
        *v = tokens
            .get(d + 1)
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| Error::parse(path, line, format!("bad vertex line '{text}'")))?;
    }
    Ok(p)
}

/// OBJ: `v x y z` and `f i j k ...` lines (1-based, `i/t/n` forms, negative indices from
/// the end); other lines are skipped.
fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Parsed> {
    let text = std::str::from_utf8(bytes).map_err(|_| Error::parse(path, 0, "not a text file"))?;
    let mut points = Vec::new();
    let mut polys = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.first().copied() {
            Some("v") => points.push(xyz_after_keyword(path, i + 1, l, &t)?),
            Some("f") => {
                let mut poly = Vec::new();
                for tok in &t[1..] {
                    let v: i64 = tok
                        .split('/')
                        .next()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| {
                            Error::parse(path, i + 1, format!("bad face item '{tok}'"))
                        })?;
                    let id = if v > 0 {
                        v - 1
                    } else {
                        points.len() as i64 + v
                    };
                    if id < 0 {
                        return Err(Error::parse(
                            path,
                            i + 1,
                            format!("face index {v} is out of range"),
                        ));
                    }
                    poly.push(id as usize);
                }
                polys.push(poly);
            }
            _ => {}
        }
    }
    Ok((points, polys))
}

/// Writes a surface as binary little-endian PLY.
pub fn write_ply(path: &Path, s: &Shape<3>) -> Result<()> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by atlasmesh\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        s.points.len(),
        s.facets.len()
    )
    .into_bytes();
    for p in &s.points {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for f in &s.facets {
        out.push(3);
        for &i in f {
            out.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    write_atomic(path, &out)
}

/// Writes a surface as binary STL (single precision, as the format has it).
pub fn write_stl(path: &Path, s: &Shape<3>) -> Result<()> {
    let mut out = vec![0u8; 80];
    out[..20].copy_from_slice(b"atlasmesh binary STL");
    out.extend_from_slice(&(s.facets.len() as u32).to_le_bytes());
    for f in &s.facets {
        let n = crate::geometry::normalize(facet_normal(&s.points, f));
        for c in n {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
        for &i in f {
            for c in s.points[i] {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    write_atomic(path, &out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Shape<3> {
        Shape {
            name: "t".into(),
            points: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            // Mixed orientation on purpose.
            facets: vec![[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]],
            landmarks: Vec::new(),
        }
    }

    #[test]
    fn a_closed_surface_is_oriented_outwards() {
        let s = prepare_surface(tetra()).unwrap();
        assert!(signed_volume(&s) > 0.0);
        assert!((signed_volume(&s) - 1.0 / 6.0).abs() < 1e-12);
        assert!(is_closed_surface(&s));
    }

    #[test]
    fn ply_and_stl_round_trip() {
        let s = prepare_surface(tetra()).unwrap();
        let dir = std::env::temp_dir().join(format!("atlasmesh-surf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for ext in ["ply", "stl"] {
            let p = dir.join(format!("t.{ext}"));
            if ext == "ply" {
                write_ply(&p, &s).unwrap();
            } else {
                write_stl(&p, &s).unwrap();
            }
            let r = read_surface(&p).unwrap();
            assert_eq!(r.points.len(), 4, "{ext}");
            assert_eq!(r.facets.len(), 4, "{ext}");
            assert!((signed_volume(&r) - 1.0 / 6.0).abs() < 1e-6, "{ext}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn legacy_vtk_polygons_are_read_as_a_surface() {
        let dir = std::env::temp_dir().join(format!("atlasmesh-vtk3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.vtk");
        std::fs::write(
            &p,
            "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nPOLYGONS 4 16\n3 0 1 2\n3 0 1 3\n3 1 2 3\n3 0 2 3\n",
        )
        .unwrap();
        let s = read_surface(&p).unwrap();
        assert_eq!((s.points.len(), s.facets.len()), (4, 4));
        assert!((signed_volume(&s) - 1.0 / 6.0).abs() < 1e-9);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn non_manifold_and_truncated_inputs_are_refused() {
        let mut s = tetra();
        s.points.push([1.0, 1.0, 1.0]);
        s.facets.push([0, 1, 4]);
        let e = prepare_surface(s).unwrap_err().to_string();
        assert!(e.contains("edge-manifold"), "{e}");
        let dir = std::env::temp_dir().join(format!("atlasmesh-trunc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.ply");
        write_ply(&p, &prepare_surface(tetra()).unwrap()).unwrap();
        let b = std::fs::read(&p).unwrap();
        std::fs::write(&p, &b[..b.len() - 7]).unwrap();
        let e = read_surface(&p).unwrap_err().to_string();
        assert!(e.contains("truncated") && e.contains("t.ply"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

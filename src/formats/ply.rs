//! PLY surfaces (ASCII and binary, either endianness) read, binary written.

use super::atomic::{MAX_COUNT, write_atomic};
use super::helpers::Parsed;
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use std::path::Path;

#[derive(Clone, Copy, Debug)]
pub(crate) enum Scalar {
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
pub(crate) enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar(n, _) | Property::List(n, _, _) => n,
        }
    }
}

pub(crate) struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

/// PLY: elements `vertex` (properties `x`, `y`, `z`) and `face` (list `vertex_indices` or
/// `vertex_index`); other elements and properties are skipped.
#[allow(
    clippy::too_many_lines,
    reason = "a parser: the header's grammar and the element reading share one cursor"
)]
pub(crate) fn parse_ply(path: &Path, bytes: &[u8]) -> Result<Parsed> {
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
                let name = t.get(1).unwrap_or(&"").to_string();
                if elements.iter().any(|e| e.name == name) {
                    return Err(err(i + 1, format!("element {name:?} is declared twice")));
                }
                if name == "vertex" {
                    super::check_points(path, count, 1)?;
                }
                elements.push(Element {
                    name,
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err(i + 1, "property before any element".into()))?;
                let bad = || err(i + 1, format!("bad property line '{l}'"));
                let name = t.get(if t.get(1) == Some(&"list") { 4 } else { 2 });
                if let Some(n) = name
                    && el.props.iter().any(|p| p.name() == *n)
                {
                    return Err(err(
                        i + 1,
                        format!("property {n:?} of element {} is declared twice", el.name),
                    ));
                }
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

pub(crate) fn index(v: f64) -> Option<usize> {
    (v >= 0.0 && v.fract() == 0.0 && v < MAX_COUNT as f64).then_some(v as usize)
}

pub(crate) fn set_xyz(xyz: &mut [f64; 3], name: &str, v: f64) {
    match name {
        "x" => xyz[0] = v,
        "y" => xyz[1] = v,
        "z" => xyz[2] = v,
        _ => {}
    }
}

pub(crate) fn store(
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
pub(crate) fn find_header_end(bytes: &[u8]) -> Option<(usize, usize)> {
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

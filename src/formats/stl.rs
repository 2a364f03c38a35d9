//! STL surfaces (ASCII and binary) read, binary written.

use super::atomic::write_atomic;
use super::helpers::{Parsed, xyz_after_keyword};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, facet_normal};
use std::collections::HashMap;
use std::path::Path;

/// STL: binary when the size matches `84 + 50 n`, else ASCII (`facet`/`vertex` lines).
/// Triangles come as corner triples; equal corners are merged into one vertex.
pub(crate) fn parse_stl(path: &Path, bytes: &[u8]) -> Result<Parsed> {
    let mut corners: Vec<Point<3>> = Vec::new();
    let binary = bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        84 + 50 * n == bytes.len()
    };
    if binary {
        let n = (bytes.len() - 84) / 50;
        // A closed triangle surface has about two triangles per vertex.
        super::check_points(path, n, 2)?;
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
                if corners.len().is_multiple_of(3_000_000) {
                    super::check_points(path, corners.len() / 3, 2)?;
                }
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

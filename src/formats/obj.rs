//! Wavefront OBJ surfaces read.

use super::helpers::{Parsed, xyz_after_keyword};
use crate::error::{Error, Result};
use std::path::Path;

/// OBJ: `v x y z` and `f i j k ...` lines (1-based, `i/t/n` forms, negative indices from
/// the end); other lines are skipped.
pub(crate) fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Parsed> {
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

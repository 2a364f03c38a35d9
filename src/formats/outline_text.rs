//! Outlines from plain text files, one point per line, blank lines between shapes.

use super::helpers::{parse_f64, read_text, stem};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use std::path::Path;

/// Plain text: one `x y` (or `x,y`) per line; `#` starts a comment. Blank lines separate
/// shapes (as in geomstats' `cells.txt`): a file of one block is one shape named after the
/// file; blocks of a file with several are named `STEM-000`, `STEM-001`, ... in file order.
pub fn read_text_outlines(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    let text = read_text(path)?;
    parse_text_outlines(path, &text, closed)
}

/// [`read_text_outlines`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_text_outlines(path: &Path, text: &str, closed: bool) -> Result<Vec<Shape<2>>> {
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

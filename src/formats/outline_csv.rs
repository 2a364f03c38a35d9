//! Outlines from a long CSV table (`shape,point,x,y`).

use super::atomic::MAX_COUNT;
use super::outline::{parse_f64, read_text};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use std::collections::HashMap;
use std::path::Path;

/// Long CSV: header `name,index,x,y`; rows grouped by name (first-appearance order), sorted by
/// index, which must run 0..n-1 without gaps or repeats.
pub fn read_long_csv(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    let text = read_text(path)?;
    parse_long_csv(path, &text, closed)
}

/// [`read_long_csv`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_long_csv(path: &Path, text: &str, closed: bool) -> Result<Vec<Shape<2>>> {
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

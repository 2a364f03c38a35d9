//! Outlines and point sets from a long CSV table: one row per point, columns found by name
//! (`shape`, `point`/`landmark`, `x`, `y`, `z`; others ignored; see [`super::csv_table`]).

use super::atomic::MAX_COUNT;
use super::csv_table::{CsvColumns, Table};
use super::helpers::{parse_f64, read_text, shown, stem};
use crate::error::{Error, Result};
use crate::geometry::{MAX_NAME_CHARS, Point, Shape};
use std::collections::HashMap;
use std::path::Path;

/// Long CSV of outlines: a header naming `shape`, `point` (or `landmark`), `x`, `y` in any
/// order among other columns; rows grouped by shape (first-appearance order), sorted by point
/// index, which must run 0..n-1 without gaps or repeats. Without a `point` column the rows
/// are in order; without a `shape` column the file holds one shape named after the file.
pub fn read_long_csv(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    let text = read_text(path)?;
    parse_long_csv(path, &text, closed)
}

/// [`read_long_csv`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_long_csv(path: &Path, text: &str, closed: bool) -> Result<Vec<Shape<2>>> {
    parse_long_csv_with(path, text, closed, &CsvColumns::default())
}

/// [`parse_long_csv`] with the columns mapped by `columns`.
pub fn parse_long_csv_with(
    path: &Path,
    text: &str,
    closed: bool,
    columns: &CsvColumns,
) -> Result<Vec<Shape<2>>> {
    Ok(point_table::<2>(path, text, columns)?
        .into_iter()
        .map(|(name, pts)| Shape::polyline(name, pts, closed))
        .collect())
}

/// 3D point sets in correspondence from a long CSV (`shape`, `point`, `x`, `y`, `z`): shapes
/// without facets, for what needs no surface.
pub fn parse_point_sets_csv(
    path: &Path,
    text: &str,
    columns: &CsvColumns,
) -> Result<Vec<Shape<3>>> {
    Ok(point_table::<3>(path, text, columns)?
        .into_iter()
        .map(|(name, points)| Shape {
            name,
            points,
            facets: Vec::new(),
            landmarks: Vec::new(),
        })
        .collect())
}

/// 3D point sets from a CSV file as shape tools write them: the long table of
/// [`parse_point_sets_csv`] (several shapes), or one shape per file with `x,y,z` columns
/// under a header that may start with `#` (NumPy's `savetxt(..., header="x,y,z")`), or no
/// header at all (three numbers per line). A one-shape file's shape is named after the file.
///
/// # Errors
/// [`Error::Parse`] naming the line for a row that is not three numbers, and the errors of
/// [`parse_point_sets_csv`].
pub fn read_point_sets_csv(path: &Path, columns: &CsvColumns) -> Result<Vec<Shape<3>>> {
    let text = read_text(path)?;
    parse_point_sets_csv(path, &with_header(&text), columns)
}

/// `text` with a header line a [`Table`] reads: a leading `#` taken off the first line, or
/// `x,y,z` put above rows of three numbers without a header.
fn with_header(text: &str) -> std::borrow::Cow<'_, str> {
    let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
    let trimmed = first.trim_start_matches('\u{feff}').trim_start();
    if let Some(rest) = trimmed.strip_prefix('#') {
        return text.replacen(first, rest.trim_start(), 1).into();
    }
    let numbers = trimmed
        .split(',')
        .map(|f| f.trim().parse::<f64>().is_ok())
        .collect::<Vec<_>>();
    if !numbers.is_empty() && numbers.iter().all(|&n| n) {
        return format!("x,y,z\n{text}").into();
    }
    text.into()
}

/// Whether the CSV file `path` holds 3D points: a `z` column with a non-zero value (a 2D
/// outline may carry `z` = 0), or rows of three numbers without a header.
///
/// # Errors
/// Those of reading the file and its header.
pub fn csv_holds_3d_points(path: &Path) -> Result<bool> {
    let text = read_text(path)?;
    let text = with_header(&text);
    let t = Table::parse(path, &text, &CsvColumns::default())?;
    let Some(z) = t.column(path, "z")? else {
        return Ok(false);
    };
    Ok(t.rows
        .iter()
        .any(|(_, f)| f[z].trim().parse::<f64>().is_ok_and(|v| v != 0.0)))
}

/// The shapes of a long table of points in dimension `D`.
fn point_table<const D: usize>(
    path: &Path,
    text: &str,
    columns: &CsvColumns,
) -> Result<Vec<(String, Vec<Point<D>>)>> {
    let expected = if D == 2 {
        "shape,point,x,y"
    } else {
        "shape,point,x,y,z"
    };
    let t = Table::parse(path, text, columns)?;
    let shape = t.column(path, "shape")?;
    let point = t.column(path, "point")?;
    let axes = ["x", "y", "z"];
    let mut cols = [0usize; D];
    for (d, c) in cols.iter_mut().enumerate() {
        *c = t.required(path, axes[d], expected)?;
    }
    let z = if D == 2 { t.column(path, "z")? } else { None };
    let mut order: Vec<String> = Vec::new();
    let mut rows: HashMap<String, Vec<(usize, Point<D>, usize)>> = HashMap::new();
    for (ln, f) in &t.rows {
        let ln = *ln;
        let name = match shape {
            None => stem(path),
            Some(c) if f[c].chars().count() > MAX_NAME_CHARS => {
                return Err(Error::parse(
                    path,
                    ln,
                    format!(
                        "a shape name of {} characters, {} (at most {MAX_NAME_CHARS})",
                        f[c].chars().count(),
                        shown(f[c])
                    ),
                ));
            }
            Some(c) => f[c].to_string(),
        };
        let idx = match point {
            Some(c) => {
                let idx: usize = f[c].parse().map_err(|_| {
                    Error::parse(
                        path,
                        ln,
                        format!("point index {} is not a non-negative integer", shown(f[c])),
                    )
                })?;
                if idx > MAX_COUNT {
                    return Err(Error::parse(
                        path,
                        ln,
                        format!("point index {idx} is implausibly large"),
                    ));
                }
                idx
            }
            None => rows.get(&name).map_or(0, Vec::len),
        };
        let mut p = [0.0; D];
        for d in 0..D {
            p[d] = parse_f64(path, ln, f[cols[d]])?;
        }
        if let Some(c) = z
            && parse_f64(path, ln, f[c])? != 0.0
        {
            return Err(Error::parse(
                path,
                ln,
                "a point has a non-zero z: 3D points (x,y,z), where 2D outlines (x,y) were expected",
            ));
        }
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
            Ok((name, r.into_iter().map(|x| x.1).collect()))
        })
        .collect()
}

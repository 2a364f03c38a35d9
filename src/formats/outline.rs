//! Reading 2D outlines: the format by extension, and the checks every reader shares.

use super::csv_table::CsvColumns;
use super::helpers::text_of;
use super::outline_csv::parse_long_csv_with;
use super::outline_text::parse_text_outlines;
use super::vtk_cells::outline_from_polydata;
use super::vtk_legacy::parse_vtk_outline;
use crate::error::{Error, Result};
use crate::geometry::Shape;
use std::path::Path;

/// Reads the outlines in `path` (format from the extension: `.csv`, `.vtk`, `.vtp`, else
/// text).
/// `closed` applies to CSV and text files; VTK files carry their own topology.
pub fn read_outlines(path: &Path, closed: bool) -> Result<Vec<Shape<2>>> {
    read_outlines_with(path, closed, &CsvColumns::default())
}

/// [`read_outlines`] with the columns of a CSV file mapped by `columns`.
pub fn read_outlines_with(
    path: &Path,
    closed: bool,
    columns: &CsvColumns,
) -> Result<Vec<Shape<2>>> {
    let bytes = crate::formats::read_input(path)?;
    parse_outlines_with(path, &bytes, closed, columns)
}

/// [`read_outlines`] of a file's bytes: the format from the extension of `path`, which only
/// names the file in messages (no file is read).
pub fn parse_outlines(path: &Path, bytes: &[u8], closed: bool) -> Result<Vec<Shape<2>>> {
    parse_outlines_with(path, bytes, closed, &CsvColumns::default())
}

/// [`parse_outlines`] with the columns of a CSV file mapped by `columns`.
pub fn parse_outlines_with(
    path: &Path,
    bytes: &[u8],
    closed: bool,
    columns: &CsvColumns,
) -> Result<Vec<Shape<2>>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let shapes = match ext.as_str() {
        "csv" => parse_long_csv_with(path, text_of(path, bytes)?, closed, columns)?,
        "vtk" => vec![parse_vtk_outline(path, bytes)?],
        "vtp" => vec![outline_from_polydata(
            path,
            &super::vtk_xml::parse_vtp(path, bytes)?,
        )?],
        _ => parse_text_outlines(path, text_of(path, bytes)?, closed)?,
    };
    if shapes.is_empty() {
        return Err(Error::parse(path, 0, "the file holds no shape"));
    }
    for s in &shapes {
        check_finite(path, s)?;
    }
    Ok(shapes)
}

/// The 2D outline of VTK polydata already read from `path` ([`crate::formats::read_polydata`]):
/// its lines chained, checked as [`read_outlines`] checks.
///
/// # Errors
/// As [`read_outlines`] for a VTK file.
pub fn outline_from_vtk(path: &Path, v: &super::VtkPolyData) -> Result<Shape<2>> {
    let s = outline_from_polydata(path, v)?;
    check_finite(path, &s)?;
    Ok(s)
}

pub(crate) fn check_finite(path: &Path, s: &Shape<2>) -> Result<()> {
    super::check_points(path, s.points.len(), 1)?;
    if let Some((i, m)) = (s.points.iter().enumerate())
        .find_map(|(i, p)| crate::geometry::coordinate_problem(p).map(|m| (i, m)))
    {
        return Err(Error::parse(
            path,
            0,
            format!("shape {}: point {i} {m}", s.name),
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

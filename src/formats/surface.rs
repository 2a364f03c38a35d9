//! Reading 3D surfaces: the format by extension (PLY, STL, OBJ, VTP, legacy VTK), then the
//! checks and orientation every surface gets.

use super::obj::parse_obj;
use super::ply::parse_ply;
use super::stl::parse_stl;
use crate::error::{Error, Result};
use crate::geometry::{Shape, prepare_surface};
use std::path::Path;

/// Reads a triangle surface; the format comes from the extension (`.ply`, `.stl`, `.obj`,
/// legacy `.vtk` POLYDATA with polygons or triangle strips, `.vtp` as VTK writes it).
/// The surface is checked and oriented by [`prepare_surface`].
pub fn read_surface(path: &Path) -> Result<Shape<3>> {
    let bytes = crate::formats::read_input(path)?;
    parse_surface(path, &bytes)
}

/// [`read_surface`] of a file's bytes: the format from the extension of `path`, which only
/// names the file (and the shape) in messages (no file is read).
pub fn parse_surface(path: &Path, bytes: &[u8]) -> Result<Shape<3>> {
    let shape = parse_vertices_and_faces(path, bytes, true)?;
    prepare_surface(shape).map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// A 3D point set (for a shape model without a mesh, `build --no-mesh`): the vertices of a
/// PLY, OBJ, VTP or legacy VTK file, which may have no faces; faces, when there are, make it
/// a surface checked and oriented as [`read_surface`] does.
///
/// # Errors
/// As [`read_surface`], but for a file without faces.
pub fn read_point_set(path: &Path) -> Result<Shape<3>> {
    let bytes = crate::formats::read_input(path)?;
    let shape = parse_vertices_and_faces(path, &bytes, false)?;
    if shape.facets.is_empty() {
        shape
            .validate()
            .map_err(|e| Error::parse(path, 0, e.to_string()))?;
        return Ok(shape);
    }
    prepare_surface(shape).map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// The vertices and (triangulated) faces of a surface file, unchecked as a surface;
/// `need_faces`: a VTK file without polygons is an error.
fn parse_vertices_and_faces(path: &Path, bytes: &[u8], need_faces: bool) -> Result<Shape<3>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (points, polys) = match ext.as_str() {
        "ply" => parse_ply(path, bytes)?,
        "stl" => parse_stl(path, bytes)?,
        "obj" => parse_obj(path, bytes)?,
        "vtp" | "vtk" => {
            let v = parse_polydata(path, bytes)?;
            if v.polygons.is_empty() && need_faces {
                return Err(Error::parse(
                    path,
                    0,
                    "no polygons: a surface needs polygons (an outline has lines)",
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
    faces_to_shape(path, name, points, &polys)
}

/// The polydata of a VTK file (`.vtk` or `.vtp`), parsed once, so that a caller can see what
/// it holds (polygons: a surface; lines: an outline) and then make the shape from it with
/// [`surface_from_polydata`] or [`crate::formats::outline_from_vtk`]. `None` for any other
/// extension (nothing is read).
///
/// # Errors
/// The file's reading and parsing errors.
pub fn read_polydata(path: &Path) -> Result<Option<super::VtkPolyData>> {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vtp") || e.eq_ignore_ascii_case("vtk"))
    {
        return Ok(None);
    }
    let bytes = crate::formats::read_input(path)?;
    parse_polydata(path, &bytes).map(Some)
}

/// The polydata of a VTK file, legacy (`.vtk`) or XML (`.vtp`) by the extension of `path`.
pub(crate) fn parse_polydata(path: &Path, bytes: &[u8]) -> Result<super::VtkPolyData> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vtp"))
    {
        super::vtk_xml::parse_vtp(path, bytes)
    } else {
        super::vtk_legacy::parse_vtk_polydata(path, bytes)
    }
}

/// The checked and oriented surface of polydata already read from `path` (its polygons
/// triangulated as fans), for a caller that looked at the polydata first.
///
/// # Errors
/// As [`read_surface`].
pub fn surface_from_polydata(path: &Path, v: super::VtkPolyData) -> Result<Shape<3>> {
    if v.polygons.is_empty() {
        return Err(Error::parse(
            path,
            0,
            "no polygons: a surface needs polygons (an outline has lines)",
        ));
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let shape = faces_to_shape(path, name, v.points, &v.polygons)?;
    prepare_surface(shape).map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// Points and polygons as a shape: every polygon checked and fanned into triangles.
fn faces_to_shape(
    path: &Path,
    name: String,
    points: Vec<[f64; 3]>,
    polys: &[Vec<usize>],
) -> Result<Shape<3>> {
    super::check_points(path, points.len(), 1)?;
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
    Ok(Shape {
        name,
        points,
        facets,
        landmarks: Vec::new(),
    })
}

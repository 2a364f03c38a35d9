//! Reading a subject, the same for every front end: a file (or arrays) in the atlas's
//! dimension, checked, its floating islands dropped with a warning that its report keeps.

use super::population::{ISLAND_SHARE, clean_shapes, is_surface_file, polydata_is_surface};
use crate::error::{Error, Result};
use crate::formats::CsvColumns;
use crate::geometry::Shape;
use std::path::Path;

/// How subject files are read (outlines in CSV and text files; surfaces carry their own
/// topology).
#[derive(Clone, Debug, Default)]
pub struct SubjectReading {
    /// Outlines in CSV and text files are open.
    pub open: bool,
    /// The columns of CSV files, where their names are not the usual ones.
    pub columns: CsvColumns,
    /// Which labels of a label map make the subject's shape.
    pub labels: super::LabelReading,
    /// Where each subject's CT is, for materials.
    pub ct: super::CtSource,
}

/// A subject ready to fit: its shape, checked and cleaned, and what a user should know about
/// it (islands dropped), which its report carries.
#[derive(Clone, Debug)]
pub struct Subject<const D: usize> {
    /// The shape (subject frame and unit).
    pub shape: Shape<D>,
    /// Warnings about the input (floating components dropped, several remaining).
    pub warnings: Vec<String>,
    /// The shape is a part (a label cut by its image's border): it is fitted as `--partial`
    /// fits, whatever the run's parameters say.
    pub partial: bool,
    /// For a label map's label: the image's smallest voxel spacing (mm).
    pub voxel_size: Option<f64>,
    /// The subject's CT (a file or a DICOM series' folder), whose HU give its mesh's
    /// materials.
    pub ct: Option<std::path::PathBuf>,
}

/// `shape` ready to fit: checked ([`Shape::validate`]) and its floating components under
/// [`ISLAND_SHARE`] of its area (length) dropped, with a warning.
///
/// # Errors
/// [`Error::Parse`] naming `origin` (a file, or `"shape K"`) for a shape that is not valid.
pub fn prepare_subject<const D: usize>(mut shape: Shape<D>, origin: &Path) -> Result<Subject<D>> {
    shape.name = crate::geometry::display_name(&shape.name);
    // The readers check this on every file; a shape made in memory (Python arrays) is
    // checked here, before any work.
    crate::formats::check_points(origin, shape.points.len(), 1)?;
    shape
        .validate()
        .map_err(|e| Error::parse(origin, 0, e.to_string()))?;
    let mut one = [shape];
    let report = clean_shapes(&mut one, ISLAND_SHARE);
    let [shape] = one;
    let warnings = report.into_iter().flat_map(|r| r.warnings).collect();
    Ok(Subject {
        shape,
        warnings,
        partial: false,
        voxel_size: None,
        ct: None,
    })
}

/// The subjects in the file `path` for an atlas of dimension `D`: a surface (PLY, STL, OBJ,
/// VTK, VTP) or a label map's label in 3D, one or more outlines (CSV, text, VTK, VTP) in 2D,
/// each prepared by [`prepare_subject`].
///
/// # Errors
/// [`Error::Population`] for a file of the other dimension (naming what it holds), the
/// errors of the readers and of [`prepare_subject`].
pub fn read_subjects<const D: usize>(
    path: &Path,
    reading: &SubjectReading,
) -> Result<Vec<Subject<D>>> {
    if D == 3 && crate::formats::is_image_file(path) {
        let s = super::read_label_surface(path, &reading.labels)?;
        let mut subject = prepare_subject(s.shape.into_dim(), path)?;
        subject.warnings.splice(0..0, s.warnings);
        subject.partial = s.partial;
        subject.voxel_size = Some(s.spacing.iter().copied().fold(f64::INFINITY, f64::min));
        subject.ct = reading.ct.for_subject(path, &subject.shape.name)?;
        return Ok(vec![subject]);
    }
    // A VTK file is parsed once: what it holds says surface or outline.
    let polydata = crate::formats::read_polydata(path)?;
    let surface = match &polydata {
        Some(v) => polydata_is_surface(path, v)?,
        None => is_surface_file(path)?,
    };
    let shapes: Vec<Shape<D>> = match (D, surface, polydata) {
        (3, true, Some(v)) => vec![crate::formats::surface_from_polydata(path, v)?.into_dim()],
        (3, true, None) => vec![super::population::read_surface_file(path)?.into_dim()],
        (2, false, Some(v)) => vec![crate::formats::outline_from_vtk(path, &v)?.into_dim()],
        (2, false, None) => {
            crate::formats::read_outlines_with(path, !reading.open, &reading.columns)?
                .into_iter()
                .map(Shape::into_dim)
                .collect()
        }
        (_, surface, _) => {
            return Err(Error::Population(format!(
                "{}: {}, but the atlas is {D}D",
                path.display(),
                if !surface {
                    "a 2D outline"
                } else if path
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
                {
                    "3D points (x,y,z)"
                } else {
                    "a 3D surface"
                }
            )));
        }
    };
    shapes
        .into_iter()
        .map(|s| {
            let mut subject = prepare_subject(s, path)?;
            subject.ct = reading.ct.for_subject(path, &subject.shape.name)?;
            Ok(subject)
        })
        .collect()
}

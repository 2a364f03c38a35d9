//! Label maps in wherever a surface goes: the recipe that reads an image, picks its labels
//! and extracts their surface ([`crate::image`]), oriented and checked as a surface file is.

use crate::error::{Error, Result};
use crate::formats::read_image;
use crate::geometry::{Shape, prepare_surface};
use crate::image::{LabelChoice, LabelSurface, LabelTable, label_mask, label_surface};
use std::path::{Path, PathBuf};

/// How label maps are read: which labels make the shape, and the names the labels have.
#[derive(Clone, Debug, Default)]
pub struct LabelReading {
    /// The labels (`--label`); `None` refuses label maps with a message asking for it.
    pub choice: Option<LabelChoice>,
    /// Label names (`--label-table`, a CSV of `label,name`); a `.seg.nrrd`'s own segment
    /// names are added to it.
    pub table: LabelTable,
}

impl LabelReading {
    /// `choice` with the names of the CSV `table` (`label,name` rows; a header line allowed).
    ///
    /// # Errors
    /// The table cannot be read or has a row that is not `number,name`.
    pub fn new(choice: Option<LabelChoice>, table: Option<&Path>) -> Result<Self> {
        let table = match table {
            Some(p) => read_label_table(p)?,
            None => LabelTable::default(),
        };
        Ok(LabelReading { choice, table })
    }
}

/// Reads a label table: `label,name` rows (TotalSegmentator's classes, a Slicer color table
/// exported as CSV), an optional header line, a UTF-8 byte-order mark ignored.
///
/// # Errors
/// [`Error::Parse`] naming the file and the line; a number or a name (case aside) given twice
/// names both lines.
pub fn read_label_table(path: &Path) -> Result<LabelTable> {
    let text = crate::formats::read_input_text(path)?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut table = LabelTable::default();
    // The line of each number and of each name (lower case), for the duplicates' message.
    let mut line_of: std::collections::HashMap<i64, usize> = Default::default();
    let mut line_of_name: std::collections::HashMap<String, usize> = Default::default();
    let shown = |s: &str| crate::geometry::display_name(s);
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut cols = line.splitn(3, [',', ';', '\t']);
        let (a, b) = (cols.next().unwrap_or(""), cols.next().unwrap_or(""));
        match a.trim().parse::<i64>() {
            Ok(v) if !b.trim().is_empty() => {
                let name = b.trim().trim_matches('"').to_string();
                if let Some(first) = line_of.insert(v, k + 1) {
                    return Err(Error::parse(
                        path,
                        k + 1,
                        format!("label {v} is named twice, on lines {first} and {}", k + 1),
                    ));
                }
                if let Some(first) = line_of_name.insert(name.to_lowercase(), k + 1) {
                    return Err(Error::parse(
                        path,
                        k + 1,
                        format!(
                            "the name {:?} is given twice, on lines {first} and {} (names are \
                             compared without case)",
                            shown(&name),
                            k + 1
                        ),
                    ));
                }
                table.names.insert(v, name);
            }
            Err(_) if k == 0 => continue,
            _ => {
                return Err(Error::parse(
                    path,
                    k + 1,
                    format!("{:?} is not a `label,name` row", shown(line)),
                ));
            }
        }
    }
    if table.names.is_empty() {
        return Err(Error::parse(path, 0, "no `label,name` row"));
    }
    Ok(table)
}

/// The surface of the chosen labels of the label map `path` (world RAS, mm), checked and
/// oriented outwards as [`crate::formats::read_surface`] does, named after the file; with the
/// warnings of the way (islands dropped, cavities filled, cut by the border).
///
/// # Errors
/// No `--label` given; the image cannot be read; the labels are absent (the message lists
/// those present); the surface is not a valid one.
pub fn read_label_surface(path: &Path, reading: &LabelReading) -> Result<LabelSurface> {
    let Some(choice) = &reading.choice else {
        return Err(Error::Parameter(format!(
            "{}: a label map (image); say which label makes the shape with --label (a number, \
             several as 1,7, or a name with --label-table)",
            path.display()
        )));
    };
    let file = read_image(path)?;
    let mut table = reading.table.clone();
    for (k, v) in file.labels.names {
        table.names.entry(k).or_insert(v);
    }
    let labels = table.resolve(choice, &path.display().to_string())?;
    let mask = label_mask(&file.image, &labels, path, &table)?;
    let mut surface = label_surface(&file.image, &mask, &shape_name(path));
    surface.warnings.extend(file.notes);
    surface.shape = prepare_surface(std::mem::replace(
        &mut surface.shape,
        Shape {
            name: String::new(),
            points: Vec::new(),
            facets: Vec::new(),
            landmarks: Vec::new(),
        },
    ))
    .map_err(|e| Error::parse(path, 0, format!("the label's surface: {e}")))?;
    Ok(surface)
}

/// The shape's name: the file's name without its extension (an image's `.nii.gz` and
/// `.seg.nrrd` whole), as [`crate::geometry::display_name`] shows it.
pub(crate) fn shape_name(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    for ext in [
        ".nii.gz",
        ".seg.nrrd",
        ".nii",
        ".nrrd",
        ".nhdr",
        ".mha",
        ".mhd",
    ] {
        if name.to_lowercase().ends_with(ext) {
            return crate::geometry::display_name(&name[..name.len() - ext.len()]);
        }
    }
    PathBuf::from(name)
        .file_stem()
        .map(|s| crate::geometry::display_name(&s.to_string_lossy()))
        .unwrap_or_default()
}

/// `atlasmesh convert MAP --label L OUT`: the label's surface ([`read_label_surface`]) written
/// to `output` in the format of its extension (PLY, STL, VTP, VTK), world RAS mm.
///
/// # Errors
/// As [`read_label_surface`]; an output extension that is not a surface format.
pub fn convert_label_map(
    input: &Path,
    output: &Path,
    reading: &LabelReading,
) -> Result<LabelSurface> {
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let format = crate::formats::ShapeFormat::parse(&ext).ok_or_else(|| {
        Error::Parameter(format!(
            "{}: a label's surface is written as .ply, .stl, .vtp or .vtk",
            output.display()
        ))
    })?;
    let surface = read_label_surface(input, reading)?;
    crate::formats::write_shape(output, &surface.shape, format)?;
    Ok(surface)
}

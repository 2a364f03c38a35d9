//! A DICOM series (a folder of CT slices, one file per slice, as scanners and PACS export
//! them) read to one image: the files of one series, sorted by their position along the
//! slices' normal, the pixel data decoded (native, deflate, RLE, JPEG, and JPEG 2000 as real
//! scanners write it, by the dicom-rs crates), the rescale slope and intercept applied (HU for
//! a CT). The geometry is DICOM's patient frame (LPS): `ImagePositionPatient`,
//! `ImageOrientationPatient` (the row then the column direction) and `PixelSpacing` (between
//! rows, then between columns); the slice step is the positions' own, so a gantry tilt is
//! kept. Turned to RAS as every image is.

use super::image_data::ImageFile;
use crate::error::{Error, Result};
use crate::image::{Image, LabelTable, VoxelType, WorldConvention};
use dicom_dictionary_std::tags;
use dicom_object::{DefaultDicomObject, OpenFileOptions, file::ReadPreamble};
use dicom_pixeldata::PixelDecoder;
use std::path::{Path, PathBuf};

/// The most files a series folder may hold.
const MAX_FILES: usize = 10_000;

/// Whether `dir` is a folder holding DICOM files (the `DICM` mark of Part 10 files).
pub fn is_dicom_series(dir: &Path) -> bool {
    dir.is_dir()
        && std::fs::read_dir(dir).is_ok_and(|mut it| {
            it.any(|e| e.is_ok_and(|e| e.path().is_file() && has_dicm(&e.path())))
        })
}

fn has_dicm(path: &Path) -> bool {
    use std::io::Read as _;
    let mut b = [0u8; 132];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut b))
        .is_ok()
        && &b[128..132] == b"DICM"
}

/// One slice as read: where it lies, how it is stored, its pixels.
struct Slice {
    file: PathBuf,
    series: String,
    position: [f64; 3],
    orientation: [f64; 6],
    spacing: [f64; 2],
    rows: usize,
    cols: usize,
    slope: f64,
    intercept: f64,
    signed: bool,
    bits: u16,
    pixels: Vec<u8>,
}

/// Reads the DICOM series in the folder `dir` (see the module doc).
///
/// # Errors
/// [`Error::Parse`] naming the folder or the file: no DICOM file, several series (listed),
/// slices of different sizes or orientations, missing slices (uneven spacing), a multi-frame
/// or colour image, pixel data that does not decode, more files or bytes than the limits.
pub fn read_dicom_series(dir: &Path) -> Result<ImageFile> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && has_dicm(p))
        .collect();
    if files.is_empty() {
        return Err(Error::parse(dir, 0, "no DICOM file in the folder"));
    }
    if files.len() > MAX_FILES {
        return Err(Error::parse(
            dir,
            0,
            format!(
                "{} DICOM files; at most {MAX_FILES} slices are read",
                files.len()
            ),
        ));
    }
    files.sort();
    let cap = super::input::max_input_bytes();
    let total: u64 = files
        .iter()
        .map(|f| std::fs::metadata(f).map(|m| m.len()).unwrap_or(0))
        .sum();
    if total > cap {
        return Err(Error::parse(
            dir,
            0,
            format!(
                "{total} bytes of DICOM files, beyond the input limit of {cap} bytes (set ATLASMESH_MAX_INPUT_BYTES to raise it)"
            ),
        ));
    }
    let mut slices = Vec::new();
    let mut notes = Vec::new();
    let mut decoded = 0u64;
    for f in &files {
        match slice(f)? {
            Some(s) => {
                // The image the slices make, within the input limit as they are decoded.
                decoded += s.pixels.len() as u64;
                if decoded > cap {
                    return Err(Error::parse(
                        dir,
                        0,
                        format!(
                            "the slices decode to more than the input limit of {cap} bytes (at \
                             {}; set ATLASMESH_MAX_INPUT_BYTES to raise it)",
                            f.display()
                        ),
                    ));
                }
                slices.push(s)
            }
            None => notes.push(format!(
                "{}: a DICOM object without pixel data (a report or a structured document?), \
                 skipped",
                f.display()
            )),
        }
    }
    if slices.is_empty() {
        return Err(Error::parse(
            dir,
            0,
            format!(
                "no DICOM image in the folder ({} objects without pixel data)",
                notes.len()
            ),
        ));
    }
    let mut image = assemble(dir, slices)?;
    image.notes = notes;
    Ok(image)
}

/// One file's slice; `None` for an object without pixel data (a dose report, a structured
/// document), which a viewer passes over too.
fn slice(file: &Path) -> Result<Option<Slice>> {
    let bad = |m: String| Error::parse(file, 0, m);
    // Read once, every declared length checked against the bytes before the parser (which
    // allocates a length before reading it) sees them.
    let bytes = super::input::read_input(file)?;
    super::dicom_lengths::check_declared_lengths(file, &bytes)?;
    let obj: DefaultDicomObject = OpenFileOptions::new()
        .read_preamble(ReadPreamble::Always)
        .from_reader(bytes.as_slice())
        .map_err(|e| bad(format!("not a readable DICOM file: {e}")))?;
    if obj.element(tags::PIXEL_DATA).is_err() {
        return Ok(None);
    }
    let text = |tag, what: &str| -> Result<String> {
        obj.element(tag)
            .ok()
            .and_then(|e| e.to_str().ok())
            .map(|s| s.trim().to_string())
            .ok_or_else(|| bad(format!("no {what}")))
    };
    let floats = |tag, what: &str, n: usize| -> Result<Vec<f64>> {
        let v: Vec<f64> = obj
            .element(tag)
            .ok()
            .and_then(|e| e.to_multi_float64().ok())
            .ok_or_else(|| bad(format!("no {what}")))?;
        if v.len() != n || v.iter().any(|x| !x.is_finite()) {
            return Err(bad(format!("{what} is not {n} finite numbers: {v:?}")));
        }
        Ok(v)
    };
    let int = |tag, what: &str| -> Result<i64> {
        obj.element(tag)
            .ok()
            .and_then(|e| e.to_int::<i64>().ok())
            .ok_or_else(|| bad(format!("no {what}")))
    };
    if obj
        .element(tags::NUMBER_OF_FRAMES)
        .ok()
        .and_then(|e| e.to_int::<i64>().ok())
        .is_some_and(|n| n > 1)
    {
        return Err(bad(
            "a multi-frame image; a series of single slices is read".into(),
        ));
    }
    if int(tags::SAMPLES_PER_PIXEL, "SamplesPerPixel").unwrap_or(1) != 1 {
        return Err(bad(
            "a colour image; a CT slice has one sample per pixel".into()
        ));
    }
    let p = floats(tags::IMAGE_POSITION_PATIENT, "ImagePositionPatient", 3)?;
    let o = floats(
        tags::IMAGE_ORIENTATION_PATIENT,
        "ImageOrientationPatient",
        6,
    )?;
    orientation_is_a_frame(&o).map_err(bad)?;
    let s = floats(tags::PIXEL_SPACING, "PixelSpacing", 2)?;
    let (slope, intercept) = rescale(&obj).map_err(bad)?;
    let rows = int(tags::ROWS, "Rows")?;
    let cols = int(tags::COLUMNS, "Columns")?;
    let bits = int(tags::BITS_ALLOCATED, "BitsAllocated")?;
    if !matches!(bits, 8 | 16 | 32) || rows <= 0 || cols <= 0 {
        return Err(bad(format!("{rows} × {cols} pixels of {bits} bits")));
    }
    within_budget(rows, cols, bits, bytes.len()).map_err(bad)?;
    let decoded = obj
        .decode_pixel_data()
        .map_err(|e| bad(format!("the pixel data does not decode: {e}")))?;
    let want = (rows * cols) as usize * (bits as usize / 8);
    let pixels = decoded.data();
    if pixels.len() < want {
        return Err(bad(format!(
            "{} bytes of pixels, {rows} × {cols} of {bits} bits need {want}",
            pixels.len()
        )));
    }
    Ok(Some(Slice {
        file: file.to_path_buf(),
        series: text(tags::SERIES_INSTANCE_UID, "SeriesInstanceUID")?,
        position: [p[0], p[1], p[2]],
        orientation: std::array::from_fn(|k| o[k]),
        spacing: [s[0], s[1]],
        rows: rows as usize,
        cols: cols as usize,
        slope,
        intercept,
        signed: int(tags::PIXEL_REPRESENTATION, "PixelRepresentation").unwrap_or(0) == 1,
        bits: bits as u16,
        pixels: pixels[..want].to_vec(),
    }))
}

/// Checks that a slice of `rows` × `cols` pixels of `bits` bits fits the decoding budget of
/// its file of `file_bytes` ([`super::input::decode_budget`]) before a codec allocates it (a
/// JPEG slice may announce 65535 × 65535 pixels); the reason otherwise.
fn within_budget(
    rows: i64,
    cols: i64,
    bits: i64,
    file_bytes: usize,
) -> std::result::Result<(), String> {
    let want = (rows.max(0) as usize)
        .saturating_mul(cols.max(0) as usize)
        .saturating_mul(bits.max(0) as usize / 8);
    let budget = super::input::decode_budget(file_bytes);
    if want > budget {
        return Err(format!(
            "{rows} × {cols} pixels of {bits} bits are {} MB, more than the {} MB a file of {} kB \
             may decode to (set ATLASMESH_MAX_DECODED_BYTES to raise it)",
            want >> 20,
            budget >> 20,
            file_bytes >> 10
        ));
    }
    Ok(())
}

/// The slice's `RescaleSlope` and `RescaleIntercept`: an absent tag takes its default (1, 0);
/// one present must be a finite number (a NaN was taken as the default, silently), and the
/// slope not 0 (every voxel would be the intercept); the reason otherwise.
fn rescale(obj: &DefaultDicomObject) -> std::result::Result<(f64, f64), String> {
    let get = |tag, what: &str, default: f64| {
        let Ok(e) = obj.element(tag) else {
            return Ok(default);
        };
        match e.to_float64() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!(
                "{what} {:?} is not a finite number",
                e.to_str().map(|s| s.trim().to_string()).unwrap_or_default()
            )),
        }
    };
    let slope = get(tags::RESCALE_SLOPE, "RescaleSlope", 1.0)?;
    if slope == 0.0 {
        return Err("RescaleSlope 0 would give every voxel the same value (the intercept)".into());
    }
    Ok((
        slope,
        get(tags::RESCALE_INTERCEPT, "RescaleIntercept", 0.0)?,
    ))
}

/// How far from unit length and from orthogonal `ImageOrientationPatient`'s two directions may
/// be (the rounding of their decimal strings; GDCM's check is of the same order).
const ORIENTATION_TOLERANCE: f64 = 1e-3;

/// Checks that `o` (`ImageOrientationPatient`: the row, then the column direction) holds two
/// orthogonal unit vectors; the reason otherwise.
fn orientation_is_a_frame(o: &[f64]) -> std::result::Result<(), String> {
    let (row, col) = ([o[0], o[1], o[2]], [o[3], o[4], o[5]]);
    let norm = |v: [f64; 3]| crate::geometry::dot(v, v).sqrt();
    let (nr, nc) = (norm(row), norm(col));
    let cosine = crate::geometry::dot(row, col) / (nr * nc).max(f64::MIN_POSITIVE);
    if (nr - 1.0).abs() > ORIENTATION_TOLERANCE
        || (nc - 1.0).abs() > ORIENTATION_TOLERANCE
        || cosine.abs() > ORIENTATION_TOLERANCE
    {
        return Err(format!(
            "ImageOrientationPatient {o:?} is not two orthogonal unit directions (lengths \
             {nr:.4} and {nc:.4}, cosine {cosine:.4})"
        ));
    }
    Ok(())
}

/// The slices of one series as one image: checked alike, sorted along their normal, evenly
/// spaced.
fn assemble(dir: &Path, mut slices: Vec<Slice>) -> Result<ImageFile> {
    let bad = |m: String| Error::parse(dir, 0, m);
    let mut series: Vec<&str> = slices.iter().map(|s| s.series.as_str()).collect();
    series.sort_unstable();
    series.dedup();
    if series.len() > 1 {
        return Err(bad(format!(
            "{} series mixed in one folder ({}); give a folder of one series",
            series.len(),
            series.join(", ")
        )));
    }
    let first = &slices[0];
    let (o, rows, cols, spacing) = (first.orientation, first.rows, first.cols, first.spacing);
    if let Some(odd) = slices.iter().find(|s| {
        s.rows != rows
            || s.cols != cols
            || s.bits != first.bits
            || s.signed != first.signed
            || (0..6).any(|k| (s.orientation[k] - o[k]).abs() > 1e-4)
            || (0..2).any(|k| (s.spacing[k] - spacing[k]).abs() > 1e-4)
    }) {
        return Err(bad(format!(
            "{} differs from {} in size, pixel type, orientation or spacing",
            odd.file.display(),
            first.file.display()
        )));
    }
    let row_dir = [o[0], o[1], o[2]];
    let col_dir = [o[3], o[4], o[5]];
    let normal = crate::geometry::cross(row_dir, col_dir);
    let along = |s: &Slice| crate::geometry::dot(s.position, normal);
    slices.sort_by(|a, b| along(a).total_cmp(&along(b)));
    let n = slices.len();
    let steps: Vec<f64> = slices
        .windows(2)
        .map(|w| along(&w[1]) - along(&w[0]))
        .collect();
    let step = if steps.is_empty() {
        1.0
    } else {
        let mut s = steps.clone();
        s.sort_by(f64::total_cmp);
        s[s.len() / 2]
    };
    if steps.iter().any(|&d| d.abs() < 1e-6) {
        return Err(bad("two slices at the same position".into()));
    }
    if let Some(k) = steps
        .iter()
        .position(|&d| (d - step).abs() > 0.05 * step.abs().max(0.01))
    {
        return Err(bad(format!(
            "the slices are not evenly spaced: {:.3} mm between {} and {} where the others are {step:.3} mm apart (missing slices?)",
            steps[k],
            slices[k].file.display(),
            slices[k + 1].file.display()
        )));
    }
    let third: [f64; 3] = if n > 1 {
        std::array::from_fn(|d| {
            (slices[n - 1].position[d] - slices[0].position[d]) / (n - 1) as f64
        })
    } else {
        crate::geometry::scale(normal, step)
    };
    let p0 = slices[0].position;
    // LPS: voxel (i = column, j = row, k = slice).
    let lps: [[f64; 4]; 3] = std::array::from_fn(|r| {
        [
            row_dir[r] * spacing[1],
            col_dir[r] * spacing[0],
            third[r],
            p0[r],
        ]
    });
    let affine: [[f64; 4]; 3] = std::array::from_fn(|r| {
        let sign = if r < 2 { -1.0 } else { 1.0 };
        lps[r].map(|v| sign * v)
    });
    let (voxel_type, data, slope, intercept) = voxels(&slices);
    Ok(ImageFile {
        image: Image {
            dims: [cols, rows, n],
            voxel_type,
            little_endian: true,
            data,
            slope,
            intercept,
            affine,
            file_convention: WorldConvention::Lps,
        },
        labels: LabelTable::default(),
        notes: Vec::new(),
    })
}

/// The slices' voxels as one image stores them: as stored with the common rescale, or as
/// float32 with each slice's own where they differ.
fn voxels(slices: &[Slice]) -> (VoxelType, Vec<u8>, f64, f64) {
    let first = &slices[0];
    let same_scaling = slices
        .iter()
        .all(|s| s.slope == first.slope && s.intercept == first.intercept);
    if same_scaling {
        let t = match (first.bits, first.signed) {
            (8, false) => VoxelType::U8,
            (8, true) => VoxelType::I8,
            (16, false) => VoxelType::U16,
            (16, true) => VoxelType::I16,
            (32, false) => VoxelType::U32,
            _ => VoxelType::I32,
        };
        let data: Vec<u8> = slices
            .iter()
            .flat_map(|s| s.pixels.iter().copied())
            .collect();
        (t, data, first.slope, first.intercept)
    } else {
        (VoxelType::F32, rescaled(slices), 1.0, 0.0)
    }
}

/// The slices' values with each slice's own rescale applied, as float32.
fn rescaled(slices: &[Slice]) -> Vec<u8> {
    let mut out = Vec::new();
    for s in slices {
        let size = (s.bits / 8) as usize;
        for c in s.pixels.chunks_exact(size) {
            let raw = match (size, s.signed) {
                (1, false) => f64::from(c[0]),
                (1, true) => f64::from(c[0] as i8),
                (2, false) => f64::from(u16::from_le_bytes([c[0], c[1]])),
                (2, true) => f64::from(i16::from_le_bytes([c[0], c[1]])),
                (_, false) => f64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
                _ => f64::from(i32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            };
            out.extend_from_slice(&((s.slope * raw + s.intercept) as f32).to_le_bytes());
        }
    }
    out
}

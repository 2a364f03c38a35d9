//! NIfTI-1 and NIfTI-2 images (`.nii`, `.nii.gz`; one file, header then voxels), world RAS.
//!
//! Written by hand rather than with the `nifti` crate: that crate reads NIfTI-1 only (not
//! NIfTI-2), inflates a file whole before its header is checked (no bound against a
//! decompression bomb or a header announcing more voxels than the file holds), and its
//! affine needs nalgebra; the header is a fixed layout of ~30 fields.
//!
//! The affine follows the standard's precedence (nifti1.h, "3 different methods"): the
//! sform when `sform_code > 0`, else the qform (quaternion, `qfac` = `pixdim[0]`) when
//! `qform_code > 0`, else the voxel sizes alone (method 1). Values are
//! `scl_slope · stored + scl_inter` when `scl_slope` is neither 0 nor NaN. Spatial units of
//! metres or microns (`xyzt_units`) are brought to mm.

use super::image_data::{ImageFile, Packing, Placement, announced_bytes, inflate, is_gzip, unpack};
use crate::error::{Error, Result};
use crate::image::{Image, LabelTable, VoxelType, WorldConvention};
use std::path::Path;

/// Reads a NIfTI file (see the module doc).
pub fn read_nifti(path: &Path) -> Result<ImageFile> {
    let bytes = super::read_input(path)?;
    parse(path, std::borrow::Cow::Owned(bytes))
}

/// The fields of a NIfTI header atlasmesh uses (both versions).
struct Header {
    dims: Vec<usize>,
    datatype: i16,
    bitpix: i16,
    pixdim: [f64; 8],
    vox_offset: usize,
    slope: f64,
    inter: f64,
    qform_code: i32,
    sform_code: i32,
    quatern: [f64; 3],
    qoffset: [f64; 3],
    srow: [[f64; 4]; 3],
    xyzt_units: i32,
    little: bool,
}

/// [`read_nifti`] of a file's bytes (`path` only names it in messages).
pub fn parse_nifti(path: &Path, bytes: &[u8]) -> Result<ImageFile> {
    parse(path, std::borrow::Cow::Borrowed(bytes))
}

/// [`parse_nifti`]; a file's bytes given whole become the voxels in place (one copy of a
/// plain file's voxels in memory, not two).
fn parse(path: &Path, bytes: std::borrow::Cow<'_, [u8]>) -> Result<ImageFile> {
    let packing = if is_gzip(&bytes) {
        Packing::Gzip
    } else {
        Packing::Raw
    };
    let head = inflate(path, &bytes, packing, 540)?;
    let h = header(path, &head)?;
    let voxel_type = voxel_type(path, h.datatype)?;
    let extra = h.dims.get(3..).unwrap_or(&[]);
    if extra.iter().any(|&d| d > 1) {
        return Err(Error::parse(
            path,
            0,
            format!(
                "a {}-dimensional image {:?}; a label map or CT is 3D",
                h.dims.len(),
                h.dims
            ),
        ));
    }
    let dims: [usize; 3] = std::array::from_fn(|k| h.dims.get(k).copied().unwrap_or(1));
    let want = announced_bytes(path, &dims, voxel_type.size())?;
    let total = h
        .vox_offset
        .checked_add(want)
        .ok_or_else(|| Error::parse(path, 0, "vox_offset and the voxels overflow"))?;
    let truncated = |e| match e {
        Error::Parse { message, .. } if message.starts_with("truncated") => Error::parse(
            path,
            0,
            format!(
                "truncated: the header announces {dims:?} voxels of {} bytes from byte {}, the file ends before",
                voxel_type.size(),
                h.vox_offset
            ),
        ),
        e => e,
    };
    let data = match (packing, bytes) {
        (Packing::Raw, std::borrow::Cow::Owned(mut all)) if all.len() >= total => {
            all.truncate(total);
            all.drain(..h.vox_offset);
            all
        }
        (_, bytes) => {
            let mut all =
                unpack(path, &bytes, packing, total, Placement::First).map_err(truncated)?;
            all.drain(..h.vox_offset);
            all
        }
    };
    let (slope, intercept) = if h.slope.is_finite() && h.slope != 0.0 {
        (h.slope, if h.inter.is_finite() { h.inter } else { 0.0 })
    } else {
        (1.0, 0.0)
    };
    let image = Image {
        dims,
        voxel_type,
        little_endian: h.little,
        data,
        slope,
        intercept,
        affine: affine(path, &h)?,
        file_convention: WorldConvention::Ras,
    };
    // The datatype decides the voxels' size; a `bitpix` that disagrees is read past with a
    // note, as nibabel reads it (its header check fixes bitpix from the datatype).
    let bits = voxel_type.size() * 8;
    let notes = if i64::from(h.bitpix) == bits as i64 {
        Vec::new()
    } else {
        vec![format!(
            "{}: bitpix {} disagrees with datatype {} ({bits} bits); the voxels are read as the \
             datatype says",
            crate::geometry::display_name(&path.display().to_string()),
            h.bitpix,
            h.datatype
        )]
    };
    Ok(ImageFile {
        image,
        labels: LabelTable::default(),
        notes,
    })
}

/// The header of either version, by `sizeof_hdr` (348 or 540, in either byte order).
fn header(path: &Path, b: &[u8]) -> Result<Header> {
    let short = || Error::parse(path, 0, "not a NIfTI file: shorter than its header");
    if b.len() < 348 {
        return Err(short());
    }
    let le = i32::from_le_bytes(b[0..4].try_into().unwrap_or_default());
    let be = i32::from_be_bytes(b[0..4].try_into().unwrap_or_default());
    let (version, little) = match (le, be) {
        (348, _) => (1, true),
        (_, 348) => (1, false),
        (540, _) => (2, true),
        (_, 540) => (2, false),
        _ => {
            return Err(Error::parse(
                path,
                0,
                "not a NIfTI file: sizeof_hdr is neither 348 (NIfTI-1) nor 540 (NIfTI-2)",
            ));
        }
    };
    let r = Fields { b, little };
    let h = if version == 1 {
        let magic = &b[344..348];
        if magic == b"ni1\0" {
            return Err(Error::parse(
                path,
                0,
                "a NIfTI-1 header whose voxels are in a separate .img file; give a single-file .nii",
            ));
        }
        if magic != b"n+1\0" {
            return Err(Error::parse(
                path,
                0,
                "not a NIfTI-1 file: its magic is not n+1",
            ));
        }
        let ndim = dimensions(path, i64::from(r.i16(40)))?;
        Header {
            dims: (1..=ndim)
                .map(|k| axis(path, k, i64::from(r.i16(40 + 2 * k))))
                .collect::<Result<_>>()?,
            datatype: r.i16(70),
            bitpix: r.i16(72),
            pixdim: std::array::from_fn(|k| r.f32(76 + 4 * k)),
            vox_offset: nonneg(path, r.f32(108), "vox_offset")?,
            slope: r.f32(112),
            inter: r.f32(116),
            qform_code: i32::from(r.i16(252)),
            sform_code: i32::from(r.i16(254)),
            quatern: std::array::from_fn(|k| r.f32(256 + 4 * k)),
            qoffset: std::array::from_fn(|k| r.f32(268 + 4 * k)),
            srow: std::array::from_fn(|row| std::array::from_fn(|k| r.f32(280 + 16 * row + 4 * k))),
            xyzt_units: i32::from(b[123]),
            little,
        }
    } else {
        if b.len() < 540 {
            return Err(short());
        }
        if &b[4..7] != b"n+2" {
            return Err(Error::parse(
                path,
                0,
                "not a NIfTI-2 file: its magic is not n+2",
            ));
        }
        let ndim = dimensions(path, r.i64(16))?;
        Header {
            dims: (1..=ndim)
                .map(|k| axis(path, k, r.i64(16 + 8 * k)))
                .collect::<Result<_>>()?,
            datatype: r.i16(12),
            bitpix: r.i16(14),
            pixdim: std::array::from_fn(|k| r.f64(104 + 8 * k)),
            vox_offset: usize::try_from(r.i64(168))
                .map_err(|_| Error::parse(path, 0, "vox_offset is negative"))?,
            slope: r.f64(176),
            inter: r.f64(184),
            qform_code: r.i32(344),
            sform_code: r.i32(348),
            quatern: std::array::from_fn(|k| r.f64(352 + 8 * k)),
            qoffset: std::array::from_fn(|k| r.f64(376 + 8 * k)),
            srow: std::array::from_fn(|row| std::array::from_fn(|k| r.f64(400 + 32 * row + 8 * k))),
            xyzt_units: r.i32(500),
            little,
        }
    };
    check_offset(path, version, h.vox_offset)?;
    if h.dims.is_empty() || h.dims.iter().take(3).any(|&d| d == 0) {
        return Err(Error::parse(
            path,
            0,
            format!("the image size {:?} has an empty axis", h.dims),
        ));
    }
    Ok(h)
}

/// The voxels of a single file follow its header and the 4-byte extension flag: a
/// `vox_offset` before byte 352 (NIfTI-1) or 544 (NIfTI-2) is refused.
fn check_offset(path: &Path, version: u8, vox_offset: usize) -> Result<()> {
    let first = if version == 1 { 352 } else { 544 };
    if vox_offset < first {
        return Err(Error::parse(
            path,
            0,
            format!(
                "vox_offset {vox_offset} lies inside the header: the voxels of a single-file \
                 NIfTI-{version} start at byte {first} or later"
            ),
        ));
    }
    Ok(())
}

/// The number of dimensions `dim[0]`: 1 to 7, as the standard says (nifti1_io refuses others).
fn dimensions(path: &Path, n: i64) -> Result<usize> {
    if (1..=7).contains(&n) {
        Ok(n as usize)
    } else {
        Err(Error::parse(
            path,
            0,
            format!("dim[0] = {n}: the number of dimensions is 1 to 7"),
        ))
    }
}

/// The size `dim[k]` of axis `k` (1-based), not negative.
fn axis(path: &Path, k: usize, n: i64) -> Result<usize> {
    usize::try_from(n)
        .map_err(|_| Error::parse(path, 0, format!("dim[{k}] = {n}: a size is not negative")))
}

/// A non-negative whole number of bytes from a float field.
fn nonneg(path: &Path, v: f64, what: &str) -> Result<usize> {
    if (0.0..1e12).contains(&v) {
        Ok(v as usize)
    } else {
        Err(Error::parse(
            path,
            0,
            format!("{what} {v} is not a byte offset"),
        ))
    }
}

/// Little- or big-endian fields of a header.
struct Fields<'a> {
    b: &'a [u8],
    little: bool,
}

impl Fields<'_> {
    fn get<const N: usize>(&self, at: usize) -> [u8; N] {
        self.b
            .get(at..at + N)
            .and_then(|s| s.try_into().ok())
            .unwrap_or([0; N])
    }
    fn i16(&self, at: usize) -> i16 {
        let a = self.get(at);
        if self.little {
            i16::from_le_bytes(a)
        } else {
            i16::from_be_bytes(a)
        }
    }
    fn i32(&self, at: usize) -> i32 {
        let a = self.get(at);
        if self.little {
            i32::from_le_bytes(a)
        } else {
            i32::from_be_bytes(a)
        }
    }
    fn i64(&self, at: usize) -> i64 {
        let a = self.get(at);
        if self.little {
            i64::from_le_bytes(a)
        } else {
            i64::from_be_bytes(a)
        }
    }
    fn f32(&self, at: usize) -> f64 {
        let a = self.get(at);
        f64::from(if self.little {
            f32::from_le_bytes(a)
        } else {
            f32::from_be_bytes(a)
        })
    }
    fn f64(&self, at: usize) -> f64 {
        let a = self.get(at);
        if self.little {
            f64::from_le_bytes(a)
        } else {
            f64::from_be_bytes(a)
        }
    }
}

/// NIfTI's datatype codes.
fn voxel_type(path: &Path, code: i16) -> Result<VoxelType> {
    Ok(match code {
        2 => VoxelType::U8,
        4 => VoxelType::I16,
        8 => VoxelType::I32,
        16 => VoxelType::F32,
        64 => VoxelType::F64,
        256 => VoxelType::I8,
        512 => VoxelType::U16,
        768 => VoxelType::U32,
        1024 => VoxelType::I64,
        1280 => VoxelType::U64,
        _ => {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "voxel datatype {code} is not read (integers of 8-64 bits, float32 and float64 are; not complex, RGB or float128)"
                ),
            ));
        }
    })
}

/// How far beyond 1 the squared norm of a qform's (b, c, d) may be: the rounding of three
/// float32 fields (nibabel's threshold is of the same order).
const QUATERNION_TOLERANCE: f64 = 1e-6;

/// The index → world (RAS, mm) affine by the standard's precedence (module doc).
fn affine(path: &Path, h: &Header) -> Result<[[f64; 4]; 3]> {
    let unit = match h.xyzt_units & 0x07 {
        1 => 1000.0, // metres
        3 => 0.001,  // microns
        _ => 1.0,    // mm, or unknown (read as mm, as nibabel and ITK do)
    };
    let pix: [f64; 3] = std::array::from_fn(|k| h.pixdim[k + 1]);
    let mut a = if h.sform_code > 0 {
        h.srow
    } else if h.qform_code > 0 {
        let [b, c, d] = h.quatern;
        // a² = 1 - (b² + c² + d²); below 0 beyond the rounding of float32 fields, (b, c, d) is
        // not the vector part of a unit quaternion, and nibabel refuses it too.
        let a2 = 1.0 - (b * b + c * c + d * d);
        if a2.is_nan() || a2 < -QUATERNION_TOLERANCE {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "the qform quaternion (b, c, d) = ({b}, {c}, {d}) is not a rotation: \
                     b² + c² + d² = {} > 1",
                    1.0 - a2
                ),
            ));
        }
        let a = a2.max(0.0).sqrt();
        let r = [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c - a * d),
                2.0 * (b * d + a * c),
            ],
            [
                2.0 * (b * c + a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d - a * b),
            ],
            [
                2.0 * (b * d - a * c),
                2.0 * (c * d + a * b),
                a * a + d * d - c * c - b * b,
            ],
        ];
        let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        let s = [pix[0], pix[1], pix[2] * qfac];
        std::array::from_fn(|row| {
            [
                r[row][0] * s[0],
                r[row][1] * s[1],
                r[row][2] * s[2],
                h.qoffset[row],
            ]
        })
    } else {
        std::array::from_fn(|row| {
            let mut v = [0.0; 4];
            v[row] = pix[row];
            v
        })
    };
    for row in &mut a {
        for v in row.iter_mut() {
            *v *= unit;
        }
    }
    if a.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::parse(
            path,
            0,
            "the voxel-to-world transform (sform/qform/pixdim) is not finite",
        ));
    }
    Ok(a)
}

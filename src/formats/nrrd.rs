//! NRRD images (`.nrrd` with the data attached, `.nhdr` with a detached data file; raw, gzip
//! or ASCII encodings), as ITK, 3D Slicer and pynrrd write them. The world frame is the
//! header's `space` (`left-posterior-superior`/`LPS`, `right-anterior-superior`/`RAS`), the
//! affine from `space directions` and `space origin` (or `spacings` alone). A 3D Slicer
//! segmentation (`.seg.nrrd`) names its labels in `SegmentN_LabelValue` / `SegmentN_Name`.
//!
//! Written by hand: the crates for NRRD on crates.io are unmaintained or read no geometry;
//! the header is `key: value` lines (the NRRD0005 specification, teem.sourceforge.net).

use super::image_data::{
    ImageFile, Packing, Placement, announced_bytes, numbers, read_with_data_file, shown, unpack,
};
use crate::error::{Error, Result};
use crate::image::{Image, LabelTable, VoxelType, WorldConvention};
use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

/// Reads a NRRD file (see the module doc).
pub fn read_nrrd(path: &Path) -> Result<ImageFile> {
    read_with_data_file(path, parse_nrrd)
}

/// [`read_nrrd`] of a header's bytes; `detached` reads a data file the header names.
pub fn parse_nrrd(
    path: &Path,
    bytes: &[u8],
    detached: &dyn Fn(&str) -> Result<Vec<u8>>,
) -> Result<ImageFile> {
    if !bytes.starts_with(b"NRRD000") {
        return Err(Error::parse(
            path,
            1,
            "not a NRRD file: it does not start with NRRD000",
        ));
    }
    let (fields, pairs, data_at) = header(path, bytes)?;
    let get = |k: &str| fields.get(k).map(String::as_str);
    let need = |k: &str| {
        get(k).ok_or_else(|| Error::parse(path, 0, format!("the header has no `{k}` field")))
    };
    let voxel_type = voxel_type(path, need("type")?)?;
    let sizes = numbers::<usize>(path, need("sizes")?, "sizes")?;
    let dimension: usize = need("dimension")?.trim().parse().unwrap_or(0);
    if dimension != sizes.len() {
        return Err(Error::parse(
            path,
            0,
            format!("dimension {dimension} but {} sizes", sizes.len()),
        ));
    }
    let dims = spatial_dims(path, &sizes)?;
    let want = announced_bytes(path, &dims, voxel_type.size())?;
    let sized = Placement::one_slice(want, dims);
    let encoding = get("encoding").unwrap_or("raw").trim().to_lowercase();
    let data_file = get("data file").or(get("datafile"));
    let stored: Cow<'_, [u8]> = match data_file {
        Some(name) => Cow::Owned(detached(name)?),
        None => Cow::Borrowed(&bytes[data_at..]),
    };
    let little = get("endian").map(str::trim) != Some("big");
    let data = match encoding.as_str() {
        "raw" => {
            let (data, placement) = skip(path, &stored, get("byte skip"), sized)?;
            unpack(path, data, Packing::Raw, want, placement)?
        }
        "gzip" | "gz" => unpack(path, &stored, Packing::Gzip, want, sized)?,
        "ascii" | "text" | "txt" => ascii(path, &stored, voxel_type, dims, little)?,
        other => {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "encoding {:?} is not read (raw, gzip and ascii are)",
                    shown(other)
                ),
            ));
        }
    };
    let convention = match get("space").map(|s| s.trim().to_lowercase()).as_deref() {
        Some("left-posterior-superior" | "lps") | None => WorldConvention::Lps,
        Some("right-anterior-superior" | "ras") => WorldConvention::Ras,
        Some(other) => {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "space {:?} is not read (left-posterior-superior and right-anterior-superior are)",
                    shown(other)
                ),
            ));
        }
    };
    let affine = affine(
        path,
        get("space directions"),
        get("space origin"),
        get("spacings"),
        sizes.len() == 4,
        convention,
    )?;
    let image = Image {
        dims,
        voxel_type,
        little_endian: little,
        data,
        slope: 1.0,
        intercept: 0.0,
        affine,
        file_convention: convention,
    };
    Ok(ImageFile {
        image,
        labels: segment_names(&pairs),
        notes: Vec::new(),
    })
}

/// The header's fields (`key: value`, keys lowercased), its key/value pairs (`key:=value`) and
/// where the data starts (after the blank line).
fn header(path: &Path, bytes: &[u8]) -> Result<(Fields, Fields, usize)> {
    let mut fields = HashMap::new();
    let mut pairs = HashMap::new();
    let mut at = 0;
    let mut line_no = 0;
    loop {
        let end = bytes[at..].iter().position(|&b| b == b'\n').map(|p| at + p);
        let line_end = end.unwrap_or(bytes.len());
        let line = std::str::from_utf8(&bytes[at..line_end])
            .map_err(|_| Error::parse(path, line_no + 1, "the header is not text"))?
            .trim_end_matches('\r');
        line_no += 1;
        at = end.map_or(bytes.len(), |e| e + 1);
        if line.is_empty() || end.is_none() {
            break;
        }
        if line_no == 1 || line.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = line.split_once(":=") {
            pairs.insert(k.to_string(), v.to_string());
        } else if let Some((k, v)) = line.split_once(": ") {
            fields.insert(k.trim().to_lowercase(), v.trim().to_string());
        } else {
            return Err(Error::parse(
                path,
                line_no,
                format!("not a `field: value` line: {:?}", shown(line)),
            ));
        }
        if line_no > 10_000 {
            return Err(Error::parse(
                path,
                line_no,
                "a header of more than 10 000 lines",
            ));
        }
    }
    Ok((fields, pairs, at))
}

/// The three spatial sizes of `sizes`: a leading non-spatial axis of one sample (a one-layer
/// segmentation) is allowed.
fn spatial_dims(path: &Path, sizes: &[usize]) -> Result<[usize; 3]> {
    match sizes {
        [1, a, b, c] | [a, b, c] => Ok([*a, *b, *c]),
        _ => Err(Error::parse(
            path,
            0,
            format!(
                "sizes {sizes:?}: a 3D image is read (a segmentation of several layers is not)"
            ),
        )),
    }
}

/// The data after `byte skip` bytes, placed as `sized` ([`Placement::Sized`]), or, for
/// `-1`, the whole data with the voxels at its end ([`Placement::Last`]).
fn skip<'a>(
    path: &Path,
    data: &'a [u8],
    byte_skip: Option<&str>,
    sized: Placement,
) -> Result<(&'a [u8], Placement)> {
    match byte_skip.map(str::trim) {
        None => Ok((data, sized)),
        Some("-1") => Ok((data, Placement::Last)),
        Some(n) => {
            let n: usize = n.parse().map_err(|_| {
                Error::parse(path, 0, format!("byte skip {:?} is not a count", shown(n)))
            })?;
            Ok((data.get(n..).unwrap_or(&[]), sized))
        }
    }
}

/// NRRD's type names.
fn voxel_type(path: &Path, t: &str) -> Result<VoxelType> {
    Ok(match t.trim().to_lowercase().as_str() {
        "signed char" | "int8" | "int8_t" => VoxelType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => VoxelType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            VoxelType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            VoxelType::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => VoxelType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => VoxelType::U32,
        "longlong"
        | "long long"
        | "long long int"
        | "signed long long"
        | "signed long long int"
        | "int64"
        | "int64_t" => VoxelType::I64,
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            VoxelType::U64
        }
        "float" => VoxelType::F32,
        "double" => VoxelType::F64,
        other => {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "type {:?} is not read (integers, float, double are)",
                    shown(other)
                ),
            ));
        }
    })
}

/// Voxels written as ASCII numbers, stored here in `voxel_type`.
fn ascii(
    path: &Path,
    stored: &[u8],
    voxel_type: VoxelType,
    dims: [usize; 3],
    little: bool,
) -> Result<Vec<u8>> {
    let n = dims.iter().product::<usize>();
    let text =
        std::str::from_utf8(stored).map_err(|_| Error::parse(path, 0, "ASCII data is not text"))?;
    let mut out = Vec::with_capacity(n * voxel_type.size());
    let mut count = 0;
    for t in text.split_whitespace().take(n) {
        let shown = crate::geometry::display_name(&t.chars().take(40).collect::<String>());
        let v: f64 = t
            .parse()
            .map_err(|_| Error::parse(path, 0, format!("data: {shown:?} is not a number")))?;
        // A value the type cannot hold exactly is refused, never saturated or truncated.
        let misfit = |what: &str| {
            Error::parse(
                path,
                0,
                format!("data: {shown:?} is {what} for the type {voxel_type:?}"),
            )
        };
        macro_rules! put {
            ($t:ty) => {{
                let x = v as $t;
                if !v.is_finite() && !voxel_type.is_float() {
                    return Err(misfit("not a whole number"));
                }
                if <$t>::MIN as f64 <= v && v <= <$t>::MAX as f64 {
                    if v.fract() != 0.0 && !voxel_type.is_float() {
                        return Err(misfit("not a whole number"));
                    }
                } else if v.is_finite() {
                    return Err(misfit("out of the range"));
                }
                out.extend_from_slice(&if little {
                    x.to_le_bytes()
                } else {
                    x.to_be_bytes()
                });
            }};
        }
        match voxel_type {
            VoxelType::U8 => put!(u8),
            VoxelType::I8 => put!(i8),
            VoxelType::U16 => put!(u16),
            VoxelType::I16 => put!(i16),
            VoxelType::U32 => put!(u32),
            VoxelType::I32 => put!(i32),
            VoxelType::U64 => put!(u64),
            VoxelType::I64 => put!(i64),
            VoxelType::F32 => put!(f32),
            VoxelType::F64 => put!(f64),
        }
        count += 1;
    }
    if count < n {
        return Err(Error::parse(
            path,
            0,
            format!("truncated: {n} voxels announced, {count} in the data"),
        ));
    }
    Ok(out)
}

/// The affine (RAS) from `space directions` (`(x,y,z)` per axis, `none` for a non-spatial
/// one) and `space origin`, or diagonal `spacings`; `leading` a non-spatial first axis.
fn affine(
    path: &Path,
    directions: Option<&str>,
    origin: Option<&str>,
    spacings: Option<&str>,
    leading: bool,
    convention: WorldConvention,
) -> Result<[[f64; 4]; 3]> {
    let vector = |s: &str, what: &str| -> Result<[f64; 3]> {
        let inner = s.trim().trim_start_matches('(').trim_end_matches(')');
        let v: Vec<f64> = inner
            .split(',')
            .map(|t| {
                t.trim().parse::<f64>().map_err(|_| {
                    Error::parse(path, 0, format!("{what}: {:?} is not a vector", shown(s)))
                })
            })
            .collect::<Result<_>>()?;
        <[f64; 3]>::try_from(v)
            .map_err(|_| Error::parse(path, 0, format!("{what}: {:?} is not a 3-vector", shown(s))))
    };
    let cols: Vec<[f64; 3]> = match (directions, spacings) {
        (Some(d), _) => d
            .split_whitespace()
            .filter(|t| *t != "none")
            .map(|t| vector(t, "space directions"))
            .collect::<Result<_>>()?,
        (None, Some(s)) => {
            let sp = numbers::<f64>(path, s, "spacings")?;
            let sp: Vec<f64> = if leading {
                sp.into_iter().skip(1).collect()
            } else {
                sp
            };
            (0..sp.len().min(3))
                .map(|k| {
                    let mut c = [0.0; 3];
                    c[k] = sp[k];
                    c
                })
                .collect()
        }
        (None, None) => vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };
    if cols.len() != 3 {
        return Err(Error::parse(
            path,
            0,
            format!("{} spatial directions; 3 are needed", cols.len()),
        ));
    }
    let o = match origin {
        Some(o) => vector(o, "space origin")?,
        None => [0.0; 3],
    };
    // In the file's convention, then to RAS (x and y turned round for LPS).
    let sign = |r: usize| {
        if convention == WorldConvention::Lps && r < 2 {
            -1.0
        } else {
            1.0
        }
    };
    Ok(std::array::from_fn(|r| {
        [
            sign(r) * cols[0][r],
            sign(r) * cols[1][r],
            sign(r) * cols[2][r],
            sign(r) * o[r],
        ]
    }))
}

/// A header's `key: value` fields or `key:=value` pairs.
type Fields = HashMap<String, String>;

/// 3D Slicer's segment names: `SegmentN_LabelValue:=V` and `SegmentN_Name:=NAME`.
fn segment_names(pairs: &HashMap<String, String>) -> LabelTable {
    let mut table = LabelTable::default();
    for (k, v) in pairs {
        let Some(seg) = k.strip_suffix("_LabelValue") else {
            continue;
        };
        if let (Ok(value), Some(name)) =
            (v.trim().parse::<i64>(), pairs.get(&format!("{seg}_Name")))
        {
            table.names.insert(value, name.trim().to_string());
        }
    }
    table
}

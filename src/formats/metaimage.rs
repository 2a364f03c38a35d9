//! MetaImage images (`.mha` with the data after the header, `.mhd` with a detached `.raw` or
//! `.zraw`), as ITK, SimpleITK and ITK-SNAP write them: `Key = Value` lines, the data's
//! geometry in `ElementSpacing`, `Offset` (or `Position`, `Origin`) and `TransformMatrix`
//! (or `Rotation`, `Orientation`: the direction of each image axis in turn), world LPS;
//! `CompressedData = True` for a zlib stream.
//!
//! Written by hand: no maintained crate reads MetaImage; the header is a few text lines
//! (ITK's MetaIO).

use super::image_data::{
    ImageFile, Packing, Placement, announced_bytes, numbers, read_with_data_file, shown, unpack,
};
use crate::error::{Error, Result};
use crate::image::{Image, LabelTable, VoxelType, WorldConvention};
use std::collections::HashMap;
use std::path::Path;

/// Reads a MetaImage file (see the module doc).
pub fn read_metaimage(path: &Path) -> Result<ImageFile> {
    read_with_data_file(path, parse_metaimage)
}

/// [`read_metaimage`] of a header's bytes; `detached` reads the data file it names.
pub fn parse_metaimage(
    path: &Path,
    bytes: &[u8],
    detached: &dyn Fn(&str) -> Result<Vec<u8>>,
) -> Result<ImageFile> {
    let (fields, data_at) = header(path, bytes)?;
    let get = |k: &str| fields.get(&k.to_lowercase()).map(String::as_str);
    let need = |k: &str| {
        get(k).ok_or_else(|| Error::parse(path, 0, format!("the header has no `{k}` field")))
    };
    if let Some(o) = get("ObjectType")
        && !o.eq_ignore_ascii_case("image")
    {
        return Err(Error::parse(
            path,
            0,
            format!("ObjectType {o}: an Image is read"),
        ));
    }
    let ndims: usize = need("NDims")?.trim().parse().unwrap_or(0);
    if ndims != 3 {
        return Err(Error::parse(
            path,
            0,
            format!("NDims {ndims}: a 3D image is read"),
        ));
    }
    if get("ElementNumberOfChannels").is_some_and(|c| c.trim() != "1") {
        return Err(Error::parse(
            path,
            0,
            "several channels per voxel; a label map or CT has one",
        ));
    }
    let dims_v = numbers::<usize>(path, need("DimSize")?, "DimSize")?;
    let dims: [usize; 3] = dims_v
        .try_into()
        .map_err(|_| Error::parse(path, 0, "DimSize needs 3 sizes"))?;
    let voxel_type = voxel_type(path, need("ElementType")?)?;
    let want = announced_bytes(path, &dims, voxel_type.size())?;
    let msb = get("ElementByteOrderMSB")
        .or(get("BinaryDataByteOrderMSB"))
        .is_some_and(|v| v.trim().eq_ignore_ascii_case("true"));
    let compressed = get("CompressedData").is_some_and(|v| v.trim().eq_ignore_ascii_case("true"));
    let data_file = need("ElementDataFile")?.trim();
    let detached_data;
    let mut placement = Placement::one_slice(want, dims);
    let stored: &[u8] = if data_file.eq_ignore_ascii_case("local") {
        &bytes[data_at..]
    } else if data_file.contains(' ') || data_file.eq_ignore_ascii_case("list") {
        return Err(Error::parse(
            path,
            0,
            format!(
                "ElementDataFile {:?}: one data file (or LOCAL) is read, not a list of slices",
                shown(data_file)
            ),
        ));
    } else {
        detached_data = detached(data_file)?;
        match get("HeaderSize").map(str::trim) {
            Some("-1") => {
                placement = Placement::Last;
                &detached_data
            }
            Some(n) if n != "0" => {
                let n: usize = n
                    .parse()
                    .map_err(|_| Error::parse(path, 0, "HeaderSize is not a count"))?;
                detached_data.get(n..).unwrap_or(&[])
            }
            _ => &detached_data,
        }
    };
    let packing = if compressed {
        Packing::Zlib
    } else {
        Packing::Raw
    };
    let data = unpack(path, stored, packing, want, placement)?;
    let affine = affine(path, &get)?;
    Ok(ImageFile {
        image: Image {
            dims,
            voxel_type,
            little_endian: !msb,
            data,
            slope: 1.0,
            intercept: 0.0,
            affine,
            file_convention: WorldConvention::Lps,
        },
        labels: LabelTable::default(),
        notes: Vec::new(),
    })
}

/// The index → world (RAS) affine of the header's `ElementSpacing`, `Offset` and
/// `TransformMatrix` (LPS; each axis's direction in turn).
fn affine<'a>(path: &Path, get: &dyn Fn(&str) -> Option<&'a str>) -> Result<[[f64; 4]; 3]> {
    let spacing = match get("ElementSpacing").or(get("ElementSize")) {
        Some(s) => vec3(path, s, "ElementSpacing")?,
        None => [1.0; 3],
    };
    let origin = match get("Offset").or(get("Position")).or(get("Origin")) {
        Some(s) => vec3(path, s, "Offset")?,
        None => [0.0; 3],
    };
    let m = match get("TransformMatrix")
        .or(get("Rotation"))
        .or(get("Orientation"))
    {
        Some(s) => numbers::<f64>(path, s, "TransformMatrix")?,
        None => vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    };
    if m.len() != 9 {
        return Err(Error::parse(path, 0, "TransformMatrix needs 9 numbers"));
    }
    // Axis k's direction is m[3k..3k+3] (LPS); RAS turns x and y round.
    let sign = |r: usize| if r < 2 { -1.0 } else { 1.0 };
    Ok(std::array::from_fn(|r| {
        [
            sign(r) * m[r] * spacing[0],
            sign(r) * m[3 + r] * spacing[1],
            sign(r) * m[6 + r] * spacing[2],
            sign(r) * origin[r],
        ]
    }))
}

/// The header's `Key = Value` fields (keys lowercased) up to and including
/// `ElementDataFile`, which ends it, and where the data starts.
fn header(path: &Path, bytes: &[u8]) -> Result<(HashMap<String, String>, usize)> {
    let mut fields = HashMap::new();
    let mut at = 0;
    let mut line_no = 0;
    while at < bytes.len() {
        let end = bytes[at..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |p| at + p);
        line_no += 1;
        let line = std::str::from_utf8(&bytes[at..end])
            .map_err(|_| Error::parse(path, line_no, "the header is not text"))?
            .trim();
        at = (end + 1).min(bytes.len());
        if line.is_empty() {
            continue;
        }
        let Some((k, v)) = line.split_once('=') else {
            return Err(Error::parse(
                path,
                line_no,
                format!("not a `Key = Value` line: {:?}", shown(line)),
            ));
        };
        let key = k.trim().to_lowercase();
        fields.insert(key.clone(), v.trim().to_string());
        if key == "elementdatafile" {
            return Ok((fields, at));
        }
        if line_no > 1000 {
            break;
        }
    }
    Err(Error::parse(
        path,
        line_no,
        "not a MetaImage header: no ElementDataFile line",
    ))
}

fn vec3(path: &Path, s: &str, what: &str) -> Result<[f64; 3]> {
    numbers::<f64>(path, s, what)?
        .try_into()
        .map_err(|_| Error::parse(path, 0, format!("{what} needs 3 numbers")))
}

/// MetaIO's element types.
fn voxel_type(path: &Path, t: &str) -> Result<VoxelType> {
    Ok(match t.trim().to_uppercase().as_str() {
        "MET_CHAR" => VoxelType::I8,
        "MET_UCHAR" => VoxelType::U8,
        "MET_SHORT" => VoxelType::I16,
        "MET_USHORT" => VoxelType::U16,
        "MET_INT" => VoxelType::I32,
        "MET_UINT" => VoxelType::U32,
        "MET_LONG_LONG" => VoxelType::I64,
        "MET_ULONG_LONG" => VoxelType::U64,
        "MET_FLOAT" => VoxelType::F32,
        "MET_DOUBLE" => VoxelType::F64,
        other => {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "ElementType {other} is not read (MET_CHAR ... MET_ULONG_LONG, MET_FLOAT, MET_DOUBLE are)"
                ),
            ));
        }
    })
}

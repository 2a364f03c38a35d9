//! What the image readers share: the image as read, decompression within the size the
//! header announces, and detached data files named beside their header.

use crate::error::{Error, Result};
use crate::image::{Image, LabelTable};
use std::io::Read as _;
use std::path::{Path, PathBuf};

/// An image as read: the image (world RAS, mm) and the label names its file carries (3D
/// Slicer's segment names in a `.seg.nrrd`; empty otherwise).
#[derive(Clone, Debug)]
pub struct ImageFile {
    /// The image.
    pub image: Image,
    /// The labels' names the file carries.
    pub labels: LabelTable,
    /// What the reader passed over and the user should know (a DICOM folder's objects
    /// without pixel data, skipped), one sentence each.
    pub notes: Vec<String>,
}

/// The bytes a header announces, checked against the input limit before anything is
/// allocated: `count` voxels of `size` bytes.
pub(super) fn announced_bytes(path: &Path, dims: &[usize], size: usize) -> Result<usize> {
    let cap = super::input::max_input_bytes();
    let n = dims
        .iter()
        .try_fold(size, |a, &d| a.checked_mul(d))
        .filter(|&n| n as u64 <= cap);
    n.ok_or_else(|| {
        Error::parse(
            path,
            0,
            format!(
                "the header announces {dims:?} voxels of {size} bytes, beyond the input limit of \
                 {cap} bytes (set ATLASMESH_MAX_INPUT_BYTES to raise it)"
            ),
        )
    })
}

/// How a data section is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Packing {
    /// As is.
    Raw,
    /// A gzip stream (one or several members).
    Gzip,
    /// A zlib stream.
    Zlib,
}

/// Where the voxels lie in a data section, and what may follow them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Placement {
    /// From its first byte; bytes after the voxels are ignored (NIfTI: a file may hold more
    /// than the volume its header describes, as nibabel reads it).
    First,
    /// Its last bytes (NRRD's `byte skip: -1`, MetaImage's `HeaderSize = -1`; raw data only).
    Last,
    /// From its first byte, with fewer than `slack` bytes after the voxels (a line end or
    /// padding, which ITK reads past too; one slice of the image, say); more is an error
    /// naming both figures: the header's sizes or type do not describe the data.
    Sized {
        /// The bytes after the voxels that are ignored.
        slack: usize,
    },
}

impl Placement {
    /// [`Placement::Sized`] with one slice of slack: of `want` voxel bytes over `dims`, the
    /// bytes of one `dims[0]` × `dims[1]` slice may follow the voxels (as ITK and teem read
    /// past them).
    pub(super) fn one_slice(want: usize, dims: [usize; 3]) -> Self {
        Placement::Sized {
            slack: want / dims[2].max(1),
        }
    }
}

/// Exactly `want` bytes of voxel data from `data`, unpacked, placed as `placement` says:
/// never more than `want` (and the slack of [`Placement::Sized`]) is inflated, so that a
/// decompression bomb stops at the size its header announces; fewer is an error naming what
/// is missing.
pub(super) fn unpack(
    path: &Path,
    data: &[u8],
    packing: Packing,
    want: usize,
    placement: Placement,
) -> Result<Vec<u8>> {
    let truncated = |got: usize| {
        Error::parse(
            path,
            0,
            format!("truncated: the header announces {want} bytes of voxels, the file holds {got}"),
        )
    };
    let too_long = |got: &str| {
        Error::parse(
            path,
            0,
            format!(
                "the header announces {want} bytes of voxels, the data holds {got}: a slice or more \
                 is left over, so the header's sizes or type do not describe the data"
            ),
        )
    };
    if packing == Packing::Raw {
        if data.len() < want {
            return Err(truncated(data.len()));
        }
        return match placement {
            Placement::First => Ok(data[..want].to_vec()),
            Placement::Last => Ok(data[data.len() - want..].to_vec()),
            Placement::Sized { slack } if data.len() - want >= slack.max(1) => {
                Err(too_long(&data.len().to_string()))
            }
            Placement::Sized { .. } => Ok(data[..want].to_vec()),
        };
    }
    let budget = super::input::decode_budget(data.len());
    if want > budget {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the header announces {} MB of voxels from {} kB of compressed data, more than \
                 the {} MB its size allows (a decompression bomb, or a header that lies; set \
                 ATLASMESH_MAX_DECODED_BYTES to raise it)",
                want >> 20,
                data.len() >> 10,
                budget >> 20
            ),
        ));
    }
    let limit = match placement {
        Placement::First => want,
        Placement::Last => {
            return Err(Error::parse(
                path,
                0,
                "compressed data cannot be placed at the end of its file (byte skip or HeaderSize -1)",
            ));
        }
        Placement::Sized { slack } => want.saturating_add(slack.max(1)),
    };
    let mut out = inflate(path, data, packing, limit)?;
    if out.len() < want {
        return Err(truncated(out.len()));
    }
    if out.len() == limit && limit > want {
        return Err(too_long(&format!("{limit} or more once inflated")));
    }
    out.truncate(want);
    Ok(out)
}

/// At most `limit` bytes of the compressed stream `data` (fewer where it ends).
pub(super) fn inflate(path: &Path, data: &[u8], packing: Packing, limit: usize) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(limit.min(data.len().saturating_mul(8)).min(1 << 30));
    let r: Box<dyn std::io::Read + '_> = match packing {
        Packing::Raw => Box::new(data),
        Packing::Gzip => Box::new(flate2::read::MultiGzDecoder::new(data)),
        Packing::Zlib => Box::new(flate2::read::ZlibDecoder::new(data)),
    };
    r.take(limit as u64).read_to_end(&mut out).map_err(|e| {
        Error::parse(
            path,
            0,
            format!("the compressed data is corrupt or cut short: {e}"),
        )
    })?;
    Ok(out)
}

/// A detached data file named in a header (`name`, as written there), beside the header:
/// a plain file name, or a path relative to the header's folder that stays in it, links
/// resolved (a link out of the folder is refused as `../` is).
pub(super) fn beside(header: &Path, name: &str) -> Result<PathBuf> {
    let rel = Path::new(name.trim());
    let plain = rel
        .components()
        .all(|c| matches!(c, std::path::Component::Normal(_)));
    if name.trim().is_empty() || !plain {
        return Err(Error::parse(
            header,
            0,
            format!(
                "the data file {:?} must be named relative to the header's folder, inside it",
                shown(name)
            ),
        ));
    }
    let folder = header.parent().unwrap_or(Path::new("."));
    let folder = if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    };
    let data = folder.join(rel);
    // Both resolved: where the data file really is must be inside the header's folder. A
    // file that does not exist is left to the read, which names it.
    if let (Ok(real), Ok(home)) = (data.canonicalize(), folder.canonicalize())
        && !real.starts_with(&home)
    {
        return Err(Error::parse(
            header,
            0,
            format!(
                "the data file {:?} is a link to {}, outside the header's folder; the data \
                 must be inside it",
                shown(name),
                real.display()
            ),
        ));
    }
    Ok(data)
}

/// A piece of a header for a message: its first 80 characters (`…` after a longer one),
/// control characters and bidirectional overrides shown as `�`; a 20 MB header line or
/// binary taken for one is never echoed whole.
pub(super) fn shown(s: &str) -> String {
    let cut: String = s.chars().take(80).collect();
    let mut out = crate::geometry::display_name(&cut);
    if s.chars().nth(80).is_some() {
        out.push('…');
    }
    out
}

/// Whether the gzip magic starts `b`.
pub(super) fn is_gzip(b: &[u8]) -> bool {
    b.starts_with(&[0x1f, 0x8b])
}

/// Numbers separated by blanks (a header's field `what`).
pub(super) fn numbers<T: std::str::FromStr>(path: &Path, s: &str, what: &str) -> Result<Vec<T>> {
    s.split_whitespace()
        .map(|t| {
            t.parse::<T>().map_err(|_| {
                Error::parse(path, 0, format!("{what}: {:?} is not a number", shown(t)))
            })
        })
        .collect()
}

/// A header's parser: the header's bytes, and a reader of the data file it names.
pub(super) type HeaderParser =
    fn(&Path, &[u8], &dyn Fn(&str) -> Result<Vec<u8>>) -> Result<ImageFile>;

/// Reads the header file `path` with `parse`, a detached data file it names read from beside
/// it ([`beside`]), both within the input limits.
pub(super) fn read_with_data_file(path: &Path, parse: HeaderParser) -> Result<ImageFile> {
    let bytes = super::read_input(path)?;
    parse(path, &bytes, &|name| {
        super::read_input(&beside(path, name)?)
    })
}

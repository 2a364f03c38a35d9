//! Images in: the format from the file's name (NIfTI `.nii`/`.nii.gz`, NRRD `.nrrd`/`.nhdr`,
//! MetaImage `.mha`/`.mhd`), each reader turning its file's world convention into RAS.

pub use super::image_data::ImageFile;
use crate::error::{Error, Result};
use std::path::Path;

/// The image formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// NIfTI-1 or NIfTI-2, `.nii` or `.nii.gz`.
    Nifti,
    /// NRRD, `.nrrd` (attached) or `.nhdr` (detached); `.seg.nrrd` from 3D Slicer.
    Nrrd,
    /// MetaImage, `.mha` (attached) or `.mhd` (detached).
    MetaImage,
}

impl ImageFormat {
    /// The format of `path` by its name, `None` for a name no image reader takes.
    pub fn of(path: &Path) -> Option<Self> {
        let name = path.file_name()?.to_string_lossy().to_lowercase();
        if name.ends_with(".nii") || name.ends_with(".nii.gz") {
            Some(ImageFormat::Nifti)
        } else if name.ends_with(".nrrd") || name.ends_with(".nhdr") {
            Some(ImageFormat::Nrrd)
        } else if name.ends_with(".mha") || name.ends_with(".mhd") {
            Some(ImageFormat::MetaImage)
        } else {
            None
        }
    }
}

/// Whether `path` is named as an image (label map or CT) atlasmesh reads.
pub fn is_image_file(path: &Path) -> bool {
    ImageFormat::of(path).is_some()
}

/// Reads the image in `path` (format by its name; see [`ImageFormat`]), or the DICOM series
/// in the folder `path` ([`super::dicom_series`]).
///
/// # Errors
/// [`Error::Parse`] naming the file and the problem: an unknown name, a malformed or
/// truncated header or data, an unsupported voxel type or encoding, a degenerate geometry;
/// data larger than the input limit ([`crate::formats::input::max_input_bytes`]).
pub fn read_image(path: &Path) -> Result<ImageFile> {
    if path.is_dir() {
        let file = super::dicom_series::read_dicom_series(path)?;
        file.image.check(path)?;
        return Ok(file);
    }
    let file = match ImageFormat::of(path) {
        Some(ImageFormat::Nifti) => super::nifti::read_nifti(path)?,
        Some(ImageFormat::Nrrd) => super::nrrd::read_nrrd(path)?,
        Some(ImageFormat::MetaImage) => super::metaimage::read_metaimage(path)?,
        None => {
            return Err(Error::parse(
                path,
                0,
                "not an image atlasmesh reads (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd)",
            ));
        }
    };
    file.image.check(path)?;
    Ok(file)
}

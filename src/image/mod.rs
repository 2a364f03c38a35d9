//! Images (section 5's next step: FE models straight from medical images): voxels on a grid
//! with their index → world affine ([`Image`]), the choice of a label map's labels
//! ([`LabelChoice`]) and the chosen labels' surface to sub-voxel accuracy
//! ([`label_surface`]).
//!
//! Frames: voxel indices `(i, j, k)` (i fastest in memory); world coordinates in mm in the
//! **RAS** convention (+x towards the patient's right, +y anterior, +z superior), NIfTI's
//! and nibabel's. Readers of LPS files (NRRD in `left-posterior-superior`, MetaImage, DICOM)
//! turn x and y round as they read ([`WorldConvention`]).

mod label_choice;
mod label_mask;
mod label_surface;
mod volume;

pub use label_choice::{LabelChoice, LabelTable};
pub use label_mask::{LabelMask, label_mask};
pub use label_surface::{LabelSurface, label_surface};
pub use volume::{Image, VoxelType, WorldConvention};

//! Putting shapes in correspondence (section 2.1): pairwise registration of a template to a
//! target that is not in correspondence with it (pre-alignment, a cubic B-spline FFD
//! minimizing eq. 2 with an annealed smoothing weight, the correspondence by projection along
//! the normals), and, for outlines with landmarks, resampling by arc length between them.
//!
//! Frames: the template in its own frame is first brought to the target's frame by the
//! pre-alignment similarity; the FFD then deforms it there. All outputs are in the target's
//! frame and units.
//!
//! | file | what it computes |
//! |---|---|
//! | `pre_align` | [`pre_align`]: the similarity that starts a registration |
//! | `registration` | [`register`]: eq. 2 and the projection along normals |
//! | `resample` | outlines resampled in correspondence by arc length |

mod pre_align;
mod registration;
mod resample;

pub use pre_align::pre_align;
pub use registration::{
    MAX_ALIGNMENT_MISFIT, REGISTRATION_WARNING_P95, RegisterParams, Registration,
    RegistrationResiduals, register,
};
pub use resample::{MAX_RESAMPLE, resample_corresponding, resample_uniform};

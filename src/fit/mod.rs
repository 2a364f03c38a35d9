//! Fitting the atlas to a subject: shape instantiation and projection (section 3,
//! Algorithm 1, eq. 5-8).
//!
//! Frames: the model lives in the atlas's reference frame; the subject in its own frame
//! (its file's units). `t_{R,T,s}` maps reference to subject.
//!
//! | file | what it holds |
//! |---|---|
//! | `params` | [`FitParams`] and the constants of the schedule |
//! | `fitter` | [`Fitter`]: starts, the schedule of `gamma`, the loop of Algorithm 1 |
//! | `update` | one update: closest points, eq. 5-8 linearized along the normals |
//! | `resolution` | the model at one resolution (all points or a coarse subset) |
//! | `state` | what a fit carries from one update to the next |
//! | `scratch` | buffers reused by the updates, apart from the maths |
//! | `result` | [`FitResult`] |
//! | `cut_cap` | the cap of an atlas of cut shapes, where no pair ends |
//! | `landmarks` | [`fit_landmarks`]: the posterior of the model given a few landmarks |

mod cut_cap;
mod fitter;
mod landmarks;
mod params;
mod resolution;
mod result;
mod scratch;
mod state;
mod update;

pub use fitter::Fitter;
pub use landmarks::{LandmarkFit, fit_landmarks};
pub use params::FitParams;
pub use result::FitResult;

#[cfg(test)]
mod tests;

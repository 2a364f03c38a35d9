//! # atlasmesh
//!
//! Subject-specific finite element meshes from a statistical shape atlas, after
//! "A statistical atlas based approach to automated subject-specific FE modeling"
//! (the paper; equation numbers in the docs refer to it).
//!
//! The modules are floors, each importing only from those below it (`scripts/check-layout.py`
//! checks it), lowest first:
//!
//! | module | stage |
//! |---|---|
//! | [`geometry`] | points, shapes, normals, closest points, rays, similarities, distances |
//! | [`image`] | images: voxels and their frame, label maps' surfaces |
//! | [`ffd`] | the B-spline FFD (eq. 1), `E_smooth`, the fit of eq. 9 |
//! | [`mesh`] | FE meshes: meshing the mean, morph (eq. 9), quality (section 5.3), repair |
//! | [`materials`] | per-element bone properties from a CT (Bonemat's method) |
//! | [`model`] | GPA, PCA and the atlas (sections 2.2-2.3, eq. 3-4) |
//! | [`register`] | correspondence by registration (eq. 2) or by arc length |
//! | [`fit`] | shape instantiation and projection (Algorithm 1, eq. 5-8) |
//! | [`eval`] | measures (section 5, eq. 6, 10-13) |
//! | [`formats`] | files in and out, one file per format |
//! | [`report`] | `report.json`, plots, pictures, `report.html` |
//! | [`study`] | the stages strung together: the run engine ([`study::run`]), build, fit a subject, leave-one-out, batches |
//!
//! Numerics never touch files; [`formats`] and [`report`] write, [`study`] decides what.

// Index loops over small fixed dimensions read like the equations they implement.
#![allow(clippy::needless_range_loop)]
#![warn(missing_docs)]
// A function over 100 lines is split, but for the parsers that say why they stay whole.
#![warn(clippy::too_many_lines)]

pub mod error;
pub mod eval;
pub mod ffd;
pub mod fit;
pub mod formats;
pub mod geometry;
pub mod image;
pub mod materials;
pub mod mesh;
pub mod model;
pub mod register;
pub mod report;
mod simd;
pub mod study;

pub use error::{Error, Result};
pub(crate) use simd::clear_simd_upper_state;

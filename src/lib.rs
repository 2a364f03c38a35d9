//! # atlasmesh
//!
//! Subject-specific finite element meshes from a statistical shape atlas, after
//! "A statistical atlas based approach to automated subject-specific FE modeling"
//! (the paper; equation numbers in the docs refer to it).
//!
//! The modules follow the pipeline: [`io`] reads shapes, [`geometry`] holds shapes, normals
//! and closest points, [`resample`] puts outlines in correspondence, [`procrustes`] and
//! [`pca`] build the shape model in [`model`] (with the mean mesh from [`fe`]), [`fit`]
//! instantiates the model on a subject (Algorithm 1), [`ffd`] and [`morph`] carry the mean
//! mesh to the subject, [`eval`] measures the result, [`export`] and [`report`] write it,
//! and [`pipeline`] strings the stages together for the command-line tool.

// Index loops over small fixed dimensions read like the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod batch;
pub mod error;
pub mod eval;
pub mod export;
pub mod fe;
pub mod ffd;
pub mod fit;
pub mod geometry;
pub mod io;
pub mod model;
pub mod morph;
pub mod pca;
pub mod procrustes;
pub mod register;
pub mod resample;

pub use error::{Error, Result};
pub mod pipeline;
pub mod repair;
pub mod report;

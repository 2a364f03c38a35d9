//! The shape model (sections 2.2-2.3): generalized Procrustes analysis into the tangent space
//! of the mean, principal component analysis, and the atlas that holds the model with the FE
//! mesh of the mean (section 2.4).
//!
//! Reference frame: the GPA frame, centred at the mean's centroid and scaled so that the
//! mean's bounding box has largest side 1 (as the paper's hands in the unit box), so that the
//! paper's parameters (gamma, alpha) keep their meaning whatever the units of the data.
//!
//! | file | what it computes |
//! |---|---|
//! | `procrustes` | similarity fits and GPA (section 2.2, eq. 3) |
//! | `pca` | eigenmodes and variances of the aligned shapes (section 2.3) |
//! | `shape_source` | shapes in correspondence read a batch at a time (a cohort on disk) |
//! | `streamed_procrustes` | GPA in passes over a shape source (section 2.2) |
//! | `randomized_pca` | the leading modes in passes over the data (randomized SVD) |
//! | `standard_normal` | draws of the standard normal distribution from a seeded stream |
//! | `atlas` | [`Atlas`]: build, `mean_shape`, `instance` (eq. 4), `coefficients` |
//! | `shape_model` | the model's vocabulary: `mean`, `project`, `truncate`, `sample`, `marginal`, `posterior` |
//!
//! The atlas file (save, load) is in [`crate::formats::atlas_file`].

mod atlas;
mod pca;
mod procrustes;
mod randomized_pca;
mod shape_model;
mod shape_source;
mod standard_normal;
mod streamed_procrustes;

pub(crate) use atlas::no_mesh;
pub use atlas::{Atlas, AtlasParams, ModeSelection, StreamParams};
pub use pca::{Pca, pca};
pub use procrustes::{Gpa, align_to_mean, fit_similarity, generalized_procrustes};
pub use randomized_pca::{RandomizedPcaParams, randomized_pca};
pub use shape_model::{MarginalModel, PosteriorModel};
pub use shape_source::ShapeSource;
pub(crate) use standard_normal::standard_normal;
pub use streamed_procrustes::{StreamedGpa, generalized_procrustes_streamed};

#[cfg(test)]
pub(crate) mod tests;

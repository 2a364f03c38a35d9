//! Measures of a fit and a morphed mesh (section 5): `E_d` (eq. 6), the two-way RMS surface
//! distance, the correlation of normals (eq. 10-13), and the shape model's compactness,
//! generalization and specificity. Corner Jacobians (section 5.3) are in
//! [`crate::mesh::quality`].
//!
//! | file | what it computes |
//! |---|---|
//! | `distance` | [`e_d`] (eq. 6), [`two_way_rms`], and, from `geometry`, [`surface_distances`] (of a delivered mesh) |
//! | `normal_correlation` | [`normal_correlation`] (eq. 10-13), [`normals_at`] |
//! | `folds` | [`fold_groups`]: the consecutive groups of a k-fold cross-validation |
//! | `model_measures` | [`shape_model_measures`] |

mod distance;
mod folds;
mod model_measures;
mod normal_correlation;

pub use crate::geometry::{SurfaceDistances, surface_distances};
pub use distance::{e_d, two_way_rms};
pub use folds::fold_groups;
pub use model_measures::{
    GENERALIZATION_FOLDS, LEAVE_ONE_OUT_UP_TO, ShapeModelMeasures, shape_model_measures,
};
pub use normal_correlation::{normal_correlation, normals_at};

#[cfg(test)]
mod tests;

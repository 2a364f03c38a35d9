//! The paper's baselines of fig. 12/20: correspondences by ICP and by FFD registration.

use crate::error::Result;
use crate::eval::{normal_correlation, normals_at};
use crate::geometry::{ClosestPointIndex, Point, Shape};
use crate::model::Atlas;

/// The baselines of the paper's fig. 12/20 for one subject: the normal correlation (eq. 13)
/// between the mean and the subject at the correspondence found (a) by a similarity ICP of
/// the mean to the subject (the closest points of the aligned mean) and (b) by the FFD
/// registration of the mean to the subject (eq. 2, with landmarks when both have them).
pub fn baseline_correlations<const D: usize>(
    atlas: &Atlas<D>,
    subject: &Shape<D>,
    index: &ClosestPointIndex<D>,
    mean_normals: &[Point<D>],
) -> Result<(f64, f64)> {
    let params = crate::register::RegisterParams::for_dimension(D);
    let mut mean = atlas.mean_shape();
    if mean.landmarks.len() != subject.landmarks.len() {
        mean.landmarks.clear();
    }
    // The ICP baseline uses no landmarks (with them pre_align would pair the landmarks).
    let unmarked = Shape {
        landmarks: Vec::new(),
        ..mean.clone()
    };
    let sim = crate::register::pre_align(&unmarked, subject, index, params.starts)?;
    let icp: Vec<_> = mean
        .points
        .iter()
        .map(|p| index.closest(&sim.apply(p)))
        .collect();
    let nc_icp = normal_correlation(mean_normals, &normals_at(subject, &icp));
    let reg = crate::register::register(&mean, subject, index, &params)?;
    let nc_ffd = normal_correlation(mean_normals, &normals_at(subject, &reg.correspondence));
    Ok((nc_icp, nc_ffd))
}

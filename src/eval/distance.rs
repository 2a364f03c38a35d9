//! Distances between a fitted shape and its subject: `E_d` (eq. 6) and the two-way RMS.

use crate::geometry::{ClosestPointIndex, Point, Shape};

/// Root mean square distance between two shapes taken both ways:
/// `sqrt((mean_a d(a_i, B)² + mean_b d(b_j, A)²) / 2)`, with `d` the distance to the closest
/// point on the other shape's facets. Units of the shapes.
pub fn two_way_rms<const D: usize>(
    a: &[Point<D>],
    a_facets: &[[usize; D]],
    b: &Shape<D>,
    b_index: &ClosestPointIndex<D>,
) -> f64 {
    let fwd = a.iter().map(|p| b_index.closest(p).dist2).sum::<f64>() / a.len() as f64;
    let ai = ClosestPointIndex::new(a, a_facets);
    let bwd = b.points.iter().map(|q| ai.closest(q).dist2).sum::<f64>() / b.points.len() as f64;
    (0.5 * (fwd + bwd)).sqrt()
}

/// `E_d` (eq. 6): `Σ_j ||Ŝ^c_j - t(S_tilde)_j||²`, with `Ŝ^c_j` the closest point on the subject
/// of instance point `j`. Subject units squared.
pub fn e_d<const D: usize>(instance: &[Point<D>], subject: &ClosestPointIndex<D>) -> f64 {
    instance.iter().map(|p| subject.closest(p).dist2).sum()
}

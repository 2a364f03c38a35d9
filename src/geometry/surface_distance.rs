//! The distances between a delivered shape and its subject, both ways: RMS, 95th
//! percentile, largest (what the delivered mesh and a registration are measured by).

use super::{ClosestPointIndex, Shape};

/// How far a delivered shape (the boundary of a morphed mesh) lies from its subject: the
/// distances from every subject point to the delivered shape and, `two_way`, from every
/// delivered point to the subject. Subject units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceDistances {
    /// `sqrt((mean d(s, M)² + mean d(m, S)²) / 2)` two-way, `sqrt(mean d(s, M)²)` one-way.
    pub rms: f64,
    /// The larger of the two directions' 95th percentiles.
    pub p95: f64,
    /// The largest distance either way.
    pub max: f64,
    /// The share of the subject's points farther than `beyond` from the delivered shape.
    pub share_beyond: f64,
}

fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let i = ((values.len() - 1) as f64 * q).round() as usize;
    values[i]
}

/// The distances between a delivered shape `delivered` and the `subject` (indexed by
/// `subject_index`): subject → delivered always, delivered → subject when `two_way` (a
/// partial subject or an open outline has no counterpart for parts of the delivered shape).
/// `share_beyond` counts the subject's points farther than `beyond` (an element size).
/// Subject units.
pub fn surface_distances<const D: usize>(
    delivered: &Shape<D>,
    subject: &Shape<D>,
    subject_index: &ClosestPointIndex<D>,
    two_way: bool,
    beyond: f64,
) -> SurfaceDistances {
    let on_delivered = ClosestPointIndex::from_shape(delivered);
    let mut to_delivered: Vec<f64> = subject
        .points
        .iter()
        .map(|q| on_delivered.closest(q).dist2.sqrt())
        .collect();
    let mut to_subject: Vec<f64> = if two_way {
        delivered
            .points
            .iter()
            .map(|p| subject_index.closest(p).dist2.sqrt())
            .collect()
    } else {
        Vec::new()
    };
    let mean_sq = |v: &[f64]| v.iter().map(|d| d * d).sum::<f64>() / v.len().max(1) as f64;
    let rms = if two_way {
        (0.5 * (mean_sq(&to_delivered) + mean_sq(&to_subject))).sqrt()
    } else {
        mean_sq(&to_delivered).sqrt()
    };
    let share_beyond = to_delivered.iter().filter(|&&d| d > beyond).count() as f64
        / to_delivered.len().max(1) as f64;
    let max = if to_delivered.iter().chain(&to_subject).any(|d| d.is_nan()) {
        f64::NAN
    } else {
        to_delivered
            .iter()
            .chain(&to_subject)
            .fold(0.0_f64, |m, &d| m.max(d))
    };
    let p95 = percentile(&mut to_delivered, 0.95).max(if two_way {
        percentile(&mut to_subject, 0.95)
    } else {
        0.0
    });
    SurfaceDistances {
        rms,
        p95,
        max,
        share_beyond,
    }
}

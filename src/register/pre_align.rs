//! Pre-alignment of a template to a target: landmarks, or a similarity ICP from several
//! starting rotations.

use crate::error::{Error, Result};
use crate::geometry::{
    ClosestPointIndex, Point, QueryMemo, Shape, Similarity, centroid, dist2, start_rotations,
};
use crate::model::fit_similarity;

/// Pre-alignment of `template` to `target`: the similarity of the landmark pairs when both
/// have the same number of landmarks; otherwise centroids and RMS radii matched, `starts`
/// rotations (2D) or the principal axes (3D) tried, each refined by a similarity ICP on the
/// closest points both ways, and the one of least two-way mean squared distance kept.
pub fn pre_align<const D: usize>(
    template: &Shape<D>,
    target: &Shape<D>,
    target_index: &ClosestPointIndex<D>,
    starts: usize,
) -> Result<Similarity<D>> {
    pre_align_scored(template, target, target_index, starts).map(|(s, _)| s)
}

/// [`pre_align`] and, without landmarks, the relative misfit of the alignment: the two-way
/// RMS distance between the aligned template and the target over the target's RMS radius
/// (0 when the landmarks aligned them).
pub(super) fn pre_align_scored<const D: usize>(
    template: &Shape<D>,
    target: &Shape<D>,
    target_index: &ClosestPointIndex<D>,
    starts: usize,
) -> Result<(Similarity<D>, f64)> {
    if !template.landmarks.is_empty() && template.landmarks.len() == target.landmarks.len() {
        let src: Vec<Point<D>> = template
            .landmarks
            .iter()
            .map(|&i| template.points[i])
            .collect();
        let dst: Vec<Point<D>> = target.landmarks.iter().map(|&i| target.points[i]).collect();
        return Ok((fit_similarity(&src, &dst, None), 0.0));
    }
    let ct = centroid(&template.points);
    let cs = centroid(&target.points);
    let rms = |p: &[Point<D>], c: Point<D>| {
        (p.iter().map(|q| dist2(*q, c)).sum::<f64>() / p.len() as f64).sqrt()
    };
    // A shape of no extent (numerically: below 1e-9 of its coordinates' size) has no pose.
    for (s, c) in [(template, ct), (target, cs)] {
        let size = s
            .points
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let r = rms(&s.points, c);
        if r.is_nan() || r <= 1e-9 * size {
            return Err(Error::Population(format!(
                "the ICP pre-alignment could not align {} to {}: {} has no extent (RMS radius \
                 {r:.3e} at coordinates of size {size:.3e})",
                template.name, target.name, s.name
            )));
        }
    }
    let s0 = rms(&target.points, cs) / rms(&template.points, ct).max(f64::MIN_POSITIVE);
    let rotations = start_rotations(&template.points, ct, &target.points, cs, starts);
    let sample = |n: usize, k: usize| -> Vec<usize> {
        let step = (n / k).max(1);
        (0..n).step_by(step).collect()
    };
    // Backward pairs are searched in the template's frame (a similarity keeps closest
    // points): its index is built once.
    let tindex = ClosestPointIndex::new(&template.points, &template.facets);
    // Similarity ICP from `sim` on the template points `ts` and target points `ss`, for at
    // most `iterations` updates; returns the two-way mean squared distance and the pose.
    let icp = |mut sim: Similarity<D>, ts: &[usize], ss: &[usize], iterations: usize| {
        let mut score = f64::INFINITY;
        let mut forward_memo = vec![QueryMemo::default(); ts.len()];
        let mut backward_memo = vec![QueryMemo::default(); ss.len()];
        let mut src = Vec::with_capacity(ts.len() + ss.len());
        let mut dst = Vec::with_capacity(ts.len() + ss.len());
        for _ in 0..iterations {
            src.clear();
            dst.clear();
            let mut fwd = 0.0;
            for (&j, memo) in ts.iter().zip(&mut forward_memo) {
                let c = target_index.closest_memo(&sim.apply(&template.points[j]), memo);
                fwd += c.dist2;
                src.push(template.points[j]);
                dst.push(c.point);
            }
            let mut bwd = 0.0;
            for (&i, memo) in ss.iter().zip(&mut backward_memo) {
                let c = tindex.closest_memo(&sim.apply_inverse(&target.points[i]), memo);
                bwd += c.dist2 * sim.s * sim.s;
                src.push(c.point);
                dst.push(target.points[i]);
            }
            let previous = score;
            score = 0.5 * (fwd / ts.len() as f64 + bwd / ss.len() as f64);
            sim = fit_similarity(&src, &dst, None);
            // Settled: the closest points no longer change the alignment's error.
            if (previous - score).abs() <= 1e-4 * score {
                break;
            }
        }
        (score, sim)
    };
    // Every start on a rough sampling, a few updates each; the best two go on to the
    // finer sampling until settled.
    let (rough_t, rough_s) = (
        sample(template.points.len(), ROUGH_POINTS),
        sample(target.points.len(), ROUGH_POINTS),
    );
    let mut rough: Vec<(f64, Similarity<D>)> = rotations
        .into_iter()
        .map(|r| {
            icp(
                Similarity::centred(s0, r, &ct, &cs),
                &rough_t,
                &rough_s,
                ROUGH_ITERATIONS,
            )
        })
        .collect();
    rough.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (ts, ss) = (
        sample(template.points.len(), FINE_POINTS),
        sample(target.points.len(), FINE_POINTS),
    );
    let best = rough
        .into_iter()
        .take(FINE_STARTS)
        .map(|(_, sim)| icp(sim, &ts, &ss, 30))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let radius = rms(&target.points, cs);
    best.map(|(score, sim)| (sim, score.sqrt() / radius.max(f64::MIN_POSITIVE)))
        .ok_or_else(|| Error::Numerical(format!("{}: no pre-alignment start", target.name)))
}

/// Points per shape of the ICP pre-alignment's rough stage, where every start rotation
/// runs [`ROUGH_ITERATIONS`] updates; then the best [`FINE_STARTS`] go on with
/// [`FINE_POINTS`] points per shape until settled.
pub(super) const ROUGH_POINTS: usize = 100;
pub(super) const ROUGH_ITERATIONS: usize = 8;
pub(super) const FINE_STARTS: usize = 2;
pub(super) const FINE_POINTS: usize = 400;

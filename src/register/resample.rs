//! Resampling outlines along a smooth interpolating curve (section 6.1: each hand sampled with
//! 2001 points).
//!
//! The curve is the centripetal Catmull-Rom spline through the input points (C1, interpolating,
//! no cusps or self-loops within a span). Arc length is measured on the spline, densely sampled.

use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, add, dist2, norm, scale, sub};

/// Sub-samples per span used to measure arc length.
const ARC_SAMPLES: usize = 64;

/// A centripetal Catmull-Rom spline through the points of an outline, open or closed.
struct Spline<'a> {
    p: &'a [Point<2>],
    closed: bool,
}

impl Spline<'_> {
    fn spans(&self) -> usize {
        if self.closed {
            self.p.len()
        } else {
            self.p.len() - 1
        }
    }

    fn ctrl(&self, i: isize) -> Point<2> {
        let n = self.p.len() as isize;
        if self.closed {
            self.p[i.rem_euclid(n) as usize]
        } else if i < 0 {
            // Reflect the second point about the first, so the end tangent is the chord.
            sub(scale(self.p[0], 2.0), self.p[1])
        } else if i >= n {
            sub(
                scale(self.p[(n - 1) as usize], 2.0),
                self.p[(n - 2) as usize],
            )
        } else {
            self.p[i as usize]
        }
    }

    /// Point at local parameter `u ∈ [0, 1]` of span `k` (from point k to point k+1).
    fn eval(&self, k: usize, u: f64) -> Point<2> {
        let k = k as isize;
        let (p0, p1, p2, p3) = (
            self.ctrl(k - 1),
            self.ctrl(k),
            self.ctrl(k + 1),
            self.ctrl(k + 2),
        );
        // Centripetal knots (alpha = 1/2); guard coincident points.
        let knot = |a: Point<2>, b: Point<2>| dist2(a, b).sqrt().sqrt().max(1e-12);
        let t0 = 0.0;
        let t1 = t0 + knot(p0, p1);
        let t2 = t1 + knot(p1, p2);
        let t3 = t2 + knot(p2, p3);
        let t = t1 + u * (t2 - t1);
        let lerp = |a: Point<2>, b: Point<2>, ta: f64, tb: f64| {
            add(
                scale(a, (tb - t) / (tb - ta)),
                scale(b, (t - ta) / (tb - ta)),
            )
        };
        let a1 = lerp(p0, p1, t0, t1);
        let a2 = lerp(p1, p2, t1, t2);
        let a3 = lerp(p2, p3, t2, t3);
        let b1 = lerp(a1, a2, t0, t2);
        let b2 = lerp(a2, a3, t1, t3);
        lerp(b1, b2, t1, t2)
    }

    /// Cumulative arc-length table of span `k`: `ARC_SAMPLES + 1` values from 0.
    fn arc_table(&self, k: usize) -> Vec<f64> {
        let mut out = Vec::with_capacity(ARC_SAMPLES + 1);
        out.push(0.0);
        let mut prev = self.eval(k, 0.0);
        for j in 1..=ARC_SAMPLES {
            let q = self.eval(k, j as f64 / ARC_SAMPLES as f64);
            let l = out[j - 1] + norm(sub(q, prev));
            out.push(l);
            prev = q;
        }
        out
    }

    /// Local parameter of span `k` at arc length `s` along it (table from `arc_table`).
    fn param_at(table: &[f64], s: f64) -> f64 {
        let j = table.partition_point(|&l| l < s).clamp(1, table.len() - 1);
        let (l0, l1) = (table[j - 1], table[j]);
        let f = if l1 > l0 { (s - l0) / (l1 - l0) } else { 0.0 };
        ((j - 1) as f64 + f.clamp(0.0, 1.0)) / ARC_SAMPLES as f64
    }
}

fn check_outline(shape: &Shape<2>) -> Result<()> {
    shape.validate()?;
    if shape.points.len() < 3 {
        return Err(Error::shape(
            &shape.name,
            "an outline needs at least 3 points",
        ));
    }
    if let Some(i) = (1..shape.points.len()).find(|&i| shape.points[i] == shape.points[i - 1]) {
        return Err(Error::shape(
            &shape.name,
            format!("points {} and {i} coincide; remove the duplicate", i - 1),
        ));
    }
    Ok(())
}

/// Resamples every outline of a population whose points correspond (same count, point `i`
/// of every shape is the same landmark) to `n` points, keeping the correspondence: each
/// interval between consecutive input points gets the same number of new points in every
/// shape, in proportion to its mean arc length over the population, and the new points are
/// spaced evenly by arc length within it. Input point `i` lands at index `index_map[i]`.
///
/// Returns the resampled shapes (landmarks set to the new indices of the input points) and
/// `index_map`.
pub fn resample_corresponding(
    shapes: &[Shape<2>],
    n: usize,
    closed: bool,
) -> Result<(Vec<Shape<2>>, Vec<usize>)> {
    let Some(first) = shapes.first() else {
        return Err(Error::Population("no shapes".into()));
    };
    if n > MAX_RESAMPLE || n.saturating_mul(shapes.len()) > 50 * MAX_RESAMPLE {
        return Err(Error::Parameter(format!(
            "--resample {n}: at most {MAX_RESAMPLE} points, and {} over all {} shapes",
            50 * MAX_RESAMPLE,
            shapes.len()
        )));
    }
    let np = first.points.len();
    for s in shapes {
        check_outline(s)?;
        if s.points.len() != np {
            return Err(Error::Population(format!(
                "shape {} has {} points but shape {} has {np}; corresponding resampling needs equal counts",
                s.name,
                s.points.len(),
                first.name
            )));
        }
    }
    let spans = if closed { np } else { np - 1 };
    let total = if closed { n } else { n.saturating_sub(1) };
    if total < spans {
        return Err(Error::Parameter(format!(
            "--resample {n} is fewer than the {np} input points; choose at least {}",
            np
        )));
    }
    let tables: Vec<Vec<Vec<f64>>> = shapes
        .iter()
        .map(|s| {
            let sp = Spline {
                p: &s.points,
                closed,
            };
            (0..spans).map(|k| sp.arc_table(k)).collect()
        })
        .collect();
    let mean_len: Vec<f64> = (0..spans)
        .map(|k| tables.iter().map(|t| t[k][ARC_SAMPLES]).sum::<f64>() / shapes.len() as f64)
        .collect();
    let counts = apportion(&mean_len, total);
    let mut index_map = Vec::with_capacity(np);
    let mut acc = 0;
    for c in &counts {
        index_map.push(acc);
        acc += c;
    }
    if !closed {
        index_map.push(acc);
    }
    let out = shapes
        .iter()
        .zip(&tables)
        .map(|(s, tab)| {
            let sp = Spline {
                p: &s.points,
                closed,
            };
            let mut pts = Vec::with_capacity(n);
            for k in 0..spans {
                let len = tab[k][ARC_SAMPLES];
                for j in 0..counts[k] {
                    let u = Spline::param_at(&tab[k], len * j as f64 / counts[k] as f64);
                    pts.push(if j == 0 { s.points[k] } else { sp.eval(k, u) });
                }
            }
            if !closed {
                pts.push(s.points[np - 1]);
            }
            let mut r = Shape::polyline(s.name.clone(), pts, closed);
            r.landmarks = index_map.clone();
            r
        })
        .collect();
    Ok((out, index_map))
}

/// The most points an outline is resampled to (the command line's bound, and Python's).
pub const MAX_RESAMPLE: usize = 1_000_000;

/// Resamples one outline to `n` points evenly spaced by arc length along its spline (for
/// outlines whose points do not correspond). Starts at the first input point; an open outline
/// also keeps its last point.
pub fn resample_uniform(shape: &Shape<2>, n: usize, closed: bool) -> Result<Shape<2>> {
    check_outline(shape)?;
    if !(3..=MAX_RESAMPLE).contains(&n) {
        return Err(Error::Parameter(format!(
            "--resample {n}: from 3 to {MAX_RESAMPLE} points"
        )));
    }
    let sp = Spline {
        p: &shape.points,
        closed,
    };
    let tables: Vec<Vec<f64>> = (0..sp.spans()).map(|k| sp.arc_table(k)).collect();
    let mut cum = vec![0.0];
    for t in &tables {
        cum.push(cum.last().copied().unwrap_or(0.0) + t[ARC_SAMPLES]);
    }
    let total = *cum.last().unwrap_or(&0.0);
    let steps = if closed { n } else { n - 1 };
    let pts = (0..n)
        .map(|j| {
            let s = total * j as f64 / steps as f64;
            let k = (cum.partition_point(|&c| c <= s).max(1) - 1).min(tables.len() - 1);
            sp.eval(k, Spline::param_at(&tables[k], s - cum[k]))
        })
        .collect();
    Ok(Shape::polyline(shape.name.clone(), pts, closed))
}

/// Splits `total` into integer parts proportional to `weights`, each at least 1 (largest
/// remainder method). `total >= weights.len()`.
fn apportion(weights: &[f64], total: usize) -> Vec<usize> {
    let m = weights.len();
    let extra = total - m;
    let sum: f64 = weights.iter().sum();
    let ideal: Vec<f64> = weights
        .iter()
        .map(|w| {
            if sum > 0.0 {
                w / sum * extra as f64
            } else {
                extra as f64 / m as f64
            }
        })
        .collect();
    let mut counts: Vec<usize> = ideal.iter().map(|x| x.floor() as usize + 1).collect();
    let assigned: usize = counts.iter().sum();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| (ideal[b] - ideal[b].floor()).total_cmp(&(ideal[a] - ideal[a].floor())));
    for &i in order.iter().take(total - assigned) {
        counts[i] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corresponding_resampling_keeps_landmarks_at_their_indices() {
        let a = Shape::polyline(
            "a",
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 3.0]],
            false,
        );
        let b = Shape::polyline(
            "b",
            vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.5]],
            false,
        );
        let (r, map) = resample_corresponding(&[a.clone(), b.clone()], 101, false).unwrap();
        assert_eq!(r[0].points.len(), 101);
        assert_eq!(map[0], 0);
        assert_eq!(map[3], 100);
        for (s, orig) in r.iter().zip([&a, &b]) {
            for (i, &m) in map.iter().enumerate() {
                assert_eq!(s.points[m], orig.points[i]);
            }
        }
    }

    #[test]
    fn uniform_resampling_of_a_circle_is_evenly_spaced() {
        let pts: Vec<Point<2>> = (0..12)
            .map(|i| {
                let t = i as f64 / 12.0 * std::f64::consts::TAU;
                [t.cos(), t.sin()]
            })
            .collect();
        let s = Shape::polyline("c", pts, true);
        let r = resample_uniform(&s, 200, true).unwrap();
        let d: Vec<f64> = (0..200)
            .map(|i| norm(sub(r.points[(i + 1) % 200], r.points[i])))
            .collect();
        let (lo, hi) = d
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(hi / lo < 1.02, "spacing {lo}..{hi}");
        // The spline stays close to the circle.
        for p in &r.points {
            assert!((norm(*p) - 1.0).abs() < 0.01);
        }
    }
}

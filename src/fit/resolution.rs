//! The shape model at one resolution (all points, or a coarse subset for the first stage).

use crate::geometry::{ClosestPointIndex, Point, Shape, facet_normal, norm};
use crate::model::Atlas;

/// The shape model at one resolution: the mean's points (a subset of the atlas's, or all),
/// their rows of the modes, and the index of the mean's facets on them (it keeps the
/// facets).
pub(super) struct Model<const D: usize> {
    pub(super) mean: Vec<Point<D>>,
    /// Rows of `Psi` of the points, row-major (`(point · D + d) · m + k`).
    pub(super) psi: Vec<f64>,
    /// Index of the mean's facets, refitted to every instance.
    pub(super) index: ClosestPointIndex<D>,
    /// Modes (the width of a row of `psi`).
    pub(super) m: usize,
}

/// Which of the fitter's models.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Level {
    Coarse,
    Full,
}

/// Indices of `k` points spread evenly over `0..n` (all of them when `k` is 0 or `>= n`).
pub(super) fn spread(n: usize, k: usize) -> Vec<usize> {
    if k == 0 || k >= n {
        return (0..n).collect();
    }
    if k == 1 {
        return vec![0];
    }
    let mut v: Vec<usize> = (0..k)
        .map(|i| ((i as f64) * (n - 1) as f64 / (k - 1) as f64).round() as usize)
        .collect();
    v.dedup();
    v
}

impl<const D: usize> Model<D> {
    pub(super) fn new(atlas: &Atlas<D>, ids: Vec<usize>, facets: Vec<[usize; D]>) -> Self {
        let m = atlas.num_modes();
        let mut psi = vec![0.0; ids.len() * D * m];
        for (j, &i) in ids.iter().enumerate() {
            for d in 0..D {
                for k in 0..m {
                    psi[(j * D + d) * m + k] = atlas.modes[(i * D + d, k)];
                }
            }
        }
        let mean: Vec<Point<D>> = ids.iter().map(|&i| atlas.mean[i]).collect();
        let index = ClosestPointIndex::new(&mean, &facets);
        Model {
            mean,
            psi,
            index,
            m,
        }
    }

    pub(super) fn len(&self) -> usize {
        self.mean.len()
    }

    /// The instance `S_bar + Psi w` (eq. 4) at the model's points, reference frame.
    pub(super) fn instance(&self, w: &[f64], out: &mut Vec<Point<D>>) {
        let m = self.m;
        out.clear();
        out.extend(self.mean.iter().enumerate().map(|(i, p)| {
            std::array::from_fn(|d| {
                let row = &self.psi[(i * D + d) * m..(i * D + d + 1) * m];
                p[d] + row.iter().zip(w).map(|(a, b)| a * b).sum::<f64>()
            })
        }));
    }

    /// The coarse model of about `k` points: for outlines, `k` of the points evenly spread
    /// over their order and the segments joining each to the next kept one along the
    /// outline; for surfaces, the vertex-clustering decimation of the mean (original points
    /// kept) with a cell chosen for about `k` points. `None`
    /// where that is no smaller than the atlas, or the decimation fails or leaves the shape
    /// without facets.
    pub(super) fn coarse(atlas: &Atlas<D>, k: usize) -> Option<Self> {
        let n = atlas.mean.len();
        if k == 0 || 2 * k >= n {
            return None;
        }
        if D == 2 {
            let ids = spread(n, k);
            let mut at = vec![usize::MAX; n];
            for (j, &i) in ids.iter().enumerate() {
                at[i] = j;
            }
            // Each kept point joins the next one along the outline (segment by segment).
            let mut next = vec![usize::MAX; n];
            for f in &atlas.facets {
                next[f[0]] = f[1];
            }
            let mut facets = Vec::new();
            for &start in &ids {
                let mut v = next[start];
                let mut steps = 0;
                while v != usize::MAX && at[v] == usize::MAX && steps < n {
                    v = next[v];
                    steps += 1;
                }
                if v != usize::MAX && at[v] != usize::MAX && v != start {
                    let mut f = [0; D];
                    f[0] = at[start];
                    f[1] = at[v];
                    facets.push(f);
                }
            }
            return (!facets.is_empty()).then(|| Model::new(atlas, ids, facets));
        }
        let shape = Shape {
            name: "mean".into(),
            points: atlas.mean.clone(),
            facets: atlas.facets.clone(),
            landmarks: Vec::new(),
        };
        let area: f64 = atlas
            .facets
            .iter()
            .map(|f| 0.5 * norm(facet_normal(&atlas.mean, f)))
            .sum();
        let mut cell = (area / k as f64).sqrt();
        for _ in 0..4 {
            let (small, ids) = shape.decimate_by_clustering(cell, [0.0; D]).ok()?;
            let got = small.points.len();
            if (k / 2..=2 * k).contains(&got) || got == 0 {
                return (!small.facets.is_empty() && 2 * got < n)
                    .then(|| Model::new(atlas, ids, small.facets));
            }
            cell *= (got as f64 / k as f64).sqrt();
        }
        None
    }
}

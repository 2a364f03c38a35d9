//! Vertex-clustering decimation of a shape.

use super::{Point, Shape, centroid, dist2};
use crate::error::{Error, Result};

impl<const D: usize> Shape<D> {
    /// Vertex-clustering decimation (Rossignac and Borrel 1993): the points are binned in
    /// cubic cells of side `cell` (shape units) whose grid starts at `offset`; each occupied
    /// cell keeps one point, the one nearest to the cell's mean (an original point, not a
    /// new one); facets are mapped to the kept points, and those that collapse (two corners
    /// in one cell) or repeat are dropped. Returns the decimated shape (landmarks dropped:
    /// re-pick them on it) and, per kept point, the index of the original point it is.
    /// The result may be non-manifold where the shape is thinner than a cell.
    pub fn decimate_by_clustering(
        &self,
        cell: f64,
        offset: Point<D>,
    ) -> Result<(Self, Vec<usize>)> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::Parameter(format!(
                "decimation cell size {cell} must be positive"
            )));
        }
        self.validate()?;
        let key = |p: &Point<D>| -> [i64; D] {
            std::array::from_fn(|d| ((p[d] - offset[d]) / cell).floor() as i64)
        };
        let mut cells: std::collections::HashMap<[i64; D], Vec<usize>> =
            std::collections::HashMap::new();
        for (i, p) in self.points.iter().enumerate() {
            cells.entry(key(p)).or_default().push(i);
        }
        let mut groups: Vec<Vec<usize>> = cells.into_values().collect();
        // Deterministic order: by the smallest original index in the cell.
        groups.sort_by_key(|g| g[0]);
        let mut map = vec![0usize; self.points.len()];
        let mut kept = Vec::with_capacity(groups.len());
        for (k, g) in groups.iter().enumerate() {
            let m = centroid(&g.iter().map(|&i| self.points[i]).collect::<Vec<_>>());
            let rep = g
                .iter()
                .copied()
                .min_by(|&a, &b| dist2(self.points[a], m).total_cmp(&dist2(self.points[b], m)))
                .unwrap_or(g[0]);
            kept.push(rep);
            for &i in g {
                map[i] = k;
            }
        }
        // Facets on the same kept points: a repeat of the same orientation is dropped; a
        // pair of opposite orientations (a fold of zero volume, where two sides of the
        // surface met in one cell) is dropped whole.
        let mut by_key: std::collections::HashMap<[usize; D], Vec<usize>> =
            std::collections::HashMap::new();
        let mut mapped = Vec::with_capacity(self.facets.len());
        for f in &self.facets {
            let g: [usize; D] = std::array::from_fn(|k| map[f[k]]);
            if (0..D).all(|a| (a + 1..D).all(|b| g[a] != g[b])) {
                let mut sorted = g;
                sorted.sort_unstable();
                by_key.entry(sorted).or_default().push(mapped.len());
                mapped.push(g);
            }
        }
        // Orientation of a facet relative to its sorted vertices: the parity of the
        // permutation (even = +1).
        let parity = |g: &[usize; D]| -> i32 {
            let mut inversions = 0;
            for a in 0..D {
                for b in a + 1..D {
                    if g[a] > g[b] {
                        inversions += 1;
                    }
                }
            }
            if D == 2 || inversions % 2 == 0 { 1 } else { -1 }
        };
        let mut keep = vec![false; mapped.len()];
        for ids in by_key.values() {
            let net: i32 = ids.iter().map(|&i| parity(&mapped[i])).sum();
            if D == 2 || net != 0 {
                let want = net.signum();
                if let Some(&i) = ids.iter().find(|&&i| D == 2 || parity(&mapped[i]) == want) {
                    keep[i] = true;
                }
            }
        }
        let facets: Vec<[usize; D]> = mapped
            .iter()
            .zip(&keep)
            .filter_map(|(g, &k)| k.then_some(*g))
            .collect();
        let shape = Shape {
            name: self.name.clone(),
            points: kept.iter().map(|&i| self.points[i]).collect(),
            facets,
            landmarks: Vec::new(),
        };
        Ok((shape, kept))
    }
}

//! Bonemat's grouping of elements into materials by a gap in Young's modulus.

use serde::Serialize;

/// One material of the solver files: its modulus and its elements.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MaterialBin {
    /// Young's modulus (MPa): the volume-weighted mean of its elements', so that the bin
    /// carries the stiffness-volume of the elements it replaces.
    pub modulus: f64,
    /// Its elements, ascending.
    pub elements: Vec<usize>,
}

/// Groups elements by modulus (Bonemat's binning): sorted by E, a bin takes elements while
/// their E is within `gap` (MPa) of its first element's. When that makes more than `max`
/// bins, the gap grows (by half, at least to the range over `max`) until it fits. Returns
/// the bins by increasing E and the gap used. `volume` weighs the bins' means.
pub fn bin_moduli(
    modulus: &[f64],
    volume: &[f64],
    gap: f64,
    max: usize,
) -> (Vec<MaterialBin>, f64) {
    let mut order: Vec<usize> = (0..modulus.len()).collect();
    order.sort_by(|&a, &b| modulus[a].total_cmp(&modulus[b]).then(a.cmp(&b)));
    let (Some(&lo), Some(&hi)) = (order.first(), order.last()) else {
        return (Vec::new(), gap);
    };
    let range = modulus[hi] - modulus[lo];
    let max = max.max(1);
    let mut gap = gap.max(0.0);
    loop {
        let starts = bin_starts(&order, modulus, gap);
        if starts.len() <= max {
            let mut bins = Vec::with_capacity(starts.len());
            for (k, &s) in starts.iter().enumerate() {
                let end = starts.get(k + 1).copied().unwrap_or(order.len());
                let members = &order[s..end];
                let w: f64 = members.iter().map(|&e| volume[e]).sum();
                let m = if w > 0.0 {
                    members.iter().map(|&e| volume[e] * modulus[e]).sum::<f64>() / w
                } else {
                    members.iter().map(|&e| modulus[e]).sum::<f64>() / members.len() as f64
                };
                let mut elements = members.to_vec();
                elements.sort_unstable();
                bins.push(MaterialBin {
                    modulus: m,
                    elements,
                });
            }
            return (bins, gap);
        }
        gap = (gap * 1.5).max(range / max as f64);
    }
}

/// Where each bin starts in `order` (elements sorted by modulus) for a gap.
fn bin_starts(order: &[usize], modulus: &[f64], gap: f64) -> Vec<usize> {
    let mut starts = vec![0];
    let mut first = modulus[order[0]];
    for (i, &e) in order.iter().enumerate().skip(1) {
        if modulus[e] - first > gap {
            starts.push(i);
            first = modulus[e];
        }
    }
    starts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gap_groups_and_the_limit_widens_it() {
        let e = [100.0, 105.0, 300.0, 111.0, 309.0, 1000.0];
        let v = [1.0, 3.0, 1.0, 1.0, 1.0, 2.0];
        let (bins, gap) = bin_moduli(&e, &v, 10.0, 10);
        assert_eq!(gap, 10.0);
        let members: Vec<Vec<usize>> = bins.iter().map(|b| b.elements.clone()).collect();
        assert_eq!(members, vec![vec![0, 1], vec![3], vec![2, 4], vec![5]]);
        assert!((bins[0].modulus - (100.0 + 3.0 * 105.0) / 4.0).abs() < 1e-12);
        let (bins, gap) = bin_moduli(&e, &v, 10.0, 2);
        assert!(bins.len() <= 2 && gap > 10.0);
        assert_eq!(bins.iter().map(|b| b.elements.len()).sum::<usize>(), 6);
        let (bins, _) = bin_moduli(&e, &v, 0.0, 100);
        assert_eq!(bins.len(), 6);
    }
}

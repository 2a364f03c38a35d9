//! Bonemat's grouping of elements into materials by a gap in Young's modulus.

use serde::Serialize;

/// One material of the solver files: its name, modulus, Poisson's ratio and elements.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MaterialBin {
    /// Its name in the solver files (`BONE_k` for a group of the CT's, a part's own name).
    pub name: String,
    /// Poisson's ratio.
    pub poisson: f64,
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
                    name: bone_material_name(bins.len()),
                    poisson: 0.3,
                    modulus: m,
                    elements,
                });
            }
            return (bins, gap);
        }
        gap = (gap * 1.5).max(range / max as f64);
    }
}

/// The name of the CT's material `k` (0-based) in the solver files: `BONE_1`, `BONE_2`, ...
pub fn bone_material_name(k: usize) -> String {
    format!("BONE_{}", k + 1)
}

/// Groups elements into `count` bins of equal width in `density` (g/cm³) between the
/// smallest and the largest (voxel FE pipelines' grouping: the spine FE benchmark's, Ogo's):
/// element `e` goes to bin `⌊(ρₑ − ρ_min) / w⌋` (the largest to the last), `w = (ρ_max −
/// ρ_min) / count`; a bin's modulus is `law` at its centre `ρ_min + (b + ½) w`. Empty bins
/// make no material. Returns the bins by increasing density and the width `w`.
pub fn bin_densities(
    density: &[f64],
    count: usize,
    law: impl Fn(f64) -> f64,
) -> (Vec<MaterialBin>, f64) {
    let lo = density.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = density.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if density.is_empty() || !(lo.is_finite() && hi.is_finite()) {
        return (Vec::new(), 0.0);
    }
    let count = count.max(1);
    let width = (hi - lo) / count as f64;
    let mut members = vec![Vec::new(); count];
    for (e, &d) in density.iter().enumerate() {
        let b = if width > 0.0 {
            (((d - lo) / width) as usize).min(count - 1)
        } else {
            0
        };
        members[b].push(e);
    }
    let bins = members
        .into_iter()
        .enumerate()
        .filter(|(_, m)| !m.is_empty())
        .enumerate()
        .map(|(k, (b, elements))| MaterialBin {
            name: bone_material_name(k),
            poisson: 0.3,
            modulus: law(lo + (b as f64 + 0.5) * width),
            elements,
        })
        .collect();
    (bins, width)
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

    #[test]
    fn equal_width_bins_take_the_law_at_their_centres() {
        // Densities -0.031 .. 0.969 in 4 bins of 0.25: centres 0.094, 0.344, 0.594, 0.844.
        let d = [-0.031, 0.2, 0.21, 0.969, 0.5];
        let (bins, w) = bin_densities(&d, 4, |r| 1000.0 * r);
        assert!((w - 0.25).abs() < 1e-15);
        let members: Vec<Vec<usize>> = bins.iter().map(|b| b.elements.clone()).collect();
        assert_eq!(members, vec![vec![0, 1, 2], vec![4], vec![3]]);
        let centres = [-0.031 + 0.125, -0.031 + 0.625, -0.031 + 0.875];
        for (b, c) in bins.iter().zip(centres) {
            assert!((b.modulus - 1000.0 * c).abs() < 1e-9, "{} {c}", b.modulus);
        }
        assert_eq!(bins[2].name, "BONE_3");
        let (one, _) = bin_densities(&[0.3, 0.3], 128, |r| r);
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].elements, vec![0, 1]);
        assert!(bin_densities(&[], 4, |r| r).0.is_empty());
    }
}

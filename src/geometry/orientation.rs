//! Closed, consistently oriented surfaces: orientation outwards, signed volume, closedness.

use super::{Shape, facet_normal, norm};
use crate::error::{Error, Result};

/// Checks a triangle surface and orients it: finite coordinates, at least one facet, no
/// degenerate facet (repeated vertex or zero area: an error naming the facet; a mesh's
/// numbering is kept so that shapes stay in correspondence), every edge shared by at most
/// two facets (edge-manifold), facets oriented consistently across every edge (flipped as
/// needed; an error when impossible, as on a Möbius strip), and, where the surface is
/// closed, normals pointing outwards (positive enclosed volume). Open surfaces are allowed.
pub fn prepare_surface(mut s: Shape<3>) -> Result<Shape<3>> {
    if s.facets.is_empty() {
        return Err(Error::shape(&s.name, "has no facets (a surface is needed)"));
    }
    s.validate()?;
    let (lo, hi) = crate::geometry::bounding_box(&s.points);
    let scale = norm(crate::geometry::sub(hi, lo));
    for (k, f) in s.facets.iter().enumerate() {
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
            return Err(Error::shape(
                &s.name,
                format!("facet {k} repeats a vertex ({f:?})"),
            ));
        }
        if norm(facet_normal(&s.points, f)) <= 1e-14 * scale * scale {
            return Err(Error::shape(
                &s.name,
                format!("facet {k} {f:?} has zero area"),
            ));
        }
    }
    // The facet across every edge.
    let nf = s.facets.len();
    let (across, closed) = facets_across_edges(&s)?;
    // Consistent orientation, component by component (breadth-first over shared edges).
    let mut flip: Vec<Option<bool>> = vec![None; nf];
    let directed =
        |f: &[usize; 3], a: usize, b: usize| (0..3).any(|e| f[e] == a && f[(e + 1) % 3] == b);
    for seed in 0..nf {
        if flip[seed].is_some() {
            continue;
        }
        flip[seed] = Some(false);
        let mut queue = vec![seed];
        while let Some(k) = queue.pop() {
            let f = s.facets[k];
            for e in 0..3 {
                // Edge slot e of the facet as listed, directed as the facet now turns.
                let (a, b) = if flip[k] == Some(true) {
                    (f[(e + 1) % 3], f[e])
                } else {
                    (f[e], f[(e + 1) % 3])
                };
                let Some(j) = across[3 * k + e] else {
                    continue;
                };
                // A consistent neighbour runs the shared edge from b to a.
                let want = directed(&s.facets[j], a, b); // flip j if it runs a -> b too
                match flip[j] {
                    None => {
                        flip[j] = Some(want);
                        queue.push(j);
                    }
                    Some(fj) if fj != want => {
                        return Err(Error::shape(
                            &s.name,
                            format!(
                                "cannot be oriented consistently (facets {k} and {j} disagree \
                                 around the edge {a}-{b} whichever way they turn)"
                            ),
                        ));
                    }
                    _ => {}
                }
            }
        }
    }
    for (f, fl) in s.facets.iter_mut().zip(&flip) {
        *f = oriented(f, *fl == Some(true));
    }
    if closed && signed_volume(&s) < 0.0 {
        for f in &mut s.facets {
            f.swap(1, 2);
        }
    }
    Ok(s)
}

/// For every edge slot `3 k + e` of the surface (the edge from vertex `e` to `e + 1` of facet
/// `k`), the other facet sharing it (`None` on the border), and whether the surface is
/// closed (no border edge).
///
/// # Errors
/// [`Error::Shape`] when an edge is shared by more than two facets (not edge-manifold).
fn facets_across_edges(s: &Shape<3>) -> Result<(Vec<Option<usize>>, bool)> {
    // The edge slots bucketed by their smaller vertex (a counting sort: linear, and several
    // times faster than a hash map of the edges or a comparison sort of them on a femur's
    // 44 000 slots); within a bucket of a few, slots of the same larger vertex pair up.
    let n = s.points.len();
    if n >= u32::MAX as usize || 3 * s.facets.len() >= u32::MAX as usize {
        return Err(Error::shape(
            &s.name,
            format!(
                "has {n} vertices and {} facets: more than a surface can have here (4 billion edges)",
                s.facets.len()
            ),
        ));
    }
    let ends: Vec<(u32, u32)> = s
        .facets
        .iter()
        .flat_map(|f| {
            (0..3).map(move |e| {
                let (a, b) = (f[e], f[(e + 1) % 3]);
                (a.min(b) as u32, a.max(b) as u32)
            })
        })
        .collect();
    let mut start = vec![0u32; n + 1];
    for &(a, _) in &ends {
        start[a as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    // (larger vertex, slot) per bucket.
    let mut bucketed = vec![(0u32, 0u32); ends.len()];
    for (slot, &(a, b)) in ends.iter().enumerate() {
        let at = &mut fill[a as usize];
        bucketed[*at as usize] = (b, slot as u32);
        *at += 1;
    }
    let mut across = vec![None; ends.len()];
    let mut closed = true;
    for v in 0..n {
        let bucket = &mut bucketed[start[v] as usize..start[v + 1] as usize];
        bucket.sort_unstable();
        for group in bucket.chunk_by(|x, y| x.0 == y.0) {
            match group {
                [_] => closed = false,
                [x, y] => {
                    across[x.1 as usize] = Some(y.1 as usize / 3);
                    across[y.1 as usize] = Some(x.1 as usize / 3);
                }
                _ => {
                    return Err(Error::shape(
                        &s.name,
                        format!(
                            "is not edge-manifold: the edge between vertices {v} and {} is shared by {} facets",
                            group[0].0,
                            group.len()
                        ),
                    ));
                }
            }
        }
    }
    Ok((across, closed))
}

fn oriented(f: &[usize; 3], flip: bool) -> [usize; 3] {
    if flip { [f[0], f[2], f[1]] } else { *f }
}

/// Volume enclosed by a closed surface (positive when its normals point outwards).
pub fn signed_volume(s: &Shape<3>) -> f64 {
    s.facets
        .iter()
        .map(|f| {
            let (a, b, c) = (s.points[f[0]], s.points[f[1]], s.points[f[2]]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Whether every edge of the surface is shared by exactly two facets.
pub fn is_closed_surface(s: &Shape<3>) -> bool {
    facets_across_edges(s).is_ok_and(|(_, closed)| closed)
}

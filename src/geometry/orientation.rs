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
    let scale = norm(crate::geometry::sub(
        crate::geometry::bounding_box(&s.points).1,
        crate::geometry::bounding_box(&s.points).0,
    ));
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
    // Facets across every edge: the edges sorted by their two vertices (a sort is several
    // times faster than a hash map of edges on a femur's 44 000 edge slots).
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
            let fk = oriented(&s.facets[k], flip[k] == Some(true));
            for e in 0..3 {
                let (a, b) = (fk[e], fk[(e + 1) % 3]);
                // The slot of edge a-b in the facet as listed (a flip turns the order).
                let slot = (0..3)
                    .find(|&t| {
                        let (x, y) = (s.facets[k][t], s.facets[k][(t + 1) % 3]);
                        (x == a && y == b) || (x == b && y == a)
                    })
                    .unwrap_or(e);
                let Some(j) = across[3 * k + slot] else {
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
    let edge = |slot: usize| {
        let f = &s.facets[slot / 3];
        let (a, b) = (f[slot % 3], f[(slot % 3 + 1) % 3]);
        (a.min(b), a.max(b))
    };
    let mut start = vec![0usize; n + 1];
    for slot in 0..3 * s.facets.len() {
        start[edge(slot).0 + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut bucketed = vec![0usize; 3 * s.facets.len()];
    for slot in 0..3 * s.facets.len() {
        let a = edge(slot).0;
        bucketed[fill[a]] = slot;
        fill[a] += 1;
    }
    let mut across = vec![None; bucketed.len()];
    let mut closed = true;
    let mut group: Vec<usize> = Vec::new();
    for v in 0..n {
        let bucket = &bucketed[start[v]..start[v + 1]];
        for (i, &x) in bucket.iter().enumerate() {
            let b = edge(x).1;
            // Each edge once, from its first slot in the bucket.
            if bucket[..i].iter().any(|&y| edge(y).1 == b) {
                continue;
            }
            group.clear();
            group.extend(bucket[i..].iter().copied().filter(|&y| edge(y).1 == b));
            match group[..] {
                [_] => closed = false,
                [x, y] => {
                    across[x] = Some(y / 3);
                    across[y] = Some(x / 3);
                }
                _ => {
                    return Err(Error::shape(
                        &s.name,
                        format!(
                            "is not edge-manifold: the edge between vertices {v} and {b} is shared by {} facets",
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

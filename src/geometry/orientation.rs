//! Closed, consistently oriented surfaces: orientation outwards, signed volume, closedness.

use super::{Shape, facet_normal, norm};
use crate::error::{Error, Result};
use std::collections::HashMap;

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
    // Edge -> facets using it.
    let mut edges: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (k, f) in s.facets.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(k);
        }
    }
    if let Some(((a, b), fs)) = edges.iter().find(|(_, fs)| fs.len() > 2) {
        return Err(Error::shape(
            &s.name,
            format!(
                "is not edge-manifold: the edge between vertices {a} and {b} is shared by {} facets",
                fs.len()
            ),
        ));
    }
    // Consistent orientation, component by component (breadth-first over shared edges).
    let nf = s.facets.len();
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
                for &j in &edges[&(a.min(b), a.max(b))] {
                    if j == k {
                        continue;
                    }
                    // A consistent neighbour runs the shared edge from b to a.
                    let same_dir = directed(&s.facets[j], a, b);
                    let want = same_dir; // flip j if it runs a -> b too
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
    }
    for (f, fl) in s.facets.iter_mut().zip(&flip) {
        *f = oriented(f, *fl == Some(true));
    }
    let closed = edges.values().all(|fs| fs.len() == 2);
    if closed && signed_volume(&s) < 0.0 {
        for f in &mut s.facets {
            f.swap(1, 2);
        }
    }
    Ok(s)
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
    let mut count: HashMap<(usize, usize), u32> = HashMap::new();
    for f in &s.facets {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count.values().all(|&c| c == 2)
}

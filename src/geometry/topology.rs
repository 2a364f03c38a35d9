//! Connected components of a shape and their genus; dropping floating islands.

use super::Shape;
use std::collections::{HashMap, HashSet};

/// One connected component of a shape (facets joined through shared vertices).
#[derive(Clone, Debug, PartialEq)]
pub struct Component {
    /// Its facets (indices into the shape's facets).
    pub facets: Vec<usize>,
    /// Its vertices.
    pub vertices: usize,
    /// Its size: area (3D) or length (2D), shape units.
    pub size: f64,
    /// Genus of a closed surface component, `(2 - χ) / 2` with `χ = V - E + F`; `None` in 2D
    /// or for an open component.
    pub genus: Option<usize>,
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn facet_size<const D: usize>(shape: &Shape<D>, f: &[usize; D]) -> f64 {
    let p = |k: usize| shape.points[f[k]];
    if D == 2 {
        super::dist2(p(0), p(1)).sqrt()
    } else {
        let (a, b, c) = (p(0), p(1), p(2));
        let u = super::sub(b, a);
        let v = super::sub(c, a);
        let cr = [
            u[1] * v[2 % D] - u[2 % D] * v[1],
            u[2 % D] * v[0] - u[0] * v[2 % D],
            u[0] * v[1] - u[1] * v[0],
        ];
        0.5 * (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt()
    }
}

/// The connected components of `shape`, largest first.
pub fn components<const D: usize>(shape: &Shape<D>) -> Vec<Component> {
    let n = shape.points.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for f in &shape.facets {
        for k in 1..D {
            let (a, b) = (find(&mut parent, f[0]), find(&mut parent, f[k]));
            if a != b {
                parent[a] = b;
            }
        }
    }
    let mut by_root: HashMap<usize, Vec<usize>> = HashMap::new();
    for (i, f) in shape.facets.iter().enumerate() {
        let r = find(&mut parent, f[0]);
        by_root.entry(r).or_default().push(i);
    }
    let mut out: Vec<Component> = by_root
        .into_values()
        .map(|facets| {
            let mut vertices = HashSet::new();
            let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
            let mut size = 0.0;
            for &fi in &facets {
                let f = &shape.facets[fi];
                vertices.extend(f.iter().copied());
                size += facet_size(shape, f);
                for k in 0..D {
                    let (a, b) = (f[k], f[(k + 1) % D]);
                    *edges.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
            let closed = D == 3 && edges.values().all(|&c| c == 2);
            let chi = vertices.len() as i64 - edges.len() as i64 + facets.len() as i64;
            let genus =
                (closed && chi <= 2 && (2 - chi) % 2 == 0).then(|| ((2 - chi) / 2) as usize);
            Component {
                facets,
                vertices: vertices.len(),
                size,
                genus,
            }
        })
        .collect();
    // Largest first; components of the same size by their first facet (the same order in
    // every run).
    out.sort_by(|a, b| {
        b.size
            .total_cmp(&a.size)
            .then(a.facets[0].cmp(&b.facets[0]))
    });
    out
}

/// `shape` without the components smaller than `min_share` of its total size (area or
/// length; the largest and those holding a landmark always stay), its vertices renumbered
/// and its landmarks with them; with the components dropped (vertex count and share of the
/// size each).
pub fn drop_small_components<const D: usize>(
    shape: &Shape<D>,
    min_share: f64,
) -> (Shape<D>, Vec<(usize, f64)>) {
    let parts = components(shape);
    let total: f64 = parts.iter().map(|c| c.size).sum();
    if parts.len() < 2 || total.is_nan() || total <= 0.0 {
        return (shape.clone(), Vec::new());
    }
    let marked: HashSet<usize> = shape.landmarks.iter().copied().collect();
    let has_landmark = |c: &Component| {
        c.facets
            .iter()
            .any(|&f| shape.facets[f].iter().any(|v| marked.contains(v)))
    };
    let (keep, drop): (Vec<&Component>, Vec<&Component>) = parts
        .iter()
        .enumerate()
        .map(|(i, c)| (i == 0 || c.size >= min_share * total || has_landmark(c), c))
        .fold((Vec::new(), Vec::new()), |(mut k, mut d), (keep, c)| {
            if keep {
                k.push(c)
            } else {
                d.push(c)
            }
            (k, d)
        });
    if drop.is_empty() {
        return (shape.clone(), Vec::new());
    }
    let mut kept_facet = vec![false; shape.facets.len()];
    for c in &keep {
        for &f in &c.facets {
            kept_facet[f] = true;
        }
    }
    let mut renumber = vec![usize::MAX; shape.points.len()];
    let mut points = Vec::new();
    let mut facets = Vec::new();
    for (f, keep) in shape.facets.iter().zip(&kept_facet) {
        if !keep {
            continue;
        }
        facets.push(f.map(|v| {
            if renumber[v] == usize::MAX {
                renumber[v] = points.len();
                points.push(shape.points[v]);
            }
            renumber[v]
        }));
    }
    let landmarks = shape.landmarks.iter().map(|&l| renumber[l]).collect();
    let dropped = drop.iter().map(|c| (c.vertices, c.size / total)).collect();
    (
        Shape {
            name: shape.name.clone(),
            points,
            facets,
            landmarks,
        },
        dropped,
    )
}

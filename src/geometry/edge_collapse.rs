//! Decimation of a closed or open triangle surface by collapsing its short edges to their
//! midpoints (Hoppe et al. 1993, "Mesh optimization", the edge collapse), each collapse kept
//! only when the surface stays edge-manifold (the link condition of Dey et al. 1999: the two
//! ends share exactly the two vertices opposite the edge) and no triangle around it turns
//! over or flattens (its normal turns by less than 60° and its area stays above a millionth
//! of the edge's square). Boundary vertices (of an open surface) stay.

use super::{Point, cross, dot, norm, sub};

/// Collapses the edges of the surface `(points, facets)` shorter than `min_edge` (shortest
/// first, several passes), in place; the points no triangle uses any more stay (compact them
/// after). Returns the number of collapses.
pub fn collapse_short_edges(
    points: &mut [Point<3>],
    facets: &mut Vec<[usize; 3]>,
    min_edge: f64,
) -> usize {
    let n = points.len();
    let mut faces_of: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (f, t) in facets.iter().enumerate() {
        for &v in t {
            faces_of[v].push(f);
        }
    }
    let boundary = boundary_vertices(n, facets);
    let mut alive = vec![true; facets.len()];
    let mut total = 0;
    for _pass in 0..4 {
        let mut edges: Vec<(f64, usize, usize)> = Vec::new();
        for (f, t) in facets.iter().enumerate() {
            if !alive[f] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a < b {
                    let l = norm(sub(points[a], points[b]));
                    if l < min_edge {
                        edges.push((l, a, b));
                    }
                }
            }
        }
        edges.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut done = 0;
        let mut touched = vec![false; n];
        for &(_, a, b) in &edges {
            if touched[a] || touched[b] || boundary[a] || boundary[b] {
                continue;
            }
            if collapse(points, facets, &mut faces_of, &mut alive, a, b) {
                touched[a] = true;
                touched[b] = true;
                done += 1;
            }
        }
        total += done;
        if done == 0 {
            break;
        }
    }
    let mut k = 0;
    facets.retain(|_| {
        k += 1;
        alive[k - 1]
    });
    total
}

/// The vertices on an edge with one triangle.
fn boundary_vertices(n: usize, facets: &[[usize; 3]]) -> Vec<bool> {
    let mut count: std::collections::HashMap<(usize, usize), u32> = Default::default();
    for t in facets {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut on = vec![false; n];
    for ((a, b), c) in count {
        if c == 1 {
            on[a] = true;
            on[b] = true;
        }
    }
    on
}

/// Collapses the edge `(a, b)` into `a` at its midpoint when the checks of the module doc
/// pass; whether it did.
fn collapse(
    points: &mut [Point<3>],
    facets: &mut [[usize; 3]],
    faces_of: &mut [Vec<usize>],
    alive: &mut [bool],
    a: usize,
    b: usize,
) -> bool {
    let live = |f: &usize| alive[*f];
    let shared: Vec<usize> = faces_of[a]
        .iter()
        .filter(|f| live(f) && facets[**f].contains(&b))
        .copied()
        .collect();
    if shared.len() != 2 {
        return false;
    }
    // Link condition: the ends' common neighbours are the two opposite vertices.
    let neighbours = |v: usize| -> Vec<usize> {
        let mut s: Vec<usize> = faces_of[v]
            .iter()
            .filter(|f| live(f))
            .flat_map(|&f| facets[f])
            .filter(|&w| w != v)
            .collect();
        s.sort_unstable();
        s.dedup();
        s
    };
    let (na, nb) = (neighbours(a), neighbours(b));
    let common = na.iter().filter(|v| nb.binary_search(v).is_ok()).count();
    if common != 2 {
        return false;
    }
    let p: Point<3> = std::array::from_fn(|k| 0.5 * (points[a][k] + points[b][k]));
    let e2 = dot(sub(points[a], points[b]), sub(points[a], points[b]));
    // No triangle around turns over or flattens.
    for &v in &[a, b] {
        for &f in faces_of[v].iter().filter(|f| live(f)) {
            if shared.contains(&f) {
                continue;
            }
            let t = facets[f];
            let before = cross(
                sub(points[t[1]], points[t[0]]),
                sub(points[t[2]], points[t[0]]),
            );
            let moved = t.map(|w| if w == a || w == b { p } else { points[w] });
            let after = cross(sub(moved[1], moved[0]), sub(moved[2], moved[0]));
            let (lb, la) = (norm(before), norm(after));
            if la <= 1e-6 * e2 || dot(before, after) < 0.5 * lb * la {
                return false;
            }
        }
    }
    for &f in &shared {
        alive[f] = false;
    }
    let moved_faces: Vec<usize> = faces_of[b].iter().copied().filter(|f| alive[*f]).collect();
    for &f in &moved_faces {
        for w in facets[f].iter_mut() {
            if *w == b {
                *w = a;
            }
        }
    }
    let mut fa: Vec<usize> = faces_of[a].iter().copied().filter(|f| alive[*f]).collect();
    fa.extend(moved_faces);
    fa.sort_unstable();
    fa.dedup();
    faces_of[a] = fa;
    faces_of[b].clear();
    points[a] = p;
    true
}

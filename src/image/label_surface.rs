//! The surface of a label mask to sub-voxel accuracy: marching tetrahedra on the mask (each
//! cube of voxel centres cut into six tetrahedra around its main diagonal, which makes the
//! surface closed and edge-manifold, without the ambiguous cases of marching cubes), its
//! edges under 0.8 voxel collapsed (the many small triangles of marching tetrahedra; the
//! surface kept manifold), then a Taubin smoothing (Taubin 1995: λ/μ steps, no shrinking)
//! whose every vertex stays within half a voxel, per axis, of where the mask's boundary put
//! it. Where the label is cut by the
//! image's border the surface is left open (a partial shape).
//!
//! Frames: the extraction works in voxel indices; the surface is returned in world
//! coordinates (mm, RAS) through the image's affine, so anisotropic and oblique grids come
//! out right.

use super::{Image, LabelMask};
use crate::geometry::{Point, Shape, collapse_short_edges};
use std::collections::HashMap;

/// A label's surface and what was found on the way.
#[derive(Clone, Debug)]
pub struct LabelSurface {
    /// The surface (world, mm, RAS); open where the label is cut by the image's border.
    pub shape: Shape<3>,
    /// Whether the label is cut by the image's border (the surface is open there).
    pub partial: bool,
    /// The voxel spacing (mm), for distances in voxels.
    pub spacing: [f64; 3],
    /// Voxels of the label's shape.
    pub voxels: usize,
    /// What a user should know (islands dropped, cavities filled, cut by the border).
    pub warnings: Vec<String>,
}

/// Edges shorter than this (voxels, index frame) are collapsed after the extraction.
const COLLAPSE_BELOW: f64 = 0.8;

/// Smoothing iterations (each a λ and a μ step).
const SMOOTHING_ITERATIONS: usize = 12;
/// Taubin's λ and μ (pass band ~0.1).
const LAMBDA: f64 = 0.5;
const MU: f64 = -0.53;

/// The six tetrahedra of a cube (corner `c` at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`), each
/// a path from corner 0 to corner 7 along the cube's edges.
const TETS: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// The surface of `mask` (a crop of `image`), named `name`: see the module doc.
pub fn label_surface(image: &Image, mask: &LabelMask, name: &str) -> LabelSurface {
    let d = mask.dims;
    let mut verts = Tessellation::default();
    let corner = |x: usize, y: usize, z: usize, c: usize| {
        mask.at(x + (c & 1), y + (c >> 1 & 1), z + (c >> 2 & 1))
    };
    for z in 0..d[2] - 1 {
        for y in 0..d[1] - 1 {
            for x in 0..d[0] - 1 {
                let ids: [usize; 8] = std::array::from_fn(|c| corner(x, y, z, c));
                let ins: [bool; 8] = ids.map(|i| mask.inside[i]);
                if ins.iter().all(|&b| b) || ins.iter().all(|&b| !b) {
                    continue;
                }
                for t in TETS {
                    verts.tetrahedron(t.map(|c| ids[c]), t.map(|c| ins[c]), mask);
                }
            }
        }
    }
    let mut warnings = mask.warnings.clone();
    let partial = mask.cut.iter().any(|&c| c);
    if partial {
        let cut_at = open_cut_faces(&mut verts, image, mask);
        warnings.push(format!(
            "the label is cut by the image's border ({}): its surface is open there, a partial shape",
            cut_at.join(", ")
        ));
    }
    let Tessellation {
        mut points,
        mut facets,
        ..
    } = verts;
    // Marching tetrahedra's many small triangles: edges under COLLAPSE_BELOW voxels go.
    collapse_short_edges(&mut points, &mut facets, COLLAPSE_BELOW);
    let (points, facets) = compact(points, facets);
    let smoothed = smooth_within_half_voxel(&points, &facets);
    let world: Vec<Point<3>> = smoothed
        .iter()
        .map(|p| image.world(std::array::from_fn(|k| p[k] + mask.origin[k] as f64)))
        .collect();
    LabelSurface {
        shape: Shape {
            name: name.to_string(),
            points: world,
            facets,
            landmarks: Vec::new(),
        },
        partial,
        spacing: image.spacing(),
        voxels: mask.voxels,
        warnings,
    }
}

/// Marching tetrahedra's output: points (crop index frame) on the edges between an inside
/// and an outside grid point, one per edge, and triangles.
#[derive(Default)]
struct Tessellation {
    points: Vec<Point<3>>,
    facets: Vec<[usize; 3]>,
    on_edge: HashMap<(usize, usize), usize>,
}

impl Tessellation {
    /// The point on the edge `(a, b)` of the grid (its midpoint).
    fn edge_point(&mut self, a: usize, b: usize, mask: &LabelMask) -> usize {
        let key = (a.min(b), a.max(b));
        if let Some(&i) = self.on_edge.get(&key) {
            return i;
        }
        let pa = grid_point(mask, a);
        let pb = grid_point(mask, b);
        self.points
            .push(std::array::from_fn(|k| 0.5 * (pa[k] + pb[k])));
        let i = self.points.len() - 1;
        self.on_edge.insert(key, i);
        i
    }

    /// The triangles of one tetrahedron (grid points `g`, which are inside: `ins`), turned so
    /// that their normals point from inside to outside.
    fn tetrahedron(&mut self, g: [usize; 4], ins: [bool; 4], mask: &LabelMask) {
        let n_in = ins.iter().filter(|&&b| b).count();
        if n_in == 0 || n_in == 4 {
            return;
        }
        let inner: Vec<usize> = (0..4).filter(|&k| ins[k]).map(|k| g[k]).collect();
        let outer: Vec<usize> = (0..4).filter(|&k| !ins[k]).map(|k| g[k]).collect();
        let (from, to) = (grid_point(mask, inner[0]), grid_point(mask, outer[0]));
        let outward: Point<3> = std::array::from_fn(|k| to[k] - from[k]);
        match n_in {
            1 | 3 => {
                let (lone, others) = if n_in == 1 {
                    (inner[0], &outer)
                } else {
                    (outer[0], &inner)
                };
                let tri = [
                    self.edge_point(lone, others[0], mask),
                    self.edge_point(lone, others[1], mask),
                    self.edge_point(lone, others[2], mask),
                ];
                self.push_oriented(tri, outward);
            }
            _ => {
                let (a, b, c, dd) = (inner[0], inner[1], outer[0], outer[1]);
                let q = [
                    self.edge_point(a, c, mask),
                    self.edge_point(a, dd, mask),
                    self.edge_point(b, dd, mask),
                    self.edge_point(b, c, mask),
                ];
                self.push_oriented([q[0], q[1], q[2]], outward);
                self.push_oriented([q[0], q[2], q[3]], outward);
            }
        }
    }

    fn push_oriented(&mut self, mut t: [usize; 3], outward: Point<3>) {
        let [a, b, c] = t.map(|i| self.points[i]);
        let u: Point<3> = std::array::from_fn(|k| b[k] - a[k]);
        let v: Point<3> = std::array::from_fn(|k| c[k] - a[k]);
        let n = crate::geometry::cross(u, v);
        if crate::geometry::dot(n, outward) < 0.0 {
            t.swap(1, 2);
        }
        self.facets.push(t);
    }
}

/// The crop index position of grid point `i`.
fn grid_point(mask: &LabelMask, i: usize) -> Point<3> {
    let d = mask.dims;
    [
        (i % d[0]) as f64,
        (i / d[0] % d[1]) as f64,
        (i / (d[0] * d[1])) as f64,
    ]
}

/// Removes the triangles of the caps that close the label where the image's border cuts it
/// (all three points between the image's last voxel and the background beyond it); returns
/// the borders cut, named.
fn open_cut_faces(t: &mut Tessellation, image: &Image, mask: &LabelMask) -> Vec<String> {
    let names = [
        "i = 0", "i = last", "j = 0", "j = last", "k = 0", "k = last",
    ];
    // The cap's plane, in crop index: half a voxel beyond the image's first or last voxel.
    let plane = |f: usize| -> f64 {
        let axis = f / 2;
        let image_index = if f.is_multiple_of(2) {
            -0.5
        } else {
            image.dims[axis] as f64 - 0.5
        };
        image_index - mask.origin[axis] as f64
    };
    let on = |p: &Point<3>, f: usize| (p[f / 2] - plane(f)).abs() < 1e-9;
    let points = &t.points;
    t.facets
        .retain(|tri| !(0..6).any(|f| mask.cut[f] && tri.iter().all(|&i| on(&points[i], f))));
    (0..6)
        .filter(|&f| mask.cut[f])
        .map(|f| names[f].to_string())
        .collect()
}

/// Drops the points no triangle uses, renumbering the triangles.
fn compact(points: Vec<Point<3>>, facets: Vec<[usize; 3]>) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
    let mut new = vec![usize::MAX; points.len()];
    let mut kept = Vec::new();
    let facets = facets
        .into_iter()
        .map(|f| {
            f.map(|i| {
                if new[i] == usize::MAX {
                    new[i] = kept.len();
                    kept.push(points[i]);
                }
                new[i]
            })
        })
        .collect();
    (kept, facets)
}

/// Taubin smoothing of the surface (crop index frame), each point kept within half a voxel
/// per axis of where it started (on the mask's boundary).
fn smooth_within_half_voxel(points: &[Point<3>], facets: &[[usize; 3]]) -> Vec<Point<3>> {
    let n = points.len();
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); n];
    for f in facets {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            nb[a].push(b);
            nb[b].push(a);
        }
    }
    for v in &mut nb {
        v.sort_unstable();
        v.dedup();
    }
    let mut x = points.to_vec();
    let mut next = x.clone();
    for _ in 0..SMOOTHING_ITERATIONS {
        for step in [LAMBDA, MU] {
            for i in 0..n {
                if nb[i].is_empty() {
                    continue;
                }
                let m = nb[i].len() as f64;
                next[i] = std::array::from_fn(|k| {
                    let avg = nb[i].iter().map(|&j| x[j][k]).sum::<f64>() / m;
                    let moved = x[i][k] + step * (avg - x[i][k]);
                    moved.clamp(points[i][k] - 0.5, points[i][k] + 0.5)
                });
            }
            std::mem::swap(&mut x, &mut next);
        }
    }
    x
}

//! The regular lattice of control points and the tensor B-spline bases on it (eq. 1).

use super::bases::cubic_bases;
use crate::geometry::{Point, bounding_box};

/// A regular lattice of control points in `D` dimensions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice<const D: usize> {
    /// Start of the lattice's domain (shape units).
    pub origin: Point<D>,
    /// Spacing `h` of the control points along each axis (shape units).
    pub spacing: Point<D>,
    /// Number of control points along each axis (at least 4).
    pub size: [usize; D],
}

impl<const D: usize> Lattice<D> {
    /// A lattice of `grid` control points per axis whose domain covers the bounding box of
    /// `points` enlarged by `margin` (a fraction of its extent) on every side.
    #[track_caller]
    pub fn around(points: &[Point<D>], grid: usize, margin: f64) -> Self {
        let (lo, hi, ext) = Self::bounds(points, grid);
        let mut origin = [0.0; D];
        let mut spacing = [0.0; D];
        for d in 0..D {
            let e = (hi[d] - lo[d]).max(1e-3 * ext);
            let m = margin * e;
            origin[d] = lo[d] - m;
            spacing[d] = (e + 2.0 * m) / (grid - 3) as f64;
        }
        Lattice {
            origin,
            spacing,
            size: [grid; D],
        }
    }

    /// A lattice of equal spacing on every axis: `grid` control points along the longest
    /// extent of the bounding box of `points` (enlarged by `margin` of each extent on every
    /// side), and as many along the other axes as that spacing needs (at least 4). A long or
    /// flat shape gets square cells and far fewer control points than `grid^D`.
    #[track_caller]
    pub fn around_isotropic(points: &[Point<D>], grid: usize, margin: f64) -> Self {
        let (lo, hi, ext) = Self::bounds(points, grid);
        let h = ext * (1.0 + 2.0 * margin) / (grid - 3) as f64;
        let mut origin = [0.0; D];
        let mut size = [grid; D];
        for d in 0..D {
            let e = (hi[d] - lo[d]) * (1.0 + 2.0 * margin);
            let spans = ((e / h - 1e-9).ceil() as usize).clamp(1, grid - 3);
            size[d] = spans + 3;
            origin[d] = 0.5 * (lo[d] + hi[d]) - 0.5 * spans as f64 * h;
        }
        Lattice {
            origin,
            spacing: [h; D],
            size,
        }
    }

    /// The bounding box of `points` and its largest side (checked: `grid >= 4`).
    #[track_caller]
    fn bounds(points: &[Point<D>], grid: usize) -> (Point<D>, Point<D>, f64) {
        assert!(
            grid >= 4,
            "a cubic B-spline lattice needs at least 4 control points per axis"
        );
        let (lo, hi) = bounding_box(points);
        let ext = (0..D)
            .map(|d| hi[d] - lo[d])
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        (lo, hi, ext)
    }

    /// Total number of control points.
    pub fn len(&self) -> usize {
        self.size.iter().product()
    }

    /// Whether the lattice has no control points (never, for a valid lattice).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Multi-index of a linear control point index (axis 0 fastest).
    pub fn multi_index(&self, mut i: usize) -> [usize; D] {
        std::array::from_fn(|d| {
            let v = i % self.size[d];
            i /= self.size[d];
            v
        })
    }

    /// Rest position of control point `i`: `origin + (j - 1) h`.
    pub fn rest_position(&self, i: usize) -> Point<D> {
        let j = self.multi_index(i);
        std::array::from_fn(|d| self.origin[d] + (j[d] as f64 - 1.0) * self.spacing[d])
    }

    /// The control points at rest (the identity deformation).
    pub fn rest(&self) -> Vec<Point<D>> {
        (0..self.len()).map(|i| self.rest_position(i)).collect()
    }

    /// Calls `f(control index, weight)` for the `4^D` control points supporting `p`, with
    /// their tensor-product basis values `B_i(u)` (eq. 1). Points outside the domain use the
    /// polynomial of the nearest span (smooth extrapolation).
    #[inline]
    pub fn for_each_basis(&self, p: &Point<D>, mut f: impl FnMut(usize, f64)) {
        let mut first = [0usize; D];
        let mut b = [[0.0; 4]; D];
        for d in 0..D {
            let u = (p[d] - self.origin[d]) / self.spacing[d];
            let k = (u.floor().max(0.0) as usize).min(self.size[d] - 4);
            b[d] = cubic_bases(u - k as f64, 0);
            first[d] = k;
        }
        // Axis 0 is contiguous in the control point order and varies fastest.
        let s1 = if D > 1 { self.size[0] } else { 0 };
        match D {
            2 => {
                for l1 in 0..4 {
                    let base = (first[1] + l1) * s1 + first[0];
                    for l0 in 0..4 {
                        f(base + l0, b[0][l0] * b[1][l1]);
                    }
                }
            }
            3 => {
                let s2 = s1 * self.size[1];
                for l2 in 0..4 {
                    for l1 in 0..4 {
                        let base = (first[2] + l2) * s2 + (first[1] + l1) * s1 + first[0];
                        for l0 in 0..4 {
                            f(base + l0, b[0][l0] * b[1][l1] * b[2][l2]);
                        }
                    }
                }
            }
            _ => {
                for c in 0..4usize.pow(D as u32) {
                    let mut idx = 0;
                    let mut stride = 1;
                    let mut w = 1.0;
                    let mut cc = c;
                    for d in 0..D {
                        let l = cc % 4;
                        cc /= 4;
                        idx += (first[d] + l) * stride;
                        stride *= self.size[d];
                        w *= b[d][l];
                    }
                    f(idx, w);
                }
            }
        }
    }

    /// The 1D Gram matrices `G^(o)[i][j] = ∫ N_i^(o)(u) N_j^(o)(u) du` over the domain of axis
    /// `d` (in span units), for `o = 0, 1, 2`, stored as `[o][i][j - i + 3]`. Exact: 4-point
    /// Gauss-Legendre per span integrates the degree-6 products exactly.
    pub(super) fn gram_1d(&self, d: usize) -> [Vec<[f64; 7]>; 3] {
        let n = self.size[d];
        const GX: [f64; 4] = [
            0.069_431_844_202_973_71,
            0.330_009_478_207_571_9,
            0.669_990_521_792_428_1,
            0.930_568_155_797_026_3,
        ];
        const GW: [f64; 4] = [
            0.173_927_422_568_726_9,
            0.326_072_577_431_273_1,
            0.326_072_577_431_273_1,
            0.173_927_422_568_726_9,
        ];
        std::array::from_fn(|o| {
            let mut g = vec![[0.0; 7]; n];
            for k in 0..n - 3 {
                for q in 0..4 {
                    let b = cubic_bases(GX[q], o);
                    for l in 0..4 {
                        for m in 0..4 {
                            g[k + l][m + 3 - l] += GW[q] * b[l] * b[m];
                        }
                    }
                }
            }
            g
        })
    }
}

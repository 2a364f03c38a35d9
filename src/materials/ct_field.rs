//! A CT as a continuous field: its values (HU) trilinearly interpolated between voxel
//! centres, sampled in voxel-index coordinates, with the world (mm, RAS) → index map.

use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::image::Image;

/// The voxel values, in `f32` when every one is exactly an `f32` (the integer CTs), in `f64`
/// otherwise.
#[derive(Clone, Debug)]
enum Values {
    F32(Vec<f32>),
    F64(Vec<f64>),
}

/// A CT ready to sample: `dims` voxels of values in HU (the image's stored values scaled),
/// voxel `(i, j, k)` centred at index coordinates `(i, j, k)`, covering
/// `[-0.5, dims - 0.5]` along each axis.
#[derive(Clone, Debug)]
pub struct CtField {
    /// Voxels per axis.
    pub dims: [usize; 3],
    /// The voxel spacing (mm).
    pub spacing: [f64; 3],
    /// Index → world (mm, RAS), the rows `[A | t]`.
    pub affine: [[f64; 4]; 3],
    /// World (mm, RAS) → index, the rows `[A⁻¹ | -A⁻¹ t]`.
    inverse: [[f64; 4]; 3],
    values: Values,
    grid: Grid,
    /// The smallest and largest value (HU).
    pub range: [f64; 2],
}

impl CtField {
    /// The field of `image` (already checked by its reader).
    ///
    /// # Errors
    /// [`Error::Parameter`] for a value that is not finite (naming the voxel).
    pub fn new(image: &Image) -> Result<Self> {
        let n = image.voxel_count();
        let mut range = [f64::INFINITY, f64::NEG_INFINITY];
        let mut small = Vec::with_capacity(n);
        let mut exact = true;
        for i in 0..n {
            let v = image.value(i);
            if !v.is_finite() {
                let (x, y) = (i % image.dims[0], i / image.dims[0]);
                return Err(Error::Parameter(format!(
                    "the CT's voxel ({}, {}, {}) is {v}, not a number of HU",
                    x,
                    y % image.dims[1],
                    y / image.dims[1]
                )));
            }
            range = [range[0].min(v), range[1].max(v)];
            exact &= f64::from(v as f32) == v;
            small.push(v as f32);
        }
        let values = if exact {
            Values::F32(small)
        } else {
            Values::F64((0..n).map(|i| image.value(i)).collect())
        };
        Ok(CtField {
            dims: image.dims,
            spacing: image.spacing(),
            affine: image.affine,
            inverse: invert_affine(&image.affine),
            values,
            grid: Grid::new(image.dims),
            range,
        })
    }

    /// The index coordinates of the world point `p` (mm, RAS).
    #[inline]
    pub fn index_of(&self, p: &Point<3>) -> Point<3> {
        std::array::from_fn(|r| {
            let a = &self.inverse[r];
            a[0] * p[0] + a[1] * p[1] + a[2] * p[2] + a[3]
        })
    }

    /// The volume of one voxel (mm³).
    pub fn voxel_volume(&self) -> f64 {
        let a = &self.affine;
        (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
            .abs()
    }

    /// The world bounding box of the CT's extent (mm, RAS): the corners of
    /// `[-0.5, dims - 0.5]` mapped.
    pub fn world_bounds(&self) -> [Point<3>; 2] {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in 0..8 {
            let ijk: Point<3> = std::array::from_fn(|d| {
                if c >> d & 1 == 0 {
                    -0.5
                } else {
                    self.dims[d] as f64 - 0.5
                }
            });
            let a = &self.affine;
            for r in 0..3 {
                let w = a[r][0] * ijk[0] + a[r][1] * ijk[1] + a[r][2] * ijk[2] + a[r][3];
                lo[r] = lo[r].min(w);
                hi[r] = hi[r].max(w);
            }
        }
        [lo, hi]
    }

    /// The trilinearly interpolated value (HU) at index coordinates `x`, or `None` outside
    /// the CT's extent. Between the outermost voxel centres and the extent's faces the
    /// outermost value holds.
    #[inline]
    pub fn sample(&self, x: &Point<3>) -> Option<f64> {
        match &self.values {
            Values::F32(v) => self.sample_in(v, x),
            Values::F64(v) => self.sample_in(v, x),
        }
    }

    #[inline]
    fn sample_in<T: Copy + Into<f64>>(&self, v: &[T], x: &Point<3>) -> Option<f64> {
        let g = &self.grid;
        if !(x[0] >= -0.5
            && x[0] <= g.hi[0]
            && x[1] >= -0.5
            && x[1] <= g.hi[1]
            && x[2] >= -0.5
            && x[2] <= g.hi[2])
        {
            return None;
        }
        // (A cast truncates, which is the floor of a non-negative value; `floor` is a call
        // into libm on baseline x86-64.)
        let c: [f64; 3] = std::array::from_fn(|d| x[d].max(0.0).min(g.top[d]));
        let i: [usize; 3] = std::array::from_fn(|d| (c[d] as usize).min(g.last[d]));
        let [fx, fy, fz]: [f64; 3] = std::array::from_fn(|d| c[d] - i[d] as f64);
        let o = i[0] + g.strides[1] * i[1] + g.strides[2] * i[2];
        let [sx, sy, sz] = g.step;
        let at = |k: usize| -> f64 { v[k].into() };
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c00 = lerp(at(o), at(o + sx), fx);
        let c10 = lerp(at(o + sy), at(o + sy + sx), fx);
        let c01 = lerp(at(o + sz), at(o + sz + sx), fx);
        let c11 = lerp(at(o + sz + sy), at(o + sz + sy + sx), fx);
        Some(lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz))
    }
}

/// The grid's constants for sampling: the extent's upper faces (`dims - 0.5`), the last
/// voxel centre (`dims - 1`), the last cell's first voxel (`dims - 2`, 0 for one voxel), the
/// strides and the steps to the next voxel (0 along an axis of one voxel).
#[derive(Clone, Debug)]
struct Grid {
    hi: [f64; 3],
    top: [f64; 3],
    last: [usize; 3],
    strides: [usize; 3],
    step: [usize; 3],
}

impl Grid {
    fn new(dims: [usize; 3]) -> Self {
        let strides = [1, dims[0], dims[0] * dims[1]];
        Grid {
            hi: dims.map(|n| n as f64 - 0.5),
            top: dims.map(|n| (n - 1) as f64),
            last: dims.map(|n| n.saturating_sub(2)),
            strides,
            step: std::array::from_fn(|d| if dims[d] > 1 { strides[d] } else { 0 }),
        }
    }
}

/// The inverse of the affine `[A | t]`: `[A⁻¹ | -A⁻¹ t]` (A checked non-singular by the
/// image's reader).
fn invert_affine(a: &[[f64; 4]; 3]) -> [[f64; 4]; 3] {
    let m = |r: usize, c: usize| a[r][c];
    let det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
        - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
        + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
    let cof = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        m(r1, c1) * m(r2, c2) - m(r1, c2) * m(r2, c1)
    };
    let mut inv = [[0.0; 4]; 3];
    for r in 0..3 {
        for c in 0..3 {
            // The inverse is the transposed cofactor matrix over the determinant.
            inv[r][c] = cof(c, r) / det;
        }
    }
    for r in 0..3 {
        inv[r][3] = -(0..3).map(|c| inv[r][c] * a[c][3]).sum::<f64>();
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{VoxelType, WorldConvention};

    /// A 3 × 3 × 3 CT of `f(i, j, k)` with index `(i, j, k)` at world `(i - 1, j - 1, k - 1)`.
    pub(crate) fn ramp(f: impl Fn(f64, f64, f64) -> f64) -> Image {
        let mut data = Vec::new();
        for k in 0..3 {
            for j in 0..3 {
                for i in 0..3 {
                    data.extend((f(i as f64 - 1.0, j as f64 - 1.0, k as f64 - 1.0)).to_le_bytes());
                }
            }
        }
        Image {
            dims: [3, 3, 3],
            voxel_type: VoxelType::F64,
            little_endian: true,
            data,
            slope: 1.0,
            intercept: 0.0,
            affine: [
                [1.0, 0.0, 0.0, -1.0],
                [0.0, 1.0, 0.0, -1.0],
                [0.0, 0.0, 1.0, -1.0],
            ],
            file_convention: WorldConvention::Ras,
        }
    }

    #[test]
    fn trilinear_values_of_the_published_ramp() {
        // HU = 5 (i + j + k) at the voxels (i, j, k) ∈ {0, 1, 2}³ centred on {-1, 0, 1}³
        // (py_bonemat_abaqus's oracle): 22.5 at (0.5, 0.5, 0.5), 16.25 at (0.25, 0, 0).
        let g = CtField::new(&ramp(|x, y, z| 5.0 * (x + y + z + 3.0))).unwrap();
        let at = |p: Point<3>| g.sample(&g.index_of(&p)).unwrap();
        assert!((at([0.5, 0.5, 0.5]) - 22.5).abs() < 1e-12);
        assert!((at([0.25, 0.0, 0.0]) - 16.25).abs() < 1e-12);
        assert!(g.sample(&[-0.6, 0.0, 0.0]).is_none());
        assert!(g.sample(&[0.0, 2.51, 0.0]).is_none());
        assert_eq!(g.sample(&[-0.4, 0.0, 0.0]), g.sample(&[0.0, 0.0, 0.0]));
        assert_eq!(g.range, [0.0, 30.0]);
    }

    #[test]
    fn inverse_affine_round_trips() {
        let mut im = ramp(|x, _, _| x);
        im.affine = [
            [0.0, -0.7, 0.1, 12.0],
            [0.8, 0.0, 0.0, -4.0],
            [0.05, 0.0, 2.5, 33.0],
        ];
        let f = CtField::new(&im).unwrap();
        let ijk = [1.25, 0.5, 1.75];
        let back = f.index_of(&im.world(ijk));
        for d in 0..3 {
            assert!((back[d] - ijk[d]).abs() < 1e-12);
        }
    }
}

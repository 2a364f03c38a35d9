//! One image type: voxels as the file stores them, and the index → world affine.

use crate::error::{Error, Result};
use crate::geometry::Point;

/// How a voxel is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum VoxelType {
    /// 8-bit unsigned.
    U8,
    /// 8-bit signed.
    I8,
    /// 16-bit unsigned.
    U16,
    /// 16-bit signed.
    I16,
    /// 32-bit unsigned.
    U32,
    /// 32-bit signed.
    I32,
    /// 64-bit unsigned.
    U64,
    /// 64-bit signed.
    I64,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

impl VoxelType {
    /// Bytes per voxel.
    pub fn size(self) -> usize {
        match self {
            VoxelType::U8 | VoxelType::I8 => 1,
            VoxelType::U16 | VoxelType::I16 => 2,
            VoxelType::U32 | VoxelType::I32 | VoxelType::F32 => 4,
            VoxelType::U64 | VoxelType::I64 | VoxelType::F64 => 8,
        }
    }

    /// Whether it holds floating-point numbers.
    pub fn is_float(self) -> bool {
        matches!(self, VoxelType::F32 | VoxelType::F64)
    }
}

/// The convention of a file's world coordinates. NIfTI's are RAS (+x right, +y anterior);
/// ITK's files (NRRD `left-posterior-superior`, MetaImage) and DICOM's are LPS (+x left,
/// +y posterior): the same point has x and y of opposite signs in the two.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum WorldConvention {
    /// Right, anterior, superior.
    Ras,
    /// Left, posterior, superior.
    Lps,
}

impl WorldConvention {
    /// `p` (mm, this convention) in RAS, or RAS in this convention (the map is its own
    /// inverse).
    pub fn to_ras(self, p: Point<3>) -> Point<3> {
        match self {
            WorldConvention::Ras => p,
            WorldConvention::Lps => [-p[0], -p[1], p[2]],
        }
    }
}

/// An image: `dims` voxels as the file stores them (`data`, x fastest, in `voxel_type` and
/// `little_endian` order), the value of a voxel `slope · stored + intercept`, and the affine
/// from voxel index `(i, j, k)` to world (mm, RAS): `world = A · (i, j, k) + t`, the rows
/// `[A | t]`.
#[derive(Clone, Debug)]
pub struct Image {
    /// Voxels per axis.
    pub dims: [usize; 3],
    /// How a voxel is stored.
    pub voxel_type: VoxelType,
    /// Byte order of `data`.
    pub little_endian: bool,
    /// The voxels' bytes.
    pub data: Vec<u8>,
    /// Scale of the stored values (NIfTI's `scl_slope`, DICOM's rescale slope); 1 by default.
    pub slope: f64,
    /// Offset of the stored values (`scl_inter`, rescale intercept); 0 by default.
    pub intercept: f64,
    /// Index → world (mm, RAS), the rows `[A | t]`.
    pub affine: [[f64; 4]; 3],
    /// The convention of the file's own world coordinates (what its header said).
    pub file_convention: WorldConvention,
}

impl Image {
    /// Checks the image: the voxel count matches the data, the affine is finite and not
    /// singular. `path` names the file in messages.
    ///
    /// # Errors
    /// [`Error::Parse`] naming `path` and the problem.
    pub fn check(&self, path: &std::path::Path) -> Result<()> {
        let bad = |m: String| Error::parse(path, 0, m);
        let n = self.dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        let bytes = n.and_then(|n| n.checked_mul(self.voxel_type.size()));
        if self.dims.contains(&0) || bytes.is_none() {
            return Err(bad(format!(
                "image size {:?} is empty or too large",
                self.dims
            )));
        }
        if bytes != Some(self.data.len()) {
            return Err(bad(format!(
                "the header says {} voxels of {} bytes ({} bytes) but the data has {} bytes",
                self.voxel_count(),
                self.voxel_type.size(),
                bytes.unwrap_or(0),
                self.data.len()
            )));
        }
        if !(self.slope.is_finite() && self.intercept.is_finite()) || self.slope == 0.0 {
            return Err(bad(format!(
                "value scaling (slope {}, intercept {}) is not finite and non-zero",
                self.slope, self.intercept
            )));
        }
        if self.affine.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad("the voxel-to-world transform is not finite".into()));
        }
        let a = &self.affine;
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        let spacing = self.spacing();
        if spacing.iter().any(|&s| s.is_nan() || s <= 0.0)
            || det.abs() <= 1e-9 * spacing.iter().product::<f64>()
        {
            return Err(bad(format!(
                "the voxel spacing {spacing:?} mm or the axes' directions are degenerate"
            )));
        }
        Ok(())
    }

    /// The number of voxels.
    pub fn voxel_count(&self) -> usize {
        self.dims.iter().product()
    }

    /// The voxel spacing (mm): the lengths of the affine's columns.
    pub fn spacing(&self) -> [f64; 3] {
        std::array::from_fn(|c| {
            (0..3)
                .map(|r| self.affine[r][c] * self.affine[r][c])
                .sum::<f64>()
                .sqrt()
        })
    }

    /// The world position (mm, RAS) of the (fractional) voxel index `ijk`.
    pub fn world(&self, ijk: [f64; 3]) -> Point<3> {
        std::array::from_fn(|r| {
            let a = &self.affine[r];
            a[0] * ijk[0] + a[1] * ijk[1] + a[2] * ijk[2] + a[3]
        })
    }

    /// The stored value of voxel `i` (linear index, x fastest), unscaled.
    #[inline]
    pub fn stored(&self, i: usize) -> f64 {
        let s = self.voxel_type.size();
        let b = &self.data[i * s..(i + 1) * s];
        macro_rules! read {
            ($t:ty) => {{
                let a: [u8; std::mem::size_of::<$t>()] = b.try_into().unwrap_or_default();
                if self.little_endian {
                    <$t>::from_le_bytes(a) as f64
                } else {
                    <$t>::from_be_bytes(a) as f64
                }
            }};
        }
        match self.voxel_type {
            VoxelType::U8 => f64::from(b[0]),
            VoxelType::I8 => f64::from(b[0] as i8),
            VoxelType::U16 => read!(u16),
            VoxelType::I16 => read!(i16),
            VoxelType::U32 => read!(u32),
            VoxelType::I32 => read!(i32),
            VoxelType::U64 => read!(u64),
            VoxelType::I64 => read!(i64),
            VoxelType::F32 => read!(f32),
            VoxelType::F64 => read!(f64),
        }
    }

    /// The label number of voxel `i`: an integer voxel (unscaled) read exactly, as an integer
    /// (never through `f64`, which merges labels beyond 2⁵³); any other its value when that is
    /// a whole number. `Err` holds a value that is no label number (NaN, a fraction, beyond
    /// `i64`).
    #[inline]
    pub fn label(&self, i: usize) -> std::result::Result<i64, f64> {
        let s = self.voxel_type.size();
        let b = &self.data[i * s..(i + 1) * s];
        let exact = self.slope == 1.0 && self.intercept == 0.0;
        macro_rules! int {
            ($t:ty) => {{
                let a: [u8; std::mem::size_of::<$t>()] = b.try_into().unwrap_or_default();
                let v = if self.little_endian {
                    <$t>::from_le_bytes(a)
                } else {
                    <$t>::from_be_bytes(a)
                };
                i64::try_from(v).map_err(|_| v as f64)
            }};
        }
        match self.voxel_type {
            VoxelType::U64 if exact => int!(u64),
            VoxelType::I64 if exact => int!(i64),
            VoxelType::U32 if exact => int!(u32),
            VoxelType::I32 if exact => int!(i32),
            _ => {
                let v = self.value(i);
                if v.is_finite() && v.fract() == 0.0 && v.abs() < 9.2e18 {
                    Ok(v as i64)
                } else {
                    Err(v)
                }
            }
        }
    }

    /// The value of voxel `i`: `slope · stored + intercept` (HU for a CT).
    #[inline]
    pub fn value(&self, i: usize) -> f64 {
        self.slope * self.stored(i) + self.intercept
    }
}

//! Similarity transforms `t_{R,T,s}` (section 3) and rotations from their generators.

use super::{Point, sub};

/// `exp(Σ_k ω_k G_k)`: the rotation by the angle `ω` (2D) or the rotation vector `ω` (3D,
/// Rodrigues).
pub fn rotation_exp<const D: usize>(w: &[f64]) -> [[f64; D]; D] {
    let mut r = Similarity::<D>::identity().r;
    match D {
        2 => {
            let (s, c) = w[0].sin_cos();
            r[0][0] = c;
            r[0][1] = -s;
            r[1][0] = s;
            r[1][1] = c;
        }
        3 => {
            let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            if th > 0.0 {
                let k = [w[0] / th, w[1] / th, w[2] / th];
                let (s, c) = th.sin_cos();
                for i in 0..3 {
                    for j in 0..3 {
                        let kk = (1.0 - c) * k[i] * k[j];
                        let cross = match (i, j) {
                            (0, 1) => -k[2],
                            (1, 0) => k[2],
                            (0, 2) => k[1],
                            (2, 0) => -k[1],
                            (1, 2) => -k[0],
                            (2, 1) => k[0],
                            _ => 0.0,
                        };
                        r[i][j] = if i == j { c } else { 0.0 } + kk + s * cross;
                    }
                }
            }
        }
        _ => unreachable!("atlasmesh supports D = 2 and D = 3"),
    }
    r
}

/// A similarity transform `t_{R,T,s}(p) = s R p + T` (section 3), from a reference frame to a
/// subject frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity<const D: usize> {
    /// Scale `s > 0`.
    pub s: f64,
    /// Rotation `R` (row-major, `det R = +1`).
    pub r: [[f64; D]; D],
    /// Translation `T`.
    pub t: Point<D>,
}

impl<const D: usize> Default for Similarity<D> {
    fn default() -> Self {
        Self::identity()
    }
}

impl<const D: usize> Similarity<D> {
    /// The identity.
    pub fn identity() -> Self {
        Similarity {
            s: 1.0,
            r: std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 })),
            t: [0.0; D],
        }
    }

    /// The similarity of scale `s` and rotation `r` that maps the point `from` onto `to`
    /// (e.g. one shape's centroid onto another's).
    pub fn centred(s: f64, r: [[f64; D]; D], from: &Point<D>, to: &Point<D>) -> Self {
        let mut sim = Similarity { s, r, t: [0.0; D] };
        sim.t = sub(*to, sim.apply(from));
        sim
    }

    /// `s R p + T`.
    #[inline]
    pub fn apply(&self, p: &Point<D>) -> Point<D> {
        std::array::from_fn(|i| {
            self.s * (0..D).map(|j| self.r[i][j] * p[j]).sum::<f64>() + self.t[i]
        })
    }

    /// `R^T (q - T) / s`.
    #[inline]
    pub fn apply_inverse(&self, q: &Point<D>) -> Point<D> {
        let d = sub(*q, self.t);
        std::array::from_fn(|i| (0..D).map(|j| self.r[j][i] * d[j]).sum::<f64>() / self.s)
    }

    /// `R v` (a direction: no scale, no translation).
    #[inline]
    pub fn rotate(&self, v: &Point<D>) -> Point<D> {
        std::array::from_fn(|i| (0..D).map(|j| self.r[i][j] * v[j]).sum::<f64>())
    }

    /// `R^T v` (a direction from the subject frame to the reference frame).
    #[inline]
    pub fn rotate_inverse(&self, v: &Point<D>) -> Point<D> {
        std::array::from_fn(|i| (0..D).map(|j| self.r[j][i] * v[j]).sum::<f64>())
    }

    /// The composition `self ∘ other`.
    pub fn compose(&self, other: &Similarity<D>) -> Similarity<D> {
        let r = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..D).map(|k| self.r[i][k] * other.r[k][j]).sum::<f64>())
        });
        Similarity {
            s: self.s * other.s,
            r,
            t: self.apply(&other.t),
        }
    }

    /// A rotation by `angle` (radians) in the plane of the first two axes.
    pub fn planar_rotation(angle: f64) -> Self {
        let mut s = Self::identity();
        let (sn, c) = angle.sin_cos();
        s.r[0][0] = c;
        s.r[0][1] = -sn;
        s.r[1][0] = sn;
        s.r[1][1] = c;
        s
    }
}

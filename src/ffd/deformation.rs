//! A deformation `f(u) = Σ P_i B_i(u)` (eq. 1): its value and Jacobian at a point.

use super::bases::cubic_bases;
use super::lattice::Lattice;
use crate::geometry::Point;

/// A B-spline deformation `f` (eq. 1): a lattice and its control points.
#[derive(Clone, Debug)]
pub struct Ffd<const D: usize> {
    /// The lattice of the control points.
    pub lattice: Lattice<D>,
    /// Control points `P_i` (shape units), `lattice.len()` of them.
    pub control: Vec<Point<D>>,
}

impl<const D: usize> Ffd<D> {
    /// The identity deformation on `lattice`.
    pub fn identity(lattice: Lattice<D>) -> Self {
        Ffd {
            control: lattice.rest(),
            lattice,
        }
    }

    /// `f(p) = Σ_i P_i B_i(u(p))` (eq. 1).
    pub fn apply(&self, p: &Point<D>) -> Point<D> {
        let mut out = [0.0; D];
        self.lattice.for_each_basis(p, |i, w| {
            for d in 0..D {
                out[d] += w * self.control[i][d];
            }
        });
        out
    }

    /// Jacobian matrix `∂f/∂x` at `p` (row `i`: gradient of `f_i`).
    pub fn jacobian(&self, p: &Point<D>) -> [[f64; D]; D] {
        let l = &self.lattice;
        let mut first = [0usize; D];
        let mut b = [[[0.0; 4]; 2]; D];
        for d in 0..D {
            let u = (p[d] - l.origin[d]) / l.spacing[d];
            let k = (u.floor().max(0.0) as usize).min(l.size[d] - 4);
            b[d][0] = cubic_bases(u - k as f64, 0);
            b[d][1] = cubic_bases(u - k as f64, 1);
            first[d] = k;
        }
        let mut jac = [[0.0; D]; D];
        for c in 0..4usize.pow(D as u32) {
            let mut idx = 0;
            let mut stride = 1;
            let mut cc = c;
            let mut ls = [0usize; D];
            for d in 0..D {
                ls[d] = cc % 4;
                cc /= 4;
                idx += (first[d] + ls[d]) * stride;
                stride *= l.size[d];
            }
            for a in 0..D {
                let mut w = 1.0 / l.spacing[a];
                for d in 0..D {
                    w *= b[d][usize::from(d == a)][ls[d]];
                }
                for i in 0..D {
                    jac[i][a] += w * self.control[idx][i];
                }
            }
        }
        jac
    }
}

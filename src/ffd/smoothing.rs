//! The smoothing energy `E_smooth` of eq. 2 and 9, exact, as a banded quadratic form.

use super::lattice::Lattice;
use crate::geometry::Point;

/// Row-banded symmetric matrix over lattice control points: entry `(i, j)` for
/// `|i_d - j_d| <= 3` on every axis, stored per row at offset `Σ (j_d - i_d + 3) 7^d`.
pub(super) struct Banded<const D: usize> {
    pub(super) lattice: Lattice<D>,
    pub(super) rows: Vec<f64>,
    pub(super) width: usize,
}

impl<const D: usize> Banded<D> {
    pub(super) fn new(lattice: Lattice<D>) -> Self {
        let width = 7usize.pow(D as u32);
        Banded {
            lattice,
            rows: vec![0.0; lattice.len() * width],
            width,
        }
    }

    #[inline]
    pub(super) fn offset(&self, i: usize, j: usize) -> usize {
        let a = self.lattice.multi_index(i);
        let b = self.lattice.multi_index(j);
        let mut o = 0;
        let mut s = 1;
        for d in 0..D {
            o += (b[d] + 3 - a[d]) * s;
            s *= 7;
        }
        o
    }

    /// Column index of row `i`'s offset `o`, if inside the lattice.
    pub(super) fn column(&self, i: usize, o: usize) -> Option<usize> {
        let a = self.lattice.multi_index(i);
        let mut oo = o;
        let mut j = 0;
        let mut stride = 1;
        for d in 0..D {
            let v = (a[d] + oo % 7).checked_sub(3)?;
            oo /= 7;
            if v >= self.lattice.size[d] {
                return None;
            }
            j += v * stride;
            stride *= self.lattice.size[d];
        }
        Some(j)
    }
}

/// The exact smoothing energy matrix `K` of the lattice (section 2.1): `P^T K P` (summed over
/// the coordinates of the control points `P`) equals the thin-plate bending energy
/// `∫_Ω Σ_{a,b} ||∂²f/∂x_a∂x_b||² dx` over the lattice's domain, integrated exactly.
///
/// Units, by `scaling`:
/// - [`Scaling::Physical`]: positions and derivatives in units of `unit` (with `unit = 1`,
///   shape units).
/// - [`Scaling::Lattice`] (the fits' normalization, after Rueckert et al. 1999):
///   positions in units of `unit`, derivatives with respect to the lattice coordinates (one
///   unit per control point spacing), and the integral divided by the lattice domain's
///   volume in those coordinates: the mean bending energy per lattice cell. A given `alpha`
///   then means the same for any lattice size and shape units.
///
/// # Deviations from the paper
/// The paper writes `||(Σ_i ∂/∂x_i)² f||²`; read literally (`(∂_x + ∂_y)² f`) it vanishes on
/// every function of `x - y` and does not regularize. We take the usual expansion of the
/// squared gradient operator into all second derivatives (Rueckert et al. 1999), which
/// vanishes exactly on affine maps (test `smoothing_energy_vanishes_on_affine_maps`). The
/// paper does not say how it scales `E_smooth`; with the lattice normalization its morph
/// weight `alpha = 50` fits the hands' boundaries to a fraction of a percent of their size.
pub(super) fn smoothing_matrix<const D: usize>(
    lattice: &Lattice<D>,
    unit: f64,
    scaling: Scaling,
) -> Banded<D> {
    let grams: Vec<[Vec<[f64; 7]>; 3]> = (0..D).map(|d| lattice.gram_1d(d)).collect();
    let (h, volume): (Vec<f64>, f64) = match scaling {
        Scaling::Physical => ((0..D).map(|d| lattice.spacing[d] / unit).collect(), 1.0),
        Scaling::Lattice => (
            vec![1.0; D],
            (0..D).map(|d| (lattice.size[d] - 3) as f64).product(),
        ),
    };
    let mut k = Banded::new(*lattice);
    for i in 0..lattice.len() {
        let a = lattice.multi_index(i);
        for o in 0..k.width {
            let Some(j) = k.column(i, o) else { continue };
            let b = lattice.multi_index(j);
            let mut v = 0.0;
            for p in 0..D {
                for q in 0..D {
                    let mut prod = 1.0;
                    for d in 0..D {
                        let ord = usize::from(d == p) + usize::from(d == q);
                        prod *=
                            grams[d][ord][a[d]][b[d] + 3 - a[d]] * h[d].powi(1 - 2 * ord as i32);
                    }
                    v += prod;
                }
            }
            k.rows[i * k.width + o] = v / volume;
        }
    }
    k
}

/// Units of `E_smooth`: see [`smoothing_matrix`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scaling {
    Physical,
    Lattice,
}

/// `E_smooth` of a control point set (the quadratic form of the private `smoothing_matrix`); lengths in units of `unit`.
pub fn smoothing_energy<const D: usize>(
    lattice: &Lattice<D>,
    control: &[Point<D>],
    unit: f64,
) -> f64 {
    let k = smoothing_matrix(lattice, unit, Scaling::Physical);
    let mut e = 0.0;
    for i in 0..lattice.len() {
        for o in 0..k.width {
            if let Some(j) = k.column(i, o) {
                let v = k.rows[i * k.width + o];
                for d in 0..D {
                    e += control[i][d] * v * control[j][d];
                }
            }
        }
    }
    e / (unit * unit)
}

//! The regularized least-squares fit of eq. 9: control points from point pairs.

use super::deformation::Ffd;
use super::lattice::Lattice;
use super::system::{FfdFit, FfdParams, FfdSystem};
use crate::error::Result;
use crate::geometry::Point;
use faer::Mat;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::LltRef;

impl<const D: usize> FfdFit<D> {
    /// Builds and factorizes the normal matrix for the source points `sources` (shape units).
    pub fn new(sources: &[Point<D>], params: &FfdParams) -> Result<Self> {
        Self::weighted(sources, None, params)
    }

    /// [`FfdFit::new`] with a weight per source point in the data term (e.g. the landmark
    /// term `beta` of eq. 2 on the landmark points); `None` means all ones. The lattice is
    /// laid around all the sources.
    pub fn weighted(
        sources: &[Point<D>],
        weights: Option<&[f64]>,
        params: &FfdParams,
    ) -> Result<Self> {
        FfdSystem::new(sources, weights, params.grid, params.margin)?.factor(params.alpha)
    }

    /// The lattice used.
    pub fn lattice(&self) -> &Lattice<D> {
        &self.lattice
    }

    /// Solves eq. 9 for targets `targets[j]` of the sources: the control points minimizing
    /// `Σ_j ||f(p_j) - q_j||² + alpha E_smooth`.
    #[track_caller]
    pub fn solve(&self, targets: &[Point<D>]) -> Ffd<D> {
        assert_eq!(
            targets.len(),
            self.sources.len(),
            "FfdFit::solve: one target per source point"
        );
        let n = self.lattice.len();
        let o = self.lattice.origin;
        let mut acc = vec![[0.0; D]; n];
        for (k, (p, q)) in self.sources.iter().zip(targets).enumerate() {
            let pw = self.weights.as_ref().map_or(1.0, |w| w[k]);
            if pw == 0.0 {
                continue;
            }
            let v: Point<D> = std::array::from_fn(|d| pw * (q[d] - o[d]) / self.unit);
            self.lattice.for_each_basis(p, |i, w| {
                if let Some(a) = acc.get_mut(i) {
                    for d in 0..D {
                        a[d] += w * v[d];
                    }
                }
            });
        }
        let mut rhs = Mat::<f64>::from_fn(n, D, |i, d| acc[i][d]);
        // K annihilates affine maps, so solving for the displacement from rest would be
        // equivalent; solving for positions relative to `origin` keeps the numbers O(1).
        let par = faer::get_global_parallelism();
        let mut scratch = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(D, par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            faer::Conj::No,
            rhs.as_mut(),
            par,
            MemStack::new(&mut scratch),
        );
        crate::clear_simd_upper_state();
        let control = (0..n)
            .map(|i| std::array::from_fn(|d| o[d] + rhs[(i, d)] * self.unit))
            .collect();
        Ffd {
            lattice: self.lattice,
            control,
        }
    }
}

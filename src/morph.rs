//! Meshing a subject by morphing the mean FE mesh (section 4, eq. 9).

use crate::error::Result;
use crate::fe::FeMesh;
use crate::ffd::{FfdFit, FfdParams};
use crate::fit::FitResult;
use crate::model::Atlas;

/// The mean mesh with the factorized FFD fit on the mean shape's points: reusable for every
/// subject of an atlas.
pub struct Morpher<const D: usize> {
    fit: FfdFit<D>,
    mesh: FeMesh<D>,
}

impl<const D: usize> Morpher<D> {
    /// Prepares the morph of `atlas.mesh` (factorizes `B^T B + alpha K` on the mean points).
    pub fn new(atlas: &Atlas<D>, params: &FfdParams) -> Result<Self> {
        Ok(Morpher {
            fit: FfdFit::new(&atlas.mean, params)?,
            mesh: atlas.mesh.clone(),
        })
    }

    /// Morphs the mean mesh onto the subject of `fit`: the FFD `f` minimizing
    /// `Σ_j ||f(p_bar_j) - p_hat_j||² + alpha E_smooth` (eq. 9), with `p_hat_j` the projected
    /// points `S_tilde^P` brought to the reference frame by `t^{-1}`, applied to every node of
    /// the mean mesh, then `t` back to the subject frame. The result is in the subject frame.
    pub fn morph(&self, fit: &FitResult<D>) -> FeMesh<D> {
        let t = &fit.similarity;
        let targets: Vec<_> = fit
            .projected
            .iter()
            .map(|p| t.apply_inverse(&p.point))
            .collect();
        let f = self.fit.solve(&targets);
        self.mesh.with_nodes(
            self.mesh
                .nodes
                .iter()
                .map(|p| t.apply(&f.apply(p)))
                .collect(),
        )
    }
}

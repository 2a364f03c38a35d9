//! What a fit returns.

use crate::geometry::{Point, Similarity, SurfacePoint};

/// Result of a fit.
#[derive(Clone, Debug)]
pub struct FitResult<const D: usize> {
    /// Mode weights `w`.
    pub weights: Vec<f64>,
    /// `t_{R,T,s}`: reference to subject frame.
    pub similarity: Similarity<D>,
    /// The fitted instance `t ∘ (S_bar + Psi w)`, subject frame.
    pub instance: Vec<Point<D>>,
    /// `S_tilde^P`: the instance projected onto the subject along its normals, subject frame.
    pub projected: Vec<SurfacePoint<D>>,
    /// Whether each model point has a partner on the subject (always, unless the fit was
    /// `partial` and the subject misses the part where the point lies).
    pub corresponded: Vec<bool>,
    /// `E_d` (eq. 6, subject units squared) at every correspondence update of the winning
    /// start. In the coarse stage, the sum over the sampled model points scaled by
    /// `N / samples`.
    pub e_d_history: Vec<f64>,
    /// The instance at the start and after every `gamma` (the locus of fig. 9), subject frame.
    pub locus: Vec<Vec<Point<D>>>,
    /// Correspondence updates of the winning start (coarse stage and final stage).
    pub iterations: usize,
    /// Whether the inner loop met the tolerance at the last `gamma`.
    pub converged: bool,
}

impl<const D: usize> FitResult<D> {
    /// The boundary correspondence this fit establishes, to morph the mean mesh by (eq. 9):
    /// the projected points `S_tilde^P` as targets of the mean's points, with the fit's frame.
    pub fn correspondence(&self) -> crate::mesh::Correspondence<D> {
        crate::mesh::Correspondence {
            targets: self.projected.iter().map(|p| p.point).collect(),
            partnered: self.corresponded.clone(),
            frame: self.similarity,
        }
    }
}

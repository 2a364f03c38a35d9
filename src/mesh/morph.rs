//! Meshing a subject by morphing the mean FE mesh (section 4, eq. 9).

use super::FeMesh;
use super::quality::{ElementQuality, mesh_quality, summarize};
use crate::error::{Error, Result};
use crate::ffd::{FfdFit, FfdParams, FfdSystem};
use crate::geometry::{Point, Similarity};

/// Each retry of a morph that inverted an element multiplies `alpha` by this.
pub const STIFFEN_FACTOR: f64 = 4.0;

/// Retries after the first morph (`alpha` up to `4^6 ≈ 4000` times the first).
pub const MAX_STIFFENINGS: usize = 6;

/// Boundary correspondences to morph by: the target of every source point, in the subject
/// frame, and the frame itself (a fit's [`crate::fit::FitResult::correspondence`] gives them).
#[derive(Clone, Debug)]
pub struct Correspondence<const D: usize> {
    /// `p_hat_j`: the target of every source point `p_bar_j` (subject frame).
    pub targets: Vec<Point<D>>,
    /// Whether each source point has a target (empty: all have); those without are left out
    /// of the data term.
    pub partnered: Vec<bool>,
    /// `t_{R,T,s}`: reference frame (where the sources and the mesh are) to subject frame.
    pub frame: Similarity<D>,
}

/// A mesh with the factorized FFD fit on its source points (the mean shape's points):
/// reusable for every subject of an atlas.
pub struct Morpher<const D: usize> {
    fit: FfdFit<D>,
    params: FfdParams,
    sources: Vec<Point<D>>,
    mesh: FeMesh<D>,
}

/// A morphed mesh and the smoothing weight that produced it.
#[derive(Clone, Debug)]
pub struct Morph<const D: usize> {
    /// The subject's mesh, subject frame.
    pub mesh: FeMesh<D>,
    /// The `alpha` of eq. 9 used: the requested one, or a stiffer one where that inverted an
    /// element.
    pub alpha: f64,
    /// Corner Jacobians of every element of `mesh` (section 5.3).
    pub quality: Vec<ElementQuality>,
}

impl<const D: usize> Morpher<D> {
    /// Prepares the morph of `mesh` by the boundary points `sources` (both in the reference
    /// frame; for an atlas, its mean mesh and mean shape's points): factorizes
    /// `B^T B + alpha K` on the sources.
    pub fn new(sources: &[Point<D>], mesh: &FeMesh<D>, params: &FfdParams) -> Result<Self> {
        Ok(Morpher {
            fit: FfdFit::new(sources, params)?,
            params: *params,
            sources: sources.to_vec(),
            mesh: mesh.clone(),
        })
    }

    /// Morphs the mesh onto the subject of `c`: the FFD `f` minimizing
    /// `Σ_j ||f(p_bar_j) - p_hat_j||² + alpha E_smooth` (eq. 9), with `p_hat_j` the targets
    /// (for a fit, the projected points `S_tilde^P`) brought to the reference frame by
    /// `t^{-1}`, applied to every node of
    /// the mean mesh, then `t` back to the subject frame. The result is in the subject frame.
    ///
    /// # Deviation from the paper
    /// Model points without a partner on the subject (a `partial` fit) are left out of the
    /// data term; the smoothing carries the deformation over them.
    ///
    /// The paper has no remedy when the morph inverts an element. Irregular correspondences
    /// (where a poor fit meets a concave corner) can fold a weakly smoothed FFD; then we
    /// solve again with `alpha` multiplied by [`STIFFEN_FACTOR`], up to
    /// [`MAX_STIFFENINGS`] times: the least smoothing of that ladder that keeps every element
    /// valid. [`Morph::alpha`] says which was used.
    ///
    /// # Panics
    /// When `c.targets` does not have one point per source.
    #[track_caller]
    pub fn morph(&self, c: &Correspondence<D>) -> Result<Morph<D>> {
        assert_eq!(
            c.targets.len(),
            self.sources.len(),
            "morph: one target per source point"
        );
        let t = &c.frame;
        let all = c.partnered.iter().all(|&c| c);
        let keep = |i: usize| all || c.partnered.get(i).copied().unwrap_or(true);
        let targets: Vec<Point<D>> = c
            .targets
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(*i))
            .map(|(_, p)| t.apply_inverse(p))
            .collect();
        let sources: Vec<Point<D>> = self
            .sources
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(*i))
            .map(|(_, p)| *p)
            .collect();
        if targets.len() < D + 1 {
            return Err(Error::Numerical(
                "the subject has partners for too few model points to morph".into(),
            ));
        }
        let mut alpha = self.params.alpha;
        // A subject with missing parts has its own data term: factorize for its points. The
        // stiffer fits share one normal-matrix system (one structure, one symbolic
        // factorization); each replaces the last, so at most one is held beside the shared
        // one (each factor of a 20³ lattice holds tens of MB).
        let mut system: Option<FfdSystem<D>> = None;
        let mut stiffer: Option<FfdFit<D>> = if all {
            None
        } else {
            Some(FfdFit::new(&sources, &self.params)?)
        };
        for attempt in 0..=MAX_STIFFENINGS {
            let solver = stiffer.as_ref().unwrap_or(&self.fit);
            let f = solver.solve(&targets);
            let mesh = self.mesh.with_nodes(
                self.mesh
                    .nodes
                    .iter()
                    .map(|p| t.apply(&f.apply(p)))
                    .collect(),
            );
            let quality = mesh_quality(&mesh);
            let valid = summarize(&quality).inverted_elements == 0;
            if valid || attempt == MAX_STIFFENINGS || self.params.alpha == 0.0 {
                return Ok(Morph {
                    mesh,
                    alpha,
                    quality,
                });
            }
            alpha *= STIFFEN_FACTOR;
            stiffer = None;
            if system.is_none() {
                system = Some(FfdSystem::new(
                    &sources,
                    None,
                    self.params.grid,
                    self.params.margin,
                )?);
            }
            if let Some(s) = system.as_mut() {
                stiffer = Some(s.factor(alpha)?);
            }
        }
        Err(Error::Numerical("the morph did not run".into()))
    }
}

//! Buffers reused by the updates of a fit, apart from the maths.

use super::resolution::Model;
use super::state::State;
use crate::geometry::{ClosestPointIndex, Point};

/// Buffers reused by every update of a fit on one model: the instance (reference frame), the
/// index of its facets and its vertex normals, for the weights `w`; the rows of the linear
/// system.
pub(super) struct Scratch<const D: usize> {
    pub(super) x: Vec<Point<D>>,
    pub(super) w: Option<Vec<f64>>,
    pub(super) indexed: bool,
    pub(super) index: ClosestPointIndex<D>,
    pub(super) normals: Vec<Point<D>>,
    pub(super) rows: Vec<f64>,
}

impl<const D: usize> Scratch<D> {
    pub(super) fn new(model: &Model<D>) -> Self {
        Scratch {
            x: Vec::new(),
            w: None,
            indexed: false,
            index: model.index.clone(),
            normals: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// Makes `x` the instance of `w` (and, with `index`, its index and normals current).
    pub(super) fn set_weights(&mut self, model: &Model<D>, w: &[f64], index: bool) {
        if self.w.as_deref() != Some(w) {
            model.instance(w, &mut self.x);
            self.w = Some(w.to_vec());
            self.indexed = false;
        }
        if index && !self.indexed {
            self.index.refit(&self.x);
            self.index.vertex_normals_into(&mut self.normals);
            self.indexed = true;
        }
    }
}

/// The scratch of each model of a fit, and which coarse model the fit uses.
pub(super) struct Scratches<const D: usize> {
    pub(super) full: Scratch<D>,
    pub(super) coarse: Scratch<D>,
    /// Whether the fit's parameters select the fitter's coarse model.
    pub(super) use_coarse: bool,
}

impl<const D: usize> Scratches<D> {
    /// Buffers for the models `full` and `coarse` (the same model when the fit has no
    /// coarse one).
    pub(super) fn new(full: &Model<D>, coarse: &Model<D>) -> Self {
        Scratches {
            full: Scratch::new(full),
            coarse: Scratch::new(coarse),
            use_coarse: !std::ptr::eq(coarse, full),
        }
    }
}

/// One start's way through Algorithm 1.
pub(super) struct Run<const D: usize> {
    pub(super) state: State<D>,
    pub(super) e_d_history: Vec<f64>,
    pub(super) locus: Vec<Vec<Point<D>>>,
    pub(super) iterations: usize,
    pub(super) converged: bool,
}

impl<const D: usize> Run<D> {
    pub(super) fn new(state: State<D>, full: &Model<D>, x: &mut Scratches<D>) -> Self {
        x.full.set_weights(full, &state.w, false);
        let locus = vec![x.full.x.iter().map(|p| state.sim.apply(p)).collect()];
        Run {
            state,
            e_d_history: Vec::new(),
            locus,
            iterations: 0,
            converged: false,
        }
    }
}

//! The statistical atlas: the shape model (mean `S_bar`, modes `Psi`, eigenvalues `Lambda`,
//! sections 2.2-2.3) and the FE mesh of the mean (section 2.4).

use super::randomized_pca::{RandomizedPcaParams, randomized_pca};
use super::shape_source::{ShapeSource, for_each_batch, read_checked};
use super::streamed_procrustes::{generalized_procrustes_streamed, tangent_shape};
use super::{Pca, generalized_procrustes, pca};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape, Similarity, bounding_box, scale};
use crate::mesh::FeMesh;
use crate::mesh::mesh_mean_shape;
use faer::Mat;
use serde::{Deserialize, Serialize};

/// How many modes the model keeps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ModeSelection {
    /// A fixed number of modes.
    Count(usize),
    /// The fewest modes explaining at least this share of the variance (paper: 0.985).
    Variance(f64),
}

/// Parameters of atlas construction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AtlasParams {
    /// How many modes to keep (section 2.3).
    pub modes: ModeSelection,
    /// Target element edge length of the mean mesh, in reference-frame units (the mean's
    /// largest bounding-box side is 1).
    pub element_size: f64,
    /// Smoothing passes of the mean mesh.
    pub smoothing_passes: usize,
}

impl Default for AtlasParams {
    fn default() -> Self {
        AtlasParams {
            modes: ModeSelection::Variance(0.985),
            element_size: 0.015,
            smoothing_passes: 8,
        }
    }
}

/// The similarity from the reference frame (the mean `mean`) to the population's mean frame
/// and size: the scale is the shapes' mean centroid size over the mean's (the scale GPA
/// removed); the rotation maps the mean onto the average of its similarity fits `T_i(mean)`
/// onto every shape (Umeyama; the rotation closest to the average rotation), the translation
/// the mean's centroid onto their average centroid. Units of the shapes; one pass over
/// `shapes`, `batch` at a time.
fn data_frame<const D: usize>(
    mean: &[Point<D>],
    shapes: &dyn ShapeSource<D>,
    batch: usize,
) -> Result<Similarity<D>> {
    let n = shapes.len() as f64;
    let size = crate::geometry::centroid_size;
    let mut sizes = 0.0;
    let mut average = vec![[0.0; D]; mean.len()];
    for_each_batch(shapes, batch, mean.len(), |_, batch| {
        for s in batch {
            let t = crate::model::fit_similarity(mean, s, None);
            sizes += size(s);
            for (a, p) in average.iter_mut().zip(mean) {
                let q = t.apply(p);
                for d in 0..D {
                    a[d] += q[d] / n;
                }
            }
        }
        Ok(())
    })?;
    let scale = sizes / n / size(mean);
    let r = crate::model::fit_similarity(mean, &average, None).r;
    Ok(Similarity::centred(
        scale,
        r,
        &crate::geometry::centroid(mean),
        &crate::geometry::centroid(&average),
    ))
}

/// The number of modes `params` keeps of `p` (section 2.3), a model of `shapes` shapes;
/// `truncated`: `p` holds only the leading modes (a streamed model), so a share of variance
/// they do not reach is an error rather than all of them.
fn modes_kept(p: &Pca, params: &AtlasParams, shapes: usize, truncated: bool) -> Result<usize> {
    match params.modes {
        ModeSelection::Count(m) => {
            if m == 0 || m > p.eigenvalues.len() {
                return Err(Error::Parameter(format!(
                    "--modes {m}: the population of {shapes} shapes has {} modes",
                    p.eigenvalues.len()
                )));
            }
            Ok(m)
        }
        ModeSelection::Variance(v) => {
            if !(v > 0.0 && v <= 1.0) {
                return Err(Error::Parameter(format!(
                    "--variance {v} must be in (0, 1]"
                )));
            }
            let m = p.modes_for_variance(v);
            let reached = p.cumulative_variance().last().copied().unwrap_or(0.0);
            if truncated && reached < v - 1e-12 {
                return Err(Error::Parameter(format!(
                    "--variance {v}: the {} leading modes computed explain {:.4} of the \
                     variance; ask for more modes (--max-modes) or a number of modes (--modes)",
                    p.eigenvalues.len(),
                    reached
                )));
            }
            Ok(m)
        }
    }
}

/// The scale from a Procrustes mean to the reference frame: one over its bounding box's
/// largest side (the reference frame's mean has largest side 1).
fn reference_scale<const D: usize>(mean: &[Point<D>]) -> f64 {
    let (lo, hi) = bounding_box(mean);
    1.0 / (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max)
}

/// Refuses a model of `shapes` identical shapes (after alignment) of `points` points:
/// nothing to model. In the reference frame (largest side 1) the total variance of real
/// populations is far above rounding (hands ~1e-3).
fn check_variance(p: &Pca, points: usize, shapes: usize) -> Result<()> {
    let total = p.total_variance;
    if total.is_nan() || total <= 1e-20 * points as f64 {
        return Err(Error::Population(format!(
            "the {shapes} shapes are identical after alignment (total variance {total:.1e}): \
             there is no variance to model; give shapes that differ"
        )));
    }
    Ok(())
}

/// How a streamed atlas ([`Atlas::build_streamed`]) reads and models its population.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StreamParams {
    /// Shapes read at a time (the memory of a pass: one batch).
    pub batch: usize,
    /// With a share of variance to keep ([`ModeSelection::Variance`]): the most modes
    /// computed; the share must be reached within them.
    pub max_modes: usize,
    /// The randomized PCA's oversampling, power iterations and seed.
    pub pca: RandomizedPcaParams,
}

impl Default for StreamParams {
    fn default() -> Self {
        StreamParams {
            batch: 256,
            max_modes: 100,
            pca: RandomizedPcaParams::default(),
        }
    }
}

/// The empty mesh of a model-only atlas ([`Atlas::build_model`]).
pub(crate) fn no_mesh<const D: usize>() -> FeMesh<D> {
    FeMesh {
        nodes: Vec::new(),
        kind: if D == 2 {
            crate::mesh::ElementKind::Quad4
        } else {
            crate::mesh::ElementKind::Hex8
        },
        connectivity: Vec::new(),
        sets: Default::default(),
    }
}

/// A statistical atlas in `D` dimensions.
#[derive(Clone, Debug)]
pub struct Atlas<const D: usize> {
    /// Mean shape `S_bar`, `N` points, reference frame.
    pub mean: Vec<Point<D>>,
    /// Modes `Psi`: `N·D × m`, orthonormal columns.
    pub modes: Mat<f64>,
    /// Eigenvalues `lambda_1..lambda_m` (reference-frame units squared).
    pub eigenvalues: Vec<f64>,
    /// Cumulative variance share of all `n_s - 1` modes of the training PCA (of the leading
    /// modes computed, for a streamed atlas: [`Atlas::build_streamed`]).
    pub cumulative_variance: Vec<f64>,
    /// Boundary facets of the shapes (shared by all, they correspond).
    pub facets: Vec<[usize; D]>,
    /// Landmark indices.
    pub landmarks: Vec<usize>,
    /// The facets (indices into `facets`, sorted) where the population was cut by a common
    /// plane (`--cut`): a flat cap, not anatomy; empty for an uncut population.
    pub cut_facets: Vec<usize>,
    /// The landmarks' ids (names in the landmark files), one per landmark, when the
    /// population's files named them; empty otherwise (landmarks are then paired by order).
    pub landmark_ids: Vec<String>,
    /// FE mesh of the mean shape (reference frame); empty for a model-only atlas
    /// ([`Atlas::build_model`]).
    pub mesh: FeMesh<D>,
    /// Parameters used to build it.
    pub params: AtlasParams,
    /// Number of training shapes.
    pub training_shapes: usize,
    /// The similarity from the reference frame to the training population's mean frame and
    /// size (the data's unit, e.g. mm): [`Atlas::to_data_frame`]. `None` for atlases written
    /// before atlases stored it (format version 2), whose shapes stay in the reference frame.
    pub data_frame: Option<Similarity<D>>,
}

impl<const D: usize> Atlas<D> {
    /// Builds the atlas from shapes in point correspondence (same count, same facets): GPA
    /// with tangent projection, PCA, mode selection, and the FE mesh of the mean.
    pub fn build(shapes: &[Shape<D>], params: &AtlasParams) -> Result<Self> {
        Self::build_meshed(shapes, params, |mean| {
            mesh_mean_shape(mean, params.element_size, params.smoothing_passes)
        })
    }

    /// The shape model alone (GPA with tangent projection, PCA, mode selection; sections
    /// 2.2-2.3) without an FE mesh of the mean ([`Atlas::has_mesh`] is false): for
    /// populations that need no mesh, 3D point sets without facets included. Such an atlas
    /// has the model's vocabulary ([`Atlas::instance`], [`Atlas::project`],
    /// [`Atlas::posterior`], ...) but no [`Atlas::morpher`].
    pub fn build_model(shapes: &[Shape<D>], params: &AtlasParams) -> Result<Self> {
        Self::build_meshed(shapes, params, |_| Ok(no_mesh::<D>()))
    }

    /// Whether the atlas has an FE mesh of its mean (not one of [`Atlas::build_model`]).
    pub fn has_mesh(&self) -> bool {
        self.mesh.num_elements() > 0
    }

    /// Builds the atlas with a template FE mesh instead of the automatic one: `meshes[i]` is
    /// a volume mesh of `shapes[i]` in that shape's frame, all with one connectivity (as in
    /// SynthAorta, or one subject meshed by hand and its morphs). Each is brought to the
    /// reference frame by the similarity that best maps its shape onto the mean (Umeyama),
    /// and their node positions are averaged: the mean FE mesh. Pass one shape's mesh alone
    /// with that shape listed first to use it as is.
    pub fn build_with_meshes(
        shapes: &[Shape<D>],
        params: &AtlasParams,
        meshes: &[FeMesh<D>],
    ) -> Result<Self> {
        if meshes.is_empty() || meshes.len() > shapes.len() {
            return Err(Error::Population(format!(
                "{} template meshes for {} shapes; give one per shape (or one for the first)",
                meshes.len(),
                shapes.len()
            )));
        }
        for (k, m) in meshes.iter().enumerate() {
            if m.kind != meshes[0].kind
                || m.connectivity != meshes[0].connectivity
                || m.nodes.len() != meshes[0].nodes.len()
            {
                return Err(Error::Mesh(format!(
                    "template mesh {k} ({}) does not share the first one's connectivity",
                    shapes[k].name
                )));
            }
            if m.nodes.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
                return Err(Error::Mesh(format!(
                    "template mesh {k} ({}) has a NaN or infinite node",
                    shapes[k].name
                )));
            }
        }
        Self::build_meshed(shapes, params, |mean| {
            let mut nodes = vec![[0.0; D]; meshes[0].nodes.len()];
            for (m, s) in meshes.iter().zip(shapes) {
                let t = crate::model::fit_similarity(&s.points, &mean.points, None);
                for (acc, p) in nodes.iter_mut().zip(&m.nodes) {
                    let q = t.apply(p);
                    for d in 0..D {
                        acc[d] += q[d] / meshes.len() as f64;
                    }
                }
            }
            let mesh = meshes[0].with_nodes(nodes);
            let q = crate::mesh::quality::summarize(&crate::mesh::quality::mesh_quality(&mesh));
            if q.inverted_elements > 0 {
                return Err(Error::Mesh(format!(
                    "the mean of the template meshes has {} inverted elements",
                    q.inverted_elements
                )));
            }
            Ok(mesh)
        })
    }

    /// Builds the atlas with the FE mesh that `mesher` makes of the mean shape (reference
    /// frame, largest side 1): [`build`](Self::build) with a mesher of its own.
    pub fn build_meshed(
        shapes: &[Shape<D>],
        params: &AtlasParams,
        mesher: impl FnOnce(&Shape<D>) -> Result<FeMesh<D>>,
    ) -> Result<Self> {
        if shapes.len() < 3 {
            return Err(Error::Population(format!(
                "{} shape(s); an atlas needs at least 3 (two give a single mode and no way to check it)",
                shapes.len()
            )));
        }
        for s in shapes {
            s.validate()?;
            if s.points.len() != shapes[0].points.len() {
                return Err(Error::Population(format!(
                    "shape {} has {} points but shape {} has {}: the shapes are not in point correspondence; register them first (the command line's --register, Python's register=True)",
                    s.name,
                    s.points.len(),
                    shapes[0].name,
                    shapes[0].points.len()
                )));
            }
        }
        let points: Vec<Vec<Point<D>>> = shapes.iter().map(|s| s.points.clone()).collect();
        let gpa = generalized_procrustes(&points)?;
        let c = reference_scale(&gpa.mean);
        let mean: Vec<Point<D>> = gpa.mean.iter().map(|p| scale(*p, c)).collect();
        let aligned: Vec<Vec<Point<D>>> = gpa
            .aligned
            .iter()
            .map(|s| s.iter().map(|p| scale(*p, c)).collect())
            .collect();
        let p = pca(&aligned, &mean)?;
        check_variance(&p, mean.len(), shapes.len())?;
        let m = modes_kept(&p, params, shapes.len(), false)?;
        let mean_shape = Shape {
            name: "mean".into(),
            points: mean.clone(),
            facets: shapes[0].facets.clone(),
            landmarks: Vec::new(),
        };
        let mesh = mesher(&mean_shape)?;
        let frame = data_frame(&mean, &points, points.len())?;
        Ok(Atlas {
            mean,
            modes: p.modes.subcols(0, m).to_owned(),
            eigenvalues: p.eigenvalues[..m].to_vec(),
            cumulative_variance: p.cumulative_variance(),
            facets: shapes[0].facets.clone(),
            landmarks: shapes[0].landmarks.clone(),
            landmark_ids: Vec::new(),
            mesh,
            params: *params,
            training_shapes: shapes.len(),
            data_frame: Some(frame),
            cut_facets: Vec::new(),
        })
    }

    /// The atlas of a population read in batches from `source` (files on disk, for a cohort
    /// larger than the memory), with the FE mesh that `mesher` makes of the mean (given the
    /// data units per reference unit, the scale of the data frame): GPA in
    /// passes over the shapes ([`crate::model::generalized_procrustes_streamed`]), the
    /// leading modes by a randomized PCA in passes ([`crate::model::randomized_pca`]; the
    /// modes asked, or `stream.max_modes` with a share of variance), the data frame in one
    /// more pass. `facets` and `landmarks` are the shapes' (they correspond). Memory: the
    /// mean, one batch and the modes' working matrices (`N·D × 2 l` and `l × n_s`, `l` the
    /// modes computed plus 10), never the population.
    ///
    /// The same model as [`Atlas::build_meshed`] of the same shapes to rounding when the
    /// modes computed plus the oversampling reach the population's `n_s - 1` modes; within the
    /// randomized PCA's accuracy otherwise.
    pub fn build_streamed(
        source: &dyn ShapeSource<D>,
        facets: Vec<[usize; D]>,
        landmarks: Vec<usize>,
        params: &AtlasParams,
        stream: &StreamParams,
        mesher: impl FnOnce(&Shape<D>, f64) -> Result<FeMesh<D>>,
    ) -> Result<Self> {
        let n = source.len();
        if n < 3 {
            return Err(Error::Population(format!(
                "{n} shape(s); an atlas needs at least 3 (two give a single mode and no way to check it)"
            )));
        }
        let gpa = generalized_procrustes_streamed(source, stream.batch)?;
        let c = reference_scale(&gpa.mean);
        let mean: Vec<Point<D>> = gpa.mean.iter().map(|p| scale(*p, c)).collect();
        let mean_shape = Shape {
            name: "mean".into(),
            points: mean.clone(),
            facets: facets.clone(),
            landmarks: landmarks.clone(),
        };
        mean_shape.validate()?;
        let rows = mean.len() * D;
        let asked = match params.modes {
            ModeSelection::Count(m) => m,
            ModeSelection::Variance(_) => stream.max_modes,
        }
        .clamp(1, (n - 1).min(rows));
        let mut columns = |range: std::ops::Range<usize>| -> Result<Mat<f64>> {
            let shapes = read_checked(source, range.clone(), mean.len())?;
            let mut a = Mat::<f64>::zeros(rows, shapes.len());
            for (j, s) in shapes.iter().enumerate() {
                let x = tangent_shape(source, range.start + j, s, &gpa.mean)?;
                for (i, (p, m)) in x.iter().zip(&mean).enumerate() {
                    for d in 0..D {
                        a[(i * D + d, j)] = p[d] * c - m[d];
                    }
                }
            }
            Ok(a)
        };
        let p = randomized_pca(n, rows, asked, stream.batch, &stream.pca, &mut columns)?;
        check_variance(&p, mean.len(), n)?;
        let m = modes_kept(&p, params, n, true)?;
        let frame = data_frame(&mean, source, stream.batch)?;
        let mesh = mesher(
            &Shape {
                landmarks: Vec::new(),
                ..mean_shape
            },
            frame.s,
        )?;
        Ok(Atlas {
            mean,
            modes: p.modes.subcols(0, m).to_owned(),
            eigenvalues: p.eigenvalues[..m].to_vec(),
            cumulative_variance: p.cumulative_variance(),
            facets,
            landmarks,
            landmark_ids: Vec::new(),
            mesh,
            params: *params,
            training_shapes: n,
            data_frame: Some(frame),
            cut_facets: Vec::new(),
        })
    }

    /// `points` (reference frame) in the data's frame and unit (the training population's
    /// mean pose and size) when the atlas knows it ([`Atlas::data_frame`]), else as given.
    pub fn to_data_frame(&self, points: &[Point<D>]) -> Vec<Point<D>> {
        match &self.data_frame {
            Some(t) => points.iter().map(|p| t.apply(p)).collect(),
            None => points.to_vec(),
        }
    }

    /// The morph of the mean mesh by the mean shape's points (eq. 9), factorized once for
    /// every subject: [`crate::mesh::Morpher::new`].
    pub fn morpher(&self, params: &crate::ffd::FfdParams) -> Result<crate::mesh::Morpher<D>> {
        if !self.has_mesh() {
            return Err(Error::Parameter(
                "this atlas is a shape model without a mean mesh (built with --no-mesh): build it with a mesh to morph one onto subjects or instances".into(),
            ));
        }
        crate::mesh::Morpher::new(&self.mean, &self.mesh, params)
    }

    /// Number of modes `m`.
    pub fn num_modes(&self) -> usize {
        self.eigenvalues.len()
    }

    /// The mean as a shape.
    pub fn mean_shape(&self) -> Shape<D> {
        Shape {
            name: "mean".into(),
            points: self.mean.clone(),
            facets: self.facets.clone(),
            landmarks: self.landmarks.clone(),
        }
    }

    /// `S_tilde = S_bar + Psi w` (eq. 4), reference frame. `w.len() == m`.
    #[track_caller]
    pub fn instance(&self, w: &[f64]) -> Vec<Point<D>> {
        assert_eq!(w.len(), self.num_modes(), "instance: one weight per mode");
        combine(&self.mean, &self.modes, w)
    }

    /// `Psi^T (x - S_bar)`: the weights of the projection of `x` (reference frame, `N` points
    /// in correspondence) into the model.
    #[track_caller]
    pub fn coefficients(&self, x: &[Point<D>]) -> Vec<f64> {
        assert_eq!(
            x.len(),
            self.mean.len(),
            "coefficients: one point per model point"
        );
        (0..self.num_modes())
            .map(|k| {
                let col = self.modes.col(k);
                x.iter()
                    .zip(&self.mean)
                    .enumerate()
                    .map(|(i, (p, m))| (0..D).map(|d| col[i * D + d] * (p[d] - m[d])).sum::<f64>())
                    .sum()
            })
            .collect()
    }
}

/// `mean + modes w`, points of `D` coordinates interleaved in the rows of `modes`.
pub(super) fn combine<const D: usize>(
    mean: &[Point<D>],
    modes: &Mat<f64>,
    w: &[f64],
) -> Vec<Point<D>> {
    let mut out = mean.to_vec();
    for (k, &wk) in w.iter().enumerate() {
        if wk == 0.0 {
            continue;
        }
        let col = modes.col(k);
        for (i, p) in out.iter_mut().enumerate() {
            for d in 0..D {
                p[d] += wk * col[i * D + d];
            }
        }
    }
    out
}

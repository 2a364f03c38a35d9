//! The statistical atlas: the shape model (mean `S_bar`, modes `Psi`, eigenvalues `Lambda`,
//! sections 2.2-2.3) and the FE mesh of the mean (section 2.4); saved as one safetensors file.
//!
//! Reference frame: the GPA frame, centred at the mean's centroid and scaled so that the
//! mean's bounding box has largest side 1 (as the paper's hands in the unit box), so that the
//! paper's parameters (gamma, alpha) keep their meaning whatever the units of the data.

use crate::error::{Error, Result};
use crate::fe::quadmesh::{QuadMeshParams, quad_mesh};
use crate::fe::{ElementKind, FeMesh};
use crate::geometry::{Point, Shape, bounding_box, scale};
use crate::pca::pca;
use crate::procrustes::generalized_procrustes;
use faer::Mat;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// Version of the atlas file format written by this build.
pub const ATLAS_FORMAT_VERSION: &str = "2";

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

/// A statistical atlas in `D` dimensions.
#[derive(Clone, Debug)]
pub struct Atlas<const D: usize> {
    /// Mean shape `S_bar`, `N` points, reference frame.
    pub mean: Vec<Point<D>>,
    /// Modes `Psi`: `N·D × m`, orthonormal columns.
    pub modes: Mat<f64>,
    /// Eigenvalues `lambda_1..lambda_m` (reference-frame units squared).
    pub eigenvalues: Vec<f64>,
    /// Cumulative variance share of all `n_s - 1` modes of the training PCA.
    pub cumulative_variance: Vec<f64>,
    /// Boundary facets of the shapes (shared by all, they correspond).
    pub facets: Vec<[usize; D]>,
    /// Landmark indices.
    pub landmarks: Vec<usize>,
    /// FE mesh of the mean shape (reference frame).
    pub mesh: FeMesh<D>,
    /// Parameters used to build it.
    pub params: AtlasParams,
    /// Number of training shapes.
    pub training_shapes: usize,
}

/// Converts between `[f64; D]` and `[f64; E]` when `D == E` (a no-op used to call
/// dimension-specific code from generic code).
pub(crate) fn same_dim<const D: usize, const E: usize>(p: &Point<D>) -> Point<E> {
    std::array::from_fn(|d| p[d])
}

/// Meshes the mean shape: quadrilaterals in 2D ([`quad_mesh`]), hexahedra in 3D
/// ([`crate::fe::hexmesh::hex_mesh`], closed surfaces only).
pub fn mesh_mean_shape<const D: usize>(
    mean: &Shape<D>,
    element_size: f64,
    smoothing_passes: usize,
) -> Result<FeMesh<D>> {
    match D {
        2 => {
            let s2 = Shape::<2> {
                name: mean.name.clone(),
                points: mean.points.iter().map(same_dim::<D, 2>).collect(),
                facets: mean.facets.iter().map(|f| [f[0], f[1]]).collect(),
                landmarks: Vec::new(),
            };
            let m = quad_mesh(
                &s2,
                &QuadMeshParams {
                    element_size,
                    smoothing_passes,
                },
            )?;
            Ok(FeMesh {
                nodes: m.nodes.iter().map(same_dim::<2, D>).collect(),
                kind: m.kind,
                connectivity: m.connectivity,
                sets: Default::default(),
            })
        }
        _ => {
            let s3 = Shape::<3> {
                name: mean.name.clone(),
                points: mean.points.iter().map(same_dim::<D, 3>).collect(),
                facets: mean.facets.iter().map(|f| [f[0], f[1], f[2 % D]]).collect(),
                landmarks: Vec::new(),
            };
            let m = crate::fe::hexmesh::hex_mesh(
                &s3,
                &crate::fe::hexmesh::HexMeshParams {
                    element_size,
                    smoothing_passes,
                },
            )?;
            Ok(FeMesh {
                nodes: m.mesh.nodes.iter().map(same_dim::<3, D>).collect(),
                kind: m.mesh.kind,
                connectivity: m.mesh.connectivity,
                sets: Default::default(),
            })
        }
    }
}

/// The data section of a safetensors file (after the 8-byte header length and the header).
fn data_section(bytes: &[u8]) -> Option<&[u8]> {
    let n = u64::from_le_bytes(bytes.get(..8)?.try_into().ok()?);
    let start = usize::try_from(n).ok()?.checked_add(8)?;
    bytes.get(start..)
}

/// CRC-32 of an atlas: its tensors' bytes, then every metadata entry but the checksum, in
/// key order (`key=value;`).
fn atlas_checksum(data: &[u8], meta: &HashMap<String, String>) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(data);
    let mut keys: Vec<&String> = meta.keys().filter(|k| *k != "checksum_crc32").collect();
    keys.sort();
    for k in keys {
        h.update(k.as_bytes());
        h.update(b"=");
        h.update(meta[k].as_bytes());
        h.update(b";");
    }
    h.finalize()
}

/// The dimension an atlas file declares, read from its header only (the safetensors header:
/// an 8-byte length, then JSON with the `__metadata__` that [`Atlas::save`] writes).
pub fn atlas_dimension(path: &Path) -> Result<usize> {
    use std::io::Read as _;
    let bad = |m: String| Error::Atlas {
        path: path.to_path_buf(),
        message: m,
    };
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut len = [0u8; 8];
    f.read_exact(&mut len)
        .map_err(|_| bad("not a safetensors file (too short)".into()))?;
    let n = u64::from_le_bytes(len);
    if n > 100_000_000 {
        return Err(bad(format!("a header of {n} bytes: not an atlas")));
    }
    let mut header = vec![0u8; n as usize];
    f.read_exact(&mut header)
        .map_err(|_| bad("the header is truncated".into()))?;
    let json: serde_json::Value = serde_json::from_slice(&header)
        .map_err(|e| bad(format!("the header is not JSON ({e})")))?;
    json["__metadata__"]["dimension"]
        .as_str()
        .and_then(|d| d.parse().ok())
        .filter(|d| *d == 2 || *d == 3)
        .ok_or_else(|| {
            bad("no dimension in the metadata; write atlases with `atlasmesh build`".into())
        })
}

impl<const D: usize> Atlas<D> {
    /// Builds the atlas from shapes in point correspondence (same count, same facets): GPA
    /// with tangent projection, PCA, mode selection, and the FE mesh of the mean.
    pub fn build(shapes: &[Shape<D>], params: &AtlasParams) -> Result<Self> {
        Self::build_meshed(shapes, params, |mean| {
            mesh_mean_shape(mean, params.element_size, params.smoothing_passes)
        })
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
                let t = crate::procrustes::fit_similarity(&s.points, &mean.points, None);
                for (acc, p) in nodes.iter_mut().zip(&m.nodes) {
                    let q = t.apply(p);
                    for d in 0..D {
                        acc[d] += q[d] / meshes.len() as f64;
                    }
                }
            }
            let mesh = meshes[0].with_nodes(nodes);
            let q = crate::fe::quality::summarize(&crate::fe::quality::mesh_quality(&mesh));
            if q.inverted_elements > 0 {
                return Err(Error::Mesh(format!(
                    "the mean of the template meshes has {} inverted elements",
                    q.inverted_elements
                )));
            }
            Ok(mesh)
        })
    }

    fn build_meshed(
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
                    "shape {} has {} points but shape {} has {}; use --resample",
                    s.name,
                    s.points.len(),
                    shapes[0].name,
                    shapes[0].points.len()
                )));
            }
        }
        let gpa =
            generalized_procrustes(&shapes.iter().map(|s| s.points.clone()).collect::<Vec<_>>())?;
        let (lo, hi) = bounding_box(&gpa.mean);
        let ext = (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
        let c = 1.0 / ext;
        let mean: Vec<Point<D>> = gpa.mean.iter().map(|p| scale(*p, c)).collect();
        let aligned: Vec<Vec<Point<D>>> = gpa
            .aligned
            .iter()
            .map(|s| s.iter().map(|p| scale(*p, c)).collect())
            .collect();
        let p = pca(&aligned, &mean)?;
        // Identical shapes (after alignment): nothing to model. In the reference frame (largest
        // side 1) the total variance of real populations is far above rounding (hands ~1e-3).
        let total: f64 = p.eigenvalues.iter().sum();
        if total.is_nan() || total <= 1e-20 * mean.len() as f64 {
            return Err(Error::Population(format!(
                "the {} shapes are identical after alignment (total variance {total:.1e}): there \
                 is no variance to model; give shapes that differ",
                shapes.len()
            )));
        }
        let m = match params.modes {
            ModeSelection::Count(m) => {
                if m == 0 || m > p.eigenvalues.len() {
                    return Err(Error::Parameter(format!(
                        "--modes {m}: the population of {} shapes has {} modes",
                        shapes.len(),
                        p.eigenvalues.len()
                    )));
                }
                m
            }
            ModeSelection::Variance(v) => {
                if !(v > 0.0 && v <= 1.0) {
                    return Err(Error::Parameter(format!(
                        "--variance {v} must be in (0, 1]"
                    )));
                }
                p.modes_for_variance(v)
            }
        };
        let mean_shape = Shape {
            name: "mean".into(),
            points: mean.clone(),
            facets: shapes[0].facets.clone(),
            landmarks: Vec::new(),
        };
        let mesh = mesher(&mean_shape)?;
        Ok(Atlas {
            mean,
            modes: p.modes.subcols(0, m).to_owned(),
            eigenvalues: p.eigenvalues[..m].to_vec(),
            cumulative_variance: p.cumulative_variance(),
            facets: shapes[0].facets.clone(),
            landmarks: shapes[0].landmarks.clone(),
            mesh,
            params: *params,
            training_shapes: shapes.len(),
        })
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
        let mut out = self.mean.clone();
        for (k, &wk) in w.iter().enumerate() {
            if wk == 0.0 {
                continue;
            }
            let col = self.modes.col(k);
            for (i, p) in out.iter_mut().enumerate() {
                for d in 0..D {
                    p[d] += wk * col[i * D + d];
                }
            }
        }
        out
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

    /// Saves the atlas as safetensors: tensors `mean [N, D]`, `modes [N·D, m]`,
    /// `eigenvalues [m]`, `cumulative_variance [n_s-1]`, `facets [F, D]` (i64),
    /// `landmarks [L]` (i64), `mesh_nodes [#nodes, D]`, `mesh_elements [#el, k]` (i64); metadata
    /// `format`, `format_version`, `dimension`, `element_kind`, `params` (JSON), `mesh_sets`
    /// (JSON: node sets, element sets, surfaces of the mean mesh),
    /// `training_shapes`. Written to a temporary name, then renamed.
    pub fn save(&self, path: &Path) -> Result<()> {
        use safetensors::{Dtype, tensor::TensorView};
        let f64s = |v: Vec<f64>| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let i64s = |v: Vec<usize>| -> Vec<u8> {
            v.iter().flat_map(|&x| (x as i64).to_le_bytes()).collect()
        };
        let n = self.mean.len();
        let m = self.num_modes();
        let k = self.mesh.kind.nodes();
        let modes: Vec<f64> = (0..n * D)
            .flat_map(|r| (0..m).map(move |c| (r, c)))
            .map(|(r, c)| self.modes[(r, c)])
            .collect();
        let bufs: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = vec![
            (
                "mean",
                Dtype::F64,
                vec![n, D],
                f64s(self.mean.iter().flatten().copied().collect()),
            ),
            ("modes", Dtype::F64, vec![n * D, m], f64s(modes)),
            (
                "eigenvalues",
                Dtype::F64,
                vec![m],
                f64s(self.eigenvalues.clone()),
            ),
            (
                "cumulative_variance",
                Dtype::F64,
                vec![self.cumulative_variance.len()],
                f64s(self.cumulative_variance.clone()),
            ),
            (
                "facets",
                Dtype::I64,
                vec![self.facets.len(), D],
                i64s(self.facets.iter().flatten().copied().collect()),
            ),
            (
                "landmarks",
                Dtype::I64,
                vec![self.landmarks.len()],
                i64s(self.landmarks.clone()),
            ),
            (
                "mesh_nodes",
                Dtype::F64,
                vec![self.mesh.nodes.len(), D],
                f64s(self.mesh.nodes.iter().flatten().copied().collect()),
            ),
            (
                "mesh_elements",
                Dtype::I64,
                vec![self.mesh.num_elements(), k],
                i64s(self.mesh.connectivity.clone()),
            ),
        ];
        let mut views = Vec::new();
        for (name, dt, shape, data) in &bufs {
            views.push((
                *name,
                TensorView::new(*dt, shape.clone(), data)
                    .map_err(|e| Error::Numerical(format!("atlas tensor {name}: {e}")))?,
            ));
        }
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), "atlasmesh-atlas".to_string());
        meta.insert(
            "format_version".to_string(),
            ATLAS_FORMAT_VERSION.to_string(),
        );
        meta.insert("dimension".to_string(), D.to_string());
        meta.insert(
            "element_kind".to_string(),
            self.mesh.kind.name().to_string(),
        );
        meta.insert(
            "training_shapes".to_string(),
            self.training_shapes.to_string(),
        );
        meta.insert(
            "params".to_string(),
            serde_json::to_string(&self.params).unwrap_or_default(),
        );
        meta.insert(
            "mesh_sets".to_string(),
            serde_json::to_string(&self.mesh.sets).unwrap_or_default(),
        );
        // The checksum covers the tensors' bytes and the other metadata: serialize once to
        // learn the data section, then again with the checksum in the header.
        let first = safetensors::serialize(views.clone(), Some(meta.clone()))
            .map_err(|e| Error::Numerical(format!("serializing the atlas: {e}")))?;
        let crc = atlas_checksum(data_section(&first).unwrap_or_default(), &meta);
        meta.insert("checksum_crc32".to_string(), format!("{crc:08x}"));
        let bytes = safetensors::serialize(views, Some(meta))
            .map_err(|e| Error::Numerical(format!("serializing the atlas: {e}")))?;
        crate::io::write_atomic(path, &bytes)
    }

    /// Loads an atlas written by [`Atlas::save`], checking format, version, dimension and
    /// shapes of every tensor.
    pub fn load(path: &Path) -> Result<Self> {
        use safetensors::{Dtype, SafeTensors};
        let bad = |m: String| Error::Atlas {
            path: path.to_path_buf(),
            message: m,
        };
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let (_, meta) = SafeTensors::read_metadata(&bytes)
            .map_err(|e| bad(format!("not a safetensors file ({e})")))?;
        let meta = meta.metadata().clone().unwrap_or_default();
        if meta.get("format").map(String::as_str) != Some("atlasmesh-atlas") {
            return Err(bad(
                "no atlasmesh metadata; write atlases with `atlasmesh build`".into(),
            ));
        }
        let version = meta.get("format_version").cloned().unwrap_or_default();
        if version != ATLAS_FORMAT_VERSION {
            return Err(bad(format!(
                "format version {version:?}, this build reads version {ATLAS_FORMAT_VERSION}; rebuild the atlas"
            )));
        }
        let stored = meta.get("checksum_crc32").cloned().unwrap_or_default();
        let mut rest = meta.clone();
        rest.remove("checksum_crc32");
        let crc = atlas_checksum(data_section(&bytes).unwrap_or_default(), &rest);
        if stored != format!("{crc:08x}") {
            return Err(bad(format!(
                "checksum mismatch (stored {stored:?}, computed {crc:08x}): the file is corrupted \
                 or was changed after it was written; rebuild the atlas or copy it again"
            )));
        }
        let dim: usize = meta
            .get("dimension")
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        if dim != D {
            return Err(bad(format!("the atlas is {dim}D, {D}D was expected")));
        }
        let kind = meta
            .get("element_kind")
            .and_then(|s| ElementKind::from_name(s))
            .ok_or_else(|| bad("unknown element kind".into()))?;
        let params: AtlasParams = meta
            .get("params")
            .and_then(|s| serde_json::from_str(s).ok())
            .ok_or_else(|| bad("missing or malformed params".into()))?;
        let sets: crate::fe::MeshSets = match meta.get("mesh_sets") {
            None => Default::default(),
            Some(j) => serde_json::from_str(j)
                .map_err(|e| bad(format!("malformed mesh_sets metadata: {e}")))?,
        };
        let training_shapes = meta
            .get("training_shapes")
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let st = SafeTensors::deserialize(&bytes).map_err(|e| bad(format!("{e}")))?;
        let get = |name: &str, dt: Dtype, cols: Option<usize>| -> Result<(Vec<usize>, Vec<u8>)> {
            let t = st
                .tensor(name)
                .map_err(|_| bad(format!("tensor {name} is missing")))?;
            if t.dtype() != dt {
                return Err(bad(format!(
                    "tensor {name} has type {:?}, {dt:?} expected",
                    t.dtype()
                )));
            }
            if let Some(c) = cols
                && (t.shape().len() != 2 || t.shape()[1] != c)
            {
                return Err(bad(format!(
                    "tensor {name} has shape {:?}, [_, {c}] expected",
                    t.shape()
                )));
            }
            Ok((t.shape().to_vec(), t.data().to_vec()))
        };
        let f64v = |b: &[u8]| -> Vec<f64> {
            b.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        };
        let idxv = |b: &[u8], limit: usize, what: &str| -> Result<Vec<usize>> {
            b.chunks_exact(8)
                .map(|c| {
                    let v = i64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
                    if v < 0 || v as usize >= limit {
                        Err(bad(format!("{what} index {v} out of range")))
                    } else {
                        Ok(v as usize)
                    }
                })
                .collect()
        };
        let (ms, mb) = get("mean", Dtype::F64, Some(D))?;
        let n = ms[0];
        let mean: Vec<Point<D>> = f64v(&mb)
            .chunks_exact(D)
            .map(|c| std::array::from_fn(|d| c[d]))
            .collect();
        let (es, eb) = get("eigenvalues", Dtype::F64, None)?;
        let m = es.first().copied().unwrap_or(0);
        let (mds, mdb) = get("modes", Dtype::F64, Some(m))?;
        if mds[0] != n * D {
            return Err(bad(format!(
                "modes have {} rows, {} expected",
                mds[0],
                n * D
            )));
        }
        let mv = f64v(&mdb);
        let modes = Mat::from_fn(n * D, m, |r, c| mv[r * m + c]);
        let (_, cvb) = get("cumulative_variance", Dtype::F64, None)?;
        let (_, fb) = get("facets", Dtype::I64, Some(D))?;
        let facets = idxv(&fb, n, "facet")?
            .chunks_exact(D)
            .map(|c| std::array::from_fn(|d| c[d]))
            .collect();
        let (_, lb) = get("landmarks", Dtype::I64, None)?;
        let (_, nb) = get("mesh_nodes", Dtype::F64, Some(D))?;
        let nodes: Vec<Point<D>> = f64v(&nb)
            .chunks_exact(D)
            .map(|c| std::array::from_fn(|d| c[d]))
            .collect();
        let (_, elb) = get("mesh_elements", Dtype::I64, Some(kind.nodes()))?;
        let connectivity = idxv(&elb, nodes.len(), "mesh node")?;
        sets.check(kind, nodes.len(), connectivity.len() / kind.nodes())
            .map_err(|m| bad(format!("mesh sets: {m}")))?;
        let all: Vec<f64> = mean
            .iter()
            .flatten()
            .chain(nodes.iter().flatten())
            .copied()
            .chain(mv.iter().copied())
            .collect();
        if all.iter().any(|x| !x.is_finite()) {
            return Err(bad("contains NaN or infinite values".into()));
        }
        Ok(Atlas {
            mean,
            modes,
            eigenvalues: f64v(&eb),
            cumulative_variance: f64v(&cvb),
            facets,
            landmarks: idxv(&lb, n, "landmark")?,
            mesh: FeMesh {
                nodes,
                kind,
                connectivity,
                sets,
            },
            params,
            training_shapes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn ellipses(n: usize) -> Vec<Shape<2>> {
        (0..n)
            .map(|k| {
                let a = 1.0 + 0.2 * (k as f64 * 1.7).sin();
                let b = 0.6 + 0.1 * (k as f64 * 2.3).cos();
                let bump = 0.1 * (k as f64 * 0.9).cos();
                let pts = (0..80)
                    .map(|i| {
                        let t = i as f64 / 80.0 * std::f64::consts::TAU;
                        [a * t.cos() + bump * (3.0 * t).cos(), b * t.sin()]
                    })
                    .collect();
                Shape::polyline(format!("e{k}"), pts, true)
            })
            .collect()
    }

    #[test]
    fn a_model_instance_gives_back_its_weights() {
        let atlas = Atlas::build(
            &ellipses(8),
            &AtlasParams {
                modes: ModeSelection::Count(3),
                element_size: 0.05,
                smoothing_passes: 2,
            },
        )
        .unwrap();
        let w: Vec<f64> = atlas
            .eigenvalues
            .iter()
            .enumerate()
            .map(|(k, l)| l.sqrt() * (k as f64 - 1.0))
            .collect();
        let x = atlas.instance(&w);
        let back = atlas.coefficients(&x);
        for (a, b) in w.iter().zip(&back) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn atlas_survives_a_save_load_round_trip() {
        let atlas = Atlas::build(
            &ellipses(6),
            &AtlasParams {
                modes: ModeSelection::Count(2),
                element_size: 0.05,
                smoothing_passes: 2,
            },
        )
        .unwrap();
        let dir = std::env::temp_dir().join(format!("atlasmesh-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.safetensors");
        atlas.save(&p).unwrap();
        let b = Atlas::<2>::load(&p).unwrap();
        assert_eq!(atlas.mean, b.mean);
        assert_eq!(atlas.modes, b.modes);
        assert_eq!(atlas.mesh, b.mesh);
        assert_eq!(atlas.params, b.params);
        assert!(Atlas::<3>::load(&p).unwrap_err().to_string().contains("2D"));
        std::fs::write(&p, b"garbage").unwrap();
        assert!(Atlas::<2>::load(&p).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}

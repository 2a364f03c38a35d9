//! The atlas file: one safetensors file with the shape model, the mean mesh and its sets,
//! a format version and a checksum.

use crate::error::{Error, Result};
use crate::geometry::{Point, Similarity};
use crate::mesh::{ElementKind, FeMesh};
use crate::model::{Atlas, AtlasParams};
use faer::Mat;
use std::collections::HashMap;
use std::path::Path;

/// Version of the atlas file format written by this build (3: the data frame, see
/// [`Atlas::data_frame`]).
pub const ATLAS_FORMAT_VERSION: &str = "3";

/// The earlier versions this build still reads (2: without the data frame).
pub const ATLAS_FORMAT_VERSIONS_READ: [&str; 2] = ["2", "3"];

/// The data frame as stored in the metadata (`data_frame`, JSON).
#[derive(serde::Serialize, serde::Deserialize)]
struct DataFrame {
    /// Scale from the reference frame to the data's unit.
    scale: f64,
    /// Rotation, row-major.
    rotation: Vec<Vec<f64>>,
    /// Translation, in the data's unit.
    translation: Vec<f64>,
}

impl DataFrame {
    fn of<const D: usize>(t: &Similarity<D>) -> Self {
        DataFrame {
            scale: t.s,
            rotation: t.r.iter().map(|r| r.to_vec()).collect(),
            translation: t.t.to_vec(),
        }
    }

    /// The similarity, checked: a finite positive scale, a rotation (orthonormal, det +1 to
    /// 1e-9), a finite translation, all of dimension `D`.
    fn similarity<const D: usize>(&self) -> std::result::Result<Similarity<D>, String> {
        let bad = || {
            "data_frame: a scale from 1e-9 to 1e9, a DxD rotation and a translation of D finite numbers are expected".to_string()
        };
        // (A scale beyond 1e±9 is no unit a shape was ever measured in: 1e300 made meshes of
        // 1e299 that their checks called perfect.)
        if !(self.scale.is_finite() && (1e-9..=1e9).contains(&self.scale))
            || self.rotation.len() != D
            || self.rotation.iter().any(|r| r.len() != D)
            || self.translation.len() != D
        {
            return Err(bad());
        }
        let r: [[f64; D]; D] =
            std::array::from_fn(|i| std::array::from_fn(|j| self.rotation[i][j]));
        let t: Point<D> = std::array::from_fn(|d| self.translation[d]);
        if r.iter().flatten().chain(&t).any(|x| !x.is_finite()) {
            return Err(bad());
        }
        for i in 0..D {
            for j in 0..D {
                let dot: f64 = (0..D).map(|k| r[i][k] * r[j][k]).sum();
                if (dot - if i == j { 1.0 } else { 0.0 }).abs() > 1e-9 {
                    return Err("data_frame: the rotation is not orthonormal".into());
                }
            }
        }
        let det = if D == 2 {
            r[0][0] * r[1][1] - r[0][1] * r[1][0]
        } else {
            r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
                - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
                + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0])
        };
        if (det - 1.0).abs() > 1e-9 {
            return Err("data_frame: the rotation is a reflection".into());
        }
        Ok(Similarity {
            s: self.scale,
            r,
            t,
        })
    }
}

/// The data section of a safetensors file (after the 8-byte header length and the header).
pub(crate) fn data_section(bytes: &[u8]) -> Option<&[u8]> {
    let n = u64::from_le_bytes(bytes.get(..8)?.try_into().ok()?);
    let start = usize::try_from(n).ok()?.checked_add(8)?;
    bytes.get(start..)
}

/// The safetensors file `bytes` with its header's keys in sorted order (the metadata's order
/// is otherwise that of a hash map, new in every run): the same atlas is the same file, byte
/// for byte. The header stays padded with spaces to a multiple of 8 bytes, as safetensors
/// writes it; the data section is unchanged (its offsets are relative to it).
fn sorted_header(bytes: &[u8]) -> Result<Vec<u8>> {
    fn sorted(v: serde_json::Value) -> serde_json::Value {
        match v {
            serde_json::Value::Object(m) => {
                let mut entries: Vec<(String, serde_json::Value)> = m.into_iter().collect();
                entries.sort_by(|a, b| a.0.cmp(&b.0));
                serde_json::Value::Object(
                    entries.into_iter().map(|(k, v)| (k, sorted(v))).collect(),
                )
            }
            other => other,
        }
    }
    let bad = |m: &str| Error::Numerical(format!("serializing the atlas: {m}"));
    let data = data_section(bytes).ok_or_else(|| bad("no data section"))?;
    let header = &bytes[8..bytes.len() - data.len()];
    let json: serde_json::Value =
        serde_json::from_slice(header).map_err(|e| bad(&format!("its header: {e}")))?;
    let mut header = serde_json::to_vec(&sorted(json)).map_err(|e| bad(&e.to_string()))?;
    header.resize(header.len().next_multiple_of(8), b' ');
    let mut out = Vec::with_capacity(8 + header.len() + data.len());
    out.extend_from_slice(&(header.len() as u64).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(data);
    Ok(out)
}

/// CRC-32 of an atlas: its tensors' bytes, then every metadata entry but the checksum, in
/// key order (`key=value;`).
pub(crate) fn atlas_checksum(data: &[u8], meta: &HashMap<String, String>) -> u32 {
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
    let size = crate::formats::input::regular_file(path)?.len();
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut len = [0u8; 8];
    f.read_exact(&mut len)
        .map_err(|_| bad("not a safetensors file (too short)".into()))?;
    let n = u64::from_le_bytes(len);
    if n > 100_000_000 || n > size {
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
    /// Saves the atlas as safetensors: tensors `mean [N, D]`, `modes [N·D, m]`,
    /// `eigenvalues [m]`, `cumulative_variance [n_s-1]`, `facets [F, D]` (i64),
    /// `landmarks [L]` (i64), `mesh_nodes [#nodes, D]`, `mesh_elements [#el, k]` (i64); metadata
    /// `format`, `format_version`, `dimension`, `element_kind`, `params` (JSON), `mesh_sets`
    /// (JSON: node sets, element sets, surfaces of the mean mesh),
    /// `training_shapes`. Written to a temporary name, then renamed.
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::formats::write_atomic(path, &self.to_bytes()?)
    }

    /// The atlas file's bytes, as [`Atlas::save`] writes them (checksum included).
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
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
        let mut meta = self.metadata();
        // The checksum covers the tensors' bytes and the other metadata: serialize once to
        // learn the data section, then again with the checksum in the header.
        let first = safetensors::serialize(views.clone(), Some(meta.clone()))
            .map_err(|e| Error::Numerical(format!("serializing the atlas: {e}")))?;
        let crc = atlas_checksum(data_section(&first).unwrap_or_default(), &meta);
        meta.insert("checksum_crc32".to_string(), format!("{crc:08x}"));
        let bytes = safetensors::serialize(views, Some(meta))
            .map_err(|e| Error::Numerical(format!("serializing the atlas: {e}")))?;
        sorted_header(&bytes)
    }

    /// The atlas file's metadata (everything but the tensors and the checksum).
    fn metadata(&self) -> HashMap<String, String> {
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), "atlasmesh-atlas".to_string());
        // An atlas without its data frame is one of version 2 (read from such a file).
        let version = if self.data_frame.is_some() {
            ATLAS_FORMAT_VERSION
        } else {
            "2"
        };
        meta.insert("format_version".to_string(), version.to_string());
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
        if !self.has_mesh() {
            meta.insert("mesh".to_string(), "none".to_string());
        }
        if !self.cut_facets.is_empty() {
            meta.insert(
                "cut_facets".to_string(),
                serde_json::to_string(&self.cut_facets).unwrap_or_default(),
            );
        }
        if !self.landmark_ids.is_empty() {
            meta.insert(
                "landmark_ids".to_string(),
                serde_json::to_string(&self.landmark_ids).unwrap_or_default(),
            );
        }
        meta.insert(
            "mesh_sets".to_string(),
            serde_json::to_string(&self.mesh.sets).unwrap_or_default(),
        );
        if let Some(t) = &self.data_frame {
            meta.insert(
                "data_frame".to_string(),
                serde_json::to_string(&DataFrame::of(t)).unwrap_or_default(),
            );
        }
        meta
    }

    /// Loads an atlas written by [`Atlas::save`], checking format, version, dimension and
    /// shapes of every tensor.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = crate::formats::read_input(path)?;
        Self::from_bytes(path, &bytes)
    }

    /// [`Atlas::load`] of an atlas file's bytes (`path` only names the file in messages).
    #[allow(
        clippy::too_many_lines,
        reason = "a parser: the file's tensors and metadata checked in the order the format lists them"
    )]
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self> {
        use safetensors::{Dtype, SafeTensors};
        let bad = |m: String| Error::Atlas {
            path: path.to_path_buf(),
            message: m,
        };
        let AtlasMetadata {
            kind,
            params,
            sets,
            training_shapes,
            data_frame,
            model_only,
            landmark_ids,
            cut_facets,
        } = AtlasMetadata::<D>::of(path, bytes)?;
        let st = SafeTensors::deserialize(bytes).map_err(|e| bad(format!("{e}")))?;
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
        if es.len() != 1 {
            return Err(bad(format!(
                "tensor eigenvalues has shape {es:?}, [_] expected"
            )));
        }
        let atlas = Atlas {
            mean,
            modes,
            eigenvalues: f64v(&eb),
            cumulative_variance: f64v(&cvb),
            facets,
            landmarks: idxv(&lb, n, "landmark")?,
            landmark_ids,
            cut_facets,
            mesh: FeMesh {
                nodes,
                kind,
                connectivity,
                sets,
            },
            params,
            training_shapes,
            data_frame,
        };
        validate(&atlas, model_only).map_err(bad)?;
        Ok(atlas)
    }
}

/// The invariants of an atlas that its tensors' shapes do not tell: a mean with facets,
/// positive finite eigenvalues in falling order, at most as many as the cumulative variance
/// has modes, a cumulative variance that rises within [0, 1], a mesh of
/// this dimension's elements, none degenerate or inverted.
fn validate<const D: usize>(a: &Atlas<D>, model_only: bool) -> std::result::Result<(), String> {
    if a.mean.len() < D + 1 || (a.facets.is_empty() && !model_only) {
        return Err(format!(
            "the mean shape has {} points and {} facets",
            a.mean.len(),
            a.facets.len()
        ));
    }
    if let Some(l) = a.eigenvalues.iter().find(|l| !(l.is_finite() && **l > 0.0)) {
        return Err(format!(
            "an eigenvalue is {l}: the variances must be positive"
        ));
    }
    if a.eigenvalues.windows(2).any(|w| w[1] > w[0]) {
        return Err("the eigenvalues must not rise (PCA orders the modes by variance)".into());
    }
    let cv = &a.cumulative_variance;
    if cv.len() < a.eigenvalues.len() {
        return Err(format!(
            "{} eigenvalues but a cumulative variance of {} modes",
            a.eigenvalues.len(),
            cv.len()
        ));
    }
    if cv.is_empty()
        || cv
            .iter()
            .any(|c| !c.is_finite() || *c < 0.0 || *c > 1.0 + 1e-9)
        || cv.windows(2).any(|w| w[1] < w[0] - 1e-12)
    {
        return Err("the cumulative variance must rise within [0, 1]".into());
    }
    if a.cut_facets.windows(2).any(|w| w[0] >= w[1])
        || a.cut_facets.last().is_some_and(|&f| f >= a.facets.len())
    {
        return Err(format!(
            "cut_facets: sorted distinct facet indices below {} expected",
            a.facets.len()
        ));
    }
    if !a.landmark_ids.is_empty() && a.landmark_ids.len() != a.landmarks.len() {
        return Err(format!(
            "{} landmark ids for {} landmarks",
            a.landmark_ids.len(),
            a.landmarks.len()
        ));
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(id) = a.landmark_ids.iter().find(|id| !seen.insert(id.as_str())) {
        return Err(format!("landmark id {id:?} is given twice"));
    }
    let kind = a.mesh.kind;
    if kind.dimension() != D {
        return Err(format!("a {D}D atlas with {} elements", kind.name()));
    }
    if model_only {
        // A shape model without a mean mesh (`build --no-mesh`): it must say so.
        return if a.mesh.nodes.is_empty() && a.mesh.num_elements() == 0 {
            Ok(())
        } else {
            Err(format!(
                "the mean mesh has no elements but {} nodes",
                a.mesh.nodes.len()
            ))
        };
    }
    if a.mesh.num_elements() == 0 {
        return Err("the mean mesh has no elements".into());
    }
    let q = crate::mesh::quality::summarize(&crate::mesh::quality::mesh_quality(&a.mesh));
    if !(q.jacobian_min.is_finite() && q.jacobian_min > 0.0 && q.scaled_jacobian_min.is_finite()) {
        return Err(format!(
            "the mean mesh has {} inverted or degenerate element(s) (smallest corner Jacobian {:e})",
            q.inverted_elements.max(1),
            q.jacobian_min
        ));
    }
    Ok(())
}

/// What an atlas file's metadata says, checked: the format and its version, the checksum of
/// the whole file, the dimension, the element kind, the parameters, the mesh sets.
struct AtlasMetadata<const D: usize> {
    kind: ElementKind,
    params: AtlasParams,
    sets: crate::mesh::MeshSets,
    training_shapes: usize,
    data_frame: Option<Similarity<D>>,
    /// A shape model without a mean mesh (`mesh = none`).
    model_only: bool,
    /// The landmarks' ids (`landmark_ids`, optional).
    landmark_ids: Vec<String>,
    /// The facets of the cut (`cut_facets`, optional).
    cut_facets: Vec<usize>,
}

impl<const D: usize> AtlasMetadata<D> {
    /// The metadata of the atlas file `bytes` (named `path`), for an atlas of dimension `D`.
    fn of(path: &Path, bytes: &[u8]) -> Result<Self> {
        use safetensors::SafeTensors;
        let bad = |m: String| Error::Atlas {
            path: path.to_path_buf(),
            message: m,
        };
        let (_, meta) = SafeTensors::read_metadata(bytes)
            .map_err(|e| bad(format!("not a safetensors file ({e})")))?;
        let meta = meta.metadata().clone().unwrap_or_default();
        if meta.get("format").map(String::as_str) != Some("atlasmesh-atlas") {
            return Err(bad(
                "no atlasmesh metadata; write atlases with `atlasmesh build`".into(),
            ));
        }
        let version = meta.get("format_version").cloned().unwrap_or_default();
        if !ATLAS_FORMAT_VERSIONS_READ.contains(&version.as_str()) {
            return Err(bad(format!(
                "format version {version:?}, this build reads versions {}; rebuild the atlas",
                ATLAS_FORMAT_VERSIONS_READ.join(" and ")
            )));
        }
        let stored = meta.get("checksum_crc32").cloned().unwrap_or_default();
        let mut rest = meta.clone();
        rest.remove("checksum_crc32");
        let crc = atlas_checksum(data_section(bytes).unwrap_or_default(), &rest);
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
        let sets: crate::mesh::MeshSets = match meta.get("mesh_sets") {
            None => Default::default(),
            Some(j) => serde_json::from_str(j)
                .map_err(|e| bad(format!("malformed mesh_sets metadata: {e}")))?,
        };
        let training_shapes = meta
            .get("training_shapes")
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let data_frame = match meta.get("data_frame") {
            None if version == "2" => None,
            None => return Err(bad("no data_frame in a version 3 atlas".into())),
            Some(j) => Some(
                serde_json::from_str::<DataFrame>(j)
                    .map_err(|e| bad(format!("malformed data_frame metadata: {e}")))?
                    .similarity::<D>()
                    .map_err(bad)?,
            ),
        };
        let model_only = match meta.get("mesh").map(String::as_str) {
            None => false,
            Some("none") => true,
            Some(other) => {
                return Err(bad(format!(
                    "mesh metadata {other:?}, \"none\" or nothing expected"
                )));
            }
        };
        let landmark_ids: Vec<String> = match meta.get("landmark_ids") {
            None => Vec::new(),
            Some(j) => serde_json::from_str(j)
                .map_err(|e| bad(format!("malformed landmark_ids metadata: {e}")))?,
        };
        let cut_facets: Vec<usize> = match meta.get("cut_facets") {
            None => Vec::new(),
            Some(j) => serde_json::from_str(j)
                .map_err(|e| bad(format!("malformed cut_facets metadata: {e}")))?,
        };
        Ok(AtlasMetadata {
            landmark_ids,
            cut_facets,
            model_only,
            kind,
            params,
            sets,
            training_shapes,
            data_frame,
        })
    }
}

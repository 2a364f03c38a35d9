//! Node sets, element sets and surfaces defined on the mean mesh by a small TOML file, so that
//! every subject's mesh carries the same sets by name (the morph moves nodes, never renumbers
//! them): the boundary conditions of a study are set once, on the mean.
//!
//! Frame: positions are fractions of the mean mesh's bounding box (0 at its minimum, 1 at its
//! maximum on every axis), radii fractions of its largest side, so that one file serves an
//! atlas in any unit. Directions are in the atlas's reference frame (the mean's axes).
//!
//! ```toml
//! [[node_set]]            # nodes in a box
//! name = "FIXED"
//! box = { min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 0.05] }
//!
//! [[node_set]]            # nodes on one side of a plane across an axis ("x", "y", "z",
//! name = "LOAD"           # or "longest": the bounding box's longest side)
//! half_space = { axis = "z", above = 0.95 }
//!
//! [[node_set]]            # nodes within a radius of an atlas landmark
//! name = "TIP"
//! landmark = 2
//! radius = 0.05
//!
//! [[element_set]]         # elements whose centroid is selected
//! name = "DISTAL"
//! half_space = { axis = "z", below = 0.3 }
//!
//! [[surface]]             # boundary faces whose outward normal lies within an angle of
//! name = "TOP"            # a direction (optionally also inside a box or half-space)
//! facing = { direction = [0.0, 0.0, 1.0], angle = 30.0 }
//! half_space = { axis = "z", above = 0.9 }
//! ```
//!
//! A node set may also use `facing` (the nodes of the boundary faces it selects). A set that
//! selects nothing is an error.

use super::{BoundaryFace, FeMesh, MeshSets, boundary_faces};
use crate::error::{Error, Result};
use crate::geometry::{Point, bounding_box, dist2};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A sets file, parsed.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetsConfig {
    /// `[[node_set]]` tables.
    #[serde(default)]
    pub node_set: Vec<SetSpec>,
    /// `[[element_set]]` tables: elements whose centroid is selected.
    #[serde(default)]
    pub element_set: Vec<SetSpec>,
    /// `[[surface]]` tables: boundary faces.
    #[serde(default)]
    pub surface: Vec<SetSpec>,
    /// The file it was read from (for messages).
    #[serde(skip)]
    pub source: PathBuf,
}

/// One set: a name and one or more selectors (all must hold).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetSpec {
    /// The set's name in every mesh written.
    pub name: String,
    /// `box`: inside a box.
    #[serde(default, rename = "box")]
    pub bbox: Option<BoxSpec>,
    /// `half_space`: on one side of a plane across an axis.
    #[serde(default)]
    pub half_space: Option<HalfSpace>,
    /// `landmark`: within `radius` of this atlas landmark.
    #[serde(default)]
    pub landmark: Option<usize>,
    /// `radius` around `landmark` (a share of the bounding box's largest side).
    #[serde(default)]
    pub radius: Option<f64>,
    /// `facing`: boundary faces looking along a direction.
    #[serde(default)]
    pub facing: Option<Facing>,
}

/// An axis-aligned box in bounding-box fractions.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Lower corner (bounding-box fractions, one per axis).
    pub min: Vec<f64>,
    /// Upper corner (bounding-box fractions, one per axis).
    pub max: Vec<f64>,
}

/// The points below and/or above a fraction along one axis (`x`, `y` or `z`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HalfSpace {
    /// `x`, `y`, `z` or `longest` (the bounding box's longest side).
    pub axis: String,
    /// Selects the points below this fraction along the axis.
    #[serde(default)]
    pub below: Option<f64>,
    /// Selects the points above this fraction along the axis.
    #[serde(default)]
    pub above: Option<f64>,
}

/// Boundary faces whose outward normal is within `angle` degrees of `direction`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Facing {
    /// The direction (reference frame; need not be unit).
    pub direction: Vec<f64>,
    /// The largest angle between a face's outward normal and `direction` (degrees).
    pub angle: f64,
}

impl SetSpec {
    /// Every number the selectors hold (bounds, fractions, radius, direction, angle).
    fn numbers(&self) -> impl Iterator<Item = f64> + '_ {
        let b = self
            .bbox
            .iter()
            .flat_map(|b| b.min.iter().chain(&b.max).copied());
        let h = self
            .half_space
            .iter()
            .flat_map(|h| h.below.into_iter().chain(h.above));
        let f = self
            .facing
            .iter()
            .flat_map(|f| f.direction.iter().copied().chain([f.angle]));
        b.chain(h).chain(self.radius).chain(f)
    }
}

impl SetsConfig {
    /// Parses and checks the text of a sets file (`path` only names the file in messages;
    /// [`SetsConfig::read`] reads the file).
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        let c: SetsConfig = toml::from_str(text).map_err(|e| Error::toml(path, text, &e))?;
        c.checked(path)
    }

    /// The tables of a sets file given as JSON (`[[node_set]]` as `"node_set": [...]`, and
    /// so on), checked as [`SetsConfig::parse`] checks a file; `name` names them in messages.
    pub fn from_json(name: &Path, json: &str) -> Result<Self> {
        let c: SetsConfig =
            serde_json::from_str(json).map_err(|e| Error::parse(name, 0, e.to_string()))?;
        c.checked(name)
    }

    /// `self` read from `path`, with its names, numbers and selectors checked.
    fn checked(mut self, path: &Path) -> Result<Self> {
        let c = &mut self;
        c.source = path.to_path_buf();
        let mut names = std::collections::HashSet::new();
        for (kind, s) in c.all() {
            if let Some(m) = super::set_name_problem(&s.name) {
                return Err(Error::parse(path, 0, format!("{kind} {:?}: {m}", s.name)));
            }
            if !names.insert((kind, s.name.to_ascii_uppercase())) {
                return Err(Error::parse(
                    path,
                    0,
                    format!("{kind} {} is defined twice", s.name),
                ));
            }
            if let Some(v) = s.numbers().find(|v| !v.is_finite()) {
                return Err(Error::parse(
                    path,
                    0,
                    format!("{kind} {}: {v} is not a finite number", s.name),
                ));
            }
            if s.radius.is_some_and(|r| r <= 0.0)
                || s.facing.as_ref().is_some_and(|f| f.angle < 0.0)
            {
                return Err(Error::parse(
                    path,
                    0,
                    format!(
                        "{kind} {}: radius must be positive and angle not negative",
                        s.name
                    ),
                ));
            }
            let selectors = [
                s.bbox.is_some(),
                s.half_space.is_some(),
                s.landmark.is_some(),
                s.facing.is_some(),
            ];
            if !selectors.contains(&true) {
                return Err(Error::parse(
                    path,
                    0,
                    format!(
                        "{kind} {}: give at least one of box, half_space, landmark (with radius), facing",
                        s.name
                    ),
                ));
            }
            if s.landmark.is_some() != s.radius.is_some() {
                return Err(Error::parse(
                    path,
                    0,
                    format!("{kind} {}: landmark and radius go together", s.name),
                ));
            }
            if kind == "surface" && s.facing.is_none() {
                return Err(Error::parse(
                    path,
                    0,
                    format!("surface {}: a surface needs `facing`", s.name),
                ));
            }
            if kind == "element_set" && (s.facing.is_some() || s.landmark.is_some()) {
                return Err(Error::parse(
                    path,
                    0,
                    format!("element_set {}: use box or half_space", s.name),
                ));
            }
            if let Some(h) = &s.half_space
                && (h.below.is_none() && h.above.is_none()
                    || !matches!(h.axis.as_str(), "x" | "y" | "z" | "longest"))
            {
                return Err(Error::parse(
                    path,
                    0,
                    format!(
                        "{kind} {}: half_space needs axis = \"x\", \"y\", \"z\" or \"longest\" and below and/or above",
                        s.name
                    ),
                ));
            }
        }
        Ok(self)
    }

    fn all(&self) -> impl Iterator<Item = (&'static str, &SetSpec)> {
        self.node_set
            .iter()
            .map(|s| ("node_set", s))
            .chain(self.element_set.iter().map(|s| ("element_set", s)))
            .chain(self.surface.iter().map(|s| ("surface", s)))
    }

    /// The sets selected on `mesh` (the mean mesh, reference frame), with `landmarks` the
    /// positions of the atlas's landmarks. Every set must select something.
    pub fn evaluate<const D: usize>(
        &self,
        mesh: &FeMesh<D>,
        landmarks: &[Point<D>],
    ) -> Result<MeshSets> {
        let select = Selector::new(&self.source, mesh, landmarks);
        let faces = boundary_faces(mesh);
        let mut sets = MeshSets::default();
        for s in &self.node_set {
            let members = select.nodes(s, mesh, &faces)?;
            sets.node_sets.insert(s.name.clone(), members);
        }
        for s in &self.element_set {
            let members = select.elements(s, mesh)?;
            sets.element_sets.insert(s.name.clone(), members);
        }
        for s in &self.surface {
            let members = select.faces(s, &faces)?;
            sets.surfaces.insert(s.name.clone(), members);
        }
        Ok(sets)
    }
}

/// The geometry a set's region is judged in: the mesh's bounding box (regions are fractions
/// of it) and the atlas's landmarks.
struct Selector<'a, const D: usize> {
    source: &'a Path,
    lo: Point<D>,
    /// The box's extent (never zero).
    ext: Point<D>,
    /// Its longest side.
    largest: f64,
    landmarks: &'a [Point<D>],
}

impl<'a, const D: usize> Selector<'a, D> {
    fn new(source: &'a Path, mesh: &FeMesh<D>, landmarks: &'a [Point<D>]) -> Self {
        let (lo, hi) = bounding_box(&mesh.nodes);
        let ext: Point<D> = std::array::from_fn(|d| (hi[d] - lo[d]).max(f64::MIN_POSITIVE));
        Selector {
            source,
            lo,
            ext,
            largest: ext.iter().copied().fold(0.0, f64::max),
            landmarks,
        }
    }

    fn bad(&self, m: String) -> Error {
        Error::parse(self.source, 0, m)
    }

    /// Whether `p` lies in the set's region (box, half space, ball around a landmark).
    fn region(&self, s: &SetSpec, p: &Point<D>) -> Result<bool> {
        let f: Point<D> = std::array::from_fn(|d| (p[d] - self.lo[d]) / self.ext[d]);
        if let Some(b) = &s.bbox {
            if b.min.len() != D || b.max.len() != D {
                return Err(self.bad(format!("{}: box min and max need {D} values each", s.name)));
            }
            if (0..D).any(|d| f[d] < b.min[d] - 1e-12 || f[d] > b.max[d] + 1e-12) {
                return Ok(false);
            }
        }
        if let Some(h) = &s.half_space {
            let ext = &self.ext;
            let a = match h.axis.as_str() {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                // The longest side of the bounding box.
                _ => (0..D).fold(0, |b, d| if ext[d] > ext[b] { d } else { b }),
            };
            if a >= D {
                return Err(self.bad(format!("{}: axis {} in a {D}D mesh", s.name, h.axis)));
            }
            if h.below.is_some_and(|b| f[a] > b + 1e-12)
                || h.above.is_some_and(|b| f[a] < b - 1e-12)
            {
                return Ok(false);
            }
        }
        if let (Some(l), Some(r)) = (s.landmark, s.radius) {
            let q = self.landmarks.get(l).ok_or_else(|| {
                self.bad(format!(
                    "{}: landmark {l}, but the atlas has {} landmarks",
                    s.name,
                    self.landmarks.len()
                ))
            })?;
            if dist2(*p, *q).sqrt() > r * self.largest {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Whether the boundary face faces the set's direction (always, when it has none).
    fn facing(&self, s: &SetSpec, f: &BoundaryFace<D>) -> Result<bool> {
        let Some(fc) = &s.facing else {
            return Ok(true);
        };
        if fc.direction.len() != D {
            return Err(self.bad(format!("{}: direction needs {D} values", s.name)));
        }
        let n: f64 = fc.direction.iter().map(|v| v * v).sum::<f64>().sqrt();
        if n == 0.0 || !n.is_finite() {
            return Err(self.bad(format!("{}: direction is zero", s.name)));
        }
        let cos: f64 = (0..D).map(|d| f.normal[d] * fc.direction[d]).sum::<f64>() / n;
        Ok(cos >= fc.angle.to_radians().cos() - 1e-12)
    }

    /// A node set's nodes: in its region, and on a boundary face facing its way if it has a
    /// direction.
    fn nodes(
        &self,
        s: &SetSpec,
        mesh: &FeMesh<D>,
        faces: &[BoundaryFace<D>],
    ) -> Result<Vec<usize>> {
        let mut members = Vec::new();
        if s.facing.is_some() {
            for f in faces {
                if self.facing(s, f)? {
                    for &n in f.nodes.iter().chain(&f.mids) {
                        if self.region(s, &mesh.nodes[n])? {
                            members.push(n);
                        }
                    }
                }
            }
            members.sort_unstable();
            members.dedup();
        } else {
            for (i, p) in mesh.nodes.iter().enumerate() {
                if self.region(s, p)? {
                    members.push(i);
                }
            }
        }
        if members.is_empty() {
            return Err(self.bad(format!("node_set {} selects no node", s.name)));
        }
        Ok(members)
    }

    /// An element set's elements: those whose centroid lies in its region.
    fn elements(&self, s: &SetSpec, mesh: &FeMesh<D>) -> Result<Vec<usize>> {
        let mut members = Vec::new();
        for e in 0..mesh.num_elements() {
            let el = mesh.element(e);
            let c: Point<D> = std::array::from_fn(|d| {
                el.iter().map(|&n| mesh.nodes[n][d]).sum::<f64>() / el.len() as f64
            });
            if self.region(s, &c)? {
                members.push(e);
            }
        }
        if members.is_empty() {
            return Err(self.bad(format!("element_set {} selects no element", s.name)));
        }
        Ok(members)
    }

    /// A surface's boundary faces (element, local face): facing its way, centroid in its region.
    fn faces(&self, s: &SetSpec, faces: &[BoundaryFace<D>]) -> Result<Vec<(usize, u8)>> {
        let mut members = Vec::new();
        for f in faces {
            if self.facing(s, f)? && self.region(s, &f.centroid)? {
                members.push((f.element, f.face));
            }
        }
        if members.is_empty() {
            return Err(self.bad(format!("surface {} selects no boundary face", s.name)));
        }
        members.sort_unstable();
        Ok(members)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{ElementKind, FacePair, face_pairs};

    fn two_cubes() -> FeMesh<3> {
        let mut nodes = Vec::new();
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..3 {
                    nodes.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let id = |x: usize, y: usize, z: usize| x + 3 * y + 6 * z;
        let hex = |x: usize| {
            vec![
                id(x, 0, 0),
                id(x + 1, 0, 0),
                id(x + 1, 1, 0),
                id(x, 1, 0),
                id(x, 0, 1),
                id(x + 1, 0, 1),
                id(x + 1, 1, 1),
                id(x, 1, 1),
            ]
        };
        FeMesh {
            nodes,
            kind: ElementKind::Hex8,
            connectivity: [hex(0), hex(1)].concat(),
            sets: Default::default(),
        }
    }

    #[test]
    fn two_cubes_share_one_face_of_their_eleven() {
        let m = two_cubes();
        let pairs = face_pairs(&m);
        assert_eq!(pairs.len(), 11);
        let inner: Vec<&FacePair> = pairs.iter().filter(|p| p.other.is_some()).collect();
        assert_eq!(inner.len(), 1);
        assert_eq!((inner[0].element, inner[0].other), (0, Some(1)));
        // The same face seen from both cubes: the nodes at x = 1.
        let f = ElementKind::Hex8.faces()[inner[0].face as usize];
        assert!(f.iter().all(|&k| m.nodes[m.element(0)[k]][0] == 1.0));
        // The boundary is the other ten, each once.
        assert_eq!(boundary_faces(&m).len(), 10);
        let listed: std::collections::HashSet<(usize, u8)> =
            pairs.iter().map(|p| (p.element, p.face)).collect();
        assert_eq!(listed.len(), 11);
    }

    #[test]
    fn boundary_faces_point_outwards() {
        let m = two_cubes();
        let f = boundary_faces(&m);
        assert_eq!(f.len(), 10);
        for b in &f {
            let c = [1.0, 0.5, 0.5];
            let out: f64 = (0..3).map(|d| (b.centroid[d] - c[d]) * b.normal[d]).sum();
            assert!(out > 0.0, "{b:?}");
        }
    }

    #[test]
    fn sets_from_a_config() {
        let tmp = tempfile::Builder::new()
            .prefix("atlasmesh-sets-")
            .tempdir()
            .unwrap();
        let dir = tmp.path();
        let p = dir.join("sets.toml");
        std::fs::write(
            &p,
            r#"
[[node_set]]
name = "LEFT"
half_space = { axis = "x", below = 0.0 }
[[node_set]]
name = "TOPNODES"
facing = { direction = [0, 0, 1], angle = 10 }
[[element_set]]
name = "RIGHT"
box = { min = [0.5, 0, 0], max = [1, 1, 1] }
[[surface]]
name = "END"
facing = { direction = [1, 0, 0], angle = 10 }
"#,
        )
        .unwrap();
        let c = SetsConfig::read(&p).unwrap();
        let s = c.evaluate(&two_cubes(), &[]).unwrap();
        assert_eq!(s.node_sets["LEFT"], vec![0, 3, 6, 9]);
        assert_eq!(s.node_sets["TOPNODES"].len(), 6);
        assert_eq!(s.element_sets["RIGHT"], vec![1]);
        assert_eq!(s.surfaces["END"], vec![(1, 3)]);
        // A set that selects nothing is an error naming the file and the set.
        std::fs::write(
            &p,
            "[[node_set]]\nname = \"NONE\"\nbox = { min = [2, 2, 2], max = [3, 3, 3] }\n",
        )
        .unwrap();
        let e = SetsConfig::read(&p)
            .unwrap()
            .evaluate(&two_cubes(), &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("sets.toml") && e.contains("NONE") && e.contains("selects no"),
            "{e}"
        );
        std::fs::write(&p, "[[node_set]]\nname = \"X\"\nbox = 3\n").unwrap();
        assert!(SetsConfig::read(&p).is_err());
    }
}

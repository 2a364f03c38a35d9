//! A load case: node sets named by geometry on the delivered mesh, and what is applied to
//! them (displacements, forces), with the rigid-body motion the conditions leave free taken
//! out at two or three nodes, so that the solver's static step is well posed.
//!
//! Frame and units: the mesh's world frame (mm, RAS for a subject or a label map's voxels),
//! displacements in mm, forces in N.
//!
//! ```toml
//! [[nodes]]               # the face of a part seen from a direction: the nodes of the
//! name = "TOP"            # part's elements within `tolerance` mm of the plane, normal to
//! part = "PADS"           # `face`, through the part's farthest node along it
//! face = [0.0, 0.0, 1.0]
//! tolerance = 0.01        # mm (default 1e-6 of the part's size)
//!
//! [[nodes]]               # the nodes within `distance` mm of a plane
//! name = "MID"
//! plane = { point = [0.0, 0.0, 10.0], normal = [0.0, 0.0, 1.0], distance = 0.5 }
//!
//! [[displacement]]        # mm; a component not given is free
//! nodes = "TOP"
//! z = -0.2
//!
//! [[displacement]]
//! nodes = "BOTTOM"
//! z = 0.0
//!
//! [[force]]               # N, the total, shared evenly by the set's nodes
//! nodes = "MID"
//! x = 10.0
//!
//! # rigid_body = true     # default: the free rigid-body motion held at a few nodes
//! ```
//!
//! The rigid-body motion a load case leaves free: a component (x, y or z) that no
//! displacement holds is free in translation, and rotations about an axis whose two other
//! components are both free. With `rigid_body` (default), the *held* set (the first
//! displacement set whose values are all 0; else the first set) anchors them: its node
//! nearest its centroid is held in every free component, the node farthest from it along the
//! first free axis in the free components after it, and, when all three are free, the node
//! farthest from the line of those two in the last. Those nodes' reactions are reported; they
//! are ~0 when the load case is balanced.

use super::FeMesh;
use crate::error::{Error, Result};
use crate::geometry::Point;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A load case file, parsed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadCase {
    /// `[[nodes]]`: node sets by geometry.
    #[serde(default)]
    pub nodes: Vec<NodeSelector>,
    /// `[[displacement]]`: prescribed displacements (mm).
    #[serde(default)]
    pub displacement: Vec<Condition>,
    /// `[[force]]`: forces (N, each the total over its set).
    #[serde(default)]
    pub force: Vec<Condition>,
    /// `[[tie]]`: node sets tied to surfaces (non-matching meshes of one model).
    #[serde(default)]
    pub tie: Vec<Tie>,
    /// Hold the free rigid-body motion at a few nodes (default true).
    #[serde(default = "yes")]
    pub rigid_body: bool,
    /// The file it was read from (for messages).
    #[serde(skip)]
    pub source: PathBuf,
}

fn yes() -> bool {
    true
}

/// A node set named by geometry: `face` (of `part`, or of the whole mesh) or `plane`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSelector {
    /// The set's name in the solver files.
    pub name: String,
    /// An element set of the mesh whose nodes only are considered (a part of a voxel mesh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
    /// The face seen from this direction (world): the nodes within `tolerance` of the plane
    /// normal to it through the farthest node along it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub face: Option<[f64; 3]>,
    /// For `face`: mm (default 1e-6 of the considered nodes' bounding-box diagonal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// The nodes within a distance of a plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<PlaneSelector>,
}

/// A plane (a point and a normal, world, mm) and a distance (mm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneSelector {
    /// A point of the plane.
    pub point: [f64; 3],
    /// Its normal (need not be unit).
    pub normal: [f64; 3],
    /// Nodes at most this far from it (mm).
    pub distance: f64,
}

/// A tie: the nodes of a set held to a surface of the mesh where they lie within a
/// tolerance of it (CalculiX `*TIE`, its slave side the nodes, its master the surface).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tie {
    /// The node set (a `[[nodes]]` name or a node set of the mesh).
    pub nodes: String,
    /// A surface of the mesh (element faces).
    pub surface: String,
    /// mm: nodes farther from the surface are not tied (default 1).
    #[serde(default = "default_tie_tolerance")]
    pub tolerance: f64,
}

fn default_tie_tolerance() -> f64 {
    1.0
}

/// Components applied to a node set: a displacement (mm) or a force (N).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Condition {
    /// The node set (a `[[nodes]]` name, or a node set of the mesh).
    pub nodes: String,
    /// The x component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<f64>,
    /// The y component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f64>,
    /// The z component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
}

impl Condition {
    /// The components given, `(axis 0..3, value)`.
    pub fn components(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        [self.x, self.y, self.z]
            .into_iter()
            .enumerate()
            .filter_map(|(c, v)| v.map(|v| (c, v)))
    }
}

/// A load case applied to a mesh: its node sets (0-based, sorted) and the conditions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AppliedLoadCase {
    /// Node sets by name: the `[[nodes]]` ones, the mesh's sets the conditions name, and the
    /// rigid-body anchors (`RIGID_1`, ...).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Those of `node_sets` that are the mesh's own (written with the mesh already).
    pub mesh_sets: std::collections::BTreeSet<String>,
    /// Prescribed displacements: `(set, axis 0..3, mm)`, the rigid-body holds last.
    pub displacements: Vec<(String, usize, f64)>,
    /// Forces: `(set, axis 0..3, N total)`.
    pub forces: Vec<(String, usize, f64)>,
    /// The sets whose reaction forces are asked for (every displacement set).
    pub reaction_sets: Vec<String>,
    /// Ties: `(node set, surface, tolerance mm)`.
    pub ties: Vec<(String, String, f64)>,
    /// For every tie (same order), the boundary faces `(element, local face)` whose corners
    /// are all of its node set: the tied side as faces, for solvers that tie a surface to a
    /// surface (FEBio's tied contact).
    pub tie_faces: Vec<Vec<(usize, u8)>>,
    /// The set, axis and value of the first non-zero displacement: the stiffness is its
    /// reaction over it.
    pub loaded: Option<(String, usize, f64)>,
}

/// Largest number of node sets or conditions read.
const MAX_ITEMS: usize = 64;

impl LoadCase {
    /// Parses and checks the text of a load case (`path` names the file in messages).
    ///
    /// # Errors
    /// [`Error::Parse`] naming the file and the problem.
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        if text.len() > 1 << 20 {
            return Err(Error::parse(
                path,
                0,
                "a load case of more than 1 MB; it is a small TOML file".to_string(),
            ));
        }
        let mut c: LoadCase = toml::from_str(text).map_err(|e| Error::toml(path, text, &e))?;
        c.source = path.to_path_buf();
        c.check().map_err(|m| Error::parse(path, 0, m))?;
        Ok(c)
    }

    fn check(&self) -> std::result::Result<(), String> {
        if self.nodes.len() > MAX_ITEMS || self.displacement.len() + self.force.len() > MAX_ITEMS {
            return Err(format!(
                "at most {MAX_ITEMS} node sets and {MAX_ITEMS} conditions"
            ));
        }
        if self.displacement.is_empty() {
            return Err("no [[displacement]]: a static step needs the model held somewhere".into());
        }
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some(p) = super::set_name_problem(&n.name) {
                return Err(format!("node set {:?}: {p}", n.name));
            }
            if self.nodes[..i].iter().any(|m| m.name == n.name) {
                return Err(format!("node set {} is named twice", n.name));
            }
            let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
            let unit = |v: &[f64; 3]| finite(v) && v.iter().map(|x| x * x).sum::<f64>() > 0.0;
            match (&n.face, &n.plane) {
                (Some(f), None) => {
                    if !unit(f) {
                        return Err(format!("node set {}: face {f:?} is no direction", n.name));
                    }
                    if let Some(t) = n.tolerance
                        && !(t.is_finite() && t >= 0.0)
                    {
                        return Err(format!("node set {}: tolerance {t} mm", n.name));
                    }
                }
                (None, Some(p)) => {
                    if !(finite(&p.point)
                        && unit(&p.normal)
                        && p.distance.is_finite()
                        && p.distance >= 0.0)
                    {
                        return Err(format!(
                            "node set {}: a plane needs a finite point, a non-zero normal and a \
                             distance ≥ 0 mm",
                            n.name
                        ));
                    }
                    if n.tolerance.is_some() {
                        return Err(format!("node set {}: tolerance is for face", n.name));
                    }
                }
                _ => {
                    return Err(format!(
                        "node set {}: give one of face = [x, y, z] or plane = {{ point, normal, \
                         distance }}",
                        n.name
                    ));
                }
            }
        }
        for t in &self.tie {
            if !(t.tolerance.is_finite() && t.tolerance > 0.0) {
                return Err(format!("tie of {}: tolerance {} mm", t.nodes, t.tolerance));
            }
        }
        for (kind, list) in [("displacement", &self.displacement), ("force", &self.force)] {
            for c in list {
                if c.components().next().is_none() {
                    return Err(format!("{kind} on {}: no component (x, y or z)", c.nodes));
                }
                if let Some((_, v)) = c.components().find(|(_, v)| !v.is_finite()) {
                    return Err(format!("{kind} on {}: {v} is not finite", c.nodes));
                }
            }
        }
        Ok(())
    }

    /// The `[[nodes]]` sets on `mesh`.
    fn selected_sets(&self, mesh: &FeMesh<3>) -> Result<BTreeMap<String, Vec<usize>>> {
        let src = self.source.display();
        let bad = |m: String| Error::Parameter(format!("{src}: {m}"));
        let mut sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for n in &self.nodes {
            let candidates: Vec<usize> = match &n.part {
                Some(p) => {
                    let Some(elements) = mesh.sets.element_sets.get(p) else {
                        let names: Vec<&str> =
                            mesh.sets.element_sets.keys().map(String::as_str).collect();
                        return Err(bad(format!(
                            "node set {}: part {p} is not an element set of the mesh (its \
                             element sets: {})",
                            n.name,
                            if names.is_empty() {
                                "none".into()
                            } else {
                                names.join(", ")
                            }
                        )));
                    };
                    let mut v: Vec<usize> = elements
                        .iter()
                        .filter(|&&e| e < mesh.num_elements())
                        .flat_map(|&e| mesh.element(e).iter().copied())
                        .collect();
                    v.sort_unstable();
                    v.dedup();
                    v
                }
                None => (0..mesh.nodes.len()).collect(),
            };
            let selected = select(&mesh.nodes, &candidates, n);
            if selected.is_empty() {
                return Err(bad(format!("node set {} selects no node", n.name)));
            }
            sets.insert(n.name.clone(), selected);
        }
        Ok(sets)
    }

    /// The node sets on `mesh` and the conditions ready to write (see the module's doc for
    /// the rigid-body holds).
    ///
    /// # Errors
    /// [`Error::Parameter`] for a part that is no element set of the mesh, a set that selects
    /// no node, a condition on an unknown set, or a component both held and loaded.
    pub fn apply(&self, mesh: &FeMesh<3>) -> Result<AppliedLoadCase> {
        let src = self.source.display();
        let bad = |m: String| Error::Parameter(format!("{src}: {m}"));
        let mut sets = self.selected_sets(mesh)?;
        let mut applied = AppliedLoadCase::default();
        let find = |sets: &BTreeMap<String, Vec<usize>>,
                    mesh_sets: &mut std::collections::BTreeSet<String>,
                    name: &str|
         -> Result<Vec<usize>> {
            if let Some(s) = sets.get(name) {
                return Ok(s.clone());
            }
            let s = mesh.sets.node_sets.get(name).cloned().ok_or_else(|| {
                bad(format!(
                    "no node set {name} (a [[nodes]] name or a node set of the mesh)"
                ))
            })?;
            mesh_sets.insert(name.to_string());
            Ok(s)
        };
        let mut held = [false; 3];
        let mut node_held: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        for c in &self.displacement {
            let members = find(&sets, &mut applied.mesh_sets, &c.nodes)?;
            for (axis, v) in c.components() {
                held[axis] = true;
                for &n in &members {
                    if let Some(&w) = node_held.get(&(n, axis))
                        && w != v
                    {
                        return Err(bad(format!(
                            "node {} is given {w} and {v} mm along {} (sets overlap)",
                            n + 1,
                            AXES[axis]
                        )));
                    }
                    node_held.insert((n, axis), v);
                }
                applied.displacements.push((c.nodes.clone(), axis, v));
                if v != 0.0 && applied.loaded.is_none() {
                    applied.loaded = Some((c.nodes.clone(), axis, v));
                }
            }
            if !applied.reaction_sets.contains(&c.nodes) {
                applied.reaction_sets.push(c.nodes.clone());
            }
            sets.entry(c.nodes.clone()).or_insert(members);
        }
        for c in &self.force {
            let members = find(&sets, &mut applied.mesh_sets, &c.nodes)?;
            for (axis, v) in c.components() {
                if members.iter().any(|&n| node_held.contains_key(&(n, axis))) {
                    return Err(bad(format!(
                        "force on {} along {}: its nodes are held along it",
                        c.nodes, AXES[axis]
                    )));
                }
                applied.forces.push((c.nodes.clone(), axis, v));
            }
            sets.entry(c.nodes.clone()).or_insert(members);
        }
        for t in &self.tie {
            let members = find(&sets, &mut applied.mesh_sets, &t.nodes)?;
            if !mesh.sets.surfaces.contains_key(&t.surface) {
                return Err(bad(no_surface(mesh, t)));
            }
            applied
                .ties
                .push((t.nodes.clone(), t.surface.clone(), t.tolerance));
            applied.tie_faces.push(faces_of(mesh, &members));
            sets.entry(t.nodes.clone()).or_insert(members);
        }
        if self.rigid_body {
            let anchor_set = self
                .displacement
                .iter()
                .find(|c| c.components().all(|(_, v)| v == 0.0))
                .unwrap_or(&self.displacement[0]);
            let anchors = &sets[&anchor_set.nodes];
            for (k, (node, axes)) in rigid_body_holds(&mesh.nodes, anchors, held)
                .into_iter()
                .enumerate()
            {
                let name = format!("RIGID_{}", k + 1);
                for axis in axes {
                    applied.displacements.push((name.clone(), axis, 0.0));
                }
                applied.reaction_sets.push(name.clone());
                sets.insert(name, vec![node]);
            }
        }
        applied.node_sets = sets;
        Ok(applied)
    }
}

/// The boundary faces of `mesh` whose corners are all among `nodes`.
fn faces_of(mesh: &FeMesh<3>, nodes: &[usize]) -> Vec<(usize, u8)> {
    let mut member = vec![false; mesh.nodes.len()];
    for &n in nodes {
        if let Some(m) = member.get_mut(n) {
            *m = true;
        }
    }
    super::boundary_faces(mesh)
        .into_iter()
        .filter(|f| f.nodes.iter().all(|&n| member[n]))
        .map(|f| (f.element, f.face))
        .collect()
}

/// Axis names.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// The nodes of `candidates` that `n` selects.
fn select(nodes: &[Point<3>], candidates: &[usize], n: &NodeSelector) -> Vec<usize> {
    let unit = |v: &[f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    let along = |p: &Point<3>, d: &[f64; 3]| p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
    if let Some(f) = &n.face {
        let d = unit(f);
        let far = candidates
            .iter()
            .map(|&i| along(&nodes[i], &d))
            .fold(f64::NEG_INFINITY, f64::max);
        let tolerance = n.tolerance.unwrap_or_else(|| {
            let (lo, hi) = candidates.iter().fold(
                ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                |(mut lo, mut hi), &i| {
                    for c in 0..3 {
                        lo[c] = lo[c].min(nodes[i][c]);
                        hi[c] = hi[c].max(nodes[i][c]);
                    }
                    (lo, hi)
                },
            );
            1e-6 * crate::geometry::dist2(lo, hi).sqrt()
        });
        candidates
            .iter()
            .copied()
            .filter(|&i| along(&nodes[i], &d) >= far - tolerance)
            .collect()
    } else if let Some(p) = &n.plane {
        let d = unit(&p.normal);
        let at = along(&p.point, &d);
        candidates
            .iter()
            .copied()
            .filter(|&i| (along(&nodes[i], &d) - at).abs() <= p.distance)
            .collect()
    } else {
        Vec::new()
    }
}

/// The nodes of `set` that hold the rigid-body motion the components `held` leave free, and
/// the axes each holds (see the module's doc).
fn rigid_body_holds(
    nodes: &[Point<3>],
    set: &[usize],
    held: [bool; 3],
) -> Vec<(usize, Vec<usize>)> {
    let free: Vec<usize> = (0..3).filter(|&c| !held[c]).collect();
    if free.is_empty() || set.is_empty() {
        return Vec::new();
    }
    let n = set.len() as f64;
    let centroid: Point<3> =
        std::array::from_fn(|c| set.iter().map(|&i| nodes[i][c]).sum::<f64>() / n);
    let nearest = |target: &Point<3>, skip: &[usize]| {
        set.iter()
            .copied()
            .filter(|i| !skip.contains(i))
            .min_by(|&a, &b| {
                crate::geometry::dist2(nodes[a], *target)
                    .total_cmp(&crate::geometry::dist2(nodes[b], *target))
                    .then(a.cmp(&b))
            })
    };
    let Some(a) = nearest(&centroid, &[]) else {
        return Vec::new();
    };
    let mut holds = vec![(a, free.clone())];
    if free.len() >= 2 {
        // The node farthest from `a` along the first free axis holds the others: the rotation
        // about the axis normal to the first two.
        let axis = free[0];
        let b = set.iter().copied().filter(|&i| i != a).max_by(|&p, &q| {
            (nodes[p][axis] - nodes[a][axis])
                .abs()
                .total_cmp(&(nodes[q][axis] - nodes[a][axis]).abs())
                .then(q.cmp(&p))
        });
        if let Some(b) = b {
            holds.push((b, free[1..].to_vec()));
            if free.len() == 3 {
                let second = free[1];
                let c = set
                    .iter()
                    .copied()
                    .filter(|&i| i != a && i != b)
                    .max_by(|&p, &q| {
                        (nodes[p][second] - nodes[a][second])
                            .abs()
                            .total_cmp(&(nodes[q][second] - nodes[a][second]).abs())
                            .then(q.cmp(&p))
                    });
                if let Some(c) = c {
                    holds.push((c, vec![free[2]]));
                }
            }
        }
    }
    holds
}

/// The problem of a tie whose surface is not in `mesh`, naming the surfaces it has.
fn no_surface(mesh: &FeMesh<3>, t: &Tie) -> String {
    let names: Vec<&str> = mesh.sets.surfaces.keys().map(String::as_str).collect();
    format!(
        "tie of {}: no surface {} in the mesh (its surfaces: {})",
        t.nodes,
        t.surface,
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{ElementKind, MeshSets};

    /// A column of `n` unit cubes along z.
    fn column(n: usize) -> FeMesh<3> {
        let mut nodes = Vec::new();
        for k in 0..=n {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                nodes.push([x, y, k as f64]);
            }
        }
        let mut connectivity = Vec::new();
        for k in 0..n {
            let b = 4 * k;
            connectivity.extend([b, b + 1, b + 2, b + 3, b + 4, b + 5, b + 6, b + 7]);
        }
        let mut sets = MeshSets::default();
        sets.element_sets.insert("TOPCUBE".into(), vec![n - 1]);
        FeMesh {
            nodes,
            kind: ElementKind::Hex8,
            connectivity,
            sets,
        }
    }

    const CASE: &str = r#"
[[nodes]]
name = "TOP"
part = "TOPCUBE"
face = [0.0, 0.0, 1.0]

[[nodes]]
name = "BOTTOM"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, -2.0], distance = 0.1 }

[[displacement]]
nodes = "TOP"
z = -0.2

[[displacement]]
nodes = "BOTTOM"
z = 0.0
"#;

    #[test]
    fn faces_planes_and_the_rigid_body_holds() {
        let m = column(3);
        let c = LoadCase::parse(Path::new("case.toml"), CASE).unwrap();
        let a = c.apply(&m).unwrap();
        assert_eq!(a.node_sets["TOP"], vec![12, 13, 14, 15]);
        assert_eq!(a.node_sets["BOTTOM"], vec![0, 1, 2, 3]);
        assert_eq!(a.loaded, Some(("TOP".into(), 2, -0.2)));
        // x and y are free: one bottom node held in x and y, one far along x in y.
        let rigid: Vec<_> = a
            .displacements
            .iter()
            .filter(|d| d.0.starts_with("RIGID"))
            .collect();
        assert_eq!(rigid.len(), 3);
        let n1 = a.node_sets["RIGID_1"][0];
        let n2 = a.node_sets["RIGID_2"][0];
        assert!(a.node_sets["BOTTOM"].contains(&n1) && a.node_sets["BOTTOM"].contains(&n2));
        assert!((m.nodes[n1][0] - m.nodes[n2][0]).abs() == 1.0);
        assert_eq!(a.reaction_sets, vec!["TOP", "BOTTOM", "RIGID_1", "RIGID_2"]);
    }

    #[test]
    fn bad_load_cases_are_refused() {
        let m = column(2);
        for (text, says) in [
            (
                "[[nodes]]\nname = \"A\"\nface = [0.0, 0.0, 0.0]\n[[displacement]]\nnodes = \"A\"\nz = 0.0\n",
                "no direction",
            ),
            (
                "[[nodes]]\nname = \"A\"\nface = [0.0, 0.0, 1.0]\n",
                "no [[displacement]]",
            ),
            (
                "[[nodes]]\nname = \"A\"\n[[displacement]]\nnodes = \"A\"\nz = 0.0\n",
                "give one of",
            ),
            (
                "[[nodes]]\nname = \"A\"\nface = [0.0, 0.0, 1.0]\n[[displacement]]\nnodes = \"A\"\n",
                "no component",
            ),
        ] {
            let e = LoadCase::parse(Path::new("c.toml"), text)
                .unwrap_err()
                .to_string();
            assert!(e.contains(says) && e.contains("c.toml"), "{e}");
        }
        let c = LoadCase::parse(
            Path::new("c.toml"),
            "[[nodes]]\nname = \"A\"\npart = \"NOPE\"\nface = [0.0, 0.0, 1.0]\n[[displacement]]\nnodes = \"A\"\nz = 0.0\n",
        )
        .unwrap();
        let e = c.apply(&m).unwrap_err().to_string();
        assert!(e.contains("TOPCUBE"), "{e}");
        let c = LoadCase::parse(
            Path::new("c.toml"),
            "[[nodes]]\nname = \"A\"\nplane = { point = [0.0, 0.0, 9.0], normal = [0.0, 0.0, 1.0], distance = 0.1 }\n[[displacement]]\nnodes = \"A\"\nz = 0.0\n",
        )
        .unwrap();
        assert!(
            c.apply(&m)
                .unwrap_err()
                .to_string()
                .contains("selects no node")
        );
        let c = LoadCase::parse(
            Path::new("c.toml"),
            "[[nodes]]\nname = \"A\"\nface = [0.0, 0.0, 1.0]\n[[displacement]]\nnodes = \"A\"\nz = 0.0\n[[displacement]]\nnodes = \"A\"\nz = 1.0\n",
        )
        .unwrap();
        assert!(
            c.apply(&m)
                .unwrap_err()
                .to_string()
                .contains("sets overlap")
        );
        let tie = |extra: &str| {
            format!(
                "[[nodes]]\nname = \"A\"\nface = [0.0, 0.0, 1.0]\n[[displacement]]\nnodes = \"A\"\nz = 0.0\n[[tie]]\nnodes = \"A\"\nsurface = \"S\"\n{extra}"
            )
        };
        let e = LoadCase::parse(Path::new("c.toml"), &tie("tolerance = -1.0\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("tolerance -1"), "{e}");
        let c = LoadCase::parse(Path::new("c.toml"), &tie("")).unwrap();
        assert_eq!(c.tie[0].tolerance, 1.0);
        let e = c.apply(&m).unwrap_err().to_string();
        assert!(e.contains("no surface S") && e.contains("none"), "{e}");
    }
}

//! A finite element mesh of one element kind, with its named sets.

use super::{ElementKind, HEX20_EDGES, TET10_EDGES};
use crate::geometry::Point;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A finite element mesh of one element kind.
#[derive(Clone, Debug, PartialEq)]
pub struct FeMesh<const D: usize> {
    /// `#nodes` node positions (shape units).
    pub nodes: Vec<Point<D>>,
    /// Element kind.
    pub kind: ElementKind,
    /// Connectivity, `kind.nodes()` node indices per element, concatenated.
    pub connectivity: Vec<usize>,
    /// Named node sets, element sets and surfaces (carried by every morph: it moves nodes).
    pub sets: MeshSets,
}

/// Named sets of a mesh, 0-based and sorted: node sets, element sets, and surfaces as
/// `(element, face)` pairs with faces numbered as in [`ElementKind::faces`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshSets {
    /// Node sets: sorted node indices by name.
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Element sets: sorted element indices by name.
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// Surfaces: `(element, face)` pairs by name, faces numbered as in [`ElementKind::faces`].
    pub surfaces: BTreeMap<String, Vec<(usize, u8)>>,
}

impl MeshSets {
    /// Adds the sets of `other`; a set of the same name is replaced.
    pub fn merge(&mut self, other: MeshSets) {
        self.node_sets.extend(other.node_sets);
        self.element_sets.extend(other.element_sets);
        self.surfaces.extend(other.surfaces);
    }

    /// Whether there is no set at all.
    pub fn is_empty(&self) -> bool {
        self.node_sets.is_empty() && self.element_sets.is_empty() && self.surfaces.is_empty()
    }

    /// Checks every name by [`set_name_problem`] and every member against a mesh of `nodes`
    /// nodes and `elements` elements of `kind`; the message names the set and the member.
    pub fn check(&self, kind: ElementKind, nodes: usize, elements: usize) -> Result<(), String> {
        let names = (self.node_sets.keys().map(|n| ("node set", n)))
            .chain(self.element_sets.keys().map(|n| ("element set", n)))
            .chain(self.surfaces.keys().map(|n| ("surface", n)));
        for (what, name) in names {
            if let Some(m) = set_name_problem(name) {
                return Err(format!("{what} {name:?}: {m}"));
            }
        }
        // The names the solver files give the whole mesh: a part under that name would merge
        // with the whole when written.
        for (name, s, reserved, total, what) in (self.node_sets.iter())
            .map(|(n, s)| (n, s, "NALL", nodes, "node"))
            .chain((self.element_sets.iter()).map(|(n, s)| (n, s, "EALL", elements, "element")))
        {
            if name.eq_ignore_ascii_case(reserved) && s.len() < total {
                return Err(format!(
                    "{what} set {name} holds {} of the {total} {what}s; {reserved} is the name \
                     the solver files give the whole mesh: rename the set",
                    s.len()
                ));
            }
        }
        for (name, s) in &self.node_sets {
            if let Some(n) = s.iter().find(|&&n| n >= nodes) {
                return Err(format!(
                    "node set {name} names node {} but the mesh has {nodes} nodes",
                    n + 1
                ));
            }
        }
        for (name, s) in &self.element_sets {
            if let Some(e) = s.iter().find(|&&e| e >= elements) {
                return Err(format!(
                    "element set {name} names element {} but the mesh has {elements} elements",
                    e + 1
                ));
            }
        }
        for (name, s) in &self.surfaces {
            if let Some((e, f)) = s
                .iter()
                .find(|(e, f)| *e >= elements || *f as usize >= kind.faces().len())
            {
                return Err(format!(
                    "surface {name} names face S{} of element {}, which does not exist",
                    f + 1,
                    e + 1
                ));
            }
        }
        Ok(())
    }
}

/// The longest set name (Abaqus's and CalculiX's limit).
pub const MAX_SET_NAME: usize = 80;

/// What is wrong with a set name, if anything. One rule for every format read and written
/// (the sets file, the atlas, `.inp`, `.msh`, `.vtu`, `.vtk`, `.feb`): 1 to [`MAX_SET_NAME`]
/// ASCII letters, digits, `_` and `-`, starting with a letter or `_`. Such a name is the same
/// token in an Abaqus keyword line, a Gmsh string, a VTK array name and an FEBio attribute, so
/// no name can break a file or inject a line into it.
pub fn set_name_problem(name: &str) -> Option<String> {
    const RULE: &str = "a set name is 1 to 80 letters, digits, _ or -, starting with a letter or _";
    let first_ok = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if !first_ok || name.len() > MAX_SET_NAME {
        return Some(RULE.to_string());
    }
    name.chars()
        .find(|&c| !(c.is_ascii_alphanumeric() || c == '_' || c == '-'))
        .map(|c| format!("{c:?} is not allowed ({RULE})"))
}

/// A quadrilateral mesh.
pub type QuadMesh = FeMesh<2>;
/// A hexahedral mesh.
pub type HexMesh = FeMesh<3>;

impl HexMesh {
    /// A block of `n × n × n` unit hexahedra from the origin, node `x + (n+1)(y + (n+1)z)` at
    /// `(x, y, z)`, elements in the [`ElementKind::Hex8`] node order (a reference mesh for
    /// checks and tests).
    pub fn block(n: usize) -> Self {
        let id = |x: usize, y: usize, z: usize| x + (n + 1) * (y + (n + 1) * z);
        let mut nodes = Vec::with_capacity((n + 1).pow(3));
        for z in 0..=n {
            for y in 0..=n {
                for x in 0..=n {
                    nodes.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let mut connectivity = Vec::with_capacity(8 * n.pow(3));
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    connectivity.extend([
                        id(x, y, z),
                        id(x + 1, y, z),
                        id(x + 1, y + 1, z),
                        id(x, y + 1, z),
                        id(x, y, z + 1),
                        id(x + 1, y, z + 1),
                        id(x + 1, y + 1, z + 1),
                        id(x, y + 1, z + 1),
                    ]);
                }
            }
        }
        FeMesh {
            nodes,
            kind: ElementKind::Hex8,
            connectivity,
            sets: Default::default(),
        }
    }
}

impl<const D: usize> FeMesh<D> {
    /// Checks that the connectivity is whole elements of nodes that exist; the message names
    /// the first element that is not.
    pub fn check_connectivity(&self) -> Result<(), String> {
        let k = self.kind.nodes();
        if !self.connectivity.len().is_multiple_of(k) {
            return Err(format!(
                "{} node indices are not whole {} elements of {k} nodes",
                self.connectivity.len(),
                self.kind.name()
            ));
        }
        if let Some(i) = self
            .connectivity
            .iter()
            .position(|&n| n >= self.nodes.len())
        {
            return Err(format!(
                "element {} names node {} but the mesh has {} nodes",
                i / k + 1,
                self.connectivity[i] + 1,
                self.nodes.len()
            ));
        }
        Ok(())
    }

    /// Number of elements.
    pub fn num_elements(&self) -> usize {
        self.connectivity.len() / self.kind.nodes()
    }
    /// Node indices of element `e`.
    pub fn element(&self, e: usize) -> &[usize] {
        let k = self.kind.nodes();
        &self.connectivity[e * k..(e + 1) * k]
    }
    /// The mesh moved by the similarity `t` (e.g. the mean mesh into a subject's frame).
    pub fn moved(&self, t: &crate::geometry::Similarity<D>) -> Self {
        self.with_nodes(self.nodes.iter().map(|p| t.apply(p)).collect())
    }

    /// The same connectivity with new node positions.
    #[track_caller]
    pub fn with_nodes(&self, nodes: Vec<Point<D>>) -> Self {
        assert_eq!(
            nodes.len(),
            self.nodes.len(),
            "with_nodes: one position per node"
        );
        FeMesh {
            nodes,
            kind: self.kind,
            connectivity: self.connectivity.clone(),
            sets: self.sets.clone(),
        }
    }

    /// The quadratic mesh of a linear 3D one (Hex8 to Hex20, Tet4 to Tet10): a node at the
    /// middle of every edge, shared by the elements around it, numbered after the linear
    /// mesh's nodes (which keep their numbers). Element sets and surfaces are kept; a node
    /// set gains the mid-edge nodes of the edges whose two ends it holds. `None` for a mesh
    /// that is already quadratic or two-dimensional.
    pub fn to_quadratic(&self) -> Option<Self> {
        let kind = match self.kind {
            ElementKind::Hex8 => ElementKind::Hex20,
            ElementKind::Tet4 => ElementKind::Tet10,
            _ => return None,
        };
        let edges: &[[usize; 3]] = match kind {
            ElementKind::Hex20 => &HEX20_EDGES,
            _ => &TET10_EDGES,
        };
        let mut nodes = self.nodes.clone();
        let mut mid: std::collections::HashMap<(usize, usize), usize> = Default::default();
        let mut connectivity = Vec::with_capacity(self.num_elements() * kind.nodes());
        for e in 0..self.num_elements() {
            let el = self.element(e);
            connectivity.extend_from_slice(el);
            for &[a, b, _] in edges {
                let key = (el[a].min(el[b]), el[a].max(el[b]));
                let m = *mid.entry(key).or_insert_with(|| {
                    let (p, q) = (self.nodes[key.0], self.nodes[key.1]);
                    nodes.push(std::array::from_fn(|d| 0.5 * (p[d] + q[d])));
                    nodes.len() - 1
                });
                connectivity.push(m);
            }
        }
        let mut sets = self.sets.clone();
        for members in sets.node_sets.values_mut() {
            let has: std::collections::HashSet<usize> = members.iter().copied().collect();
            members.extend(
                mid.iter()
                    .filter(|((a, b), _)| has.contains(a) && has.contains(b))
                    .map(|(_, &m)| m),
            );
            members.sort_unstable();
        }
        Some(FeMesh {
            nodes,
            kind,
            connectivity,
            sets,
        })
    }
}

//! FEBio `.feb` 4.0: the `Mesh` section with node sets, element sets and surfaces, and a
//! model around it.

use super::helpers::xyz;
use crate::error::{Error, Result};
use crate::mesh::{ElementKind, FeMesh};
use std::fmt::Write as _;
use std::path::Path;

/// The FEBio 4.0 `Mesh` section of a 3D mesh.
pub fn feb<const D: usize>(mesh: &FeMesh<D>, path: &Path) -> Result<String> {
    if D != 3 {
        return Err(Error::Mesh(format!(
            "{}: FEBio is a 3D solver; write 2D meshes as .inp, .msh, .vtu or .vtk",
            path.display()
        )));
    }
    let mut s = String::with_capacity(mesh.nodes.len() * 80 + mesh.connectivity.len() * 8);
    s.push_str("<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>\n<febio_spec version=\"4.0\">\n");
    let _ = writeln!(
        s,
        "  <!-- atlasmesh {}: the mesh and its sets; add Material, MeshDomains and Step -->",
        env!("CARGO_PKG_VERSION")
    );
    s.push_str("  <Mesh>\n    <Nodes name=\"nodes\">\n");
    for (i, p) in mesh.nodes.iter().enumerate() {
        let q = xyz(p);
        let _ = writeln!(
            s,
            "      <node id=\"{}\">{:.17e},{:.17e},{:.17e}</node>",
            i + 1,
            q[0],
            q[1],
            q[2]
        );
    }
    let _ = writeln!(
        s,
        "    </Nodes>\n    <Elements type=\"{}\" name=\"Part1\">",
        mesh.kind.febio_type()
    );
    for e in 0..mesh.num_elements() {
        let ids: Vec<String> = mesh
            .element(e)
            .iter()
            .map(|n| (n + 1).to_string())
            .collect();
        let _ = writeln!(s, "      <elem id=\"{}\">{}</elem>", e + 1, ids.join(","));
    }
    s.push_str("    </Elements>\n");
    let list = |m: &[usize]| {
        m.iter()
            .map(|n| (n + 1).to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    for (name, m) in &mesh.sets.node_sets {
        let _ = writeln!(s, "    <NodeSet name=\"{name}\">{}</NodeSet>", list(m));
    }
    for (name, m) in &mesh.sets.element_sets {
        let _ = writeln!(
            s,
            "    <ElementSet name=\"{name}\">{}</ElementSet>",
            list(m)
        );
    }
    for (name, faces) in &mesh.sets.surfaces {
        let _ = writeln!(s, "    <Surface name=\"{name}\">");
        for (k, &(e, f)) in faces.iter().enumerate() {
            let el = mesh.element(e);
            let local = mesh.kind.face_nodes(f as usize);
            let t = match local.len() {
                4 => "quad4",
                8 => "quad8",
                6 => "tri6",
                _ => "tri3",
            };
            let ids: Vec<String> = local.iter().map(|&c| (el[c] + 1).to_string()).collect();
            let _ = writeln!(s, "      <{t} id=\"{}\">{}</{t}>", k + 1, ids.join(","));
        }
        s.push_str("    </Surface>\n");
    }
    s.push_str("  </Mesh>\n</febio_spec>\n");
    Ok(s)
}

/// The element-type table of this format.
impl ElementKind {
    /// FEBio element type name.
    pub fn febio_type(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "quad4",
            ElementKind::Tri3 => "tri3",
            ElementKind::Hex8 => "hex8",
            ElementKind::Tet4 => "tet4",
            ElementKind::Hex20 => "hex20",
            ElementKind::Tet10 => "tet10",
        }
    }
}

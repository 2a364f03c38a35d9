//! FEBio `.feb` 4.0: the `Mesh` section with node sets, element sets and surfaces, and a
//! model around it.

use super::helpers::xyz;
use crate::error::{Error, Result};
use crate::mesh::{ElementKind, FeMesh};
use std::fmt::Write as _;
use std::path::Path;

/// The FEBio 4.0 `Mesh` section of a 3D mesh.
pub fn feb<const D: usize>(mesh: &FeMesh<D>, path: &Path) -> Result<String> {
    feb_with_materials(mesh, path, None)
}

/// [`feb`], and with `map` one isotropic elastic material per bin (E in MPa, ν): the
/// elements in one part per material (`BONE_k`, keeping their ids) and a `SolidDomain`
/// tying each part to its material. Units: mm, N, MPa.
pub fn feb_with_materials<const D: usize>(
    mesh: &FeMesh<D>,
    path: &Path,
    map: Option<&crate::materials::MaterialMap>,
) -> Result<String> {
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
    if let Some(m) = map {
        materials(&mut s, m);
    }
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
    s.push_str("    </Nodes>\n");
    let all: Vec<usize> = (0..mesh.num_elements()).collect();
    let parts: Vec<(String, &[usize])> = match map {
        Some(m) => m
            .bins
            .iter()
            .map(|b| (b.name.clone(), b.elements.as_slice()))
            .collect(),
        None => vec![("Part1".into(), all.as_slice())],
    };
    for (name, elements) in &parts {
        element_part(&mut s, mesh, name, elements);
    }
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
    s.push_str("  </Mesh>\n");
    if map.is_some() {
        s.push_str("  <MeshDomains>\n");
        for (name, _) in &parts {
            let _ = writeln!(s, "    <SolidDomain name=\"{name}\" mat=\"{name}\"/>");
        }
        s.push_str("  </MeshDomains>\n");
    }
    s.push_str("</febio_spec>\n");
    Ok(s)
}

/// One `Elements` part named `name` holding `elements` (their ids kept).
fn element_part<const D: usize>(s: &mut String, mesh: &FeMesh<D>, name: &str, elements: &[usize]) {
    let _ = writeln!(
        s,
        "    <Elements type=\"{}\" name=\"{name}\">",
        mesh.kind.febio_type()
    );
    for &e in elements {
        let ids: Vec<String> = mesh
            .element(e)
            .iter()
            .map(|n| (n + 1).to_string())
            .collect();
        let _ = writeln!(s, "      <elem id=\"{}\">{}</elem>", e + 1, ids.join(","));
    }
    s.push_str("    </Elements>\n");
}

/// The `Material` section: one isotropic elastic material per bin of `map` (E in MPa).
fn materials(s: &mut String, map: &crate::materials::MaterialMap) {
    s.push_str("  <Material>\n");
    for (k, bin) in map.bins.iter().enumerate() {
        let _ = writeln!(
            s,
            "    <material id=\"{}\" name=\"{}\" type=\"isotropic elastic\">\n      \
             <density>1</density>\n      <E>{:.6e}</E>\n      <v>{}</v>\n    </material>",
            k + 1,
            bin.name,
            bin.modulus,
            bin.poisson
        );
    }
    s.push_str("  </Material>\n");
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

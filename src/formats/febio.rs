//! FEBio `.feb` 4.0: the `Mesh` section with node sets, element sets and surfaces, and a
//! model around it: with materials, one per group and a domain per part; with a load case,
//! a static step (`Control`, `Boundary`, `Loads`, tied `Contact`, `LoadData`, `Output`).

use super::helpers::xyz;
use crate::error::{Error, Result};
use crate::mesh::{AXES, AppliedLoadCase, ElementKind, FeMesh};
use std::fmt::Write as _;
use std::path::Path;

/// The FEBio 4.0 `Mesh` section of a 3D mesh.
pub fn feb<const D: usize>(mesh: &FeMesh<D>, path: &Path) -> Result<String> {
    feb_with_materials(mesh, path, None, None)
}

/// [`feb`], and with `map` one isotropic elastic material per bin (E in MPa, ν): the
/// elements in one part per material (`BONE_k`, keeping their ids) and a `SolidDomain`
/// tying each part to its material; with `load`, its static step (the sections after `MeshDomains`). Units:
/// mm, N, MPa.
pub fn feb_with_materials<const D: usize>(
    mesh: &FeMesh<D>,
    path: &Path,
    map: Option<&crate::materials::MaterialMap>,
    load: Option<&AppliedLoadCase>,
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
        "  <!-- atlasmesh {}: {} -->",
        env!("CARGO_PKG_VERSION"),
        match (map, load) {
            (None, None) => "the mesh and its sets; add Material, MeshDomains and a step",
            (None, Some(_)) => "the mesh, its sets and a static step; add Material and MeshDomains",
            (Some(_), None) => "the mesh, its sets and materials; add a step",
            (Some(_), Some(_)) => "the model and its static step",
        }
    );
    if load.is_some() {
        s.push_str(
            "  <Module type=\"solid\"/>\n  <Control>\n    <analysis>STATIC</analysis>\n    \
             <time_steps>1</time_steps>\n    <step_size>1</step_size>\n  </Control>\n",
        );
    }
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
    sets(&mut s, mesh, load);
    s.push_str("  </Mesh>\n");
    if map.is_some() {
        s.push_str("  <MeshDomains>\n");
        for (name, _) in &parts {
            let _ = writeln!(s, "    <SolidDomain name=\"{name}\" mat=\"{name}\"/>");
        }
        s.push_str("  </MeshDomains>\n");
    }
    if let Some(l) = load {
        feb_step(&mut s, mesh, map, l);
    }
    s.push_str("</febio_spec>\n");
    Ok(s)
}

/// The static step of `load` (the sections after `MeshDomains`), as the CalculiX step
/// ([`super::inp_step`]) says it: every zero displacement a `zero displacement` condition
/// (its held components together), every other a `prescribed displacement` (mm), every
/// force a `nodal_force` (N, the total shared evenly by the set's nodes), all ramped by load
/// controller 1 over the one time step; every tie a `tied-node-on-facet` contact of the tied
/// nodes' faces (`TIE_k_NODES`) on the surface, nodes farther than its tolerance (mm) left
/// free, its penalty (N/mm³) ten times the stiffest material's E over the tied faces' median
/// size (a start: check that the tie's gaps are small against the displacements); the reaction
/// forces (`Rx;Ry;Rz`) of every displacement set in the log file, the displacement, stress and
/// reaction forces in the plot file.
fn feb_step<const D: usize>(
    s: &mut String,
    mesh: &FeMesh<D>,
    map: Option<&crate::materials::MaterialMap>,
    load: &AppliedLoadCase,
) {
    s.push_str("  <Boundary>\n");
    let mut held: std::collections::BTreeMap<&str, [bool; 3]> = std::collections::BTreeMap::new();
    for (k, (set, axis, v)) in load.displacements.iter().enumerate() {
        if *v == 0.0 {
            held.entry(set.as_str()).or_default()[*axis] = true;
        } else {
            let _ = writeln!(
                s,
                "    <bc name=\"DISPLACEMENT_{n}\" type=\"prescribed displacement\" \
                 node_set=\"{set}\">\n      <dof>{}</dof>\n      <value lc=\"1\">{v:e}</value>\n      \
                 <relative>0</relative>\n    </bc>",
                AXES[*axis],
                n = k + 1
            );
        }
    }
    for (set, axes) in &held {
        let _ = writeln!(
            s,
            "    <bc name=\"HOLD_{set}\" type=\"zero displacement\" node_set=\"{set}\">\n      \
             <x_dof>{}</x_dof>\n      <y_dof>{}</y_dof>\n      <z_dof>{}</z_dof>\n    </bc>",
            u8::from(axes[0]),
            u8::from(axes[1]),
            u8::from(axes[2])
        );
    }
    s.push_str("  </Boundary>\n");
    if !load.forces.is_empty() {
        s.push_str("  <Loads>\n");
        for (k, (set, axis, v)) in load.forces.iter().enumerate() {
            let each = v / load.node_sets[set].len().max(1) as f64;
            let mut f = [0.0; 3];
            f[*axis] = each;
            let _ = writeln!(
                s,
                "    <nodal_load name=\"FORCE_{n}\" type=\"nodal_force\" node_set=\"{set}\">\n      \
                 <relative>0</relative>\n      <value lc=\"1\">{:e},{:e},{:e}</value>\n      \
                 <shell_bottom>0</shell_bottom>\n    </nodal_load>",
                f[0],
                f[1],
                f[2],
                n = k + 1
            );
        }
        s.push_str("  </Loads>\n");
    }
    if !load.ties.is_empty() {
        let stiffest = map
            .and_then(|m| m.bins.iter().map(|b| b.modulus).reduce(f64::max))
            .unwrap_or(1.0);
        s.push_str("  <Contact>\n");
        for (k, ((_, _, tolerance), faces)) in load.ties.iter().zip(&load.tie_faces).enumerate() {
            let penalty = 10.0 * stiffest / median_face_size(mesh, faces);
            let _ = writeln!(
                s,
                "    <contact name=\"TIE_{n}\" type=\"tied-node-on-facet\" surface_pair=\"TIE_{n}\">\n      \
                 <laugon>0</laugon>\n      <tolerance>0.01</tolerance>\n      \
                 <penalty>{penalty:e}</penalty>\n      <minaug>0</minaug>\n      \
                 <maxaug>10</maxaug>\n      <search_tolerance>0.01</search_tolerance>\n      \
                 <max_distance>{tolerance:e}</max_distance>\n      <special>1</special>\n      \
                 <node_reloc>0</node_reloc>\n    </contact>",
                n = k + 1
            );
        }
        s.push_str("  </Contact>\n");
    }
    s.push_str(
        "  <LoadData>\n    <load_controller id=\"1\" name=\"RAMP\" type=\"loadcurve\">\n      \
         <interpolate>LINEAR</interpolate>\n      <points>\n        <point>0,0</point>\n        \
         <point>1,1</point>\n      </points>\n    </load_controller>\n  </LoadData>\n  <Output>\n    \
         <plotfile type=\"febio\">\n      <var type=\"displacement\"/>\n      \
         <var type=\"stress\"/>\n      <var type=\"reaction forces\"/>\n    </plotfile>\n    \
         <logfile>\n",
    );
    for set in &load.reaction_sets {
        let ids: Vec<String> = load.node_sets[set]
            .iter()
            .map(|n| (n + 1).to_string())
            .collect();
        let _ = writeln!(
            s,
            "      <node_data name=\"RF_{set}\" data=\"Rx;Ry;Rz\" delim=\",\">{}</node_data>",
            ids.join(",")
        );
    }
    s.push_str("    </logfile>\n  </Output>\n");
}

/// The median size of `faces` of `mesh` (the mean of their two diagonals over √2; mm), 1
/// when there are none.
fn median_face_size<const D: usize>(mesh: &FeMesh<D>, faces: &[(usize, u8)]) -> f64 {
    let mut sizes: Vec<f64> = faces
        .iter()
        .map(|&(e, f)| {
            let el = mesh.element(e);
            let c: Vec<_> = mesh
                .kind
                .face_nodes(f as usize)
                .iter()
                .map(|&k| mesh.nodes[el[k]])
                .collect();
            let d =
                |a: usize, b: usize| crate::geometry::dist2(c[a % c.len()], c[b % c.len()]).sqrt();
            0.5 * (d(0, 2) + d(1, 3)) / std::f64::consts::SQRT_2
        })
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if sizes.is_empty() {
        return 1.0;
    }
    sizes.sort_by(f64::total_cmp);
    sizes[sizes.len() / 2]
}

/// The `Mesh` section's sets: the mesh's node sets and those of `load`, its element sets, its
/// surfaces and the sides of `load`'s ties (`TIE_k_NODES`), and a `SurfacePair` per tie.
fn sets<const D: usize>(s: &mut String, mesh: &FeMesh<D>, load: Option<&AppliedLoadCase>) {
    let list = |m: &[usize]| {
        m.iter()
            .map(|n| (n + 1).to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    let load_sets = load.into_iter().flat_map(|l| {
        l.node_sets
            .iter()
            .filter(|(name, _)| !l.mesh_sets.contains(*name))
    });
    for (name, m) in mesh.sets.node_sets.iter().chain(load_sets) {
        let _ = writeln!(s, "    <NodeSet name=\"{name}\">{}</NodeSet>", list(m));
    }
    for (name, m) in &mesh.sets.element_sets {
        let _ = writeln!(
            s,
            "    <ElementSet name=\"{name}\">{}</ElementSet>",
            list(m)
        );
    }
    let tie_sides: Vec<(String, &Vec<(usize, u8)>)> = load
        .iter()
        .flat_map(|l| l.tie_faces.iter().enumerate())
        .map(|(k, faces)| (format!("TIE_{}_NODES", k + 1), faces))
        .collect();
    let tie_sides = tie_sides.iter().map(|(n, f)| (n, *f));
    for (name, faces) in mesh.sets.surfaces.iter().chain(tie_sides) {
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
    for (k, (_, surface, _)) in load.iter().flat_map(|l| l.ties.iter()).enumerate() {
        let _ = writeln!(
            s,
            "    <SurfacePair name=\"TIE_{n}\">\n      <primary>TIE_{n}_NODES</primary>\n      \
             <secondary>{surface}</secondary>\n    </SurfacePair>",
            n = k + 1
        );
    }
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

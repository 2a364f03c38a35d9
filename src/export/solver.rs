//! FE meshes for solvers, with their node sets, element sets and surfaces:
//!
//! - **Abaqus / CalculiX `.inp`**: `*NODE`, `*ELEMENT` (`C3D8`, `C3D4`, `CPS4`, `CPS3`),
//!   `*NSET`, `*ELSET`, `*SURFACE, TYPE=ELEMENT` (lines `element, Sk`), 1-based ids.
//! - **Gmsh `.msh` 4.1** (ASCII): physical groups for the sets. Elements are split into one
//!   entity per combination of element sets (each entity carries the physical tag `EALL` and
//!   those of its sets);
//!   every surface is an entity of boundary-face elements of dimension `D - 1`; every node in
//!   a node set gets a point entity holding a 1-node element, tagged with its sets.
//! - **FEBio `.feb` 4.0**: the `Mesh` section (`Nodes`, `Elements`, `NodeSet`, `ElementSet`,
//!   `Surface`) to merge with a study's materials and steps; 3D meshes only.
//! - **Legacy VTK** (ASCII `UNSTRUCTURED_GRID`), sets as 0/1 point and cell data `set_NAME`.
//!
//! Node ordering within elements and faces: see [`crate::fe::ElementKind`] (the same in all
//! four formats for these linear elements). Coordinates in the mesh's units; 2D meshes get
//! `z = 0` where a format wants three.

use crate::error::{Error, Result};
use crate::fe::FeMesh;
use crate::fe::quality::ElementQuality;
use crate::geometry::{Point, bounding_box};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The FE mesh formats written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MeshFormat {
    Vtu,
    Vtk,
    Inp,
    Msh,
    Feb,
}

impl MeshFormat {
    /// All formats.
    pub const ALL: [MeshFormat; 5] = [
        MeshFormat::Vtu,
        MeshFormat::Vtk,
        MeshFormat::Inp,
        MeshFormat::Msh,
        MeshFormat::Feb,
    ];

    /// File extension.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Vtu => "vtu",
            MeshFormat::Vtk => "vtk",
            MeshFormat::Inp => "inp",
            MeshFormat::Msh => "msh",
            MeshFormat::Feb => "feb",
        }
    }

    /// The format of a file name's extension.
    pub fn from_path(path: &Path) -> Option<Self> {
        let e = path.extension()?.to_string_lossy().to_ascii_lowercase();
        Self::ALL.into_iter().find(|f| f.extension() == e)
    }

    /// The format named `s` (an extension).
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().trim_start_matches('.').to_ascii_lowercase();
        Self::ALL.into_iter().find(|f| f.extension() == s)
    }
}

/// Writes `mesh` to `path` in the format of its extension; `reference` (the mean mesh) gives
/// the displacement and `quality` the per-element Jacobians where the format carries data
/// (VTU, VTK).
pub fn write_mesh<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
) -> Result<()> {
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        Error::Parameter(format!(
            "{}: unknown mesh format; use .vtu, .vtk, .inp, .msh or .feb",
            path.display()
        ))
    })?;
    if mesh.kind.dimension() != D {
        return Err(Error::Mesh(format!(
            "{}: {} elements in a {D}D mesh",
            path.display(),
            mesh.kind.name()
        )));
    }
    let text = match format {
        MeshFormat::Vtu => return super::write_vtu_with_quality(path, mesh, reference, quality),
        MeshFormat::Vtk => vtk(mesh, reference, quality),
        MeshFormat::Inp => inp(mesh, path),
        MeshFormat::Msh => msh(mesh),
        MeshFormat::Feb => feb(mesh, path)?,
    };
    crate::io::write_atomic(path, text.as_bytes())
}

fn xyz<const D: usize>(p: &Point<D>) -> [f64; 3] {
    [p[0], p[1], if D > 2 { p[2] } else { 0.0 }]
}

/// Comma-separated 1-based ids, `per_line` per line (Abaqus allows 16 per data line).
fn id_lines(out: &mut String, ids: impl IntoIterator<Item = usize>, per_line: usize) {
    let mut k = 0;
    for i in ids {
        if k > 0 {
            out.push_str(if k % per_line == 0 { ",\n" } else { ", " });
        }
        let _ = write!(out, "{}", i + 1);
        k += 1;
    }
    if k > 0 {
        out.push('\n');
    }
}

/// The nodes and elements of a mesh as an Abaqus/CalculiX model (no materials or steps).
pub fn inp<const D: usize>(mesh: &FeMesh<D>, path: &Path) -> String {
    let mut s = String::with_capacity(mesh.nodes.len() * 70 + mesh.connectivity.len() * 8);
    let _ = writeln!(
        s,
        "*HEADING\natlasmesh {}: {}",
        env!("CARGO_PKG_VERSION"),
        path.file_stem()
            .map(|f| f.to_string_lossy().to_string())
            .unwrap_or_default()
    );
    inp_mesh(&mut s, mesh);
    s
}

/// `*NODE`, `*ELEMENT` and the sets (appended to `s`).
pub fn inp_mesh<const D: usize>(s: &mut String, mesh: &FeMesh<D>) {
    // CalculiX reads at most 20 characters per number: 13 significant digits.
    s.push_str("*NODE, NSET=NALL\n");
    for (i, p) in mesh.nodes.iter().enumerate() {
        if D == 2 {
            let _ = writeln!(s, "{}, {:.12e}, {:.12e}", i + 1, p[0], p[1]);
        } else {
            let q = xyz(p);
            let _ = writeln!(s, "{}, {:.12e}, {:.12e}, {:.12e}", i + 1, q[0], q[1], q[2]);
        }
    }
    let _ = writeln!(s, "*ELEMENT, TYPE={}, ELSET=EALL", mesh.kind.abaqus_type());
    for e in 0..mesh.num_elements() {
        let _ = write!(s, "{}", e + 1);
        for (k, n) in mesh.element(e).iter().enumerate() {
            // At most 16 entries on a data line: a C3D20's last 5 nodes go on a second line.
            if k == 15 {
                s.push_str(",\n");
                let _ = write!(s, "{}", n + 1);
            } else {
                let _ = write!(s, ", {}", n + 1);
            }
        }
        s.push('\n');
    }
    for (name, members) in &mesh.sets.node_sets {
        let _ = writeln!(s, "*NSET, NSET={name}");
        id_lines(s, members.iter().copied(), 16);
    }
    for (name, members) in &mesh.sets.element_sets {
        let _ = writeln!(s, "*ELSET, ELSET={name}");
        id_lines(s, members.iter().copied(), 16);
    }
    for (name, faces) in &mesh.sets.surfaces {
        let _ = writeln!(s, "*SURFACE, NAME={name}, TYPE=ELEMENT");
        for (e, f) in faces {
            let _ = writeln!(s, "{}, S{}", e + 1, f + 1);
        }
    }
}

/// Gmsh 4.1 ASCII with physical groups for the sets.
pub fn msh<const D: usize>(mesh: &FeMesh<D>) -> String {
    let sets = &mesh.sets;
    // Physical tags, unique over all sets: element sets (dim D), surfaces (dim D-1), node
    // sets (dim 0).
    let mut names: Vec<(usize, usize, String)> = Vec::new(); // (dim, tag, name)
    let mut tag = 0;
    let mut tag_of = |d: usize, n: &str, names: &mut Vec<(usize, usize, String)>| {
        tag += 1;
        names.push((d, tag, n.to_string()));
        tag
    };
    // Every element is in the physical group EALL (readers such as meshio expect a physical
    // tag on every element), then in those of its element sets.
    let all_tag = tag_of(D, "EALL", &mut names);
    let mut el_tags: BTreeMap<&str, usize> = BTreeMap::new();
    for n in sets.element_sets.keys() {
        el_tags.insert(n, tag_of(D, n, &mut names));
    }
    let mut sf_tags: BTreeMap<&str, usize> = BTreeMap::new();
    for n in sets.surfaces.keys() {
        sf_tags.insert(n, tag_of(D - 1, n, &mut names));
    }
    let mut nd_tags: BTreeMap<&str, usize> = BTreeMap::new();
    for n in sets.node_sets.keys() {
        nd_tags.insert(n, tag_of(0, n, &mut names));
    }
    // Elements grouped by the element sets that hold them.
    let ne = mesh.num_elements();
    let mut member_of: Vec<Vec<usize>> = vec![vec![all_tag]; ne];
    for (n, m) in &sets.element_sets {
        for &e in m {
            if e < ne {
                member_of[e].push(el_tags[n.as_str()]);
            }
        }
    }
    let mut groups: BTreeMap<Vec<usize>, Vec<usize>> = BTreeMap::new();
    for (e, t) in member_of.into_iter().enumerate() {
        groups.entry(t).or_default().push(e);
    }
    // Nodes grouped by the node sets that hold them.
    let nn = mesh.nodes.len();
    let mut node_member: Vec<Vec<usize>> = vec![Vec::new(); nn];
    for (n, m) in &sets.node_sets {
        for &i in m {
            if i < nn {
                node_member[i].push(nd_tags[n.as_str()]);
            }
        }
    }
    let tagged_nodes: Vec<usize> = (0..nn).filter(|&i| !node_member[i].is_empty()).collect();
    let (lo, hi) = bounding_box(&mesh.nodes);
    let (lo, hi) = (xyz(&lo), xyz(&hi));
    let bbox = format!(
        "{} {} {} {} {} {}",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    let mut s = String::with_capacity(nn * 70 + mesh.connectivity.len() * 8);
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    if !names.is_empty() {
        let _ = writeln!(s, "$PhysicalNames\n{}", names.len());
        for (d, t, n) in &names {
            let _ = writeln!(s, "{d} {t} \"{n}\"");
        }
        s.push_str("$EndPhysicalNames\n");
    }
    // Entities: points (tagged nodes), then D-1 (surfaces), then D (element groups).
    let surfaces: Vec<(&String, &Vec<(usize, u8)>)> = sets.surfaces.iter().collect();
    let mut counts = [0usize; 4];
    counts[0] = tagged_nodes.len();
    counts[D - 1] += surfaces.len();
    counts[D] += groups.len();
    s.push_str("$Entities\n");
    let _ = writeln!(s, "{} {} {} {}", counts[0], counts[1], counts[2], counts[3]);
    let mut entity_lines: [Vec<String>; 4] = Default::default();
    for (k, &i) in tagged_nodes.iter().enumerate() {
        let q = xyz(&mesh.nodes[i]);
        let t = &node_member[i];
        entity_lines[0].push(format!(
            "{} {} {} {} {} {}",
            k + 1,
            q[0],
            q[1],
            q[2],
            t.len(),
            t.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        ));
    }
    for (k, (n, _)) in surfaces.iter().enumerate() {
        entity_lines[D - 1].push(format!("{} {bbox} 1 {} 0", k + 1, sf_tags[n.as_str()]));
    }
    // Entity tags are numbered per dimension.
    let volume_base = 0;
    for (k, (t, _)) in groups.iter().enumerate() {
        let tags = t
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" ");
        entity_lines[D].push(format!(
            "{} {bbox} {} {}{}0",
            volume_base + k + 1,
            t.len(),
            tags,
            if t.is_empty() { "" } else { " " }
        ));
    }
    for lines in &entity_lines {
        for l in lines {
            s.push_str(l);
            s.push('\n');
        }
    }
    s.push_str("$EndEntities\n");
    // All nodes in the first element group's entity.
    let _ = writeln!(s, "$Nodes\n1 {nn} 1 {nn}\n{D} {} 0 {nn}", volume_base + 1);
    for i in 0..nn {
        let _ = writeln!(s, "{}", i + 1);
    }
    for p in &mesh.nodes {
        let q = xyz(p);
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", q[0], q[1], q[2]);
    }
    s.push_str("$EndNodes\n");
    // Elements: the FE elements by group, then surface faces, then the points.
    let quadratic = mesh.kind.linear() != mesh.kind;
    let face_type = match (D, mesh.kind.faces()[0].len(), quadratic) {
        (2, _, _) => 1,     // 2-node line
        (_, 3, false) => 2, // triangle
        (_, 3, true) => 9,  // 6-node triangle
        (_, _, false) => 3, // quadrangle
        (_, _, true) => 16, // 8-node quadrangle
    };
    let n_faces: usize = surfaces.iter().map(|(_, f)| f.len()).sum();
    let total = ne + n_faces + tagged_nodes.len();
    let n_blocks = groups.len() + surfaces.len() + tagged_nodes.len();
    let _ = writeln!(s, "$Elements\n{n_blocks} {total} 1 {total}");
    for (k, (_, els)) in groups.iter().enumerate() {
        let _ = writeln!(
            s,
            "{D} {} {} {}",
            volume_base + k + 1,
            mesh.kind.gmsh_type(),
            els.len()
        );
        for &e in els {
            let _ = write!(s, "{}", e + 1);
            // Gmsh's order of the nodes (its own for the mid-edge nodes).
            let el = mesh.element(e);
            let mut gmsh = vec![0; el.len()];
            for (k, &g) in mesh.kind.gmsh_order().iter().enumerate() {
                gmsh[g] = el[k];
            }
            for n in gmsh {
                let _ = write!(s, " {}", n + 1);
            }
            s.push('\n');
        }
    }
    // Element tags: the FE elements keep their 1-based ids; faces and points follow.
    let mut next = ne;
    for (k, (_, faces)) in surfaces.iter().enumerate() {
        let _ = writeln!(s, "{} {} {face_type} {}", D - 1, k + 1, faces.len());
        for &(e, f) in faces.iter() {
            next += 1;
            let el = mesh.element(e);
            let _ = write!(s, "{next}");
            // Corners, then (quadratic) the mid-edge nodes in the order of the face's edges,
            // as Gmsh's 6-node triangle and 8-node quadrangle have them.
            for c in mesh.kind.face_nodes(f as usize) {
                let _ = write!(s, " {}", el[c] + 1);
            }
            s.push('\n');
        }
    }
    for (k, &i) in tagged_nodes.iter().enumerate() {
        next += 1;
        let _ = writeln!(s, "0 {} 15 1\n{next} {}", k + 1, i + 1);
    }
    s.push_str("$EndElements\n");
    s
}

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

/// Legacy VTK, ASCII.
pub fn vtk<const D: usize>(
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
) -> String {
    let nn = mesh.nodes.len();
    let ne = mesh.num_elements();
    let k = mesh.kind.nodes();
    let mut s = String::with_capacity(nn * 60 + ne * 40);
    let _ = writeln!(
        s,
        "# vtk DataFile Version 4.2\natlasmesh {}\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {nn} double",
        env!("CARGO_PKG_VERSION")
    );
    for p in &mesh.nodes {
        let q = xyz(p);
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", q[0], q[1], q[2]);
    }
    let _ = writeln!(s, "CELLS {ne} {}", ne * (k + 1));
    for e in 0..ne {
        let _ = write!(s, "{k}");
        for n in mesh.element(e) {
            let _ = write!(s, " {n}");
        }
        s.push('\n');
    }
    let _ = writeln!(s, "CELL_TYPES {ne}");
    for _ in 0..ne {
        let _ = writeln!(s, "{}", mesh.kind.vtk_type());
    }
    let mask = |s: &mut String, name: &str, m: &[usize], n: usize| {
        let mut v = vec![0u8; n];
        for &i in m {
            if i < n {
                v[i] = 1;
            }
        }
        let _ = writeln!(
            s,
            "SCALARS set_{name} unsigned_char 1\nLOOKUP_TABLE default"
        );
        for c in v.chunks(32) {
            let line: Vec<&str> = c.iter().map(|x| if *x == 1 { "1" } else { "0" }).collect();
            let _ = writeln!(s, "{}", line.join(" "));
        }
    };
    if quality.len() == ne || !mesh.sets.element_sets.is_empty() {
        let _ = writeln!(s, "CELL_DATA {ne}");
    }
    if quality.len() == ne {
        s.push_str("SCALARS jacobian_min double 1\nLOOKUP_TABLE default\n");
        for q in quality {
            let _ = writeln!(s, "{:.17e}", q.jacobian_min);
        }
        s.push_str("SCALARS scaled_jacobian_min double 1\nLOOKUP_TABLE default\n");
        for q in quality {
            let _ = writeln!(s, "{:.17e}", q.scaled_jacobian_min);
        }
    }
    for (name, m) in &mesh.sets.element_sets {
        mask(&mut s, name, m, ne);
    }
    let reference = reference.filter(|r| r.nodes.len() == nn);
    if reference.is_some() || !mesh.sets.node_sets.is_empty() {
        let _ = writeln!(s, "POINT_DATA {nn}");
    }
    if let Some(r) = reference {
        s.push_str("VECTORS displacement double\n");
        for (p, o) in mesh.nodes.iter().zip(&r.nodes) {
            let (a, b) = (xyz(p), xyz(o));
            let _ = writeln!(
                s,
                "{:.17e} {:.17e} {:.17e}",
                a[0] - b[0],
                a[1] - b[1],
                a[2] - b[2]
            );
        }
    }
    for (name, m) in &mesh.sets.node_sets {
        mask(&mut s, name, m, nn);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fe::{ElementKind, MeshSets};

    fn two_cubes() -> FeMesh<3> {
        let mut nodes = Vec::new();
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..3 {
                    nodes.push([x as f64 * 1.5, y as f64, z as f64 + 0.25]);
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
        let mut sets = MeshSets::default();
        sets.node_sets.insert("LEFT".into(), vec![0, 3, 6, 9]);
        sets.node_sets.insert("ONE".into(), vec![5]);
        sets.element_sets.insert("RIGHT".into(), vec![1]);
        sets.surfaces.insert("END".into(), vec![(1, 3)]);
        sets.surfaces.insert("BOTTOM".into(), vec![(0, 0), (1, 0)]);
        FeMesh {
            nodes,
            kind: ElementKind::Hex8,
            connectivity: [hex(0), hex(1)].concat(),
            sets,
        }
    }

    fn quads() -> FeMesh<2> {
        let nodes = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ];
        let mut sets = MeshSets::default();
        sets.node_sets.insert("BASE".into(), vec![0, 1, 2]);
        sets.element_sets.insert("FIRST".into(), vec![0]);
        sets.surfaces.insert("TOP".into(), vec![(0, 2), (1, 2)]);
        FeMesh {
            nodes,
            kind: ElementKind::Quad4,
            connectivity: vec![0, 1, 4, 3, 1, 2, 5, 4],
            sets,
        }
    }

    fn round_trip<const D: usize>(m: &FeMesh<D>, name: &str) {
        let dir = std::env::temp_dir().join(format!("atlasmesh-rt-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let q = crate::fe::quality::mesh_quality(m);
        for ext in ["inp", "msh", "vtk", "vtu"] {
            let p = dir.join(format!("{name}.{ext}"));
            write_mesh(&p, m, None, &q).unwrap();
            let r: FeMesh<D> = crate::io::femesh::read_fe_mesh(&p).unwrap();
            // .inp keeps 13 significant digits (CalculiX reads 20 characters per number).
            let tol = if ext == "inp" { 1e-11 } else { 1e-15 };
            assert_eq!(r.kind, m.kind, "{ext}");
            assert_eq!(r.connectivity, m.connectivity, "{ext}");
            for (a, b) in r.nodes.iter().zip(&m.nodes) {
                assert!(
                    (0..D).all(|d| (a[d] - b[d]).abs() <= tol * (1.0 + b[d].abs())),
                    "{ext}"
                );
            }
            assert_eq!(r.sets.node_sets, m.sets.node_sets, "{ext} node sets");
            assert_eq!(
                r.sets.element_sets, m.sets.element_sets,
                "{ext} element sets"
            );
            if ext == "inp" || ext == "msh" {
                assert_eq!(r.sets.surfaces, m.sets.surfaces, "{ext} surfaces");
            }
        }
        let feb = dir.join(format!("{name}.feb"));
        let w = write_mesh(&feb, m, None, &q);
        assert_eq!(w.is_ok(), D == 3);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn every_format_reads_back_with_its_sets() {
        round_trip(&two_cubes(), "hex");
        round_trip(&quads(), "quad");
        // Quadratic: mid-edge nodes in each program's order and back; sets carried.
        let hex20 = two_cubes().to_quadratic().unwrap();
        assert_eq!(hex20.nodes.len(), 12 + 20);
        round_trip(&hex20, "hex20");
        let tets = FeMesh {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
            kind: ElementKind::Tet4,
            connectivity: vec![0, 1, 2, 3, 1, 2, 3, 4],
            sets: MeshSets {
                node_sets: [("TIP".to_string(), vec![3, 4])].into(),
                surfaces: [("BASE".to_string(), vec![(0, 0)])].into(),
                ..Default::default()
            },
        };
        let tet10 = tets.to_quadratic().unwrap();
        // The mid-edge node of 3-4 joins TIP; 9 edges, 9 mid-edge nodes.
        assert_eq!(tet10.nodes.len(), 5 + 9);
        assert_eq!(tet10.sets.node_sets["TIP"].len(), 3);
        round_trip(&tet10, "tet10");
    }

    #[test]
    fn deck_nodes_are_replaced_and_nothing_else() {
        let dir = std::env::temp_dir().join(format!("atlasmesh-deck-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = two_cubes();
        let mut text = inp(&m, &dir.join("d.inp"));
        text.push_str("*MATERIAL, NAME=BONE\n*ELASTIC\n17000., 0.3\n*STEP\n*STATIC\n*END STEP\n");
        let p = dir.join("d.inp");
        std::fs::write(&p, &text).unwrap();
        let deck = crate::io::femesh::read_inp(&p).unwrap();
        let moved: Vec<Point<3>> = m.nodes.iter().map(|p| [p[0] * 2.0, p[1], p[2]]).collect();
        let out = deck.with_nodes(&moved).unwrap();
        assert!(out.contains("*MATERIAL, NAME=BONE\n*ELASTIC\n17000., 0.3\n*STEP"));
        std::fs::write(&p, &out).unwrap();
        let again = crate::io::femesh::read_inp(&p).unwrap();
        for (a, b) in again.mesh.nodes.iter().zip(&moved) {
            assert!((0..3).all(|d| (a[d] - b[d]).abs() < 1e-11 * (1.0 + b[d].abs())));
        }
        assert_eq!(again.mesh.connectivity, m.connectivity);
        assert_eq!(again.mesh.sets, m.sets);
        std::fs::remove_dir_all(&dir).ok();
    }
}

//! Gmsh `.msh` (2.2 and 4.1 ASCII read, 4.1 written) with physical groups as sets.

use super::gmsh_parsed::{MshElement, Parsed, gmsh_dimension, physical_names};
use super::helpers::{check_mesh, xyz};
use crate::error::{Error, Result};
use crate::geometry::{Point, bounding_box};
use crate::mesh::{ALL_KINDS, ElementKind, FeMesh, MeshSets};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;

/// Reads a Gmsh mesh, version 2.2 or 4.1, ASCII or binary (either byte order, as the file
/// says). The elements of the highest dimension form the mesh; physical groups become sets
/// (see the module doc).
pub fn read_msh(path: &Path) -> Result<FeMesh<3>> {
    let bytes = crate::formats::read_input(path)?;
    parse_msh(path, &bytes)
}

/// [`read_msh`] of a file's bytes (`path` only names the file in messages): no file is read.
pub fn parse_msh(path: &Path, bytes: &[u8]) -> Result<FeMesh<3>> {
    let format = super::gmsh_binary::mesh_format(path, bytes)?;
    let parsed = if format.binary {
        super::gmsh_binary::parse(path, bytes, &format)?
    } else {
        let text = std::str::from_utf8(bytes)
            .map_err(|_| Error::parse(path, 0, "an ASCII .msh file holds invalid UTF-8"))?;
        parse_ascii(path, text)?
    };
    assemble(path, parsed)
}

/// The ASCII `.msh` file's sections.
#[allow(
    clippy::too_many_lines,
    reason = "a parser: one pass over the file's sections, each section's branch beside the others"
)]
fn parse_ascii(path: &Path, text: &str) -> Result<Parsed> {
    let section = |name: &str| -> Option<(usize, Vec<&str>)> {
        let start = text
            .find(&format!("${name}\n"))
            .or_else(|| text.find(&format!("${name}\r\n")))?;
        let line0 = text[..start].lines().count() + 2;
        let body_start = start + name.len() + 2;
        let end = text[body_start..].find(&format!("$End{name}"))? + body_start;
        Some((line0, text[body_start..end].lines().collect()))
    };
    let (_, fmt) = section("MeshFormat")
        .ok_or_else(|| Error::parse(path, 1, "no $MeshFormat section: not a Gmsh mesh"))?;
    let head: Vec<&str> = fmt
        .first()
        .map(|l| l.split_whitespace().collect())
        .unwrap_or_default();
    let version = head.first().copied().unwrap_or("");
    let needed = |name: &str| {
        section(name).ok_or_else(|| {
            let m = if text.contains(&format!("${name}")) {
                format!("${name} is not closed by $End{name} (truncated?)")
            } else {
                format!("no ${name} section")
            };
            Error::parse(path, 0, m)
        })
    };
    let (nl, nbody) = needed("Nodes")?;
    let (el, ebody) = needed("Elements")?;
    let names = match section("PhysicalNames") {
        Some((ln, body)) => physical_names(path, ln, &body)?,
        None => HashMap::new(),
    };
    let num = |ln: usize, s: &str| -> Result<f64> {
        s.parse::<f64>()
            .map_err(|_| Error::parse(path, ln, format!("{s:?} is not a number")))
    };
    let int = |ln: usize, s: &str| -> Result<i64> {
        s.parse::<i64>()
            .map_err(|_| Error::parse(path, ln, format!("{s:?} is not an integer")))
    };
    let ints = |ln: usize, l: &str| -> Result<Vec<i64>> {
        l.split_whitespace().map(|s| int(ln, s)).collect()
    };
    // A 4.1 block header: four integers on line `row` of a section starting at line `ln`.
    let block_header = |body: &[&str], ln: usize, row: usize, what: &str| -> Result<Vec<i64>> {
        let line = body
            .get(row)
            .ok_or_else(|| Error::parse(path, ln + row, format!("{what} is short (truncated?)")))?;
        let b = ints(ln + row, line)?;
        if b.len() != 4 {
            return Err(Error::parse(
                path,
                ln + row,
                format!("a {what} block header needs 4 numbers"),
            ));
        }
        Ok(b)
    };
    let mut node_index: HashMap<i64, usize> = HashMap::new();
    let mut nodes: Vec<Point<3>> = Vec::new();
    // (dim, gmsh type, node tags, physical tags, element tag)
    let mut elements: Vec<MshElement> = Vec::new();
    let too_many = |ln: usize, n: i64| -> Result<usize> {
        if n < 0 || n as usize > crate::formats::MAX_COUNT {
            Err(Error::parse(path, ln, format!("count {n} is out of range")))
        } else {
            Ok(n as usize)
        }
    };
    if version.starts_with('2') {
        let n = too_many(nl, int(nl, nbody.first().copied().unwrap_or("").trim())?)?;
        if nbody.len() < n + 1 {
            return Err(Error::parse(
                path,
                nl,
                format!(
                    "{n} nodes announced, {} present",
                    nbody.len().saturating_sub(1)
                ),
            ));
        }
        for (k, l) in nbody[1..=n].iter().enumerate() {
            let f: Vec<&str> = l.split_whitespace().collect();
            if f.len() < 4 {
                return Err(Error::parse(path, nl + 1 + k, "a node needs tag x y z"));
            }
            node_index.insert(int(nl + 1 + k, f[0])?, nodes.len());
            nodes.push([
                num(nl + 1 + k, f[1])?,
                num(nl + 1 + k, f[2])?,
                num(nl + 1 + k, f[3])?,
            ]);
        }
        let m = too_many(el, int(el, ebody.first().copied().unwrap_or("").trim())?)?;
        if ebody.len() < m + 1 {
            return Err(Error::parse(
                path,
                el,
                format!(
                    "{m} elements announced, {} present",
                    ebody.len().saturating_sub(1)
                ),
            ));
        }
        for (k, l) in ebody[1..=m].iter().enumerate() {
            let ln = el + 1 + k;
            let f: Vec<i64> = l
                .split_whitespace()
                .map(|s| int(ln, s))
                .collect::<Result<_>>()?;
            if f.len() < 3 || f[2] < 0 || f.len() < 3 + f[2] as usize {
                return Err(Error::parse(path, ln, "a short element line"));
            }
            let t = f[1] as u32;
            let ntags = f[2] as usize;
            let phys = if ntags > 0 { vec![f[3]] } else { vec![] };
            let Some(dim) = gmsh_dimension(t) else {
                continue;
            };
            elements.push((dim, t, f[3 + ntags..].to_vec(), phys, f[0]));
        }
    } else if version.starts_with("4.1") {
        // Entities: physical tags per (dim, entity tag).
        let mut phys_of: HashMap<(usize, i64), Vec<i64>> = HashMap::new();
        if let Some((ln, body)) = section("Entities") {
            let counts: Vec<i64> = body
                .first()
                .map(|l| {
                    l.split_whitespace()
                        .map(|s| int(ln, s))
                        .collect::<Result<_>>()
                })
                .transpose()?
                .unwrap_or_default();
            let mut row = 1;
            for (dim, &c) in counts.iter().enumerate().take(4) {
                for _ in 0..c.max(0) {
                    let l = body
                        .get(row)
                        .ok_or_else(|| Error::parse(path, ln + row, "$Entities is short"))?;
                    let f: Vec<&str> = l.split_whitespace().collect();
                    let skip = if dim == 0 { 4 } else { 7 };
                    if f.len() <= skip {
                        return Err(Error::parse(path, ln + row, "a short entity line"));
                    }
                    let tag = int(ln + row, f[0])?;
                    let np = too_many(ln + row, int(ln + row, f[skip])?)?;
                    let tags = f
                        .get(skip + 1..skip + 1 + np)
                        .ok_or_else(|| Error::parse(path, ln + row, "a short entity line"))?
                        .iter()
                        .map(|s| int(ln + row, s))
                        .collect::<Result<Vec<_>>>()?;
                    phys_of.insert((dim, tag), tags);
                    row += 1;
                }
            }
        }
        let head = ints(nl, nbody.first().copied().unwrap_or(""))?;
        let blocks = too_many(nl, *head.first().unwrap_or(&-1))?;
        let mut row = 1;
        for _ in 0..blocks {
            let b = block_header(&nbody, nl, row, "$Nodes")?;
            if b[2] != 0 {
                return Err(Error::parse(
                    path,
                    nl + row,
                    "parametric nodes are not read",
                ));
            }
            let n = too_many(nl + row, b[3])?;
            if nbody.len() < row + 1 + 2 * n {
                return Err(Error::parse(path, nl + row, "$Nodes is short (truncated?)"));
            }
            for k in 0..n {
                let tag = int(nl + row + 1 + k, nbody[row + 1 + k].trim())?;
                let ln = nl + row + 1 + n + k;
                let c: Vec<f64> = nbody[row + 1 + n + k]
                    .split_whitespace()
                    .map(|s| num(ln, s))
                    .collect::<Result<_>>()?;
                if c.len() != 3 {
                    return Err(Error::parse(path, ln, "a node needs x y z"));
                }
                node_index.insert(tag, nodes.len());
                nodes.push([c[0], c[1], c[2]]);
            }
            row += 1 + 2 * n;
        }
        let head = ints(el, ebody.first().copied().unwrap_or(""))?;
        let blocks = too_many(el, *head.first().unwrap_or(&-1))?;
        let mut row = 1;
        for _ in 0..blocks {
            let b = block_header(&ebody, el, row, "$Elements")?;
            let dim = b[0].max(0) as usize;
            let phys = phys_of.get(&(dim, b[1])).cloned().unwrap_or_default();
            let n = too_many(el + row, b[3])?;
            if ebody.len() < row + 1 + n {
                return Err(Error::parse(
                    path,
                    el + row,
                    "$Elements is short (truncated?)",
                ));
            }
            for k in 0..n {
                let ln = el + row + 1 + k;
                let f: Vec<i64> = ebody[row + 1 + k]
                    .split_whitespace()
                    .map(|s| int(ln, s))
                    .collect::<Result<_>>()?;
                elements.push((
                    dim,
                    b[2] as u32,
                    f.get(1..).unwrap_or_default().to_vec(),
                    phys.clone(),
                    f.first().copied().unwrap_or(0),
                ));
            }
            row += 1 + n;
        }
    } else {
        return Err(Error::parse(
            path,
            2,
            format!("Gmsh format version {version}; 2.2 and 4.1 are read"),
        ));
    }
    Ok(Parsed {
        names,
        node_index,
        nodes,
        elements,
        line: el,
    })
}

/// The FE mesh of a parsed file: the elements of the highest dimension, of one kind; physical
/// groups of the lower dimensions as node sets (points) and surfaces (faces).
#[allow(
    clippy::too_many_lines,
    reason = "a parser: the parse's second half: elements, then the physical groups as sets, one error path"
)]
fn assemble(path: &Path, p: Parsed) -> Result<FeMesh<3>> {
    let Parsed {
        names,
        node_index,
        nodes,
        mut elements,
        line: el,
    } = p;
    if node_index.len() != nodes.len() {
        // A repeated tag would silently replace the earlier node.
        return Err(Error::parse(
            path,
            0,
            format!(
                "{} node tags are repeated ({} nodes, {} distinct tags)",
                nodes.len() - node_index.len(),
                nodes.len(),
                node_index.len()
            ),
        ));
    }
    let top = elements
        .iter()
        .filter(|e| ElementKind::from_gmsh_type(e.1).is_some())
        .map(|e| e.0)
        .max()
        .ok_or_else(|| {
            Error::parse(
                path,
                el,
                "no triangle, quadrangle, tetrahedron or hexahedron",
            )
        })?;
    // The mesh's elements in the order of their tags (a writer may group them by entity).
    elements.sort_by_key(|e| (e.0 != top, e.4));
    let mut kind: Option<ElementKind> = None;
    let mut conn = Vec::new();
    let mut sets = MeshSets::default();
    let mut face_of: HashMap<Vec<usize>, (usize, u8)> = HashMap::new();
    let node = |ln: usize, t: i64| -> Result<usize> {
        node_index.get(&t).copied().ok_or_else(|| {
            Error::parse(
                path,
                ln,
                format!("an element names node {t}, which is not defined"),
            )
        })
    };
    let mut found: BTreeMap<u32, usize> = BTreeMap::new();
    for e in elements.iter().filter(|e| e.0 == top) {
        *found.entry(e.1).or_default() += 1;
    }
    if found.len() > 1
        || found
            .keys()
            .any(|&t| ElementKind::from_gmsh_type(t).is_none())
    {
        let listed: Vec<String> = found
            .iter()
            .map(|(t, n)| format!("{n} of Gmsh type {t}"))
            .collect();
        return Err(Error::parse(
            path,
            el,
            format!(
                "the {top}D elements are {}; one kind of triangles (2), quadrangles (3), tetrahedra (4, 11) or hexahedra (5, 17) is read",
                listed.join(", ")
            ),
        ));
    }
    for (dim, t, tags, phys, _) in elements.iter().filter(|e| e.0 == top) {
        let k = ElementKind::from_gmsh_type(*t)
            .ok_or_else(|| Error::parse(path, el, format!("element type {t} is not read")))?;
        kind = Some(k);
        if tags.len() != k.nodes() {
            return Err(Error::parse(
                path,
                el,
                format!("a {} with {} nodes", k.name(), tags.len()),
            ));
        }
        let e = conn.len() / k.nodes();
        // Gmsh numbers the mid-edge nodes of quadratic elements its own way.
        for &g in k.gmsh_order() {
            conn.push(node(el, tags[g])?);
        }
        for p in phys {
            let name = names
                .get(&(*dim, *p))
                .cloned()
                .unwrap_or_else(|| format!("physical_{p}"));
            sets.element_sets.entry(name).or_default().push(e);
        }
    }
    let kind = kind.ok_or_else(|| Error::parse(path, el, "no elements"))?;
    for e in 0..conn.len() / kind.nodes() {
        for (f, local) in kind.faces().iter().enumerate() {
            let mut key: Vec<usize> = local.iter().map(|&c| conn[e * kind.nodes() + c]).collect();
            key.sort_unstable();
            face_of.insert(key, (e, f as u8));
        }
    }
    for (dim, t, tags, phys, _) in &elements {
        if phys.is_empty() || *dim == top {
            continue;
        }
        let mut ids: Vec<usize> = tags.iter().map(|&n| node(el, n)).collect::<Result<_>>()?;
        // A face of a quadratic element (3-node line, 6-node triangle, 8- or 9-node
        // quadrangle) is matched by its corners, which Gmsh lists first; a node set takes
        // all of its nodes.
        let corners = match t {
            8 => 2,
            9 => 3,
            16 | 10 => 4,
            _ => ids.len(),
        };
        if *dim + 1 == top {
            ids.truncate(corners);
        }
        for p in phys {
            let name = names
                .get(&(*dim, *p))
                .cloned()
                .unwrap_or_else(|| format!("physical_{p}"));
            if *dim == 0 {
                sets.node_sets
                    .entry(name)
                    .or_default()
                    .extend(ids.iter().copied());
            } else if *dim + 1 == top {
                let mut key = ids.clone();
                key.sort_unstable();
                let f = face_of.get(&key).ok_or_else(|| {
                    Error::parse(
                        path,
                        el,
                        format!("physical group {name}: a face that is not an element's face"),
                    )
                })?;
                sets.surfaces.entry(name).or_default().push(*f);
            }
        }
    }
    for v in sets
        .node_sets
        .values_mut()
        .chain(sets.element_sets.values_mut())
    {
        v.sort_unstable();
        v.dedup();
    }
    for v in sets.surfaces.values_mut() {
        v.sort_unstable();
        v.dedup();
    }
    // The whole-mesh group the writer adds is not carried as a set.
    super::helpers::drop_whole_mesh_sets(path, &mut sets, nodes.len(), conn.len() / kind.nodes())?;
    check_mesh(path, &nodes, kind, &conn, &sets)?;
    Ok(FeMesh {
        nodes,
        kind,
        connectivity: conn,
        sets,
    })
}

/// Gmsh 4.1 ASCII with physical groups for the sets.
pub fn msh<const D: usize>(mesh: &FeMesh<D>) -> String {
    msh_with_element_data(mesh, &[])
}

/// [`msh`] with one `$ElementData` view per named per-element field (`(name, one value per
/// element)`, names plain), the elements by their ids.
pub fn msh_with_element_data<const D: usize>(
    mesh: &FeMesh<D>,
    fields: &[(&str, Vec<f64>)],
) -> String {
    let g = Groups::of(mesh);
    let nn = mesh.nodes.len();
    let (lo, hi) = bounding_box(&mesh.nodes);
    let (lo, hi) = (xyz(&lo), xyz(&hi));
    let bbox = format!(
        "{} {} {} {} {} {}",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    let mut s = String::with_capacity(nn * 70 + mesh.connectivity.len() * 8);
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    if !g.names.is_empty() {
        let _ = writeln!(s, "$PhysicalNames\n{}", g.names.len());
        for (d, t, n) in &g.names {
            let _ = writeln!(s, "{d} {t} \"{n}\"");
        }
        s.push_str("$EndPhysicalNames\n");
    }
    entities(&mut s, mesh, &g, &bbox);
    // All nodes in the first element group's entity.
    let _ = writeln!(s, "$Nodes\n1 {nn} 1 {nn}\n{D} 1 0 {nn}");
    for i in 0..nn {
        let _ = writeln!(s, "{}", i + 1);
    }
    for p in &mesh.nodes {
        let q = xyz(p);
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", q[0], q[1], q[2]);
    }
    s.push_str("$EndNodes\n");
    elements(&mut s, mesh, &g);
    for (name, values) in fields {
        let _ = writeln!(
            s,
            "$ElementData\n1\n\"{name}\"\n1\n0.0\n3\n0\n1\n{}",
            values.len()
        );
        for (e, v) in values.iter().enumerate() {
            let _ = writeln!(s, "{} {v:.17e}", e + 1);
        }
        s.push_str("$EndElementData\n");
    }
    s
}

/// The physical groups of a mesh as the `.msh` writer lays them out: tags unique over all sets
/// (element sets of dimension D, surfaces D-1, node sets 0), the elements grouped by the
/// element sets that hold them, one point entity per node set (a node in two sets is a point
/// element in both).
struct Groups<'m> {
    /// `(dimension, tag, name)` of every physical group.
    names: Vec<(usize, usize, String)>,
    /// Tag of every surface.
    sf_tags: BTreeMap<&'m str, usize>,
    /// Elements by the tags of the sets that hold them.
    groups: BTreeMap<Vec<usize>, Vec<usize>>,
    /// Every node set: its physical tag and its nodes.
    node_sets: Vec<(usize, &'m Vec<usize>)>,
    /// The surfaces, by name.
    surfaces: Vec<(&'m String, &'m Vec<(usize, u8)>)>,
}

impl<'m> Groups<'m> {
    fn of<const D: usize>(mesh: &'m FeMesh<D>) -> Self {
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
        let node_sets = sets
            .node_sets
            .iter()
            .filter(|(_, m)| !m.is_empty())
            .map(|(n, m)| (nd_tags[n.as_str()], m))
            .collect();
        let surfaces: Vec<(&String, &Vec<(usize, u8)>)> = sets.surfaces.iter().collect();
        Groups {
            names,
            sf_tags,
            groups,
            node_sets,
            surfaces,
        }
    }
}

/// The `$Entities` section: points (one per node set, at its first node), then D-1
/// (surfaces), then D (element groups), each within the bounding box `bbox`.
fn entities<const D: usize>(s: &mut String, mesh: &FeMesh<D>, g: &Groups, bbox: &str) {
    let Groups {
        sf_tags,
        groups,
        node_sets,
        surfaces,
        ..
    } = g;
    let mut counts = [0usize; 4];
    counts[0] = node_sets.len();
    counts[D - 1] += surfaces.len();
    counts[D] += groups.len();
    s.push_str("$Entities\n");
    let _ = writeln!(s, "{} {} {} {}", counts[0], counts[1], counts[2], counts[3]);
    let mut entity_lines: [Vec<String>; 4] = Default::default();
    for (k, (t, m)) in node_sets.iter().enumerate() {
        let q = xyz(&mesh.nodes[m[0]]);
        entity_lines[0].push(format!("{} {} {} {} 1 {t}", k + 1, q[0], q[1], q[2]));
    }
    for (k, (n, _)) in surfaces.iter().enumerate() {
        entity_lines[D - 1].push(format!("{} {bbox} 1 {} 0", k + 1, sf_tags[n.as_str()]));
    }
    // Entity tags are numbered per dimension, from 1.
    for (k, (t, _)) in groups.iter().enumerate() {
        let tags = t
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" ");
        entity_lines[D].push(format!(
            "{} {bbox} {} {}{}0",
            k + 1,
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
}

/// The `$Elements` section: the FE elements by group (in Gmsh's node order), then the
/// surfaces' faces, then the point elements of every node set.
fn elements<const D: usize>(s: &mut String, mesh: &FeMesh<D>, g: &Groups) {
    let Groups {
        groups,
        node_sets,
        surfaces,
        ..
    } = g;
    let ne = mesh.num_elements();
    let quadratic = mesh.kind.linear() != mesh.kind;
    let face_type = match (D, mesh.kind.faces()[0].len(), quadratic) {
        (2, _, _) => 1,     // 2-node line
        (_, 3, false) => 2, // triangle
        (_, 3, true) => 9,  // 6-node triangle
        (_, _, false) => 3, // quadrangle
        (_, _, true) => 16, // 8-node quadrangle
    };
    let n_faces: usize = surfaces.iter().map(|(_, f)| f.len()).sum();
    let n_points: usize = node_sets.iter().map(|(_, m)| m.len()).sum();
    let total = ne + n_faces + n_points;
    let n_blocks = groups.len() + surfaces.len() + node_sets.len();
    let _ = writeln!(s, "$Elements\n{n_blocks} {total} 1 {total}");
    for (k, (_, els)) in groups.iter().enumerate() {
        let _ = writeln!(s, "{D} {} {} {}", k + 1, mesh.kind.gmsh_type(), els.len());
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
    for (k, (_, m)) in node_sets.iter().enumerate() {
        let _ = writeln!(s, "0 {} 15 {}", k + 1, m.len());
        for &i in m.iter() {
            next += 1;
            let _ = writeln!(s, "{next} {}", i + 1);
        }
    }
    s.push_str("$EndElements\n");
}

/// The element-type table of this format.
impl ElementKind {
    /// Gmsh element type number.
    pub fn gmsh_type(self) -> u32 {
        match self {
            ElementKind::Tri3 => 2,
            ElementKind::Quad4 => 3,
            ElementKind::Tet4 => 4,
            ElementKind::Hex8 => 5,
            ElementKind::Tet10 => 11,
            ElementKind::Hex20 => 17,
        }
    }
    /// The kind of Gmsh element type `t`.
    pub fn from_gmsh_type(t: u32) -> Option<Self> {
        ALL_KINDS.into_iter().find(|k| k.gmsh_type() == t)
    }
    /// For each node in this crate's (VTK) order, its place in Gmsh's order of the element's
    /// nodes (the identity for the linear kinds).
    pub fn gmsh_order(self) -> &'static [usize] {
        match self {
            // Gmsh's hexahedron 20: edges (0,1) (0,3) (0,4) (1,2) (1,5) (2,3) (2,6) (3,7)
            // (4,5) (4,7) (5,6) (6,7).
            ElementKind::Hex20 => &[
                0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
            ],
            // Gmsh's tetrahedron 10: edges (0,1) (1,2) (2,0) (0,3) (2,3) (1,3).
            ElementKind::Tet10 => &[0, 1, 2, 3, 4, 5, 6, 7, 9, 8],
            ElementKind::Quad4 => &[0, 1, 2, 3],
            ElementKind::Tri3 => &[0, 1, 2],
            ElementKind::Tet4 => &[0, 1, 2, 3],
            ElementKind::Hex8 => &[0, 1, 2, 3, 4, 5, 6, 7],
        }
    }
}

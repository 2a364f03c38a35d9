//! Reading FE meshes that users bring as templates, with their sets: Abaqus/CalculiX `.inp`,
//! Gmsh `.msh` (2.2 and 4.1, ASCII), VTU and legacy VTK (ASCII `UNSTRUCTURED_GRID`). One
//! element type per mesh (tri3, quad4, tet4, hex8, tet10, hex20); node ordering as in
//! [`crate::fe::ElementKind`] (Gmsh's mid-edge nodes reordered to it).
//!
//! Sets: `.inp` `*NSET`, `*ELSET` (lists, `GENERATE` ranges, other sets by name) and
//! `*SURFACE, TYPE=ELEMENT` (`element or element set, Sk`); `.msh` physical groups (of the
//! elements' dimension: element sets; one lower: surfaces, matched to element faces; points:
//! node sets); VTU/VTK `set_NAME` point and cell data.

use crate::error::{Error, Result};
use crate::fe::{ElementKind, FeMesh, MeshSets};
use crate::geometry::Point;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Reads an FE mesh of dimension `D` (format from the extension).
pub fn read_fe_mesh<const D: usize>(path: &Path) -> Result<FeMesh<D>> {
    to_dimension(path, read_fe_mesh_raw(path)?)
}

/// Reads an FE mesh with 3D node coordinates, whatever its elements' dimension
/// (`mesh.kind.dimension()` tells; [`to_dimension`] converts).
pub fn read_fe_mesh_raw(path: &Path) -> Result<FeMesh<3>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "inp" => Ok(read_inp(path)?.mesh),
        "msh" => read_msh(path),
        "vtu" => super::vtkxml::read_vtu(path),
        "vtk" => read_vtk_unstructured(path),
        _ => Err(Error::parse(
            path,
            0,
            "unknown FE mesh format; use .inp, .msh, .vtu or .vtk",
        )),
    }
}

/// A 3D-coordinate mesh as a mesh of dimension `D` (2D: elements must be 2D and `z` zero).
pub fn to_dimension<const D: usize>(path: &Path, m: FeMesh<3>) -> Result<FeMesh<D>> {
    if m.kind.dimension() != D {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the mesh has {} elements ({}D) but a {D}D mesh is needed",
                m.kind.name(),
                m.kind.dimension()
            ),
        ));
    }
    if D == 2
        && let Some(i) = m.nodes.iter().position(|p| p[2] != 0.0)
    {
        return Err(Error::parse(
            path,
            0,
            format!("node {} of a 2D mesh has z = {}", i + 1, m.nodes[i][2]),
        ));
    }
    let nodes: Vec<Point<D>> = m
        .nodes
        .iter()
        .map(|p| std::array::from_fn(|d| p[d]))
        .collect();
    check_mesh(path, &nodes, m.kind, &m.connectivity, &m.sets)?;
    Ok(FeMesh {
        nodes,
        kind: m.kind,
        connectivity: m.connectivity,
        sets: m.sets,
    })
}

fn check_mesh<const D: usize>(
    path: &Path,
    nodes: &[Point<D>],
    kind: ElementKind,
    conn: &[usize],
    sets: &MeshSets,
) -> Result<()> {
    if conn.is_empty() {
        return Err(Error::parse(path, 0, "the mesh has no elements"));
    }
    if let Some(i) = nodes.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(Error::parse(
            path,
            0,
            format!("node {} has a NaN or infinite coordinate", i + 1),
        ));
    }
    sets.check(kind, nodes.len(), conn.len() / kind.nodes())
        .map_err(|m| Error::parse(path, 0, m))
}

/// A set as read: display name, its items (line, id or set name), and whether `GENERATE`.
type RawSet = (String, Vec<(usize, String)>, bool);
/// A surface as read: display name and its items (line, element or element set, face).
type RawSurface = (String, Vec<(usize, String, String)>);
/// A Gmsh element as read: dimension, type, node tags, physical tags, element tag.
type MshElement = (usize, u32, Vec<i64>, Vec<i64>, i64);

/// An `.inp` deck: the mesh, and the 1-based node ids in file order (node `k` of the mesh has
/// id `node_ids[k]`).
#[derive(Clone, Debug)]
pub struct InpDeck {
    pub mesh: FeMesh<3>,
    pub node_ids: Vec<u64>,
    pub text: String,
}

fn keyword_params(line: &str) -> (String, HashMap<String, String>) {
    let mut parts = line.trim_start_matches('*').split(',');
    let kw = parts.next().unwrap_or("").trim().to_ascii_uppercase();
    let mut params = HashMap::new();
    for p in parts {
        let mut kv = p.splitn(2, '=');
        let k = kv.next().unwrap_or("").trim().to_ascii_uppercase();
        let v = kv.next().unwrap_or("").trim().to_string();
        if !k.is_empty() {
            params.insert(k, v);
        }
    }
    (kw, params)
}

/// Reads an Abaqus/CalculiX input file: `*NODE`, `*ELEMENT`, `*NSET`, `*ELSET`, `*SURFACE`;
/// other keywords (materials, steps, ...) are skipped here and kept in `text`.
pub fn read_inp(path: &Path) -> Result<InpDeck> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut node_ids: Vec<u64> = Vec::new();
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let mut nodes: Vec<Point<3>> = Vec::new();
    let mut kind: Option<ElementKind> = None;
    let mut elem_index: HashMap<u64, usize> = HashMap::new();
    let mut conn: Vec<usize> = Vec::new();
    // Sets by upper-case name, as raw ids until all nodes and elements are known.
    let mut nsets: BTreeMap<String, RawSet> = BTreeMap::new();
    let mut elsets: BTreeMap<String, RawSet> = BTreeMap::new();
    let mut surfaces: BTreeMap<String, RawSurface> = BTreeMap::new();
    enum Block {
        None,
        Node(Option<String>),
        Element(ElementKind, Option<String>),
        NSet(String),
        ElSet(String),
        Surface(String),
    }
    let mut block = Block::None;
    let mut pending: Vec<u64> = Vec::new();
    let mut pending_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with("**") {
            continue;
        }
        if line.starts_with('*') {
            if !pending.is_empty() {
                return Err(Error::parse(
                    path,
                    pending_line,
                    "an element's node list is cut short",
                ));
            }
            let (kw, p) = keyword_params(line);
            block = match kw.as_str() {
                "NODE" => Block::Node(p.get("NSET").cloned()),
                "ELEMENT" => {
                    let t = p.get("TYPE").cloned().unwrap_or_default();
                    let k = ElementKind::from_abaqus_type(&t).ok_or_else(|| {
                        Error::parse(
                            path,
                            ln,
                            format!(
                                "element type {t:?} is not supported; atlasmesh reads C3D8 (and R, H, I variants), C3D20, C3D4, C3D10 (and M), CPS4/CPE4/CAX4 and CPS3/CPE3/CAX3"
                            ),
                        )
                    })?;
                    if let Some(k0) = kind
                        && k0 != k
                    {
                        return Err(Error::parse(
                            path,
                            ln,
                            format!(
                                "element type {t} after {} elements; one element type per mesh",
                                k0.abaqus_type()
                            ),
                        ));
                    }
                    kind = Some(k);
                    Block::Element(k, p.get("ELSET").cloned())
                }
                "NSET" => {
                    let name = p.get("NSET").cloned().unwrap_or_default();
                    let e = nsets.entry(name.to_ascii_uppercase()).or_insert((
                        name.clone(),
                        Vec::new(),
                        false,
                    ));
                    e.2 = p.contains_key("GENERATE");
                    Block::NSet(name.to_ascii_uppercase())
                }
                "ELSET" => {
                    let name = p.get("ELSET").cloned().unwrap_or_default();
                    let e = elsets.entry(name.to_ascii_uppercase()).or_insert((
                        name.clone(),
                        Vec::new(),
                        false,
                    ));
                    e.2 = p.contains_key("GENERATE");
                    Block::ElSet(name.to_ascii_uppercase())
                }
                "SURFACE" => {
                    let name = p.get("NAME").cloned().unwrap_or_default();
                    let t = p
                        .get("TYPE")
                        .map(|s| s.to_ascii_uppercase())
                        .unwrap_or_else(|| "ELEMENT".into());
                    if t != "ELEMENT" {
                        return Err(Error::parse(
                            path,
                            ln,
                            format!("*SURFACE {name}: only TYPE=ELEMENT surfaces are read"),
                        ));
                    }
                    surfaces
                        .entry(name.to_ascii_uppercase())
                        .or_insert((name.clone(), Vec::new()));
                    Block::Surface(name.to_ascii_uppercase())
                }
                "INCLUDE" => {
                    return Err(Error::parse(
                        path,
                        ln,
                        "*INCLUDE is not followed; give the included file's mesh directly",
                    ));
                }
                _ => Block::None,
            };
            continue;
        }
        let fields: Vec<&str> = line
            .split(',')
            .map(str::trim)
            .filter(|f| !f.is_empty())
            .collect();
        let int = |f: &str| -> Result<u64> {
            f.parse::<u64>()
                .map_err(|_| Error::parse(path, ln, format!("{f:?} is not a positive integer id")))
        };
        match &mut block {
            Block::None => {}
            Block::Node(set) => {
                if fields.len() < 3 || fields.len() > 4 {
                    return Err(Error::parse(
                        path,
                        ln,
                        format!(
                            "a node line needs id, x, y[, z]; found {} fields",
                            fields.len()
                        ),
                    ));
                }
                let id = int(fields[0])?;
                let mut p = [0.0; 3];
                for (d, f) in fields[1..].iter().enumerate() {
                    p[d] = f
                        .parse::<f64>()
                        .map_err(|_| Error::parse(path, ln, format!("{f:?} is not a number")))?;
                    if !p[d].is_finite() {
                        return Err(Error::parse(path, ln, "a NaN or infinite coordinate"));
                    }
                }
                if node_index.insert(id, nodes.len()).is_some() {
                    return Err(Error::parse(
                        path,
                        ln,
                        format!("node {id} is defined twice"),
                    ));
                }
                node_ids.push(id);
                nodes.push(p);
                if let Some(s) = set {
                    nsets
                        .entry(s.to_ascii_uppercase())
                        .or_insert((s.clone(), Vec::new(), false))
                        .1
                        .push((ln, id.to_string()));
                }
            }
            Block::Element(k, set) => {
                if pending.is_empty() {
                    pending_line = ln;
                }
                for f in &fields {
                    pending.push(int(f)?);
                }
                let need = k.nodes() + 1;
                if pending.len() > need {
                    return Err(Error::parse(
                        path,
                        ln,
                        format!(
                            "{} values for a {} element (id and {} nodes expected)",
                            pending.len(),
                            k.abaqus_type(),
                            k.nodes()
                        ),
                    ));
                }
                if pending.len() == need {
                    let id = pending[0];
                    if elem_index.insert(id, conn.len() / k.nodes()).is_some() {
                        return Err(Error::parse(
                            path,
                            ln,
                            format!("element {id} is defined twice"),
                        ));
                    }
                    for &n in &pending[1..] {
                        let idx = *node_index.get(&n).ok_or_else(|| {
                            Error::parse(
                                path,
                                ln,
                                format!(
                                    "element {id} names node {n}, which is not defined (above)"
                                ),
                            )
                        })?;
                        conn.push(idx);
                    }
                    if let Some(s) = set {
                        elsets
                            .entry(s.to_ascii_uppercase())
                            .or_insert((s.clone(), Vec::new(), false))
                            .1
                            .push((ln, id.to_string()));
                    }
                    pending.clear();
                }
            }
            Block::NSet(name) => {
                if let Some(e) = nsets.get_mut(name.as_str()) {
                    e.1.extend(fields.iter().map(|f| (ln, f.to_string())));
                }
            }
            Block::ElSet(name) => {
                if let Some(e) = elsets.get_mut(name.as_str()) {
                    e.1.extend(fields.iter().map(|f| (ln, f.to_string())));
                }
            }
            Block::Surface(name) => {
                if fields.len() != 2 {
                    return Err(Error::parse(
                        path,
                        ln,
                        "a *SURFACE line needs an element (or element set) and a face Sk",
                    ));
                }
                if let Some(e) = surfaces.get_mut(name.as_str()) {
                    e.1.push((ln, fields[0].to_string(), fields[1].to_ascii_uppercase()));
                }
            }
        }
    }
    if !pending.is_empty() {
        return Err(Error::parse(
            path,
            pending_line,
            "the file ends inside an element's node list (truncated?)",
        ));
    }
    let kind =
        kind.ok_or_else(|| Error::parse(path, 0, "no *ELEMENT block: the file has no mesh"))?;
    if nodes.is_empty() {
        return Err(Error::parse(path, 0, "no *NODE block"));
    }
    // Resolve the sets: ids, GENERATE ranges and other sets by name.
    fn resolve(
        path: &Path,
        what: &str,
        raw: &BTreeMap<String, RawSet>,
        index: &HashMap<u64, usize>,
    ) -> Result<BTreeMap<String, Vec<usize>>> {
        let mut out: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (key, (name, items, generate)) in raw {
            let mut members = Vec::new();
            let get = |ln: usize, id: u64| -> Result<usize> {
                index.get(&id).copied().ok_or_else(|| {
                    Error::parse(
                        path,
                        ln,
                        format!("{what} set {name} names {what} {id}, which does not exist"),
                    )
                })
            };
            if *generate {
                for ch in items.chunks(3) {
                    let ln = ch[0].0;
                    let v: Vec<u64> = ch
                        .iter()
                        .map(|(_, f)| f.parse::<u64>())
                        .collect::<std::result::Result<_, _>>()
                        .map_err(|_| Error::parse(path, ln, "GENERATE needs first, last, step"))?;
                    let (a, b, s) = (v[0], *v.get(1).unwrap_or(&v[0]), *v.get(2).unwrap_or(&1));
                    if s == 0 || b < a || (b - a) / s > 100_000_000 {
                        return Err(Error::parse(path, ln, "GENERATE: bad range"));
                    }
                    let mut id = a;
                    while id <= b {
                        members.push(get(ln, id)?);
                        id += s;
                    }
                }
            } else {
                for (ln, f) in items {
                    match f.parse::<u64>() {
                        Ok(id) => members.push(get(*ln, id)?),
                        Err(_) => {
                            let other = raw.get(&f.to_ascii_uppercase()).filter(|_| f != key);
                            let Some((_, sub, _)) = other else {
                                return Err(Error::parse(
                                    path,
                                    *ln,
                                    format!(
                                        "{what} set {name}: {f:?} is neither an id nor a set defined before"
                                    ),
                                ));
                            };
                            for (l2, g) in sub {
                                let id = g.parse::<u64>().map_err(|_| {
                                    Error::parse(path, *l2, "nested sets of sets are not read")
                                })?;
                                members.push(get(*l2, id)?);
                            }
                        }
                    }
                }
            }
            members.sort_unstable();
            members.dedup();
            out.insert(name.clone(), members);
        }
        Ok(out)
    }
    // The whole-mesh sets this writer adds are not carried as sets.
    let node_sets: BTreeMap<String, Vec<usize>> = resolve(path, "node", &nsets, &node_index)?
        .into_iter()
        .filter(|(n, _)| !n.eq_ignore_ascii_case("NALL"))
        .collect();
    let element_sets_all = resolve(path, "element", &elsets, &elem_index)?;
    let mut surface_sets: BTreeMap<String, Vec<(usize, u8)>> = BTreeMap::new();
    for (name, items) in surfaces.values() {
        let mut faces = Vec::new();
        for (ln, target, face) in items {
            let f: u8 = face
                .strip_prefix('S')
                .and_then(|v| v.parse::<u8>().ok())
                .filter(|v| *v >= 1 && (*v as usize) <= kind.faces().len())
                .ok_or_else(|| {
                    Error::parse(
                        path,
                        *ln,
                        format!(
                            "surface {name}: face {face:?}; a {} has faces S1-S{}",
                            kind.abaqus_type(),
                            kind.faces().len()
                        ),
                    )
                })?
                - 1;
            match target.parse::<u64>() {
                Ok(id) => {
                    let e = *elem_index.get(&id).ok_or_else(|| {
                        Error::parse(
                            path,
                            *ln,
                            format!("surface {name} names element {id}, which does not exist"),
                        )
                    })?;
                    faces.push((e, f));
                }
                Err(_) => {
                    let set = element_sets_all
                        .iter()
                        .find(|(k, _)| k.eq_ignore_ascii_case(target))
                        .ok_or_else(|| {
                            Error::parse(
                                path,
                                *ln,
                                format!("surface {name} names element set {target}, which is not defined"),
                            )
                        })?;
                    faces.extend(set.1.iter().map(|&e| (e, f)));
                }
            }
        }
        faces.sort_unstable();
        faces.dedup();
        surface_sets.insert(name.clone(), faces);
    }
    let element_sets = element_sets_all
        .into_iter()
        .filter(|(n, _)| !n.eq_ignore_ascii_case("EALL"))
        .collect();
    Ok(InpDeck {
        mesh: FeMesh {
            nodes,
            kind,
            connectivity: conn,
            sets: MeshSets {
                node_sets,
                element_sets,
                surfaces: surface_sets,
            },
        },
        node_ids,
        text,
    })
}

impl InpDeck {
    /// The deck with the coordinates of its nodes replaced by `nodes` (same order as the
    /// mesh), every other line as it was.
    pub fn with_nodes<const D: usize>(&self, nodes: &[Point<D>]) -> Result<String> {
        if nodes.len() != self.node_ids.len() {
            return Err(Error::Mesh(format!(
                "the deck has {} nodes but the mesh {}",
                self.node_ids.len(),
                nodes.len()
            )));
        }
        let index: HashMap<u64, usize> = self
            .node_ids
            .iter()
            .enumerate()
            .map(|(k, id)| (*id, k))
            .collect();
        let mut out = String::with_capacity(self.text.len() + nodes.len() * 16);
        let mut in_node = false;
        for line in self.text.lines() {
            let t = line.trim();
            if t.starts_with('*') && !t.starts_with("**") {
                in_node = keyword_params(t).0 == "NODE";
            } else if in_node && !t.is_empty() && !t.starts_with("**") {
                let id = t
                    .split(',')
                    .next()
                    .and_then(|f| f.trim().parse::<u64>().ok());
                if let Some(k) = id.and_then(|id| index.get(&id).copied()) {
                    let p = nodes[k];
                    out.push_str(&self.node_ids[k].to_string());
                    // CalculiX reads at most 20 characters per number.
                    for v in p.iter() {
                        out.push_str(&format!(", {v:.12e}"));
                    }
                    out.push('\n');
                    continue;
                }
            }
            out.push_str(line);
            out.push('\n');
        }
        Ok(out)
    }
}

/// Reads a Gmsh mesh, version 2.2 or 4.1, ASCII. The elements of the highest dimension form
/// the mesh; physical groups become sets (see the module doc).
pub fn read_msh(path: &Path) -> Result<FeMesh<3>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
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
    if head.get(1) != Some(&"0") {
        return Err(Error::parse(
            path,
            2,
            "binary .msh files are not read; save as ASCII",
        ));
    }
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
    let mut names: HashMap<(usize, i64), String> = HashMap::new();
    if let Some((ln, body)) = section("PhysicalNames") {
        for (k, l) in body.iter().enumerate().skip(1) {
            let mut it = l.splitn(3, char::is_whitespace);
            let (Some(d), Some(t), Some(n)) = (it.next(), it.next(), it.next()) else {
                return Err(Error::parse(
                    path,
                    ln + k,
                    "a physical name needs dim, tag, name",
                ));
            };
            let d: usize = d
                .parse()
                .map_err(|_| Error::parse(path, ln + k, "bad dimension"))?;
            let t: i64 = t
                .parse()
                .map_err(|_| Error::parse(path, ln + k, "bad tag"))?;
            names.insert((d, t), n.trim().trim_matches('"').to_string());
        }
    }
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
        if n < 0 || n as usize > crate::io::MAX_COUNT {
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
            let dim = match t {
                15 => 0,
                1 => 1,
                2 | 3 => 2,
                4 | 5 => 3,
                _ => continue,
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
    for (dim, t, tags, phys, _) in elements.iter().filter(|e| e.0 == top) {
        let k = ElementKind::from_gmsh_type(*t).ok_or_else(|| {
            Error::parse(
                path,
                el,
                format!("element type {t} among the {top}D elements is not read"),
            )
        })?;
        if kind.is_some_and(|k0| k0 != k) {
            return Err(Error::parse(path, el, "one element type per mesh"));
        }
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
            // The whole-mesh group the writer adds is not carried as a set.
            if name != "EALL" {
                sets.element_sets.entry(name).or_default().push(e);
            }
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
    check_mesh(path, &nodes, kind, &conn, &sets)?;
    Ok(FeMesh {
        nodes,
        kind,
        connectivity: conn,
        sets,
    })
}

/// Reads a legacy VTK ASCII `UNSTRUCTURED_GRID` (one cell type), with `set_NAME` scalars as
/// sets.
pub fn read_vtk_unstructured(path: &Path) -> Result<FeMesh<3>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let lines: Vec<&str> = text.lines().collect();
    if !lines
        .first()
        .is_some_and(|l| l.starts_with("# vtk DataFile"))
    {
        return Err(Error::parse(path, 1, "not a legacy VTK file"));
    }
    if lines.get(2).map(|l| l.trim().to_ascii_uppercase()) != Some("ASCII".into()) {
        return Err(Error::parse(
            path,
            3,
            "binary legacy VTK meshes are not read; use ASCII or VTU",
        ));
    }
    if !text.contains("UNSTRUCTURED_GRID") {
        return Err(Error::parse(path, 4, "not an UNSTRUCTURED_GRID"));
    }
    // Tokens with their line numbers.
    let toks: Vec<(usize, &str)> = lines
        .iter()
        .enumerate()
        .skip(3)
        .flat_map(|(i, l)| l.split_whitespace().map(move |t| (i + 1, t)))
        .collect();
    let mut at = 0;
    let find = |kw: &str, from: usize| {
        toks[from..]
            .iter()
            .position(|t| t.1.eq_ignore_ascii_case(kw))
            .map(|p| p + from)
    };
    let count = |i: usize| -> Result<usize> {
        let (ln, t) = toks
            .get(i)
            .copied()
            .ok_or_else(|| Error::parse(path, 0, "truncated"))?;
        let n: usize = t
            .parse()
            .map_err(|_| Error::parse(path, ln, format!("{t:?} is not a count")))?;
        if n > crate::io::MAX_COUNT {
            return Err(Error::parse(path, ln, format!("count {n} is out of range")));
        }
        Ok(n)
    };
    let p = find("POINTS", at).ok_or_else(|| Error::parse(path, 0, "no POINTS"))?;
    let n = count(p + 1)?;
    at = p + 3;
    let vals = toks
        .get(at..at + 3 * n)
        .ok_or_else(|| Error::parse(path, 0, "POINTS is short (truncated?)"))?;
    let mut nodes = Vec::with_capacity(n);
    for c in vals.chunks(3) {
        let v: Vec<f64> = c
            .iter()
            .map(|(ln, t)| {
                t.parse::<f64>()
                    .map_err(|_| Error::parse(path, *ln, format!("{t:?} is not a number")))
            })
            .collect::<Result<_>>()?;
        nodes.push([v[0], v[1], v[2]]);
    }
    at += 3 * n;
    let c = find("CELLS", at).ok_or_else(|| Error::parse(path, 0, "no CELLS"))?;
    let ne = count(c + 1)?;
    let size = count(c + 2)?;
    let body = toks
        .get(c + 3..c + 3 + size)
        .ok_or_else(|| Error::parse(path, 0, "CELLS is short (truncated?)"))?;
    let t =
        find("CELL_TYPES", c + 3 + size).ok_or_else(|| Error::parse(path, 0, "no CELL_TYPES"))?;
    let types = toks
        .get(t + 2..t + 2 + ne)
        .ok_or_else(|| Error::parse(path, 0, "CELL_TYPES is short"))?;
    let kind = types
        .first()
        .and_then(|(_, s)| s.parse::<u8>().ok())
        .and_then(ElementKind::from_vtk_type)
        .ok_or_else(|| {
            Error::parse(
                path,
                0,
                "cell type: triangles, quads, tetrahedra or hexahedra",
            )
        })?;
    if types
        .iter()
        .any(|(_, s)| s.parse::<u8>().ok() != Some(kind.vtk_type()))
    {
        return Err(Error::parse(path, 0, "one cell type per mesh"));
    }
    let mut conn = Vec::with_capacity(ne * kind.nodes());
    let mut i = 0;
    for _ in 0..ne {
        let (ln, k) = body
            .get(i)
            .copied()
            .ok_or_else(|| Error::parse(path, 0, "CELLS is short"))?;
        if k.parse::<usize>().ok() != Some(kind.nodes()) {
            return Err(Error::parse(
                path,
                ln,
                format!("a cell of {k} nodes; {} expected", kind.nodes()),
            ));
        }
        for (ln, v) in body
            .get(i + 1..i + 1 + kind.nodes())
            .ok_or_else(|| Error::parse(path, ln, "CELLS is short"))?
        {
            let v: usize = v
                .parse()
                .map_err(|_| Error::parse(path, *ln, "a bad node index"))?;
            if v >= n {
                return Err(Error::parse(
                    path,
                    *ln,
                    format!("node index {v} of {n} nodes"),
                ));
            }
            conn.push(v);
        }
        i += 1 + kind.nodes();
    }
    let mut sets = MeshSets::default();
    let mut section = 0; // 1 point data, 2 cell data
    let mut k = t + 2 + ne;
    while k < toks.len() {
        let w = toks[k].1.to_ascii_uppercase();
        if w == "POINT_DATA" {
            section = 1;
            k += 2;
            continue;
        }
        if w == "CELL_DATA" {
            section = 2;
            k += 2;
            continue;
        }
        let len = if section == 1 { n } else { ne };
        if w == "SCALARS" {
            let name = toks.get(k + 1).map(|t| t.1).unwrap_or("");
            let mut j = k + 3;
            if toks.get(j).is_some_and(|t| t.1.parse::<usize>().is_ok()) {
                j += 1;
            }
            if toks
                .get(j)
                .is_some_and(|t| t.1.eq_ignore_ascii_case("LOOKUP_TABLE"))
            {
                j += 2;
            }
            let v = toks
                .get(j..j + len)
                .ok_or_else(|| Error::parse(path, 0, format!("{name} is short")))?;
            if let Some(set) = name.strip_prefix("set_") {
                let members: Vec<usize> = (0..len).filter(|&q| v[q].1 != "0").collect();
                if section == 1 {
                    sets.node_sets.insert(set.to_string(), members);
                } else {
                    sets.element_sets.insert(set.to_string(), members);
                }
            }
            k = j + len;
            continue;
        }
        if w == "VECTORS" {
            k += 3 + 3 * len;
            continue;
        }
        k += 1;
    }
    check_mesh(path, &nodes, kind, &conn, &sets)?;
    Ok(FeMesh {
        nodes,
        kind,
        connectivity: conn,
        sets,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str, text: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("atlasmesh-femesh-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn bad_gmsh_and_abaqus_files_are_errors_not_panics() {
        let head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
        for (name, elements) in [
            ("neg.msh", "$Elements\n1\n1 4 -5 1 2 3 4\n$EndElements\n"),
            (
                "huge.msh",
                "$Elements\n1\n1 4 99999999 1 2 3 4\n$EndElements\n",
            ),
            ("node.msh", "$Elements\n1\n1 4 0 1 2 3 9\n$EndElements\n"),
            ("count.msh", "$Elements\n5\n1 4 0 1 2 3 4\n$EndElements\n"),
        ] {
            let p = tmp(name, &format!("{head}{elements}"));
            let e = read_fe_mesh::<3>(&p).unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        }
        let ok = tmp(
            "ok.msh",
            &format!("{head}$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n"),
        );
        let m = read_fe_mesh::<3>(&ok).unwrap();
        assert_eq!(m.kind, ElementKind::Tet4);
        for (name, text) in [
            (
                "gen.inp",
                "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D4\n1, 1, 1, 1, 1\n*NSET, NSET=A, GENERATE\n5, 1, 1\n",
            ),
            (
                "short.inp",
                "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D8\n1, 1, 1\n",
            ),
            ("nan.inp", "*NODE\n1, nan, 0, 0\n"),
            (
                "surf.inp",
                "*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=C3D4\n1, 1, 1, 1, 1\n*SURFACE, NAME=S\n1, S9\n",
            ),
        ] {
            let p = tmp(name, text);
            let e = read_fe_mesh::<3>(&p).unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        }
    }
}

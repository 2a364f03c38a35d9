//! Abaqus/CalculiX `.inp`: meshes with `*NSET`, `*ELSET`, `*SURFACE` read and written, and
//! whole decks whose node coordinates are replaced.

use super::helpers::{id_lines, xyz};
use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::mesh::{ElementKind, FeMesh, MeshSets};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;

/// A set as read: display name, its items (line, id or set name), and whether `GENERATE`.
pub(crate) type RawSet = (String, Vec<(usize, String)>, bool);
/// A surface as read: display name and its items (line, element or element set, face).
pub(crate) type RawSurface = (String, Vec<(usize, String, String)>);

/// An `.inp` deck: the mesh, and the 1-based node ids in file order (node `k` of the mesh has
/// id `node_ids[k]`).
#[derive(Clone, Debug)]
pub struct InpDeck {
    /// The mesh with its sets (0-based).
    pub mesh: FeMesh<3>,
    /// The 1-based id in the file of every node of `mesh`.
    pub node_ids: Vec<u64>,
    /// The deck's text as read.
    pub text: String,
}

pub(crate) fn keyword_params(line: &str) -> (String, HashMap<String, String>) {
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
    let text = crate::formats::read_input_text(path)?;
    parse_inp(path, &text)
}

/// [`read_inp`] of a file's text (`path` only names the file in messages): no file is read.
#[allow(
    clippy::too_many_lines,
    reason = "a parser: one pass over the deck's keyword lines, each keyword's branch beside the others"
)]
pub fn parse_inp(path: &Path, text: &str) -> Result<InpDeck> {
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
    let node_sets: BTreeMap<String, Vec<usize>> = resolve(path, "node", &nsets, &node_index)?;
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
    let mut sets = MeshSets {
        node_sets,
        element_sets: element_sets_all,
        surfaces: surface_sets,
    };
    // The whole-mesh sets this writer adds are not carried as sets.
    super::helpers::drop_whole_mesh_sets(path, &mut sets, nodes.len(), conn.len() / kind.nodes())?;
    super::helpers::check_mesh(path, &nodes, kind, &conn, &sets)?;
    Ok(InpDeck {
        mesh: FeMesh {
            nodes,
            kind,
            connectivity: conn,
            sets,
        },
        node_ids,
        text: text.to_string(),
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

/// The mesh ([`inp`]) with one material per bin of `map`: per bin an `*ELSET` of its name
/// (`BONE_k`, or a part's: not written again when the mesh has that set already), a
/// `*MATERIAL` of the same name with `*ELASTIC` E (MPa), ν, and a `*SOLID SECTION` (plane
/// stress of unit thickness in 2D). Units: mm, N, MPa.
pub fn inp_with_materials<const D: usize>(
    mesh: &FeMesh<D>,
    path: &Path,
    map: &crate::materials::MaterialMap,
) -> String {
    let mut s = inp(mesh, path);
    let grouping = match map.summary.bin_width {
        Some(w) => format!("equal-width bins of density ({w:.6} g/cm³)"),
        None => format!("a gap of {:.4} MPa", map.summary.gap),
    };
    let _ = writeln!(
        s,
        "** Materials from the CT: {} (groups of E (MPa) by {grouping}, and the recipe's \
         parts); per element values in the .vtu",
        map.bins.len(),
    );
    for bin in &map.bins {
        let name = &bin.name;
        if mesh.sets.element_sets.get(name) != Some(&bin.elements) {
            let _ = writeln!(s, "*ELSET, ELSET={name}");
            id_lines(&mut s, bin.elements.iter().copied(), 16);
        }
        let _ = writeln!(
            s,
            "*MATERIAL, NAME={name}\n*ELASTIC\n{:.6e}, {}",
            bin.modulus, bin.poisson
        );
        let _ = writeln!(s, "*SOLID SECTION, ELSET={name}, MATERIAL={name}");
        if D == 2 {
            s.push_str("1.\n");
        }
    }
    s
}

/// A static step of `load` (appended after the model): its node sets, its ties (`*TIE` of
/// a node surface to an element surface, nodes not moved onto it), `*STEP` and
/// `*STATIC`, `*BOUNDARY` for every displacement (mm), `*CLOAD` for every force (N, the total
/// shared evenly by the set's nodes), the reaction force totals of every displacement set
/// asked of the `.dat` file (`*NODE PRINT ... TOTALS=ONLY`) and the displacements and
/// stresses of the `.frd` file.
pub fn inp_step(s: &mut String, load: &crate::mesh::AppliedLoadCase) {
    for (name, members) in &load.node_sets {
        if load.mesh_sets.contains(name) {
            continue;
        }
        let _ = writeln!(s, "*NSET, NSET={name}");
        id_lines(s, members.iter().copied(), 16);
    }
    for (k, (nodes, surface, tolerance)) in load.ties.iter().enumerate() {
        let _ = writeln!(
            s,
            "*SURFACE, NAME=TIE_{n}_NODES, TYPE=NODE\n{nodes}\n*TIE, NAME=TIE_{n}, POSITION \
             TOLERANCE={tolerance:e}, ADJUST=NO\nTIE_{n}_NODES, {surface}",
            n = k + 1
        );
    }
    s.push_str("*STEP\n*STATIC\n*BOUNDARY\n");
    for (set, axis, v) in &load.displacements {
        let _ = writeln!(s, "{set}, {c}, {c}, {v:e}", c = axis + 1);
    }
    if !load.forces.is_empty() {
        s.push_str("*CLOAD\n");
        for (set, axis, v) in &load.forces {
            let members = &load.node_sets[set];
            let each = v / members.len() as f64;
            for n in members {
                let _ = writeln!(s, "{}, {}, {each:e}", n + 1, axis + 1);
            }
        }
    }
    for set in &load.reaction_sets {
        let _ = writeln!(s, "*NODE PRINT, NSET={set}, TOTALS=ONLY\nRF");
    }
    s.push_str("*NODE FILE\nU\n*EL FILE\nS, E\n*END STEP\n");
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

/// The element-type table of this format.
impl ElementKind {
    /// Abaqus/CalculiX element type written (plane stress in 2D).
    pub fn abaqus_type(self) -> &'static str {
        match self {
            ElementKind::Quad4 => "CPS4",
            ElementKind::Tri3 => "CPS3",
            ElementKind::Hex8 => "C3D8",
            ElementKind::Tet4 => "C3D4",
            ElementKind::Hex20 => "C3D20",
            ElementKind::Tet10 => "C3D10",
        }
    }
    /// The kind of an Abaqus/CalculiX element type (continuum elements of these node counts:
    /// plane stress/strain, axisymmetric, 3D, with their reduced/hybrid/incompatible-mode
    /// variants).
    pub fn from_abaqus_type(t: &str) -> Option<Self> {
        let t = t.trim().to_ascii_uppercase();
        let base: String = t
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect();
        let stem = base.trim_end_matches(['R', 'H', 'I', 'T', 'M']);
        match stem {
            "C3D8" => Some(ElementKind::Hex8),
            "C3D4" => Some(ElementKind::Tet4),
            "C3D20" => Some(ElementKind::Hex20),
            "C3D10" => Some(ElementKind::Tet10),
            "CPS4" | "CPE4" | "CAX4" => Some(ElementKind::Quad4),
            "CPS3" | "CPE3" | "CAX3" => Some(ElementKind::Tri3),
            _ => None,
        }
    }
}

//! Solver decks around the atlas's mean mesh, copied for every subject with its node
//! coordinates: an Abaqus/CalculiX `.inp` ([`InpDeck`]) or an FEBio 4.0 `.feb` model
//! ([`FebDeck`]: the mean mesh's `.feb` from `atlasmesh convert ATLAS mean.feb` with the
//! materials, domains, boundary conditions and steps added).

use super::abaqus::InpDeck;
use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::mesh::{ALL_KINDS, ElementKind, FeMesh};
use quick_xml::events::{BytesText, Event};
use std::path::Path;

/// A solver deck.
#[derive(Clone, Debug)]
pub enum Deck {
    /// Abaqus/CalculiX.
    Inp(InpDeck),
    /// FEBio.
    Feb(FebDeck),
}

impl Deck {
    /// Reads the deck in `path` (`.inp` or `.feb`).
    pub fn read(path: &Path) -> Result<Deck> {
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref()
        {
            Some("inp") => Ok(Deck::Inp(super::read_inp(path)?)),
            Some("feb") => {
                let text = crate::formats::read_input_text(path)?;
                Ok(Deck::Feb(FebDeck::parse(path, &text)?))
            }
            _ => Err(Error::parse(
                path,
                0,
                "a deck is an Abaqus/CalculiX .inp or an FEBio .feb file",
            )),
        }
    }
    /// The deck's mesh (node coordinates and elements as in the file).
    pub fn mesh(&self) -> &FeMesh<3> {
        match self {
            Deck::Inp(d) => &d.mesh,
            Deck::Feb(d) => &d.mesh,
        }
    }
    /// The file extension (`inp`, `feb`).
    pub fn extension(&self) -> &'static str {
        match self {
            Deck::Inp(_) => "inp",
            Deck::Feb(_) => "feb",
        }
    }
    /// The deck's text with the nodes moved to `nodes` (in the mesh's order); everything else
    /// as in the file.
    pub fn with_nodes<const D: usize>(&self, nodes: &[Point<D>]) -> Result<String> {
        match self {
            Deck::Inp(d) => d.with_nodes(nodes),
            Deck::Feb(d) => d.with_nodes(nodes),
        }
    }

    /// Writes [`Deck::with_nodes`] as `dir/BASE_deck.EXT` (through a temporary and a rename);
    /// returns the file's name.
    pub fn write_with_nodes<const D: usize>(
        &self,
        nodes: &[Point<D>],
        dir: &std::path::Path,
        base: &str,
    ) -> Result<String> {
        let name = format!("{base}_deck.{}", self.extension());
        crate::formats::write_atomic(&dir.join(&name), self.with_nodes(nodes)?.as_bytes())?;
        Ok(name)
    }
}

/// An FEBio 4.0 model: its text and the mesh of its `Mesh` section (`Nodes`, `Elements`).
#[derive(Clone, Debug)]
pub struct FebDeck {
    /// The mesh (0-based; node `k` has id `k + 1`).
    pub mesh: FeMesh<3>,
    /// The file's text as read.
    pub text: String,
}

/// Numbers separated by commas.
fn numbers<T: std::str::FromStr>(path: &Path, s: &str, what: &str) -> Result<Vec<T>> {
    s.split(',')
        .map(|t| {
            t.trim().parse().map_err(|_| {
                Error::parse(path, 0, format!("{what}: {:?} is not a number", t.trim()))
            })
        })
        .collect()
}

impl FebDeck {
    /// Parses an FEBio file: nodes with ids 1..N, elements of one kind.
    #[allow(
        clippy::too_many_lines,
        reason = "a parser: one pass over the FEBio deck's sections, each section's branch beside the others"
    )]
    pub fn parse(path: &Path, text: &str) -> Result<FebDeck> {
        let bad = |m: String| Error::parse(path, 0, m);
        let mut r = quick_xml::Reader::from_str(text);
        let mut stack: Vec<String> = Vec::new();
        let mut nodes: Vec<Option<[f64; 3]>> = Vec::new();
        let mut kind: Option<ElementKind> = None;
        let mut connectivity = Vec::new();
        let mut node_id: Option<usize> = None;
        let mut root = None;
        loop {
            match r.read_event().map_err(|e| {
                bad(format!(
                    "not well-formed XML near byte {} ({e})",
                    r.error_position()
                ))
            })? {
                Event::Start(e) => {
                    let tag = e.local_name().as_ref().to_string();
                    let parent = stack.last().map(String::as_str);
                    if root.is_none() {
                        root = Some(tag.clone());
                    }
                    if tag == "node" && parent == Some("Nodes") {
                        let id = e
                            .try_get_attribute("id")
                            .ok()
                            .flatten()
                            .and_then(|a| a.value.trim().parse::<usize>().ok())
                            .filter(|i| (1..=super::MAX_COUNT).contains(i))
                            .ok_or_else(|| bad("a <node> without a valid id".into()))?;
                        node_id = Some(id);
                    }
                    if tag == "Elements" && parent == Some("Mesh") {
                        let t = e
                            .try_get_attribute("type")
                            .ok()
                            .flatten()
                            .map(|a| a.value.into_owned())
                            .unwrap_or_default();
                        let k = ALL_KINDS
                            .into_iter()
                            .find(|k| k.febio_type() == t)
                            .ok_or_else(|| bad(format!("element type {t:?} is not read")))?;
                        if kind.is_some_and(|k0| k0 != k) {
                            return Err(bad("elements of several types; one kind is read".into()));
                        }
                        kind = Some(k);
                    }
                    stack.push(tag);
                }
                Event::End(_) => {
                    stack.pop();
                    node_id = None;
                }
                Event::Text(t) => {
                    let parent = stack.get(stack.len().wrapping_sub(2)).map(String::as_str);
                    match (stack.last().map(String::as_str), parent) {
                        (Some("node"), Some("Nodes")) => {
                            let id = node_id.unwrap_or(0);
                            let v: Vec<f64> = numbers(path, &t, &format!("node {id}"))?;
                            if v.len() != 3 || v.iter().any(|c| !c.is_finite()) {
                                return Err(bad(format!(
                                    "node {id}: three finite coordinates expected"
                                )));
                            }
                            if nodes.len() < id {
                                nodes.resize(id, None);
                            }
                            if nodes[id - 1].replace([v[0], v[1], v[2]]).is_some() {
                                return Err(bad(format!("node {id} is given twice")));
                            }
                        }
                        (Some("elem"), Some("Elements")) => {
                            let k = kind.map_or(0, ElementKind::nodes);
                            let ids: Vec<usize> = numbers(path, &t, "an element")?;
                            if ids.len() != k {
                                return Err(bad(format!(
                                    "an element of {} nodes, {k} expected",
                                    ids.len()
                                )));
                            }
                            connectivity.extend(ids);
                        }
                        _ => {}
                    }
                }
                Event::Eof => break,
                _ => {}
            }
        }
        if root.as_deref() != Some("febio_spec") {
            return Err(bad("not an FEBio file (no <febio_spec>)".into()));
        }
        let nodes: Vec<[f64; 3]> = nodes
            .into_iter()
            .enumerate()
            .map(|(i, p)| {
                p.ok_or_else(|| bad(format!("node ids skip {}: ids must run 1..N", i + 1)))
            })
            .collect::<Result<_>>()?;
        let kind = kind.ok_or_else(|| bad("no <Elements> in <Mesh>".into()))?;
        let connectivity = connectivity
            .into_iter()
            .map(|i| {
                i.checked_sub(1)
                    .filter(|&i| i < nodes.len())
                    .ok_or_else(|| bad(format!("an element names node {i}, which is not defined")))
            })
            .collect::<Result<_>>()?;
        Ok(FebDeck {
            mesh: FeMesh {
                nodes,
                kind,
                connectivity,
                sets: Default::default(),
            },
            text: text.to_string(),
        })
    }

    /// The model with node `k` (id `k + 1`) at `nodes[k]`.
    pub fn with_nodes<const D: usize>(&self, nodes: &[Point<D>]) -> Result<String> {
        if nodes.len() != self.mesh.nodes.len() {
            return Err(Error::Mesh(format!(
                "the deck has {} nodes but the mesh {}",
                self.mesh.nodes.len(),
                nodes.len()
            )));
        }
        let mut r = quick_xml::Reader::from_str(&self.text);
        let mut w = quick_xml::Writer::new(Vec::with_capacity(self.text.len() + nodes.len() * 16));
        let mut stack: Vec<String> = Vec::new();
        let mut node_id: Option<usize> = None;
        let xml = |e: quick_xml::Error| Error::Mesh(format!("the FEBio deck: {e}"));
        loop {
            let ev = r.read_event().map_err(xml)?;
            match &ev {
                Event::Start(e) => {
                    let tag = e.local_name().as_ref().to_string();
                    if tag == "node" && stack.last().map(String::as_str) == Some("Nodes") {
                        node_id = e
                            .try_get_attribute("id")
                            .ok()
                            .flatten()
                            .and_then(|a| a.value.trim().parse::<usize>().ok());
                    }
                    stack.push(tag);
                }
                Event::End(_) => {
                    stack.pop();
                    node_id = None;
                }
                Event::Text(_) => {
                    if let Some(k) = node_id
                        .and_then(|i| i.checked_sub(1))
                        .filter(|&k| k < nodes.len())
                    {
                        let p = super::helpers::xyz(&nodes[k]);
                        let t = format!("{:.17e},{:.17e},{:.17e}", p[0], p[1], p[2]);
                        w.write_event(Event::Text(BytesText::new(&t)))
                            .map_err(|e| Error::Mesh(format!("the FEBio deck: {e}")))?;
                        continue;
                    }
                }
                Event::Eof => break,
                _ => {}
            }
            w.write_event(ev)
                .map_err(|e| Error::Mesh(format!("the FEBio deck: {e}")))?;
        }
        String::from_utf8(w.into_inner())
            .map_err(|_| Error::Mesh("the FEBio deck is not UTF-8".into()))
    }
}

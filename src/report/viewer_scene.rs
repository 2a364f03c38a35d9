//! The JSON contract between a page and `viewer.js`: one serde type per object, versioned
//! ([`SCENE_VERSION`]). [`super::viewer::scene_json`] writes it; `viewer.js` reads it through
//! its typedef `Scene` (at the top of the script, with the same names), and CI type-checks
//! the script against that typedef (`scripts/js`). Rust owns the work both would do: the
//! faces between elements are paired here ([`crate::mesh::face_pairs`]), the colour maps are
//! sampled here from the PNG pictures' (`render`), and text reaches the page through the
//! DOM's `textContent`, never as markup.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The version of the scene's JSON; a change of meaning increments it.
pub const SCENE_VERSION: u32 = 1;

/// An array as the page carries it: gzip, then base64, of little-endian `f32`, `u32`, or
/// `i16` times `scale`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Packed {
    /// Single-precision numbers.
    F32 {
        /// The packed bytes.
        f32: String,
    },
    /// Indices.
    U32 {
        /// The packed bytes.
        u32: String,
    },
    /// 16-bit integers, each times `scale`.
    I16 {
        /// The packed bytes.
        i16: String,
        /// What one step is worth.
        scale: f64,
    },
}

/// The whole scene of one view.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneJson {
    /// [`SCENE_VERSION`].
    pub version: u32,
    /// 2 or 3.
    pub dimension: usize,
    /// What is drawn.
    pub layers: Vec<LayerJson>,
    /// What the layers can be coloured by (the first at first).
    pub fields: Vec<FieldJson>,
    /// The camera's first direction.
    pub view: ViewJson,
    /// The colour maps, sampled.
    pub colormaps: ColorMapsJson,
    /// The model page's modes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modes: Option<ModesJson>,
}

/// Where the camera looks along, and its up direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewJson {
    /// The direction looked along ("front").
    pub look: [f64; 3],
    /// Up on the screen.
    pub up: [f64; 3],
}

/// The name of a colour map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MapName {
    /// Scaled Jacobian: absolute (0 to 1), red at or below 0.
    Jacobian,
    /// Distance: blue through white to red.
    Distance,
    /// Magnitude: dark blue through teal to yellow.
    Magnitude,
}

/// A quantity to colour by.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldJson {
    /// Key of the values in the layers.
    pub id: String,
    /// Its name (menu and legend).
    pub label: String,
    /// Its unit ("" for none).
    pub unit: String,
    /// The value at the colour bar's low end.
    pub lo: f64,
    /// The value at the colour bar's high end.
    pub hi: f64,
    /// The colour map.
    pub map: MapName,
}

/// A colour map sampled at 256 even steps over its range, with the colours of a value below
/// it (a scaled Jacobian at or below 0) and of a value that is not a number.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColorMapJson {
    /// 256 RGB colours from the low end to the high end.
    pub lut: Vec<[u8; 3]>,
    /// The colour of a value at or below the low end where the map marks it (else `lut[0]`).
    pub below: [u8; 3],
    /// The colour of NaN.
    pub nan: [u8; 3],
}

/// The three colour maps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColorMapsJson {
    /// [`MapName::Jacobian`].
    pub jacobian: ColorMapJson,
    /// [`MapName::Distance`].
    pub distance: ColorMapJson,
    /// [`MapName::Magnitude`].
    pub magnitude: ColorMapJson,
}

/// One thing drawn.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LayerJson {
    /// Key (the modes' displacements name the layer by it).
    pub id: String,
    /// Its name in the layer list.
    pub label: String,
    /// Shown at first.
    pub visible: bool,
    /// 1 opaque, below 1 see-through.
    pub opacity: f64,
    /// Colour without a field (RGB in 0..1).
    pub color: [f64; 3],
    /// Points, `f32` × 3 each.
    pub positions: Packed,
    /// Elements outlined in magenta (0-based).
    pub worst: Vec<usize>,
    /// A surface: its triangles (`u32` × 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub triangles: Option<Packed>,
    /// An outline: its segments (`u32` × 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segments: Option<Packed>,
    /// An FE mesh: its cells and their faces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<CellsJson>,
    /// Values per point, by field id (`f32`).
    pub point_values: BTreeMap<String, Packed>,
    /// Values per cell, by field id (`f32`).
    pub cell_values: BTreeMap<String, Packed>,
}

/// The cells of an FE mesh and every distinct face with the one or two cells it belongs to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellsJson {
    /// Nodes per cell (quadratic kinds: corners first).
    pub nodes_per_cell: usize,
    /// Corner nodes per cell.
    pub corners: usize,
    /// The faces of a cell, by local node (2D: the cell's outline).
    pub faces: Vec<Vec<usize>>,
    /// The cells' nodes (`u32`, `nodes_per_cell` each).
    pub nodes: Packed,
    /// Every distinct face as the slot `cell × faces.len() + local` of the first cell it
    /// belongs to and its local face number in it, in increasing order, each given as its
    /// difference from the previous one (the first from 0) (`u32`: small numbers that
    /// compress well).
    pub face_slot_steps: Packed,
    /// The other cell it belongs to, given as its difference from the first (always
    /// positive), 0 on the boundary (`u32`).
    pub face_other_steps: Packed,
}

/// The model page's modes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModesJson {
    /// The modes' standard deviations (the data's unit).
    pub sd: Vec<f64>,
    /// The slider's reach in standard deviations.
    pub max_sd: f64,
    /// Per layer id, per mode: every point's displacement at +1 sd (`i16` × 3).
    pub displacements: BTreeMap<String, Vec<Packed>>,
    /// Per mode: the largest displacement of any point at +1 sd.
    pub max_displacement: Vec<f64>,
}

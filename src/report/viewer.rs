//! The scene of the report's interactive 3D view: layers of points (surfaces by their
//! triangles, outlines by their segments, FE meshes by their cells), values to colour them by,
//! the worst elements, and the modes' displacements of the model page. [`viewer_html`] puts a
//! scene into a page as JSON beside the viewer (`viewer.js`: WebGL 1, written here, inlined,
//! no network), which draws it with rotation, zoom, pan, layer toggles, a clipping plane
//! through the volume (the elements on one side kept whole, the faces between kept and
//! removed elements drawn) and a mode slider.
//!
//! Arrays travel gzip-compressed and base64-encoded (little-endian `f32` positions and values,
//! `u32` indices, the modes' displacements as `i16` times a scale); the browser inflates them
//! with its `DecompressionStream`. Positions are
//! those of the files written (the subject's frame and unit), in single precision: the view
//! is for looking, the files hold the numbers.

use super::viewer_scene::{
    CellsJson, ColorMapJson, ColorMapsJson, FieldJson, LayerJson, MapName, ModesJson, Packed,
    SCENE_VERSION, SceneJson, ViewJson,
};
use crate::geometry::Point;
use crate::mesh::{ElementKind, FacePair, FeMesh};
use base64::Engine as _;
use std::io::Write as _;

/// How a field's values become colours (the PNG pictures' maps, `render`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorMap {
    /// Scaled Jacobian: red (≤ 0) through yellow (0.5) to green (1).
    Jacobian,
    /// Distance: blue (low) through white to red (high).
    Distance,
    /// A magnitude (displacement): dark blue through teal to yellow.
    Magnitude,
}

/// A quantity the layers can be coloured by.
#[derive(Clone, Debug)]
pub struct Field {
    /// Key of the values in the layers (`point_values` / `cell_values`).
    pub id: String,
    /// What it is, for the menu and the legend.
    pub label: String,
    /// Its unit (empty for none).
    pub unit: String,
    /// The values at the colour bar's ends.
    pub range: (f64, f64),
    /// The colour map.
    pub map: ColorMap,
}

impl Field {
    /// The scaled Jacobian (cell values `sj`), 0 to 1, labelled `label`.
    pub fn scaled_jacobian(label: &str) -> Self {
        Field {
            id: "sj".into(),
            label: label.into(),
            unit: String::new(),
            range: (0.0, 1.0),
            map: ColorMap::Jacobian,
        }
    }
}

/// What a layer is drawn from.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// Triangles (a surface), by point index.
    Triangles(Vec<[usize; 3]>),
    /// Segments (an outline), by point index.
    Segments(Vec<[usize; 2]>),
    /// FE cells with their faces paired ([`crate::mesh::face_pairs`]): the viewer draws the
    /// boundary (and, clipped, the faces between kept and removed cells).
    Cells {
        /// Nodes per cell in `cells` (quadratic kinds: corners first).
        nodes_per_cell: usize,
        /// Corner nodes per cell.
        corners: usize,
        /// The faces drawn of a cell, by local corner (2D: the cell's outline).
        faces: Vec<Vec<usize>>,
        /// The cells' nodes, `nodes_per_cell` each.
        cells: Vec<usize>,
        /// Every distinct face of the cells with the one or two cells it belongs to (2D:
        /// every cell's outline, alone).
        pairs: Vec<FacePair>,
    },
}

/// One thing drawn.
#[derive(Clone, Debug)]
pub struct Layer {
    /// Key (the modes' displacements name the layer by it).
    pub id: String,
    /// Its name in the layer list.
    pub label: String,
    /// Shown at first.
    pub visible: bool,
    /// 1 opaque; below 1 drawn after the opaque layers, see-through.
    pub opacity: f64,
    /// Colour when no field applies (RGB in 0..1).
    pub color: [f64; 3],
    /// Points (3D; 2D points get z = 0).
    pub points: Vec<Point<3>>,
    /// What is drawn of the points.
    pub geometry: Geometry,
    /// Values per point, by field id.
    pub point_values: Vec<(String, Vec<f64>)>,
    /// Values per cell, by field id.
    pub cell_values: Vec<(String, Vec<f64>)>,
    /// Cells outlined in magenta over everything (0-based).
    pub worst: Vec<usize>,
}

impl Layer {
    /// A layer of a surface (3D: triangles) or an outline (2D: segments) of `points` and
    /// `facets`, not shown until [`Layer::shown`].
    pub fn shape<const D: usize>(
        id: &str,
        label: &str,
        points: &[Point<D>],
        facets: &[[usize; D]],
    ) -> Self {
        let geometry = if D == 3 {
            Geometry::Triangles(facets.iter().map(|f| [f[0], f[1], f[2]]).collect())
        } else {
            Geometry::Segments(facets.iter().map(|f| [f[0], f[1 % D]]).collect())
        };
        Layer::of(id, label, points, geometry)
    }

    /// A hidden grey layer of `geometry` on `points`, without values.
    fn of<const D: usize>(id: &str, label: &str, points: &[Point<D>], geometry: Geometry) -> Self {
        Layer {
            id: id.into(),
            label: label.into(),
            visible: false,
            opacity: 1.0,
            color: [0.75, 0.75, 0.78],
            points: points.iter().map(crate::geometry::in_3d::<D>).collect(),
            geometry,
            point_values: Vec::new(),
            cell_values: Vec::new(),
            worst: Vec::new(),
        }
    }

    /// A layer of the FE mesh `mesh` (its cells; quadratic kinds drawn by their corners).
    pub fn mesh<const D: usize>(id: &str, label: &str, mesh: &FeMesh<D>) -> Self {
        let geometry = Geometry::Cells {
            nodes_per_cell: mesh.kind.nodes(),
            corners: mesh.kind.linear().nodes(),
            faces: drawn_faces(mesh.kind),
            cells: mesh.connectivity.clone(),
            pairs: if mesh.kind.linear().dimension() == 3 {
                crate::mesh::face_pairs(mesh)
            } else {
                (0..mesh.num_elements())
                    .map(|element| FacePair {
                        element,
                        face: 0,
                        other: None,
                    })
                    .collect()
            },
        };
        Layer::of(id, label, &mesh.nodes, geometry)
    }

    /// This layer shown at first, with `opacity` and `color`.
    pub fn shown(mut self, opacity: f64, color: [f64; 3]) -> Self {
        self.visible = true;
        self.opacity = opacity;
        self.color = color;
        self
    }
}

/// The modes of the model page: every layer named moves by `w` times its displacement for
/// the mode chosen, `w` in standard deviations from the slider.
#[derive(Clone, Debug)]
pub struct Modes {
    /// The modes' standard deviations `sqrt(lambda_k)` (the data's unit), one per mode shown.
    pub sd: Vec<f64>,
    /// The slider's reach (standard deviations either way).
    pub max_sd: f64,
    /// Per layer id, per mode: the displacement of every point at +1 sd.
    pub displacements: Vec<(String, Vec<Vec<Point<3>>>)>,
}

/// A view: the layers, the fields, and where the camera looks from at first.
#[derive(Clone, Debug)]
pub struct Scene {
    /// 2 or 3 (2D scenes are looked at along -z).
    pub dimension: usize,
    /// What is drawn.
    pub layers: Vec<Layer>,
    /// What it can be coloured by (the first at first).
    pub fields: Vec<Field>,
    /// The model page's modes.
    pub modes: Option<Modes>,
    /// The direction the camera looks along and its up direction at first ("front"; "back"
    /// looks the other way).
    pub look: ([f64; 3], [f64; 3]),
}

impl Scene {
    /// An empty scene of dimension `dimension`, looked at along the smallest principal axis
    /// of `points` (3D, the largest horizontal, as the PNG pictures) or along -z (2D).
    pub fn new(dimension: usize, points: &[Point<3>]) -> Self {
        let look = if dimension == 3 && points.len() >= 3 {
            let v = crate::report::render::View::fitting(points);
            let r = v.rotation;
            ([-r[2][0], -r[2][1], -r[2][2]], r[1])
        } else {
            ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0])
        };
        Scene {
            dimension,
            layers: Vec::new(),
            fields: Vec::new(),
            modes: None,
            look,
        }
    }
}

/// Gzip, then base64: how the page carries an array.
fn packed(bytes: &[u8]) -> String {
    let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::new(6));
    // Writing into a Vec cannot fail.
    let _ = z.write_all(bytes);
    let gz = z.finish().unwrap_or_default();
    base64::engine::general_purpose::STANDARD.encode(gz)
}

fn f32s(values: impl Iterator<Item = f64>) -> Packed {
    let bytes: Vec<u8> = values.flat_map(|v| (v as f32).to_le_bytes()).collect();
    Packed::F32 {
        f32: packed(&bytes),
    }
}

fn u32s(values: impl Iterator<Item = usize>) -> Packed {
    let bytes: Vec<u8> = values
        .flat_map(|v| u32::try_from(v).unwrap_or(u32::MAX).to_le_bytes())
        .collect();
    Packed::U32 {
        u32: packed(&bytes),
    }
}

fn points_value(points: &[Point<3>]) -> Packed {
    f32s(points.iter().flat_map(|p| p.iter().copied()))
}

/// Displacements as 16-bit integers times a scale (the largest component over 32767): a
/// third of the page's size in single precision after compression, to a 30 000th of the
/// largest displacement.
fn displacements_value(d: &[Point<3>]) -> Packed {
    let largest = d
        .iter()
        .flatten()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = if largest > 0.0 {
        largest / 32767.0
    } else {
        1.0
    };
    let bytes: Vec<u8> = d
        .iter()
        .flatten()
        .flat_map(|v| {
            let q = if v.is_finite() {
                (v / scale).round()
            } else {
                0.0
            };
            (q.clamp(-32767.0, 32767.0) as i16).to_le_bytes()
        })
        .collect();
    Packed::I16 {
        i16: packed(&bytes),
        scale,
    }
}

fn layer_value(l: &Layer) -> LayerJson {
    let values = |vals: &[(String, Vec<f64>)]| {
        vals.iter()
            .map(|(k, x)| (k.clone(), f32s(x.iter().copied())))
            .collect()
    };
    let (mut triangles, mut segments, mut cells_json) = (None, None, None);
    match &l.geometry {
        Geometry::Triangles(t) => triangles = Some(u32s(t.iter().flatten().copied())),
        Geometry::Segments(s) => segments = Some(u32s(s.iter().flatten().copied())),
        Geometry::Cells {
            nodes_per_cell,
            corners,
            faces,
            cells,
            pairs,
        } => {
            cells_json = Some(CellsJson {
                nodes_per_cell: *nodes_per_cell,
                corners: *corners,
                faces: faces.clone(),
                nodes: u32s(cells.iter().copied()),
                face_slot_steps: u32s(pairs.iter().scan(0, |last, p| {
                    let slot = p.element * faces.len() + usize::from(p.face);
                    let step = slot - *last;
                    *last = slot;
                    Some(step)
                })),
                face_other_steps: u32s(
                    pairs
                        .iter()
                        .map(|p| p.other.map_or(0, |o| o.saturating_sub(p.element))),
                ),
            })
        }
    }
    LayerJson {
        id: l.id.clone(),
        label: l.label.clone(),
        visible: l.visible,
        opacity: l.opacity,
        color: l.color,
        positions: points_value(&l.points),
        worst: l.worst.clone(),
        triangles,
        segments,
        cells: cells_json,
        point_values: values(&l.point_values),
        cell_values: values(&l.cell_values),
    }
}

/// `color` sampled at 256 even steps of `0..=1`.
fn sampled(color: impl Fn(f64) -> [u8; 3], below: [u8; 3]) -> ColorMapJson {
    ColorMapJson {
        lut: (0..256).map(|i| color(f64::from(i) / 255.0)).collect(),
        below,
        nan: [153, 153, 153],
    }
}

/// The PNG pictures' colour maps ([`super::render`]), sampled for the viewer.
fn colormaps() -> ColorMapsJson {
    use super::render::{distance_color, jacobian_color, magnitude_color};
    let distance = distance_color(1.0);
    ColorMapsJson {
        // (0 itself is "inverted" in the pictures: the lowest step is just above it.)
        jacobian: sampled(|t| jacobian_color(t.max(1e-9)), jacobian_color(0.0)),
        distance: sampled(&distance, distance(0.0)),
        magnitude: sampled(magnitude_color, magnitude_color(0.0)),
    }
}

/// The scene as the typed JSON `viewer.js` reads ([`SceneJson`]).
pub fn scene_value(scene: &Scene) -> SceneJson {
    let fields = scene
        .fields
        .iter()
        .map(|f| FieldJson {
            id: f.id.clone(),
            label: f.label.clone(),
            unit: f.unit.clone(),
            lo: finite_or(f.range.0, 0.0),
            hi: finite_or(f.range.1, 1.0),
            map: match f.map {
                ColorMap::Jacobian => MapName::Jacobian,
                ColorMap::Distance => MapName::Distance,
                ColorMap::Magnitude => MapName::Magnitude,
            },
        })
        .collect();
    let modes = scene.modes.as_ref().map(|m| ModesJson {
        sd: m.sd.clone(),
        max_sd: m.max_sd,
        displacements: m
            .displacements
            .iter()
            .map(|(id, per_mode)| {
                (
                    id.clone(),
                    per_mode.iter().map(|d| displacements_value(d)).collect(),
                )
            })
            .collect(),
        // The largest displacement of any layer at 1 sd, per mode (the colour bar's end).
        max_displacement: (0..m.sd.len())
            .map(|k| {
                m.displacements
                    .iter()
                    .filter_map(|(_, d)| d.get(k))
                    .flat_map(|d| d.iter().map(|p| crate::geometry::norm(*p)))
                    .fold(0.0, f64::max)
            })
            .collect(),
    });
    SceneJson {
        version: SCENE_VERSION,
        dimension: scene.dimension,
        layers: scene.layers.iter().map(layer_value).collect(),
        fields,
        view: ViewJson {
            look: scene.look.0,
            up: scene.look.1,
        },
        colormaps: colormaps(),
        modes,
    }
}

/// The scene as the JSON `viewer.js` reads, ready to sit in a `<script>` element.
pub fn scene_json(scene: &Scene) -> String {
    let text = serde_json::to_string(&scene_value(scene)).unwrap_or_default();
    // (`<` escaped so that no name can close the script element the JSON sits in.)
    text.replace('<', "\\u003c")
}

fn finite_or(x: f64, or: f64) -> f64 {
    if x.is_finite() { x } else { or }
}

/// The viewer's styles, for the page's `<style>`.
pub const VIEWER_STYLE: &str = ".am-viewer{display:flex;flex-wrap:wrap;gap:10px;align-items:flex-start;margin:0.5em 0}\
.am-canvas{border:1px solid #ccc;cursor:grab;max-width:100%;background:#fff}\
.am-panel{font-size:0.9em;min-width:240px;max-width:320px}.am-panel>div{margin:0 0 6px}.am-panel select{max-width:100%}\
.am-bar{height:12px;border:1px solid #999;margin-top:4px}.am-caption{color:#555;clear:both}\
.am-info{color:#555}";

/// The viewer's script, once per page, after its viewers.
pub const VIEWER_SCRIPT: &str = include_str!("viewer.js");

/// A viewer of `scene` for a page: its container (`width × height` pixels of canvas) and the
/// scene's JSON, named `id` (unique in the page). The page needs [`VIEWER_STYLE`] and, once,
/// [`VIEWER_SCRIPT`].
pub fn viewer_html(scene: &Scene, id: &str, width: usize, height: usize) -> String {
    format!(
        "<div class=\"am-viewer\" data-scene=\"{id}\" data-width=\"{width}\" data-height=\"{height}\">The 3D view needs JavaScript and WebGL.</div>\n<script type=\"application/json\" id=\"{id}\">{}</script>\n",
        scene_json(scene)
    )
}

/// The mesh's faces drawn of a kind in 3D (its faces) and 2D (the cell itself), by local
/// corner: what [`Layer::mesh`] gives the viewer.
pub fn drawn_faces(kind: ElementKind) -> Vec<Vec<usize>> {
    let linear = kind.linear();
    if linear.dimension() == 3 {
        linear.faces().iter().map(|f| f.to_vec()).collect()
    } else {
        vec![(0..linear.nodes()).collect()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read as _;

    fn unpack(v: &Packed) -> Vec<u8> {
        let text = match v {
            Packed::F32 { f32 } => f32,
            Packed::U32 { u32 } => u32,
            Packed::I16 { i16, .. } => i16,
        };
        let b = base64::engine::general_purpose::STANDARD
            .decode(text)
            .unwrap();
        let mut out = Vec::new();
        flate2::read::GzDecoder::new(&b[..])
            .read_to_end(&mut out)
            .unwrap();
        out
    }

    #[test]
    fn a_scene_carries_its_arrays_back_exactly() {
        let mesh = FeMesh::<2> {
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            kind: ElementKind::Quad4,
            connectivity: vec![0, 1, 2, 3],
            sets: Default::default(),
        };
        let mut l = Layer::mesh("mesh", "a </script> mesh", &mesh);
        l.cell_values.push(("sj".into(), vec![0.5]));
        let mut scene = Scene::new(2, &[]);
        scene.layers.push(l);
        let text = scene_json(&scene);
        assert!(!text.contains("</script>"), "{text}");
        // Read back through the typed schema, as the page's contract.
        let v: SceneJson = serde_json::from_str(&text).unwrap();
        assert_eq!(v.version, SCENE_VERSION);
        assert_eq!(v.colormaps.jacobian.lut.len(), 256);
        assert_eq!(v.colormaps.jacobian.below, [200, 0, 0]);
        let layer = &v.layers[0];
        assert_eq!(layer.label, "a </script> mesh");
        let c = layer.cells.as_ref().unwrap();
        let cells: Vec<u32> = unpack(&c.nodes)
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(cells, vec![0, 1, 2, 3]);
        let pos: Vec<f32> = unpack(&layer.positions)
            .chunks(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(pos, vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]);
        assert_eq!(c.faces, vec![vec![0, 1, 2, 3]]);
        assert_eq!(unpack(&c.face_slot_steps), 0u32.to_le_bytes());
        assert_eq!(unpack(&c.face_other_steps), 0u32.to_le_bytes());
        let sj = unpack(&layer.cell_values["sj"]);
        assert_eq!(f32::from_le_bytes(sj[..4].try_into().unwrap()), 0.5);
    }

    #[test]
    fn displacements_come_back_within_half_a_step() {
        let d: Vec<Point<3>> = (0..100)
            .map(|i| {
                let t = i as f64 * 0.37;
                [t.sin() * 2.5, t.cos() * 0.01, -1e-3 * i as f64]
            })
            .collect();
        let v = displacements_value(&d);
        let Packed::I16 { scale, .. } = v else {
            panic!("not i16")
        };
        assert!((scale - 2.5 / 32767.0).abs() < 1e-6, "{scale}");
        let back: Vec<f64> = unpack(&v)
            .chunks(2)
            .map(|c| f64::from(i16::from_le_bytes([c[0], c[1]])) * scale)
            .collect();
        for (a, b) in d.iter().flatten().zip(&back) {
            assert!((a - b).abs() <= 0.5 * scale + 1e-15, "{a} {b}");
        }
        // Nothing moves: no division by zero.
        assert!(matches!(
            displacements_value(&[[0.0; 3]]),
            Packed::I16 { scale, .. } if scale == 1.0
        ));
    }

    #[test]
    fn hexahedra_show_their_six_faces_and_quadrilaterals_themselves() {
        assert_eq!(drawn_faces(ElementKind::Hex20).len(), 6);
        assert_eq!(drawn_faces(ElementKind::Quad4), vec![vec![0, 1, 2, 3]]);
        assert_eq!(drawn_faces(ElementKind::Tet10).len(), 4);
    }
}

//! A small software rasterizer for the report's 3D pictures (figs. 23 and 27 of the paper):
//! triangle surfaces drawn with a z-buffer under an orthographic camera, each triangle
//! coloured by a value (per vertex, interpolated; or per triangle) and shaded by the angle of
//! its normal to the viewer. No display or GPU is needed; the result is a PNG in memory.
//!
//! Frames: the camera looks along the smallest principal axis of the points (the largest
//! extent across the picture, horizontal); units do not matter (the picture is fitted).

use crate::error::{Error, Result};
use crate::geometry::Point;

/// An RGB picture.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major RGB bytes, top row first.
    pub rgb: Vec<u8>,
}

impl Image {
    /// A white picture.
    pub fn new(width: usize, height: usize) -> Self {
        Image {
            width,
            height,
            rgb: vec![255; width * height * 3],
        }
    }

    /// The picture as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let err = |e: png::EncodingError| Error::Numerical(format!("PNG encoding: {e}"));
            let mut w = enc.write_header().map_err(err)?;
            w.write_image_data(&self.rgb).map_err(err)?;
        }
        Ok(out)
    }

    /// Copies `other` into this picture with its top-left corner at `(x, y)`.
    pub fn paste(&mut self, other: &Image, x: usize, y: usize) {
        for r in 0..other.height.min(self.height.saturating_sub(y)) {
            let w = other.width.min(self.width.saturating_sub(x));
            let src = &other.rgb[r * other.width * 3..(r * other.width + w) * 3];
            let at = ((y + r) * self.width + x) * 3;
            self.rgb[at..at + w * 3].copy_from_slice(src);
        }
    }
}

/// A view: the rotation taking world coordinates to camera coordinates (rows: right, up,
/// towards the viewer), and the window (centre and half-size) it shows.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// World to camera rotation (rows: right, up, towards the viewer).
    pub rotation: [[f64; 3]; 3],
    /// World point at the picture's centre.
    pub center: Point<3>,
    /// Half the width and half the height of the window shown (world units); a picture of
    /// another aspect shows more on the longer side.
    pub half: [f64; 2],
}

impl View {
    /// The view of `points` along their smallest principal axis, the largest horizontal,
    /// tilted by 20° about the horizontal so the relief shows.
    pub fn fitting(points: &[Point<3>]) -> Self {
        let axes = crate::geometry::principal_axes_of(points);
        let tilt = 20f64.to_radians();
        let (s, co) = tilt.sin_cos();
        // right = axis 0; up = axis 1 tilted towards axis 2; out = axis 2 tilted back.
        let up: [f64; 3] = std::array::from_fn(|d| co * axes[1][d] + s * axes[2][d]);
        let out: [f64; 3] = std::array::from_fn(|d| -s * axes[1][d] + co * axes[2][d]);
        // The window: the points' extent across and up, centred on them.
        Self::framing(points, [axes[0], up, out])
    }

    /// The side view of `points` with the world direction `up` vertical (a load's axis),
    /// seen across their largest horizontal extent: the window fitted as [`View::fitting`]'s.
    pub fn upright(points: &[Point<3>], up: [f64; 3]) -> Self {
        let norm = |v: [f64; 3]| {
            let l = dot(&v, &v).sqrt();
            (l > 1e-12).then(|| v.map(|x| x / l))
        };
        let up = norm(up).unwrap_or([0.0, 0.0, 1.0]);
        let axes = crate::geometry::principal_axes_of(points);
        let right = axes
            .iter()
            .find_map(|a| norm(std::array::from_fn(|d| a[d] - dot(a, &up) * up[d])))
            .unwrap_or([1.0, 0.0, 0.0]);
        let out = [
            right[1] * up[2] - right[2] * up[1],
            right[2] * up[0] - right[0] * up[2],
            right[0] * up[1] - right[1] * up[0],
        ];
        Self::framing(points, [right, up, out])
    }

    /// The view by `rotation` (rows: right, up, towards the viewer) whose window holds
    /// `points`, centred on them.
    fn framing(points: &[Point<3>], rotation: [[f64; 3]; 3]) -> Self {
        let c = crate::geometry::centroid(points);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            let q = sub(*p, c);
            for k in 0..2 {
                let v = dot(&rotation[k], &q);
                lo[k] = lo[k].min(v);
                hi[k] = hi[k].max(v);
            }
        }
        if points.is_empty() {
            (lo, hi) = ([-1.0; 2], [1.0; 2]);
        }
        let mid: [f64; 2] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
        let center =
            std::array::from_fn(|d| c[d] + mid[0] * rotation[0][d] + mid[1] * rotation[1][d]);
        let extent = (0.5 * (hi[0] - lo[0])).max(0.5 * (hi[1] - lo[1]));
        let half = std::array::from_fn(|k| {
            (0.5 * (hi[k] - lo[k]))
                .max(0.02 * extent)
                .max(f64::MIN_POSITIVE)
                * 1.05
        });
        View {
            rotation,
            center,
            half,
        }
    }

    /// The same view from the other side: turned half round about the vertical.
    pub fn back(&self) -> View {
        let [r, u, o] = self.rotation;
        View {
            rotation: [r.map(|v| -v), u, o.map(|v| -v)],
            ..*self
        }
    }

    /// The height of a picture `width` pixels wide that the view fills (cropped to the
    /// shape), between 0.3 and 1.25 times the width.
    pub fn height_for(&self, width: usize) -> usize {
        let h = width as f64 * self.half[1] / self.half[0];
        (h.round() as usize)
            .clamp(width * 3 / 10, width * 5 / 4)
            .max(1)
    }

    fn project(&self, p: &Point<3>, w: usize, h: usize) -> [f64; 3] {
        let q = sub(*p, self.center);
        let x = dot(&self.rotation[0], &q);
        let y = dot(&self.rotation[1], &q);
        let z = dot(&self.rotation[2], &q);
        let scale = (0.5 * w as f64 / self.half[0]).min(0.5 * h as f64 / self.half[1]);
        [0.5 * w as f64 + x * scale, 0.5 * h as f64 - y * scale, z]
    }
}

fn sub(a: Point<3>, b: Point<3>) -> Point<3> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Colours of the pictures: values mapped through `color` (e.g. [`distance_color`]).
pub type ColorMap<'a> = &'a dyn Fn(f64) -> [u8; 3];

/// Draws the triangles `facets` of `points` into a `w × h` picture under `view`. `vertex`
/// gives a value per point (interpolated across each triangle) or `face` one per triangle;
/// `color` maps a value to a colour. Both sides of a triangle are lit alike (open surfaces
/// show their inside).
#[allow(clippy::too_many_arguments)]
pub fn render(
    points: &[Point<3>],
    facets: &[[usize; 3]],
    vertex: Option<&[f64]>,
    face: Option<&[f64]>,
    color: ColorMap,
    view: &View,
    w: usize,
    h: usize,
) -> Image {
    let mut img = Image::new(w, h);
    let mut depth = vec![f64::NEG_INFINITY; w * h];
    let proj: Vec<[f64; 3]> = points.iter().map(|p| view.project(p, w, h)).collect();
    for (t, f) in facets.iter().enumerate() {
        let [a, b, c] = [proj[f[0]], proj[f[1]], proj[f[2]]];
        // Shade by the normal's angle to the viewer (camera frame: z towards the viewer).
        let e1 = sub(points[f[1]], points[f[0]]);
        let e2 = sub(points[f[2]], points[f[0]]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let nl = dot(&n, &n).sqrt();
        if nl == 0.0 || !nl.is_finite() {
            continue;
        }
        let facing = (dot(&view.rotation[2], &n) / nl).abs();
        let shade = 0.35 + 0.65 * facing;
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area.abs() < 1e-12 {
            continue;
        }
        let x0 = a[0].min(b[0]).min(c[0]).floor().max(0.0) as usize;
        let x1 = (a[0].max(b[0]).max(c[0]).ceil() as usize).min(w.saturating_sub(1));
        let y0 = a[1].min(b[1]).min(c[1]).floor().max(0.0) as usize;
        let y1 = (a[1].max(b[1]).max(c[1]).ceil() as usize).min(h.saturating_sub(1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let w0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) / area;
                let w1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                let k = y * w + x;
                if z <= depth[k] {
                    continue;
                }
                depth[k] = z;
                let v = match (vertex, face) {
                    (Some(v), _) => w0 * v[f[0]] + w1 * v[f[1]] + w2 * v[f[2]],
                    (None, Some(fv)) => fv[t],
                    (None, None) => f64::NAN,
                };
                let rgb = if v.is_nan() {
                    [200, 200, 205]
                } else {
                    color(v)
                };
                for (ch, val) in rgb.iter().enumerate() {
                    img.rgb[3 * k + ch] = (f64::from(*val) * shade) as u8;
                }
            }
        }
    }
    img
}

/// [`render`] from the front (`view`) and from the back ([`View::back`]), side by side, each
/// `width / 2` pixels wide and as high as the shape needs ([`View::height_for`]).
#[allow(clippy::too_many_arguments)]
pub fn render_front_back(
    points: &[Point<3>],
    facets: &[[usize; 3]],
    vertex: Option<&[f64]>,
    face: Option<&[f64]>,
    color: ColorMap,
    view: &View,
    width: usize,
) -> Image {
    let w = (width / 2).max(1);
    let h = view.height_for(w);
    let mut out = Image::new(2 * w, h);
    for (k, v) in [*view, view.back()].iter().enumerate() {
        let img = render(points, facets, vertex, face, color, v, w, h);
        out.paste(&img, k * w, 0);
    }
    out
}

/// The top of a distance colour scale: the 95th percentile of `distances` (the colours then
/// spread over the errors seen), within [1e-4, 5e-2] of `diagonal` (a perfect fit is not all
/// red, a stray vertex does not wash the rest out). Units of the distances.
pub fn distance_scale(distances: &[f64], diagonal: f64) -> f64 {
    let mut d: Vec<f64> = distances
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    d.sort_by(f64::total_cmp);
    let p95 = d
        .get(((d.len() as f64 * 0.95) as usize).min(d.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    p95.clamp(1e-4 * diagonal, 5e-2 * diagonal)
}

/// Blue (0) through white to red (`max`): a distance.
pub fn distance_color(max: f64) -> impl Fn(f64) -> [u8; 3] {
    move |v: f64| {
        let t = (v / max.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        if t < 0.5 {
            let s = 2.0 * t;
            [(60.0 + 195.0 * s) as u8, (110.0 + 145.0 * s) as u8, 255]
        } else {
            let s = 2.0 * (t - 0.5);
            [255, (255.0 - 200.0 * s) as u8, (255.0 - 215.0 * s) as u8]
        }
    }
}

/// Blue (`-max`) through white (0) to red (`max`): a signed displacement (inwards negative).
pub fn signed_color(max: f64) -> impl Fn(f64) -> [u8; 3] {
    let c = distance_color(2.0 * max);
    move |v: f64| c(v + max)
}

/// A colour bar for [`annotated`]: the map, the values at its two ends and their labels.
pub struct Legend<'a> {
    /// The colour map.
    pub color: ColorMap<'a>,
    /// The value at the bar's low end.
    pub lo: f64,
    /// The value at the bar's high end.
    pub hi: f64,
    /// The label at the low end.
    pub lo_label: String,
    /// The label at the high end (with the unit).
    pub hi_label: String,
}

/// `img` with a strip above holding `title` and, with `legend`, a strip below holding a
/// colour bar with a label at each end. Text needs a system font (see
/// [`font_available`]); without one the strips hold only the bar.
pub fn annotated(img: &Image, title: &str, legend: Option<&Legend>) -> Image {
    const TOP: usize = 22;
    let bottom = if legend.is_some() { 26 } else { 0 };
    let (w, h) = (img.width, img.height + TOP + bottom);
    let mut out = Image::new(w, h);
    out.paste(img, 0, TOP);
    let bar = legend.map(|l| {
        let (x0, x1) = (w / 3, w - w / 3);
        let (y0, y1) = (h - 20, h - 8);
        for x in x0..x1 {
            let t = (x - x0) as f64 / (x1 - x0 - 1).max(1) as f64;
            let rgb = (l.color)(l.lo + t * (l.hi - l.lo));
            for y in y0..y1 {
                let k = 3 * (y * w + x);
                out.rgb[k..k + 3].copy_from_slice(&rgb);
            }
        }
        (x0, x1, y0, l)
    });
    if !font_available() {
        return out;
    }
    use plotters::prelude::*;
    {
        let root =
            BitMapBackend::with_buffer(&mut out.rgb, (w as u32, h as u32)).into_drawing_area();
        let font = ("sans-serif", 14).into_font().color(&BLACK);
        // Drawing text fails only without a font, checked above; a picture without its
        // labels is still right, so a failure here is not an error.
        let _ = root.draw(&Text::new(title.to_string(), (6, 4), font.clone()));
        if let Some((x0, x1, y0, l)) = bar {
            let right = font.pos(plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Right,
                plotters::style::text_anchor::VPos::Top,
            ));
            let _ = root.draw(&Text::new(
                l.lo_label.clone(),
                (x0 as i32 - 6, y0 as i32 - 2),
                right,
            ));
            let _ = root.draw(&Text::new(
                l.hi_label.clone(),
                (x1 as i32 + 6, y0 as i32 - 2),
                font,
            ));
        }
        let _ = root.present();
    }
    out
}

/// A small copy of the PNG picture `png` (8-bit RGB or RGBA, as this crate writes them), at
/// most `max_width` pixels wide: each pixel the mean of a square of the original's.
///
/// # Errors
/// [`Error::Numerical`] when `png` does not decode (not a picture of this crate's).
pub fn thumbnail(png: &[u8], max_width: usize) -> Result<Vec<u8>> {
    let err = |e: png::DecodingError| Error::Numerical(format!("PNG decoding: {e}"));
    let mut dec = png::Decoder::new(std::io::Cursor::new(png));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().map_err(err)?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(err)?;
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Indexed => {
            return Err(Error::Numerical("PNG decoding: indexed colours".into()));
        }
    };
    let (w, h) = (info.width as usize, info.height as usize);
    let k = w.div_ceil(max_width.max(1)).max(1);
    let (tw, th) = ((w / k).max(1), (h / k).max(1));
    let mut out = Image::new(tw, th);
    for y in 0..th {
        for x in 0..tw {
            let mut sum = [0usize; 3];
            for dy in 0..k {
                for dx in 0..k {
                    let at = ((y * k + dy).min(h - 1) * info.line_size)
                        + (x * k + dx).min(w - 1) * channels;
                    for (c, s) in sum.iter_mut().enumerate() {
                        *s += usize::from(buf[at + if channels >= 3 { c } else { 0 }]);
                    }
                }
            }
            for c in 0..3 {
                out.rgb[3 * (y * tw + x) + c] = (sum[c] / (k * k)) as u8;
            }
        }
    }
    out.png()
}

/// Dark blue (0) through teal (0.5) to yellow (1): a magnitude (a mode's displacement).
pub fn magnitude_color(t: f64) -> [u8; 3] {
    const A: [f64; 3] = [0.18, 0.16, 0.45];
    const B: [f64; 3] = [0.13, 0.57, 0.55];
    const C: [f64; 3] = [0.99, 0.9, 0.15];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (p, q, w) = if t < 0.5 {
        (A, B, 2.0 * t)
    } else {
        (B, C, 2.0 * t - 1.0)
    };
    std::array::from_fn(|d| ((p[d] + (q[d] - p[d]) * w) * 255.0).round() as u8)
}

/// Red (inverted, ≤ 0) through yellow to green (1): a scaled Jacobian.
pub fn jacobian_color(s: f64) -> [u8; 3] {
    if s <= 0.0 {
        return [200, 0, 0];
    }
    let t = s.clamp(0.0, 1.0);
    let (r, g) = if t < 0.5 {
        (255.0, 510.0 * t)
    } else {
        (510.0 * (1.0 - t), 255.0)
    };
    [r as u8, g as u8, 60]
}

/// The boundary of a volume mesh as triangles (each quadrilateral face split in two), with
/// the scaled Jacobian of the element each face belongs to.
pub fn boundary_triangles(
    mesh: &crate::mesh::FeMesh<3>,
    element_value: &[f64],
) -> (Vec<[usize; 3]>, Vec<f64>) {
    let mut tris = Vec::new();
    let mut values = Vec::new();
    for f in crate::mesh::boundary_faces(mesh) {
        let v = element_value.get(f.element).copied().unwrap_or(f64::NAN);
        for t in 1..f.nodes.len().saturating_sub(1) {
            tris.push([f.nodes[0], f.nodes[t], f.nodes[t + 1]]);
            values.push(v);
        }
    }
    (tris, values)
}

/// Registers a font for plot labels from the usual system locations; `false` when none is
/// found (plots are then drawn without text).
pub fn font_available() -> bool {
    static FONT: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FONT.get_or_init(|| {
        let candidates = [
            "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/TTF/DejaVuSans.ttf",
            "/usr/share/fonts/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
            "/Library/Fonts/Arial.ttf",
            "C:\\Windows\\Fonts\\arial.ttf",
        ];
        for c in candidates {
            if let Ok(b) = std::fs::read(c) {
                let leaked: &'static [u8] = Box::leak(b.into_boxed_slice());
                if plotters::style::register_font(
                    "sans-serif",
                    plotters::style::FontStyle::Normal,
                    leaked,
                )
                .is_ok()
                {
                    return true;
                }
            }
        }
        false
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_distance_scale_follows_the_errors_within_bounds() {
        let d: Vec<f64> = (0..100).map(|i| i as f64 * 0.01).collect();
        // The 95th percentile of 0..0.99: 0.95.
        assert!((distance_scale(&d, 100.0) - 0.95).abs() < 1e-12);
        assert!((distance_scale(&[0.0; 10], 100.0) - 0.01).abs() < 1e-12);
        assert!((distance_scale(&[1e3, f64::NAN], 100.0) - 5.0).abs() < 1e-12);
        assert!((distance_scale(&[], 100.0) - 0.01).abs() < 1e-12);
    }

    #[test]
    fn a_tetrahedron_is_drawn_in_its_colour() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let f = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let view = View::fitting(&p);
        let img = render(
            &p,
            &f,
            None,
            Some(&[1.0; 4]),
            &jacobian_color,
            &view,
            64,
            48,
        );
        // Some pixels are green-ish (scaled Jacobian 1), the corners stay white.
        let green = img
            .rgb
            .chunks(3)
            .filter(|c| c[1] > c[0] && c[1] > 60)
            .count();
        assert!(green > 200, "{green} green pixels");
        assert_eq!(&img.rgb[..3], &[255, 255, 255]);
        let png = img.png().unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
}

//! A shape: points plus boundary facets (segments in 2D, triangles in 3D), with landmarks.

use super::{Point, bounding_box, norm, sub, vertex_normals};
use crate::error::{Error, Result};

/// Number of points of the paper's hands (2001), for which its `gamma` (eq. 5) and `beta`
/// (eq. 2) values were chosen: weights of sums over points are referred to this count.
pub const REFERENCE_POINTS: f64 = 2001.0;

/// A shape: points and boundary facets (`D` point indices each), with its landmark indices.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape<const D: usize> {
    /// Name used in messages and reports (file stem, or the shape's id in a CSV).
    pub name: String,
    /// `#V` points.
    pub points: Vec<Point<D>>,
    /// `#F` facets, each `D` indices into `points`, oriented consistently.
    pub facets: Vec<[usize; D]>,
    /// Indices of landmark points (may be empty).
    pub landmarks: Vec<usize>,
}

/// A 2D outline (polyline, open or closed).
pub type Contour2 = Shape<2>;
/// A 3D triangle surface.
pub type Surface3 = Shape<3>;

impl Shape<2> {
    /// A polyline through `points` in order; `closed` adds the segment from the last point to
    /// the first.
    pub fn polyline(name: impl Into<String>, points: Vec<Point<2>>, closed: bool) -> Self {
        let n = points.len();
        let mut facets: Vec<[usize; 2]> = (1..n).map(|i| [i - 1, i]).collect();
        if closed && n > 2 {
            facets.push([n - 1, 0]);
        }
        Shape {
            name: name.into(),
            points,
            facets,
            landmarks: Vec::new(),
        }
    }

    /// Whether the outline is closed (its last segment returns to the first point).
    pub fn is_closed(&self) -> bool {
        self.facets.len() == self.points.len() && self.points.len() > 2
    }
}

impl<const D: usize> Shape<D> {
    /// This shape as a `Shape<E>`, where `E == D`: the one conversion between the generic
    /// dimension of a caller and the dimension a file or an array was found to have, chosen
    /// where data comes in.
    ///
    /// # Panics
    /// When `E != D` (a broken caller contract).
    #[track_caller]
    pub fn into_dim<const E: usize>(self) -> Shape<E> {
        assert_eq!(D, E, "a {D}D shape taken as {E}D");
        Shape {
            name: self.name,
            points: self
                .points
                .iter()
                .map(|p| std::array::from_fn(|d| p[d]))
                .collect(),
            facets: self
                .facets
                .iter()
                .map(|f| std::array::from_fn(|d| f[d]))
                .collect(),
            landmarks: self.landmarks,
        }
    }

    /// Checks that the shape can be used: at least `D + 1` points, finite coordinates, facet
    /// indices in range, non-zero extent.
    pub fn validate(&self) -> Result<()> {
        if self.points.len() < D + 1 {
            return Err(Error::shape(
                &self.name,
                format!(
                    "has {} points; at least {} are needed",
                    self.points.len(),
                    D + 1
                ),
            ));
        }
        if let Some((i, m)) = (self.points.iter().enumerate())
            .find_map(|(i, p)| super::point::coordinate_problem(p).map(|m| (i, m)))
        {
            return Err(Error::shape(&self.name, format!("point {i} {m}")));
        }
        if let Some(f) = self
            .facets
            .iter()
            .position(|f| f.iter().any(|&i| i >= self.points.len()))
        {
            return Err(Error::shape(
                &self.name,
                format!("facet {f} refers to a point that does not exist"),
            ));
        }
        if let Some(&l) = self.landmarks.iter().find(|&&l| l >= self.points.len()) {
            return Err(Error::shape(
                &self.name,
                format!(
                    "landmark index {l} is out of range (the shape has {} points)",
                    self.points.len()
                ),
            ));
        }
        let (lo, hi) = bounding_box(&self.points);
        if (0..D).all(|d| hi[d] - lo[d] <= 0.0) {
            return Err(Error::shape(&self.name, "all points coincide"));
        }
        Ok(())
    }

    /// Length of the bounding box diagonal (shape units).
    pub fn bbox_diagonal(&self) -> f64 {
        let (lo, hi) = bounding_box(&self.points);
        norm(sub(hi, lo))
    }

    /// A size that stray points cannot inflate: the diagonal of the box between the 0.5th and
    /// the 99.5th percentiles of the points along each axis (shape units). Equal to the
    /// bounding-box diagonal but for the outermost 1 % of the points; a far vertex or a small
    /// fragment leaves it unchanged.
    pub fn robust_diagonal(&self) -> f64 {
        let n = self.points.len();
        if n == 0 {
            return 0.0;
        }
        let lo_i = ((n - 1) as f64 * 0.005).round() as usize;
        let hi_i = ((n - 1) as f64 * 0.995).round() as usize;
        let mut axis: Vec<f64> = Vec::with_capacity(n);
        let mut d2 = 0.0;
        for d in 0..D {
            axis.clear();
            axis.extend(self.points.iter().map(|p| p[d]));
            axis.sort_by(f64::total_cmp);
            d2 += (axis[hi_i] - axis[lo_i]).powi(2);
        }
        d2.sqrt()
    }

    /// Vertex normals: the area-weighted average of the surrounding facet normals (section
    /// 2.1; in 2D the length-weighted average of the segment normals), normalized. For a
    /// counter-clockwise outline or an outward-oriented surface they point outwards.
    pub fn vertex_normals(&self) -> Vec<Point<D>> {
        vertex_normals(&self.points, &self.facets)
    }

    /// Median facet size: see [`median_edge_length`].
    pub fn median_edge_length(&self) -> f64 {
        median_edge_length(&self.points, &self.facets)
    }
}

/// The longest shape name kept (characters); a longer one keeps its start and a checksum.
pub const MAX_NAME_CHARS: usize = 200;

/// Whether `c` must not reach a page or a terminal as it is: a control character, or an
/// invisible one that reorders or hides text (bidirectional overrides and isolates,
/// zero-width characters).
pub fn hidden_char(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{061C}' | '\u{200B}'..='\u{200F}' | '\u{202A}'..='\u{202E}'
            | '\u{2060}'..='\u{2069}' | '\u{FEFF}')
}

/// A shape's name as it may be shown (report titles, pages, messages, `report.json`):
/// control characters and the invisible ones that reorder or hide text (bidirectional
/// overrides and isolates, zero-width characters: display spoofing) replaced by `�`, and a
/// name longer than [`MAX_NAME_CHARS`] cut with a checksum of the whole, so that two long
/// names stay apart.
pub fn display_name(name: &str) -> String {
    let count = name.chars().count();
    let keep = if count > MAX_NAME_CHARS {
        MAX_NAME_CHARS - 9
    } else {
        count
    };
    let mut s: String = name
        .chars()
        .take(keep)
        .map(|c| if hidden_char(c) { '\u{FFFD}' } else { c })
        .collect();
    if count > MAX_NAME_CHARS {
        s.push_str(&format!("~{:08x}", crc32fast::hash(name.as_bytes())));
    }
    s
}

/// Median length of the facets' first edges (segment lengths in 2D); 0 without facets.
pub fn median_edge_length<const D: usize>(points: &[Point<D>], facets: &[[usize; D]]) -> f64 {
    let mut l: Vec<f64> = facets
        .iter()
        .map(|f| norm(sub(points[f[1]], points[f[0]])))
        .collect();
    if l.is_empty() {
        return 0.0;
    }
    let mid = l.len() / 2;
    *l.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// A triangulated sphere-like surface: a pole, `rings - 1` rings of `sectors` points, a pole;
/// point `(theta, phi)` (latitude from -pi/2 to pi/2, longitude) placed by `at`. The facets
/// face outwards for the unit sphere.
pub fn uv_sphere(
    sectors: usize,
    rings: usize,
    at: impl Fn(f64, f64) -> Point<3>,
) -> (Vec<Point<3>>, Vec<[usize; 3]>) {
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    let mut points = vec![at(-FRAC_PI_2, 0.0)];
    for j in 1..rings {
        let th = PI * j as f64 / rings as f64 - FRAC_PI_2;
        for i in 0..sectors {
            points.push(at(th, TAU * i as f64 / sectors as f64));
        }
    }
    points.push(at(FRAC_PI_2, 0.0));
    let top = points.len() - 1;
    let ring = |j: usize, i: usize| 1 + (j - 1) * sectors + i % sectors;
    let mut facets = Vec::new();
    for i in 0..sectors {
        facets.push([0, ring(1, i + 1), ring(1, i)]);
        facets.push([top, ring(rings - 1, i), ring(rings - 1, i + 1)]);
    }
    for j in 1..rings - 1 {
        for i in 0..sectors {
            facets.push([ring(j, i), ring(j, i + 1), ring(j + 1, i + 1)]);
            facets.push([ring(j, i), ring(j + 1, i + 1), ring(j + 1, i)]);
        }
    }
    (points, facets)
}

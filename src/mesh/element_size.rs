//! The element size of the mean mesh: asked for as a length in the data's unit, as a share
//! of the mean's extent, or chosen from the mean's thickness.

use crate::error::{Error, Result};
use crate::geometry::{Shape, bounding_box, local_thickness, thickness_quantile};

/// Elements across the thinnest part of the mean that the automatic size aims at.
pub const ELEMENTS_ACROSS: f64 = 6.0;

/// The share of the mean's largest extent that the automatic size never exceeds (the
/// coarsest mesh it picks).
pub const COARSEST_SHARE: f64 = 0.015;

/// How the mean mesh's element edge length is chosen.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementSize {
    /// From the mean's thickness: about [`ELEMENTS_ACROSS`] elements across its thinnest part
    /// (the 5th percentile of the local thickness), at most [`COARSEST_SHARE`] of its
    /// largest extent, and no more elements than the budget. An open outline (no thickness
    /// across its opening) gets [`COARSEST_SHARE`].
    Auto,
    /// A length in the unit of the population's data (mm for mm data).
    Length(f64),
    /// A share of the mean's largest extent.
    Share(f64),
}

impl std::str::FromStr for ElementSize {
    type Err = String;

    /// `auto`, `2` (a length in the data's unit) or `1.5%` (a share of the largest extent).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let t = s.trim();
        if t.eq_ignore_ascii_case("auto") {
            return Ok(ElementSize::Auto);
        }
        let (number, share) = match t.strip_suffix('%') {
            Some(n) => (n.trim(), true),
            None => (t, false),
        };
        let v: f64 = number
            .parse()
            .map_err(|_| format!("`{s}` is not a length, a share with % or `auto`"))?;
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("`{s}`: the element size must be positive"));
        }
        if share {
            if v >= 50.0 {
                return Err(format!("`{s}`: a share must be below 50 %"));
            }
            Ok(ElementSize::Share(v / 100.0))
        } else {
            Ok(ElementSize::Length(v))
        }
    }
}

/// The largest element count the automatic size may give: hexahedra in 3D, quadrilaterals
/// in 2D (the mesh, the morph and the repair of every subject scale with it).
pub fn element_budget(dimension: usize) -> f64 {
    if dimension == 3 { 150_000.0 } else { 20_000.0 }
}

/// The element edge length for `size`, as a share of the largest extent of `mean` (the
/// reference frame's unit of the mesher), where one unit of `mean` is `data_per_mean` units
/// of the data.
///
/// # Errors
/// [`Error::Parameter`] when the size is not below half the extent.
pub fn resolve_element_size<const D: usize>(
    size: ElementSize,
    mean: &Shape<D>,
    data_per_mean: f64,
) -> Result<f64> {
    let (lo, hi) = bounding_box(&mean.points);
    let extent = (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let share = match size {
        ElementSize::Share(s) => s,
        ElementSize::Length(l) => l / (data_per_mean * extent),
        ElementSize::Auto => {
            // An open outline (the hands: no wrist) has no thickness across its opening.
            let open = D == 2 && mean.facets.len() < mean.points.len();
            let thin = if open {
                COARSEST_SHARE
            } else {
                thickness_quantile(&local_thickness(mean), 0.05)
                    .map_or(COARSEST_SHARE, |t| t / (ELEMENTS_ACROSS * extent))
            };
            // The budget: the inside's measure over the element's.
            let inside = content(mean) / extent.powi(D as i32);
            let finest = (inside / element_budget(D)).powf(1.0 / D as f64);
            thin.min(COARSEST_SHARE).max(finest)
        }
    };
    if !(share.is_finite() && share > 0.0 && share < 0.5) {
        return Err(Error::Parameter(format!(
            "element size {size:?} is {share:.3} of the mean's largest extent ({:.4} in the \
             data's unit); it must be below half of it",
            data_per_mean * extent
        )));
    }
    Ok(share)
}

/// The area (2D) or volume (3D) inside a closed shape, shape units.
fn content<const D: usize>(s: &Shape<D>) -> f64 {
    let twice: f64 = s
        .facets
        .iter()
        .map(|f| {
            let (a, b) = (s.points[f[0]], s.points[f[1]]);
            if D == 2 {
                a[0] * b[1] - a[1] * b[0]
            } else {
                let c = s.points[f[2 % D]];
                let det = a[0] * (b[1] * c[2 % D] - b[2 % D] * c[1])
                    - a[1] * (b[0] * c[2 % D] - b[2 % D] * c[0])
                    + a[2 % D] * (b[0] * c[1] - b[1] * c[0]);
                det / 3.0
            }
        })
        .sum();
    (0.5 * twice).abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An ellipsoid of semi-axes 1, 1, `c`, oriented outwards.
    fn ellipsoid(c: f64) -> Shape<3> {
        let (points, facets) = crate::geometry::uv_sphere(48, 24, |th, ph| {
            [th.cos() * ph.cos(), th.cos() * ph.sin(), c * th.sin()]
        });
        crate::geometry::prepare_surface(Shape {
            name: "ellipsoid".into(),
            points,
            facets,
            landmarks: Vec::new(),
        })
        .unwrap()
    }

    #[test]
    fn sizes_parse_as_lengths_shares_or_auto() {
        assert_eq!("2".parse::<ElementSize>(), Ok(ElementSize::Length(2.0)));
        assert_eq!("1.5%".parse::<ElementSize>(), Ok(ElementSize::Share(0.015)));
        assert_eq!("auto".parse::<ElementSize>(), Ok(ElementSize::Auto));
        assert!("-1".parse::<ElementSize>().is_err());
        assert!("60%".parse::<ElementSize>().is_err());
        assert!("mm".parse::<ElementSize>().is_err());
    }

    /// A sphere of radius 1 in a mean frame where one unit is 50 data units: 2 data units
    /// are 2 / (50 · 2) of the extent; the automatic size of a sphere (thickness 2) is about
    /// the coarsest share.
    #[test]
    fn lengths_are_in_the_data_unit_and_auto_follows_the_thickness() {
        let s = ellipsoid(1.0);
        let l = resolve_element_size(ElementSize::Length(2.0), &s, 50.0).unwrap();
        assert!((l - 0.02).abs() < 1e-3, "{l}");
        let auto = resolve_element_size(ElementSize::Auto, &s, 50.0).unwrap();
        // (just above it: at 1.5 % a ball of side 1 would need more elements than the budget)
        assert!((COARSEST_SHARE..0.0155).contains(&auto), "{auto}");
        // A flat disc (a sphere squashed to a twentieth): about 6 elements across its
        // thickness 0.1, which is 0.1 / 6 / 2 of its extent.
        let auto = resolve_element_size(ElementSize::Auto, &ellipsoid(0.05), 50.0).unwrap();
        assert!(auto < COARSEST_SHARE && auto > 0.005, "{auto}");
        assert!(resolve_element_size(ElementSize::Length(200.0), &s, 50.0).is_err());
    }
}

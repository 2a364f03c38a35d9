//! Elements in their natural coordinates: shape functions and their derivatives, and the
//! composite Gauss rules that integrate over an element's volume.
//!
//! Natural coordinates: `[-1, 1]^D` for quadrilaterals and hexahedra (corner `c` at the
//! signs of [`corner_signs`]), the unit simplex for triangles and tetrahedra (corner 0 at
//! the origin, corner `d` at the unit vector `d`). A rule splits the unit cube `[0, 1]^D`
//! into sub-cells and puts a Gauss-Legendre rule in each; simplices are reached from the
//! cube by the collapsed (Duffy) map `ξ = (u, (1 - u) v, (1 - u)(1 - v) w)`, of Jacobian
//! `(1 - u)² (1 - v)`, so that a polynomial over the simplex stays a polynomial over the cube.

use crate::mesh::{ElementKind, HEX20_EDGES};

/// Gauss-Legendre points and weights on `[0, 1]`, for 1 to 4 points (exact for degree
/// `2n - 1`).
fn gauss(n: usize) -> &'static [(f64, f64)] {
    const G1: [(f64, f64); 1] = [(0.5, 1.0)];
    const G2: [(f64, f64); 2] = [
        (0.211_324_865_405_187_1, 0.5),
        (0.788_675_134_594_812_9, 0.5),
    ];
    const G3: [(f64, f64); 3] = [
        (0.112_701_665_379_258_3, 5.0 / 18.0),
        (0.5, 8.0 / 18.0),
        (0.887_298_334_620_741_7, 5.0 / 18.0),
    ];
    const G4: [(f64, f64); 4] = [
        (0.069_431_844_202_973_71, 0.173_927_422_568_726_9),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
    ];
    match n {
        1 => &G1,
        2 => &G2,
        3 => &G3,
        _ => &G4,
    }
}

/// Gauss points per direction in each sub-cell for an element kind: exact, over a straight
/// or curved element, for the trilinear CT of a field linear in position (linear kinds:
/// degree 3 per direction; quadratic: degree 7).
pub fn gauss_points(kind: ElementKind) -> usize {
    if kind.linear() == kind { 2 } else { 4 }
}

/// The signs of the natural coordinates of each corner of a quadrilateral or hexahedron
/// (node order of [`ElementKind`]).
pub fn corner_signs(kind: ElementKind) -> &'static [[f64; 3]] {
    const QUAD: [[f64; 3]; 4] = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    const HEX: [[f64; 3]; 8] = [
        [-1.0, -1.0, -1.0],
        [1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, 1.0],
    ];
    match kind {
        ElementKind::Quad4 => &QUAD,
        _ => &HEX,
    }
}

/// A point of a rule: its cube coordinates `u ∈ [0, 1]^D` and its weight (the cube's
/// volume shared among the points).
#[derive(Clone, Copy, Debug)]
pub struct CubePoint {
    /// Coordinates in the unit cube (the unused ones 0).
    pub u: [f64; 3],
    /// Weight; the weights of a rule sum to 1.
    pub weight: f64,
}

/// The composite rule over `[0, 1]^dim`: `cells[d]` sub-cells along direction `d`, a
/// `g`-point Gauss-Legendre rule in each (points written into `out`, which is cleared).
pub fn cube_rule(dim: usize, cells: [usize; 3], g: usize, out: &mut Vec<CubePoint>) {
    out.clear();
    let rule = gauss(g);
    let n: [usize; 3] = std::array::from_fn(|d| if d < dim { cells[d].max(1) } else { 1 });
    let per: [usize; 3] = std::array::from_fn(|d| if d < dim { rule.len() } else { 1 });
    let cell_weight = 1.0 / (n[0] * n[1] * n[2]) as f64;
    for c2 in 0..n[2] {
        for c1 in 0..n[1] {
            for c0 in 0..n[0] {
                let cell = [c0, c1, c2];
                for p2 in 0..per[2] {
                    for p1 in 0..per[1] {
                        for p0 in 0..per[0] {
                            let p = [p0, p1, p2];
                            let mut u = [0.0; 3];
                            let mut w = cell_weight;
                            for d in 0..dim {
                                let (x, wx) = rule[p[d]];
                                u[d] = (cell[d] as f64 + x) / n[d] as f64;
                                w *= wx;
                            }
                            out.push(CubePoint { u, weight: w });
                        }
                    }
                }
            }
        }
    }
}

/// The natural coordinates of the cube point `u` for `kind` and the factor its weight takes
/// (the map's Jacobian from the cube: `2^D` for `[-1, 1]^D`, the collapsed map's for
/// simplices).
#[inline]
pub fn natural_point(kind: ElementKind, u: &[f64; 3]) -> ([f64; 3], f64) {
    match kind {
        ElementKind::Quad4 => ([2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0, 0.0], 4.0),
        ElementKind::Hex8 | ElementKind::Hex20 => {
            ([2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0, 2.0 * u[2] - 1.0], 8.0)
        }
        ElementKind::Tri3 => ([u[0], (1.0 - u[0]) * u[1], 0.0], 1.0 - u[0]),
        ElementKind::Tet4 | ElementKind::Tet10 => {
            let a = 1.0 - u[0];
            let b = 1.0 - u[1];
            ([u[0], a * u[1], a * b * u[2]], a * a * b)
        }
    }
}

/// The shape functions of `kind` at the natural point `xi` into `n` and their derivatives
/// by the natural coordinates into `dn` (one entry per node).
#[inline]
pub fn shape_functions(kind: ElementKind, xi: &[f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    match kind {
        ElementKind::Quad4 | ElementKind::Hex8 => {
            let dim = kind.dimension();
            let scale = 0.5f64.powi(dim as i32);
            for (c, s) in corner_signs(kind).iter().enumerate() {
                let f: [f64; 3] =
                    std::array::from_fn(|d| if d < dim { 1.0 + xi[d] * s[d] } else { 1.0 });
                n[c] = scale * f[0] * f[1] * f[2];
                dn[c] = [
                    scale * s[0] * f[1] * f[2],
                    scale * f[0] * s[1] * f[2],
                    if dim == 3 {
                        scale * f[0] * f[1] * s[2]
                    } else {
                        0.0
                    },
                ];
            }
        }
        ElementKind::Hex20 => hex20(xi, n, dn),
        ElementKind::Tri3 | ElementKind::Tet4 => {
            let dim = kind.dimension();
            n[0] = 1.0 - xi[..dim].iter().sum::<f64>();
            dn[0] = std::array::from_fn(|d| if d < dim { -1.0 } else { 0.0 });
            for c in 1..=dim {
                n[c] = xi[c - 1];
                dn[c] = [0.0; 3];
                dn[c][c - 1] = 1.0;
            }
        }
        ElementKind::Tet10 => tet10(xi, n, dn),
    }
}

/// The 20-node serendipity hexahedron: corners `(1+ξξᵢ)(1+ηηᵢ)(1+ζζᵢ)(ξξᵢ+ηηᵢ+ζζᵢ-2)/8`,
/// mid-edge nodes `(1-ξ²)(1+ηηᵢ)(1+ζζᵢ)/4` (the zero coordinate squared).
fn hex20(xi: &[f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    let signs = corner_signs(ElementKind::Hex8);
    for (c, s) in signs.iter().enumerate() {
        let f: [f64; 3] = std::array::from_fn(|d| 1.0 + xi[d] * s[d]);
        let sum = xi[0] * s[0] + xi[1] * s[1] + xi[2] * s[2];
        n[c] = 0.125 * f[0] * f[1] * f[2] * (sum - 2.0);
        for d in 0..3 {
            let (e1, e2) = ((d + 1) % 3, (d + 2) % 3);
            dn[c][d] = 0.125 * s[d] * f[e1] * f[e2] * (sum - 2.0 + f[d]);
        }
    }
    for &[a, b, m] in &HEX20_EDGES {
        let s: [f64; 3] = std::array::from_fn(|d| 0.5 * (signs[a][d] + signs[b][d]));
        let z = (0..3).find(|&d| s[d] == 0.0).unwrap_or(0);
        let (e1, e2) = ((z + 1) % 3, (z + 2) % 3);
        let (f1, f2) = (1.0 + xi[e1] * s[e1], 1.0 + xi[e2] * s[e2]);
        let q = 1.0 - xi[z] * xi[z];
        n[m] = 0.25 * q * f1 * f2;
        dn[m][z] = -0.5 * xi[z] * f1 * f2;
        dn[m][e1] = 0.25 * q * s[e1] * f2;
        dn[m][e2] = 0.25 * q * f1 * s[e2];
    }
}

/// The 10-node tetrahedron: corners `L(2L - 1)`, mid-edge nodes `4 Lₐ L_b`, with the
/// barycentric `L₀ = 1 - ξ - η - ζ`, `L₁ = ξ`, `L₂ = η`, `L₃ = ζ`.
fn tet10(xi: &[f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    let l = [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]];
    let dl: [[f64; 3]; 4] = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    for c in 0..4 {
        n[c] = l[c] * (2.0 * l[c] - 1.0);
        dn[c] = std::array::from_fn(|d| (4.0 * l[c] - 1.0) * dl[c][d]);
    }
    for &[a, b, m] in &crate::mesh::TET10_EDGES {
        n[m] = 4.0 * l[a] * l[b];
        dn[m] = std::array::from_fn(|d| 4.0 * (l[a] * dl[b][d] + l[b] * dl[a][d]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ALL_KINDS;

    /// Shape functions sum to 1 (their derivatives to 0), are 1 at their own node, and the
    /// derivatives match finite differences.
    #[test]
    fn shape_functions_interpolate_and_differentiate() {
        for kind in ALL_KINDS {
            let k = kind.nodes();
            let mut n = vec![0.0; k];
            let mut dn = vec![[0.0; 3]; k];
            let dim = kind.dimension();
            for u in [[0.3, 0.2, 0.4], [0.7, 0.1, 0.25], [0.05, 0.9, 0.5]] {
                let (xi, _) = natural_point(kind, &u);
                shape_functions(kind, &xi, &mut n, &mut dn);
                assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{kind:?}");
                for d in 0..dim {
                    assert!(dn.iter().map(|g| g[d]).sum::<f64>().abs() < 1e-12);
                    let h = 1e-6;
                    let (mut a, mut b) = (xi, xi);
                    a[d] += h;
                    b[d] -= h;
                    let (mut na, mut nb) = (vec![0.0; k], vec![0.0; k]);
                    let mut scratch = vec![[0.0; 3]; k];
                    shape_functions(kind, &a, &mut na, &mut scratch);
                    shape_functions(kind, &b, &mut nb, &mut scratch);
                    for i in 0..k {
                        let fd = (na[i] - nb[i]) / (2.0 * h);
                        assert!((fd - dn[i][d]).abs() < 1e-6, "{kind:?} node {i} d{d}");
                    }
                }
            }
        }
    }

    #[test]
    fn composite_rules_integrate_the_cube() {
        let mut pts = Vec::new();
        for (dim, cells, g) in [(3, [2, 3, 1], 2), (2, [4, 1, 1], 4), (3, [1, 1, 1], 1)] {
            cube_rule(dim, cells, g, &mut pts);
            assert!((pts.iter().map(|p| p.weight).sum::<f64>() - 1.0).abs() < 1e-14);
            // ∫ u0³ u1 over the unit cube = 1/8.
            let i: f64 = pts.iter().map(|p| p.weight * p.u[0].powi(3) * p.u[1]).sum();
            if g >= 2 {
                assert!((i - 0.125).abs() < 1e-14, "{dim} {cells:?} {g}");
            }
        }
    }
}

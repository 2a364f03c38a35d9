//! One element's CT integrals, as Bonemat takes them (Taddei et al. 2004, 2007): the CT
//! trilinearly interpolated and integrated over the element's volume in its natural
//! coordinates.

use super::ct_field::CtField;
use super::natural_coordinates::{
    CubePoint, cube_rule, gauss_points, natural_point, shape_functions,
};
use super::recipe::{IntegrationMethod, ResolvedRecipe};
use crate::geometry::{Point, cross, dot, norm};
use crate::mesh::ElementKind;

/// What one element holds of the CT.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ElementIntegral {
    /// Mean HU over the part of the element inside the CT.
    pub hu: f64,
    /// Mean Young's modulus (MPa): V3 the mean of E over the element, V2 E of the mean HU;
    /// at least the recipe's floor.
    pub modulus: f64,
    /// Share of the element's volume outside the CT's extent.
    pub outside: f64,
    /// Share of the inside volume below the soft-tissue threshold.
    pub soft: f64,
    /// Largest HU sampled in the element.
    pub hu_max: f64,
    /// The element's volume (mm³).
    pub volume: f64,
}

/// One point of a rule with its shape functions: `[weight · factor, N₀.., ∂N₀/∂ξ.., ..]`
/// (the weight includes the map from the cube; the derivatives `dim` per node).
type RuleTable = Vec<f64>;

/// Scratch for [`integrate_element`]: the rules met so far with their shape functions
/// evaluated, by element kind and sub-cells (an element's neighbours mostly share one).
#[derive(Default)]
pub struct IntegrationScratch {
    rules: std::collections::HashMap<(ElementKind, [usize; 3]), RuleTable>,
    points: Vec<CubePoint>,
}

impl IntegrationScratch {
    /// The table of the rule of `kind` with `cells` sub-cells.
    fn rule(&mut self, kind: ElementKind, cells: [usize; 3]) -> &RuleTable {
        let points = &mut self.points;
        self.rules.entry((kind, cells)).or_insert_with(|| {
            cube_rule(kind.dimension(), cells, gauss_points(kind), points);
            let (k, dim) = (kind.nodes(), kind.dimension());
            let mut n = vec![0.0; k];
            let mut dn = vec![[0.0; 3]; k];
            let mut t = Vec::with_capacity(points.len() * (1 + k + k * dim));
            for p in points.iter() {
                let (xi, factor) = natural_point(kind, &p.u);
                if kind == ElementKind::Hex8 {
                    // The trilinear map in its monomial form needs only ξ.
                    t.extend([p.weight * factor, xi[0], xi[1], xi[2]]);
                    continue;
                }
                shape_functions(kind, &xi, &mut n, &mut dn);
                t.push(p.weight * factor);
                t.extend_from_slice(&n);
                for g in &dn {
                    t.extend_from_slice(&g[..dim]);
                }
            }
            t
        })
    }
}

/// The density-elasticity law tabulated over a CT's range of HU, linear between entries
/// (every 1/16 HU; coarser for a range beyond [`ModulusTable::MAX_ENTRIES`] steps): V3
/// evaluates E at every integration point, and a power per point would cost more than the
/// rest of the point. Measured: within 1e-5 relative of the law where E is above 10 × its
/// floor (the table's steepest part is near zero density).
#[derive(Clone, Debug)]
pub struct ModulusTable {
    lo: f64,
    step: f64,
    values: Vec<f64>,
}

impl ModulusTable {
    /// Most entries.
    pub const MAX_ENTRIES: usize = 1 << 20;

    /// The law of `recipe` (its floor included) over `range` (HU).
    pub fn new(recipe: &ResolvedRecipe, range: [f64; 2]) -> Self {
        let lo = range[0].min(range[1]);
        let span = (range[1] - range[0]).abs().max(1.0);
        let step = (span / (Self::MAX_ENTRIES - 2) as f64).max(1.0 / 16.0);
        let n = (span / step).ceil() as usize + 2;
        let values = (0..n)
            .map(|i| recipe.modulus(lo + i as f64 * step))
            .collect();
        ModulusTable { lo, step, values }
    }

    /// E (MPa) at `hu` (clamped to the table's range).
    #[inline]
    pub fn at(&self, hu: f64) -> f64 {
        let t = ((hu - self.lo) / self.step).clamp(0.0, (self.values.len() - 2) as f64);
        let i = t as usize;
        let f = t - i as f64;
        self.values[i] + f * (self.values[i + 1] - self.values[i])
    }
}

/// What every element's integration shares: the recipe, its law tabulated over the CT's
/// range, and the volume of one voxel (mm³; a pixel's area in 2D).
pub struct ElementRule<'a> {
    /// The recipe.
    pub recipe: &'a ResolvedRecipe,
    /// The law over the CT's HU.
    pub table: ModulusTable,
    /// mm³ per unit of index-space volume.
    pub voxel_volume: f64,
}

impl<'a> ElementRule<'a> {
    /// The rule of `recipe` on `ct`, `voxel_volume` mm³ a voxel.
    pub fn new(ct: &CtField, recipe: &'a ResolvedRecipe, voxel_volume: f64) -> Self {
        ElementRule {
            recipe,
            table: ModulusTable::new(recipe, ct.range),
            voxel_volume,
        }
    }
}

/// The sub-cells of the element of index-space `nodes` along each natural direction: its
/// extent along the direction in voxels times `per_voxel`, at least 1, at most 64
/// (hexahedra and quadrilaterals by their edges along each direction; simplices by their
/// longest edge).
fn sub_cells(kind: ElementKind, nodes: &[Point<3>], per_voxel: f64) -> [usize; 3] {
    let len = |a: usize, b: usize| {
        let (p, q) = (nodes[a], nodes[b]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    let cells = |l: f64| ((l * per_voxel).ceil() as usize).clamp(1, 64);
    let longest = |edges: &[[usize; 2]]| edges.iter().map(|e| len(e[0], e[1])).fold(0.0, f64::max);
    match kind.linear() {
        ElementKind::Hex8 => [
            cells(longest(&[[0, 1], [3, 2], [4, 5], [7, 6]])),
            cells(longest(&[[0, 3], [1, 2], [4, 7], [5, 6]])),
            cells(longest(&[[0, 4], [1, 5], [2, 6], [3, 7]])),
        ],
        ElementKind::Quad4 => [
            cells(longest(&[[0, 1], [3, 2]])),
            cells(longest(&[[0, 3], [1, 2]])),
            1,
        ],
        ElementKind::Tri3 => {
            let c = cells(longest(&[[0, 1], [1, 2], [2, 0]]));
            [c, c, 1]
        }
        _ => {
            let c = cells(longest(&[[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]]));
            [c; 3]
        }
    }
}

/// The most integration points of one element: an element of hundreds of voxels gets
/// fewer sub-cells per voxel rather than unbounded time.
pub const MAX_POINTS_PER_ELEMENT: usize = 1 << 18;

/// `cells` scaled down evenly until `cells` × `per_cell` points fit
/// [`MAX_POINTS_PER_ELEMENT`].
fn within_budget(cells: [usize; 3], per_cell: usize) -> [usize; 3] {
    let total = cells.iter().product::<usize>() * per_cell;
    if total <= MAX_POINTS_PER_ELEMENT {
        return cells;
    }
    let f = (MAX_POINTS_PER_ELEMENT as f64 / total as f64).cbrt();
    cells.map(|c| ((c as f64 * f).floor() as usize).max(1))
}

/// The hexahedron's trilinear map `x = Σ N_c(ξ) x_c` in monomial form:
/// `a₀ + a₁ξ + a₂η + a₃ζ + a₄ξη + a₅ηζ + a₆ζξ + a₇ξηζ`.
fn trilinear_coefficients(nodes: &[Point<3>]) -> [Point<3>; 8] {
    let signs = super::natural_coordinates::corner_signs(ElementKind::Hex8);
    let mut a = [[0.0; 3]; 8];
    for (node, s) in nodes.iter().zip(signs) {
        let m = [
            1.0,
            s[0],
            s[1],
            s[2],
            s[0] * s[1],
            s[1] * s[2],
            s[2] * s[0],
            s[0] * s[1] * s[2],
        ];
        for (ai, mi) in a.iter_mut().zip(m) {
            for c in 0..3 {
                ai[c] += 0.125 * mi * node[c];
            }
        }
    }
    a
}

/// A hexahedron's point and Jacobian determinant at `(ξ, η, ζ)` from its monomial form.
#[inline]
fn trilinear_point(a: &[Point<3>; 8], u: f64, v: f64, w: f64) -> (Point<3>, f64) {
    let mut x = [0.0; 3];
    let mut j = [[0.0; 3]; 3];
    for c in 0..3 {
        x[c] = a[0][c]
            + a[1][c] * u
            + a[2][c] * v
            + a[3][c] * w
            + a[4][c] * u * v
            + a[5][c] * v * w
            + a[6][c] * w * u
            + a[7][c] * u * v * w;
        j[0][c] = a[1][c] + a[4][c] * v + a[6][c] * w + a[7][c] * v * w;
        j[1][c] = a[2][c] + a[4][c] * u + a[5][c] * w + a[7][c] * u * w;
        j[2][c] = a[3][c] + a[5][c] * v + a[6][c] * u + a[7][c] * u * v;
    }
    (x, dot(j[0], cross(j[1], j[2])).abs())
}

/// Any element's point and Jacobian determinant (in 2D the area of the two tangents) from
/// its shape functions `n` and their derivatives `dn` (`dim` per node) at the point.
#[inline]
fn mapped_point(nodes: &[Point<3>], p: &[f64], k: usize, dim: usize) -> (Point<3>, f64) {
    let (n, dn) = p.split_at(k);
    let mut x = [0.0; 3];
    let mut j = [[0.0; 3]; 3]; // j[d] = ∂x/∂ξ_d
    for (a, node) in nodes.iter().enumerate() {
        let g = &dn[a * dim..(a + 1) * dim];
        for c in 0..3 {
            x[c] += n[a] * node[c];
            for d in 0..dim {
                j[d][c] += g[d] * node[c];
            }
        }
    }
    let det = if dim == 3 {
        dot(j[0], cross(j[1], j[2])).abs()
    } else {
        norm(cross(j[0], j[1]))
    };
    (x, det)
}

/// Integrates the CT over one element whose nodes are `nodes` in the CT's index
/// coordinates (voxels): `∫ f(HU(x)) dV` over the element by the composite Gauss rule in
/// its natural coordinates (`x = Σ Nᵢ(ξ) xᵢ`, `dV = |det ∂x/∂ξ| dξ`; in 2D the area of the
/// two tangents), `subcells_per_voxel` sub-cells per voxel of extent (Bonemat's integration;
/// Taddei et al. 2007). The rule is exact for a CT linear in position, straight or curved
/// element. Points outside the CT count as outside and are left out of the means.
pub fn integrate_element(
    ct: &CtField,
    kind: ElementKind,
    nodes: &[Point<3>],
    rule: &ElementRule,
    scratch: &mut IntegrationScratch,
) -> ElementIntegral {
    let recipe = rule.recipe;
    let dim = kind.dimension();
    let k = kind.nodes();
    let cells = within_budget(
        sub_cells(kind, nodes, recipe.recipe.integration.subcells_per_voxel),
        gauss_points(kind).pow(dim as u32),
    );
    let table = scratch.rule(kind, cells);
    let v3 = recipe.recipe.integration.method == IntegrationMethod::V3;
    let soft_hu = recipe.recipe.checks.soft_tissue_hu;
    let (mut total, mut inside, mut hu, mut e, mut soft) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut hu_max = f64::NEG_INFINITY;
    let hex8 = (kind == ElementKind::Hex8).then(|| trilinear_coefficients(nodes));
    let stride = if hex8.is_some() { 4 } else { 1 + k + k * dim };
    for p in table.chunks_exact(stride) {
        let (x, det) = match &hex8 {
            Some(a) => trilinear_point(a, p[1], p[2], p[3]),
            None => mapped_point(nodes, &p[1..], k, dim),
        };
        let w = p[0] * det;
        total += w;
        if let Some(h) = ct.sample(&x) {
            inside += w;
            hu += w * h;
            if v3 {
                e += w * rule.table.at(h);
            }
            if h < soft_hu {
                soft += w;
            }
            hu_max = hu_max.max(h);
        }
    }
    let mut hu = if inside > 0.0 { hu / inside } else { f64::NAN };
    if recipe.recipe.integration.method == IntegrationMethod::Centroid {
        // The CT at the mean of the nodes (a voxel's centre for a voxel's hexahedron).
        let mut c = [0.0; 3];
        for n in nodes {
            for d in 0..3 {
                c[d] += n[d] / nodes.len() as f64;
            }
        }
        if let Some(h) = ct.sample(&c) {
            hu = h;
        }
    }
    let modulus = if !v3 || inside <= 0.0 {
        recipe.modulus(hu)
    } else {
        (e / inside).max(recipe.recipe.modulus.floor)
    };
    ElementIntegral {
        hu,
        modulus,
        outside: if total > 0.0 {
            (1.0 - inside / total).max(0.0)
        } else {
            1.0
        },
        soft: if inside > 0.0 { soft / inside } else { 0.0 },
        hu_max,
        volume: total * rule.voxel_volume,
    }
}

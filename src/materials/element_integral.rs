//! One element's CT integrals, as Bonemat takes them (Taddei et al. 2004, 2007): the CT
//! trilinearly interpolated and integrated over the element's volume in its natural
//! coordinates.

use super::ct_field::CtField;
use super::natural_coordinates::{CubePoint, cube_rule, gauss_points, natural_point, shape_functions};
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

/// Scratch for [`integrate_element`]: the rule's points and the shape functions.
#[derive(Default)]
pub struct IntegrationScratch {
    points: Vec<CubePoint>,
    cells: [usize; 3],
    kind: Option<ElementKind>,
    n: Vec<f64>,
    dn: Vec<[f64; 3]>,
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

/// Integrates the CT over one element whose nodes are `nodes` in the CT's index
/// coordinates (voxels): `∫ f(HU(x)) dV` over the element by the composite Gauss rule in
/// its natural coordinates (`x = Σ Nᵢ(ξ) xᵢ`, `dV = |det ∂x/∂ξ| dξ`; in 2D the area of the
/// two tangents), `recipe.integration.subcells_per_voxel` sub-cells per voxel of extent. The
/// rule is exact for a CT linear in position, straight or curved element. Points outside the
/// CT count as outside and are left out of the means. `voxel_volume` (mm³) turns the
/// index-space volume into the element's.
pub fn integrate_element(
    ct: &CtField,
    kind: ElementKind,
    nodes: &[Point<3>],
    recipe: &ResolvedRecipe,
    voxel_volume: f64,
    scratch: &mut IntegrationScratch,
) -> ElementIntegral {
    let cells = within_budget(
        sub_cells(kind, nodes, recipe.recipe.integration.subcells_per_voxel),
        gauss_points(kind).pow(kind.dimension() as u32),
    );
    if scratch.kind != Some(kind) || scratch.cells != cells {
        cube_rule(kind.dimension(), cells, gauss_points(kind), &mut scratch.points);
        scratch.kind = Some(kind);
        scratch.cells = cells;
        scratch.n.resize(kind.nodes(), 0.0);
        scratch.dn.resize(kind.nodes(), [0.0; 3]);
    }
    let v3 = recipe.recipe.integration.method == IntegrationMethod::V3;
    let soft_hu = recipe.recipe.checks.soft_tissue_hu;
    let (mut total, mut inside, mut hu, mut e, mut soft) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut hu_max = f64::NEG_INFINITY;
    let dim = kind.dimension();
    let IntegrationScratch { points, n, dn, .. } = scratch;
    for p in points.iter() {
        let (xi, factor) = natural_point(kind, &p.u);
        shape_functions(kind, &xi, n, dn);
        let mut x = [0.0; 3];
        let mut j = [[0.0; 3]; 3]; // j[d] = ∂x/∂ξ_d
        for (k, node) in nodes.iter().enumerate() {
            for c in 0..3 {
                x[c] += n[k] * node[c];
                for d in 0..dim {
                    j[d][c] += dn[k][d] * node[c];
                }
            }
        }
        let det = if dim == 3 {
            dot(j[0], cross(j[1], j[2])).abs()
        } else {
            norm(cross(j[0], j[1]))
        };
        let w = p.weight * factor * det;
        total += w;
        if let Some(h) = ct.sample(&x) {
            inside += w;
            hu += w * h;
            if v3 {
                e += w * recipe.modulus(h);
            }
            if h < soft_hu {
                soft += w;
            }
            hu_max = hu_max.max(h);
        }
    }
    let hu = if inside > 0.0 { hu / inside } else { f64::NAN };
    let modulus = if !v3 || inside <= 0.0 {
        recipe.modulus(hu)
    } else {
        (e / inside).max(recipe.recipe.modulus.floor)
    };
    ElementIntegral {
        hu,
        modulus,
        outside: if total > 0.0 { (1.0 - inside / total).max(0.0) } else { 1.0 },
        soft: if inside > 0.0 { soft / inside } else { 0.0 },
        hu_max,
        volume: total * voxel_volume,
    }
}

//! The materials' figures: exact on ramps, the published ramp values, V3 against a dense
//! integration, the recipe and the checks.

use super::*;
use crate::geometry::Point;
use crate::image::{Image, VoxelType, WorldConvention};
use crate::mesh::{ElementKind, FeMesh};
use rand::{RngExt, SeedableRng};

/// An image of `dims` f64 voxels of `f(world)` with the affine rows `affine`.
fn image(dims: [usize; 3], affine: [[f64; 4]; 3], f: impl Fn(Point<3>) -> f64) -> Image {
    let mut im = Image {
        dims,
        voxel_type: VoxelType::F64,
        little_endian: true,
        data: Vec::new(),
        slope: 1.0,
        intercept: 0.0,
        affine,
        file_convention: WorldConvention::Ras,
    };
    let mut data = Vec::with_capacity(dims.iter().product::<usize>() * 8);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                data.extend(f(im.world([i as f64, j as f64, k as f64])).to_le_bytes());
            }
        }
    }
    im.data = data;
    im
}

fn recipe(text: &str) -> ResolvedRecipe {
    MaterialRecipe::parse(std::path::Path::new("recipe.toml"), text)
        .unwrap()
        .law()
        .unwrap()
}

/// One element's integral on `ct` (nodes in world mm).
fn integral(
    ct: &CtField,
    kind: ElementKind,
    nodes: &[Point<3>],
    r: &ResolvedRecipe,
) -> ElementIntegral {
    let idx: Vec<Point<3>> = nodes.iter().map(|p| ct.index_of(p)).collect();
    let rule = ElementRule::new(ct, r, ct.voxel_volume());
    integrate_element(ct, kind, &idx, &rule, &mut IntegrationScratch::default())
}

/// A distorted hexahedron (planar-faced frustum, tilted) from `o`, about `size` mm.
fn hex8(o: Point<3>, size: f64) -> Vec<Point<3>> {
    let (a, b) = (size, 0.6 * size);
    let c = (a - b) / 2.0;
    let mut v = vec![
        [0.0, 0.0, 0.0],
        [a, 0.0, 0.0],
        [a, a, 0.0],
        [0.0, a, 0.0],
        [c, c, 0.9 * size],
        [c + b, c, 0.9 * size],
        [c + b, c + b, 0.9 * size],
        [c, c + b, 0.9 * size],
    ];
    for p in &mut v {
        let q = *p;
        *p = [
            o[0] + q[0] + 0.2 * q[2],
            o[1] + q[1] - 0.1 * q[0],
            o[2] + q[2] + 0.15 * q[1],
        ];
    }
    v
}

/// The quadratic element of the linear `corners` of `kind` with every mid-edge node moved
/// by `bend` (a curved element).
fn curved(kind: ElementKind, corners: &[Point<3>], bend: Point<3>) -> Vec<Point<3>> {
    let mesh = FeMesh {
        nodes: corners.to_vec(),
        kind: kind.linear(),
        connectivity: (0..corners.len()).collect(),
        sets: Default::default(),
    }
    .to_quadratic()
    .unwrap();
    let mut nodes: Vec<Point<3>> = mesh.element(0).iter().map(|&n| mesh.nodes[n]).collect();
    for (k, p) in nodes.iter_mut().enumerate().skip(corners.len()) {
        let s = if k % 2 == 0 { 1.0 } else { -0.5 };
        *p = std::array::from_fn(|d| p[d] + s * bend[d]);
    }
    nodes
}

/// The volume centroid of an element by a fine midpoint rule of the test's own (not the
/// composite Gauss rule under test).
fn centroid_midpoint(kind: ElementKind, nodes: &[Point<3>]) -> Point<3> {
    let n = 60;
    let mut sn = vec![0.0; kind.nodes()];
    let mut dn = vec![[0.0; 3]; kind.nodes()];
    let (mut v, mut c) = (0.0, [0.0; 3]);
    let dim = kind.dimension();
    for a in 0..n {
        for b in 0..n {
            for z in 0..(if dim == 3 { n } else { 1 }) {
                let u = [
                    (a as f64 + 0.5) / n as f64,
                    (b as f64 + 0.5) / n as f64,
                    (z as f64 + 0.5) / n as f64,
                ];
                let (xi, f) = natural_coordinates::natural_point(kind, &u);
                natural_coordinates::shape_functions(kind, &xi, &mut sn, &mut dn);
                let mut x = [0.0; 3];
                let mut j = [[0.0; 3]; 3];
                for (k, p) in nodes.iter().enumerate() {
                    for cc in 0..3 {
                        x[cc] += sn[k] * p[cc];
                        for d in 0..dim {
                            j[d][cc] += dn[k][d] * p[cc];
                        }
                    }
                }
                let det = if dim == 3 {
                    crate::geometry::dot(j[0], crate::geometry::cross(j[1], j[2])).abs()
                } else {
                    crate::geometry::norm(crate::geometry::cross(j[0], j[1]))
                };
                v += f * det;
                for cc in 0..3 {
                    c[cc] += f * det * x[cc];
                }
            }
        }
    }
    c.map(|x| x / v)
}

#[test]
fn linear_ct_integrals_equal_the_value_at_the_centroid() {
    // A CT linear in position on an oblique, anisotropic grid (mm, RAS).
    let affine = [
        [0.7, 0.1, 0.0, -20.0],
        [-0.05, 0.6, 0.0, -18.0],
        [0.0, 0.0, 1.3, -25.0],
    ];
    let f = |p: Point<3>| 120.0 + 9.0 * p[0] - 4.0 * p[1] + 6.5 * p[2];
    let ct = CtField::new(&image([70, 70, 40], affine, f)).unwrap();
    let default = recipe("");
    let fine = recipe("[integration]\nsubcells_per_voxel = 6.0\n");
    let h8 = hex8([-3.0, -2.0, -4.0], 6.0);
    let t4: Vec<Point<3>> = [0, 1, 3, 4].iter().map(|&k| h8[k]).collect();
    let h20 = curved(ElementKind::Hex20, &h8, [0.4, -0.3, 0.5]);
    let t10 = curved(ElementKind::Tet10, &t4, [-0.5, 0.3, 0.4]);
    for (kind, nodes) in [
        (ElementKind::Hex8, h8.clone()),
        (ElementKind::Tet4, t4.clone()),
        (ElementKind::Hex20, h20),
        (ElementKind::Tet10, t10),
    ] {
        let i = integral(&ct, kind, &nodes, &default);
        let j = integral(&ct, kind, &nodes, &fine);
        // Exact: a finer composite rule changes nothing but round-off.
        assert!(
            (i.hu - j.hu).abs() <= 1e-9 * i.hu.abs(),
            "{kind:?}: {} vs {}",
            i.hu,
            j.hu
        );
        assert!((i.volume - j.volume).abs() <= 1e-9 * i.volume, "{kind:?}");
        // And it is the value at the volume centroid (found by the test's own rule).
        let c = centroid_midpoint(kind, &nodes);
        assert!(
            (i.hu - f(c)).abs() <= 1e-4 * f(c).abs(),
            "{kind:?}: {} vs {}",
            i.hu,
            f(c)
        );
        assert_eq!(i.outside, 0.0);
    }
    // The frustum's centroid is known in closed form: the same HU to 1e-9.
    let (a, b, h) = (6.0, 3.6, 5.4);
    let zbar = h * (a * a + 2.0 * a * b + 3.0 * b * b) / (4.0 * (a * a + a * b + b * b));
    let frustum: Vec<Point<3>> = [
        [0.0, 0.0, 0.0],
        [a, 0.0, 0.0],
        [a, a, 0.0],
        [0.0, a, 0.0],
        [1.2, 1.2, h],
        [1.2 + b, 1.2, h],
        [1.2 + b, 1.2 + b, h],
        [1.2, 1.2 + b, h],
    ]
    .map(|p| [p[0] - 3.0, p[1] - 3.0, p[2] - 2.0])
    .to_vec();
    let i = integral(&ct, ElementKind::Hex8, &frustum, &default);
    let c = [0.0, 0.0, zbar - 2.0];
    assert!(
        (i.hu - f(c)).abs() <= 1e-9 * f(c).abs(),
        "{} vs {}",
        i.hu,
        f(c)
    );
    let v = h / 3.0 * (a * a + a * b + b * b);
    assert!((i.volume - v).abs() <= 1e-9 * v);
    // Straight-sided quadratic elements are their linear ones.
    for (lin, nodes) in [(ElementKind::Hex8, &h8), (ElementKind::Tet4, &t4)] {
        let q = curved(lin.linear(), nodes, [0.0; 3]);
        let kind = if lin == ElementKind::Hex8 {
            ElementKind::Hex20
        } else {
            ElementKind::Tet10
        };
        let (x, y) = (
            integral(&ct, lin, nodes, &default),
            integral(&ct, kind, &q, &default),
        );
        assert!((x.hu - y.hu).abs() <= 1e-9 * x.hu.abs());
    }
    // A tetrahedron's centroid is the mean of its corners.
    let i = integral(&ct, ElementKind::Tet4, &t4, &default);
    let c: Point<3> = std::array::from_fn(|d| t4.iter().map(|p| p[d]).sum::<f64>() / 4.0);
    assert!((i.hu - f(c)).abs() <= 1e-9 * f(c).abs());
}

#[test]
fn quads_over_pixels_of_a_2d_image() {
    let affine = [
        [0.5, 0.0, 0.0, -10.0],
        [0.0, 0.4, 0.0, -8.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    let f = |p: Point<3>| 50.0 + 3.0 * p[0] + 7.0 * p[1];
    let ct = CtField::new(&image([60, 60, 1], affine, f)).unwrap();
    // A convex quadrilateral; its centroid by the polygon formula.
    let q: [Point<2>; 4] = [[-4.0, -3.0], [3.0, -4.0], [5.0, 4.0], [-2.0, 2.5]];
    let mesh = FeMesh {
        nodes: q.to_vec(),
        kind: ElementKind::Quad4,
        connectivity: vec![0, 1, 2, 3],
        sets: Default::default(),
    };
    let m = map_materials(&mesh, &ct, &recipe("")).unwrap();
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for k in 0..4 {
        let (p, r) = (q[k], q[(k + 1) % 4]);
        let x = p[0] * r[1] - r[0] * p[1];
        a += x / 2.0;
        cx += (p[0] + r[0]) * x;
        cy += (p[1] + r[1]) * x;
    }
    let c = [cx / (6.0 * a), cy / (6.0 * a), 0.0];
    assert!(
        (m.hu[0] - f(c)).abs() <= 1e-9 * f(c).abs(),
        "{} vs {}",
        m.hu[0],
        f(c)
    );
    assert!((m.volume[0] - a).abs() <= 1e-9 * a);
    // A 2D mesh on a 3D CT is refused.
    let ct3 = CtField::new(&image([4, 4, 4], affine, f)).unwrap();
    assert!(map_materials(&mesh, &ct3, &recipe("")).is_err());
}

#[test]
fn the_published_ramp_values() {
    // HU = 5 (i + j + k) at voxels (i, j, k) ∈ {0, 1, 2}³ centred on {-1, 0, 1}³.
    let affine = [
        [1.0, 0.0, 0.0, -1.0],
        [0.0, 1.0, 0.0, -1.0],
        [0.0, 0.0, 1.0, -1.0],
    ];
    let ct = CtField::new(&image([3, 3, 3], affine, |p| {
        5.0 * (p[0] + p[1] + p[2] + 3.0)
    }))
    .unwrap();
    let r = recipe("");
    let unit_hex: Vec<Point<3>> = HexUnit::corners();
    let unit_tet: Vec<Point<3>> = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let hex = integral(&ct, ElementKind::Hex8, &unit_hex, &r);
    assert!((hex.hu - 22.5).abs() < 1e-12, "{}", hex.hu);
    let tet = integral(&ct, ElementKind::Tet4, &unit_tet, &r);
    assert!((tet.hu - 18.75).abs() < 1e-12, "{}", tet.hu);
    let tet10 = integral(
        &ct,
        ElementKind::Tet10,
        &curved(ElementKind::Tet4, &unit_tet, [0.0; 3]),
        &r,
    );
    assert!((tet10.hu - 18.75).abs() < 1e-12, "{}", tet10.hu);
    assert!((hex.volume - 1.0).abs() < 1e-12 && (tet.volume - 1.0 / 6.0).abs() < 1e-12);
}

/// The unit cube's corners in the Hex8 order.
struct HexUnit;
impl HexUnit {
    fn corners() -> Vec<Point<3>> {
        natural_coordinates::corner_signs(ElementKind::Hex8)
            .iter()
            .map(|s| s.map(|v| 0.5 * (v + 1.0)))
            .collect()
    }
}

/// The largest relative difference of V3's E (default rule) to a dense integration
/// (`dense` sub-cells per voxel) over hexahedra and tetrahedra 0.5-5 voxels across on `ct`.
fn v3_error(ct: &CtField, recipe_text: &str, dense: f64) -> f64 {
    let r = recipe(recipe_text);
    let dense = recipe(&format!(
        "{recipe_text}\n[integration]\nsubcells_per_voxel = {dense}\n"
    ));
    let mut worst: f64 = 0.0;
    for (k, size) in [0.5, 0.8, 1.0, 1.7, 2.5, 3.3, 5.0].into_iter().enumerate() {
        for seed in 0..4 {
            let o = [
                5.3 + 6.0 * seed as f64 + 0.1 * k as f64,
                6.1 + 3.0 * k as f64,
                4.7 + seed as f64,
            ];
            let h8 = hex8(o, size);
            let t4: Vec<Point<3>> = [0, 1, 3, 4].iter().map(|&c| h8[c]).collect();
            for (kind, nodes) in [(ElementKind::Hex8, h8.clone()), (ElementKind::Tet4, t4)] {
                let a = integral(ct, kind, &nodes, &r).modulus;
                let b = integral(ct, kind, &nodes, &dense).modulus;
                worst = worst.max((a - b).abs() / b);
            }
        }
    }
    worst
}

/// A 40³ CT of 1 mm: `f` at each voxel plus uniform noise of ± `noise` HU.
fn noisy_ct(f: impl Fn(Point<3>) -> f64, noise: f64) -> CtField {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let n: Vec<f64> = (0..40 * 40 * 40)
        .map(|_| rng.random_range(-noise..noise))
        .collect();
    let affine = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    CtField::new(&image([40, 40, 40], affine, |p| {
        f(p) + n[p[0] as usize + 40 * (p[1] as usize + 40 * p[2] as usize)]
    }))
    .unwrap()
}

#[test]
fn v3_on_a_nonlinear_law_matches_a_dense_integration() {
    // Bone-like: trabecular HU varying over millimetres with scanner noise of ±60 HU, under
    // the femoral-neck power law (E ∝ ρ^1.49).
    let bone = noisy_ct(
        |p| 500.0 + 300.0 * (p[0] / 3.0).sin() * (p[1] / 4.0).cos() + 8.0 * p[2],
        60.0,
    );
    let e = v3_error(&bone, "", 12.0);
    assert!(
        e < 0.005,
        "bone-like CT: V3 within {:.3} % of the dense integration",
        100.0 * e
    );
    // The hardest case, pure noise from -200 to 1800 HU (a kink at every voxel face).
    let noise = noisy_ct(|_| 800.0, 1000.0);
    let e = v3_error(&noise, "", 12.0);
    assert!(
        e < 0.02,
        "noise CT: V3 within {:.3} % of the dense integration",
        100.0 * e
    );
}

#[test]
fn recipes_presets_and_calibration() {
    let r = recipe("");
    assert_eq!(r.law.name, "morgan-2003-femoral-neck");
    // Schileo 2008's chain and Morgan's femoral neck law at 1000 HU.
    let qct: f64 = 0.0008 * 1000.0;
    let app = (0.877 * qct + 0.079) / 0.6;
    assert!((r.modulus(1000.0) - 6850.0 * app.powf(1.49)).abs() < 1e-9);
    assert_eq!(r.modulus(-1000.0), 1.0);
    // Keyak's three pieces are continuous to a few MPa at their joints.
    let k = recipe("[modulus]\nlaw = \"keyak-2003\"\n");
    for rho in [0.27, 0.6] {
        let (a, b) = (k.law.modulus(rho - 1e-9), k.law.modulus(rho + 1e-9));
        assert!((a - b).abs() < 0.02 * a, "{rho}: {a} vs {b}");
    }
    // Rods fit the calibration line.
    let c = recipe(
        "[calibration]\nrods = [{ hu = 0.0, density = 0.1 }, { hu = 500.0, density = 0.5 }, { hu = 1000.0, density = 0.9 }]\n",
    );
    assert!(
        (c.calibration.slope - 0.0008).abs() < 1e-12
            && (c.calibration.intercept - 0.1).abs() < 1e-12
    );
    // Every field is optional, one table at a time.
    for text in [
        "[calibration]\nintercept = 0.1\n",
        "[density]\nash_slope = 0.9\n",
        "[modulus]\nfloor = 5.0\n",
        "[integration]\nmethod = \"v2\"\n",
        "[integration]\nsubcells_per_voxel = 2.0\n",
        "[materials]\ngap = 1.0\n",
        "[checks]\nmetal_hu = 2500.0\n",
    ] {
        MaterialRecipe::parse(std::path::Path::new("r.toml"), text).unwrap();
    }
    // A custom piecewise law, and the errors that name the field.
    let p = recipe(
        "[modulus]\nlaw = \"custom\"\ndensity = \"ash\"\npieces = [{ coefficient = 1000.0, exponent = 2.0 }, { from = 0.5, coefficient = 500.0, exponent = 1.0, offset = 0.0 }]\n",
    );
    assert_eq!(p.law.modulus(0.25), 62.5);
    assert_eq!(p.law.modulus(0.8), 400.0);
    let path = std::path::Path::new("r.toml");
    for (text, needle) in [
        ("[modulus]\nlaw = \"morgan\"\n", "unknown law"),
        ("[modulus]\nlaw = \"custom\"\n", "density"),
        ("[modulus]\npoisson = 0.7\n", "Poisson"),
        ("[calibration]\nslope = -1.0\n", "slope"),
        (
            "[calibration]\nrods = [{ hu = 1.0, density = 0.1 }]\n",
            "one phantom rod",
        ),
        ("[calibration]\nslop = 1.0\n", "unknown field"),
        ("[integration]\nmethod = \"v4\"\n", "unknown variant"),
        (
            "[modulus]\nlaw = \"custom\"\ndensity = \"app\"\npieces = [{ coefficient = 1.0, exponent = 1.0, from = 0.5 }, { coefficient = 1.0, exponent = 1.0, from = 0.2 }]\n",
            "not above",
        ),
    ] {
        let e = MaterialRecipe::parse(path, text).unwrap_err().to_string();
        assert!(e.contains(needle) && e.contains("r.toml"), "{text}: {e}");
    }
}

#[test]
fn a_block_of_bone_with_metal_and_air_is_flagged() {
    // A 10 mm cube of 800 HU, one voxel of 4000 HU (metal) and a pocket of air.
    let affine = [
        [0.5, 0.0, 0.0, -2.0],
        [0.0, 0.5, 0.0, -2.0],
        [0.0, 0.0, 0.5, -2.0],
    ];
    let ct = CtField::new(&image([40, 40, 40], affine, |p| {
        if (p[0] - 5.0).abs() < 0.6 && (p[1] - 5.0).abs() < 0.6 && (p[2] - 5.0).abs() < 0.6 {
            4000.0
        } else if p[0] < 2.0 && p[1] < 2.0 && p[2] < 2.0 {
            -1000.0
        } else {
            800.0
        }
    }))
    .unwrap();
    let mut mesh = FeMesh::block(5);
    for p in &mut mesh.nodes {
        *p = p.map(|v| 2.0 * v);
    }
    let r = recipe("[calibration]\nslope = 0.0009\n");
    let m = map_materials(&mesh, &ct, &r).unwrap();
    let s = &m.summary;
    assert_eq!(m.hu.len(), 125);
    assert!(
        s.metal_elements >= 1 && s.warnings.iter().any(|w| w.starts_with("metal")),
        "{:?}",
        s.warnings
    );
    assert!(s.air_elements >= 1, "{s:?}");
    assert!(!s.warnings.iter().any(|w| w.contains("no phantom")));
    // Every element is in one material; the bins' E are within the gap of their elements'.
    assert_eq!(m.bins.iter().map(|b| b.elements.len()).sum::<usize>(), 125);
    assert!(s.binning_error_max <= s.gap + 1e-9);
    // Moved out of the CT: an error that says how much.
    for p in &mut mesh.nodes {
        p[0] += 15.0;
    }
    let e = map_materials(&mesh, &ct, &r).unwrap_err().to_string();
    assert!(
        e.contains("outside the CT") && e.contains("% of the mesh's volume"),
        "{e}"
    );
}

#[test]
fn the_tabulated_law_is_the_law() {
    for text in [
        "",
        "[modulus]\nlaw = \"keyak-2003\"\n",
        "[modulus]\nlaw = \"morgan-2003-vertebra\"\n",
    ] {
        let r = recipe(text);
        let t = ModulusTable::new(&r, [-1024.0, 3071.0]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..20_000 {
            let h: f64 = rng.random_range(-1024.0..3071.0);
            let (a, b) = (t.at(h), r.modulus(h));
            // (Away from a jump of a piecewise law, which the table smears over one step.)
            let jump = (r.modulus(h - 0.15) - r.modulus(h + 0.15)).abs() > 1e-3 * b;
            if b > 10.0 * r.recipe.modulus.floor && !jump {
                assert!((a - b).abs() <= 1e-5 * b, "{text}: {h} HU: {a} vs {b}");
            }
        }
    }
}

#[test]
fn v2_takes_e_of_the_mean_and_v3_the_mean_of_e() {
    // On a CT varying across an element, a convex law gives V3 ≥ V2 (Jensen), and V2 is the
    // law at the element's mean HU exactly.
    let affine = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    let ct = CtField::new(&image([20, 20, 20], affine, |p| 200.0 + 80.0 * p[0])).unwrap();
    let h = hex8([4.0, 4.0, 4.0], 6.0);
    let (v2, v3) = (recipe("[integration]\nmethod = \"v2\"\n"), recipe(""));
    let a = integral(&ct, ElementKind::Hex8, &h, &v2);
    let b = integral(&ct, ElementKind::Hex8, &h, &v3);
    assert_eq!(a.hu, b.hu);
    assert_eq!(a.modulus, v2.modulus(a.hu));
    assert!(
        b.modulus > a.modulus * 1.001,
        "V3 {} vs V2 {}",
        b.modulus,
        a.modulus
    );
}

#[test]
fn a_law_or_calibration_without_a_finite_modulus_over_the_ct_is_refused() {
    // The default recipe over a clinical CT's range: finite everywhere.
    recipe("").check_over([-1024.0, 3071.0]).unwrap();
    // A coefficient of 1e308 (E = inf), a calibration slope of 1e300, a CT of 1e300 HU.
    let huge_law = recipe(
        "[modulus]\nlaw = \"custom\"\ndensity = \"app\"\npieces = [{ coefficient = 1e308, exponent = 2.0 }]\n",
    );
    let huge_slope = recipe("[calibration]\nslope = 1e300\n");
    for (r, range, what) in [
        (&huge_law, [-1024.0, 3071.0], "E = inf"),
        (&huge_slope, [-1024.0, 3071.0], "E = inf"),
        (&recipe(""), [0.0, 1e300], "E = inf"),
        (&recipe(""), [0.0, f64::INFINITY], "not finite"),
    ] {
        let e = r.check_over(range).unwrap_err().to_string();
        assert!(e.contains(what), "{range:?}: {e}");
    }
    // And through the map: no element mapped, the error says why.
    let affine = [
        [1.0, 0.0, 0.0, -0.5],
        [0.0, 1.0, 0.0, -0.5],
        [0.0, 0.0, 1.0, -0.5],
    ];
    let ct = CtField::new(&image([4, 4, 4], affine, |p| 1e300 * (1.0 + p[0]))).unwrap();
    let e = map_materials(&FeMesh::block(2), &ct, &recipe(""))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a finite modulus"), "{e}");
}

#[test]
fn a_huge_recipe_is_refused_before_it_is_parsed() {
    let text = format!(
        "[calibration]\nrods = [{}]\n",
        "{ hu = 0.0, density = 0.1 }, ".repeat(40_000)
    );
    let e = MaterialRecipe::parse(std::path::Path::new("huge.toml"), &text)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("huge.toml") && e.contains("at most 1024 kB"),
        "{e}"
    );
}

#[test]
fn an_image_of_density_takes_its_unit_and_no_hu_checks() {
    let kopperdahl = "[modulus]\nlaw = \"kopperdahl-2002-vertebra\"\nfloor = 0.0001\n";
    // 200 mg/cc is 0.2 g/cc of K2HPO4: E = 2980 · 0.2^1.05 MPa.
    let mg = recipe(&format!(
        "[calibration]\nimage = \"density\"\nunit = \"mg/cc\"\n{kopperdahl}"
    ));
    assert!((mg.modulus(200.0) - 2980.0 * 0.2f64.powf(1.05)).abs() < 1e-9);
    assert!(mg.law.source.contains("Kopperdahl"));
    // mg/cc is the default unit; g/cc takes the same density in grams.
    let default = recipe(&format!("[calibration]\nimage = \"density\"\n{kopperdahl}"));
    assert_eq!(default.modulus(200.0), mg.modulus(200.0));
    let g = recipe(&format!(
        "[calibration]\nimage = \"density\"\nunit = \"g/cc\"\n{kopperdahl}"
    ));
    assert!((g.modulus(0.2) - mg.modulus(200.0)).abs() < 1e-9);
    // A negative density gets the floor, as the benchmark's recipe says.
    assert_eq!(mg.modulus(-31.0), 0.0001);
    let path = std::path::Path::new("r.toml");
    for (text, needle) in [
        (
            "[calibration]\nimage = \"density\"\nslope = 0.001\n",
            "takes no slope",
        ),
        (
            "[calibration]\nimage = \"density\"\nrods = [{ hu = 0.0, density = 0.0 }, { hu = 1.0, density = 1.0 }]\n",
            "takes no slope",
        ),
        (
            "[calibration]\nunit = \"mg/cc\"\n",
            "a unit is for an image of density",
        ),
        (
            "[calibration]\nimage = \"density\"\nunit = \"kg/m3\"\n",
            "unknown variant",
        ),
    ] {
        let e = MaterialRecipe::parse(path, text).unwrap_err().to_string();
        assert!(e.contains(needle) && e.contains("r.toml"), "{text}: {e}");
    }
    // A block of 50-400 mg/cc (no value below 0, and above the HU checks' soft-tissue
    // threshold nowhere near metal): mapped as density, none of the HU checks speaks and no
    // calibration is missing; the same values read as HU are flagged as never rescaled.
    let affine = [
        [1.0, 0.0, 0.0, -1.0],
        [0.0, 1.0, 0.0, -1.0],
        [0.0, 0.0, 1.0, -1.0],
    ];
    let ct = CtField::new(&image([12, 12, 12], affine, |p| 50.0 + 35.0 * p[0])).unwrap();
    let mut mesh = FeMesh::block(4);
    for p in &mut mesh.nodes {
        *p = p.map(|v| 2.0 * v);
    }
    let m = map_materials(&mesh, &ct, &mg).unwrap();
    assert!(m.summary.warnings.is_empty(), "{:?}", m.summary.warnings);
    // Each element's E is its material's (within the grouping's gap of 10 MPa) of the law at
    // its density (V3 averages E over the element: within 0.5 % for this near-linear law).
    for (e, rho) in m.modulus.iter().zip(&m.density) {
        let law = 2980.0 * rho.powf(1.05);
        assert!(
            (e - law).abs() <= 10.0 + 0.005 * law,
            "E {e} at {rho} g/cc, law {law}"
        );
    }
    let as_hu = map_materials(&mesh, &ct, &recipe("[calibration]\nslope = 0.001\n")).unwrap();
    assert!(
        as_hu
            .summary
            .warnings
            .iter()
            .any(|w| w.contains("not rescaled")),
        "{:?}",
        as_hu.summary.warnings
    );
}

/// A voxel mesh of a density image (one hexahedron per voxel, `centroid`): each element takes
/// its voxel's value, the QCT floor raises the negative ones, equal-width bins take the law
/// at their centres, and a part keeps its constant material out of the bins and the summary.
#[test]
fn voxel_models_take_their_voxels_equal_width_bins_and_parts() {
    let affine = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    // 4 × 1 × 2 voxels of mg/cc: z = 0 bone -100, 100, 300, 900; z = 1 a pad (0).
    let values = [-100.0, 100.0, 300.0, 900.0, 0.0, 0.0, 0.0, 0.0];
    let im = image([4, 1, 2], affine, |p| {
        values[p[0].round() as usize + 4 * p[2].round() as usize]
    });
    let ct = CtField::new(&im).unwrap();
    let labels = Image {
        data: vec![1, 1, 1, 1, 2, 2, 2, 2],
        voxel_type: VoxelType::U8,
        ..im.clone()
    };
    let parts = [
        crate::mesh::VoxelPart {
            name: "BONE".into(),
            labels: vec![1],
        },
        crate::mesh::VoxelPart {
            name: "PADS".into(),
            labels: vec![2],
        },
    ];
    let mesh = crate::mesh::voxel_mesh(&labels, &parts, "labels").unwrap();
    let r = recipe(
        "[calibration]\nimage = \"density\"\n[density]\nqct_floor = -0.031\n[modulus]\nlaw = \
         \"kopperdahl-2002-vertebra\"\nfloor = 0.0001\n[integration]\nmethod = \"centroid\"\n\
         [materials]\ngrouping = \"equal-width\"\nbins = 4\n[[part]]\nname = \"PADS\"\nmodulus \
         = 2500.0\n",
    );
    let m = map_materials(&mesh, &ct, &r).unwrap();
    for (e, v) in [-100.0, 100.0, 300.0, 900.0].iter().enumerate() {
        assert!((m.hu[e] - v).abs() < 1e-9, "{} {v}", m.hu[e]);
    }
    // Densities -0.031 (floored), 0.1, 0.3, 0.9 g/cm³ in 4 bins of (0.931 / 4).
    assert!((m.density[0] + 0.031).abs() < 1e-12);
    let w = 0.931 / 4.0;
    assert!((m.summary.bin_width.unwrap() - w).abs() < 1e-12);
    let law = |rho: f64| (2980.0 * rho.max(0.0).powf(1.05)).max(0.0001);
    let bins: Vec<(Vec<usize>, f64)> = m
        .bins
        .iter()
        .map(|b| (b.elements.clone(), b.modulus))
        .collect();
    assert_eq!(bins.len(), 4);
    assert_eq!(bins[0].0, vec![0, 1]);
    assert!((bins[0].1 - law(-0.031 + 0.5 * w)).abs() < 1e-9);
    assert_eq!(bins[1].0, vec![2]);
    assert!((bins[1].1 - law(-0.031 + 1.5 * w)).abs() < 1e-9);
    assert_eq!(bins[2].0, vec![3]);
    assert!((bins[2].1 - law(-0.031 + 3.5 * w)).abs() < 1e-9);
    assert_eq!(
        (m.bins[3].name.as_str(), m.bins[3].modulus),
        ("PADS", 2500.0)
    );
    assert_eq!(m.bins[3].elements, vec![4, 5, 6, 7]);
    assert_eq!(m.modulus[5], 2500.0);
    assert_eq!(m.summary.elements, 4);
    assert_eq!(m.summary.parts[0].elements, 4);
    assert!((m.summary.volume - 4.0).abs() < 1e-9);
    // A part that is no element set, and parts that hold everything.
    let bad = recipe("[[part]]\nname = \"CEMENT\"\nmodulus = 2500.0\n");
    let e = map_materials(&mesh, &ct, &bad).unwrap_err().to_string();
    assert!(e.contains("CEMENT") && e.contains("BONE, PADS"), "{e}");
    let all = recipe(
        "[[part]]\nname = \"PADS\"\nmodulus = 2500.0\n[[part]]\nname = \"BONE\"\nmodulus = 1.0\n",
    );
    assert!(map_materials(&mesh, &ct, &all).is_err());
    for text in [
        "[[part]]\nname = \"A B\"\nmodulus = 1.0\n",
        "[[part]]\nname = \"A\"\nmodulus = -1.0\n",
        "[materials]\nbins = 0\n",
        "[materials]\ngrouping = \"quantile\"\n",
    ] {
        let p = MaterialRecipe::parse(std::path::Path::new("r.toml"), text);
        assert!(p.is_err(), "{text}");
    }
}

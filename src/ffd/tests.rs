use super::*;
use crate::geometry::Point;

#[test]
fn bspline_bases_sum_to_one_and_derivatives_to_zero() {
    for k in 0..=20 {
        let t = k as f64 / 20.0;
        assert!((cubic_bases(t, 0).iter().sum::<f64>() - 1.0).abs() < 1e-14);
        assert!(cubic_bases(t, 1).iter().sum::<f64>().abs() < 1e-14);
        assert!(cubic_bases(t, 2).iter().sum::<f64>().abs() < 1e-14);
        assert!(cubic_bases(t, 0).iter().all(|&b| b >= 0.0));
    }
}

#[test]
fn tensor_bases_sum_to_one_3d() {
    let l = Lattice::<3>::around(&[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]], 6, 0.1);
    for p in [[0.1, 0.5, 2.9], [0.9, 1.9, 0.1], [0.5, 1.0, 1.5]] {
        let mut s = 0.0;
        l.for_each_basis(&p, |_, w| s += w);
        assert!((s - 1.0).abs() < 1e-13);
    }
}

#[test]
fn undeformed_ffd_is_the_identity() {
    let l = Lattice::<2>::around(&[[-1.0, 0.0], [3.0, 2.0]], 8, 0.1);
    let f = Ffd::identity(l);
    for p in [[-1.0, 0.0], [0.3, 1.7], [3.0, 2.0], [1.234, 0.001]] {
        let q = f.apply(&p);
        assert!(
            (q[0] - p[0]).abs() < 1e-12 && (q[1] - p[1]).abs() < 1e-12,
            "{p:?} -> {q:?}"
        );
        let j = f.jacobian(&p);
        assert!(
            (j[0][0] - 1.0).abs() < 1e-12 && j[0][1].abs() < 1e-12 && (j[1][1] - 1.0).abs() < 1e-12
        );
    }
}

#[test]
fn smoothing_energy_vanishes_on_affine_maps() {
    let l = Lattice::<2>::around(&[[0.0, 0.0], [1.0, 1.0]], 7, 0.0);
    let affine: Vec<Point<2>> = l
        .rest()
        .iter()
        .map(|p| [2.0 * p[0] + 0.5 * p[1] + 1.0, -p[0] + 3.0 * p[1]])
        .collect();
    assert!(smoothing_energy(&l, &affine, 1.0).abs() < 1e-9);
}

#[test]
fn smoothing_energy_is_exact_for_a_quadratic() {
    // Control points reproducing f(x, y) = (x², 0): E = ∫∫ (f_xx)² = 4 · area.
    // Uniform cubic B-splines reproduce x² with control values x_j² - h²/3.
    let l = Lattice::<2>::around(&[[0.0, 0.0], [1.0, 1.0]], 9, 0.0);
    let h = l.spacing[0];
    let ctrl: Vec<Point<2>> = l
        .rest()
        .iter()
        .map(|p| [p[0] * p[0] - h * h / 3.0, 0.0])
        .collect();
    let f = Ffd {
        lattice: l,
        control: ctrl.clone(),
    };
    let q = f.apply(&[0.3, 0.6]);
    assert!((q[0] - 0.09).abs() < 1e-12, "reproduces x²: {q:?}");
    let e = smoothing_energy(&l, &ctrl, 1.0);
    assert!((e - 4.0).abs() < 1e-9, "E = {e}");
}

#[test]
fn fit_recovers_a_smooth_deformation() {
    let src: Vec<Point<2>> = (0..400)
        .map(|i| [(i % 20) as f64 / 19.0, (i / 20) as f64 / 19.0])
        .collect();
    let g = |p: &Point<2>| [p[0] + 0.05 * (2.0 * p[1]).sin(), p[1] + 0.03 * p[0] * p[0]];
    let dst: Vec<Point<2>> = src.iter().map(g).collect();
    let fit = FfdFit::new(
        &src,
        &FfdParams {
            grid: 10,
            alpha: 1e-4,
            margin: 0.1,
        },
    )
    .unwrap();
    let f = fit.solve(&dst);
    let err: f64 = src
        .iter()
        .zip(&dst)
        .map(|(p, q)| crate::geometry::dist2(f.apply(p), *q))
        .sum::<f64>()
        / 400.0;
    assert!(err.sqrt() < 1e-3, "rms {}", err.sqrt());
}

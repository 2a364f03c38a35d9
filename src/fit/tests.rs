use super::*;
use crate::geometry::{ClosestPointIndex, Point, Shape, Similarity};
use crate::model::Atlas;
use crate::model::{AtlasParams, ModeSelection};

fn atlas() -> Atlas<2> {
    atlas_of(120)
}

/// Mode weights of `sigmas` standard deviations along the first modes.
fn weights_at(a: &Atlas<2>, sigmas: [f64; 3]) -> Vec<f64> {
    a.eigenvalues
        .iter()
        .zip(sigmas)
        .map(|(l, f)| f * l.sqrt())
        .collect()
}

/// The egg population with `points` points per outline.
fn atlas_of(points: usize) -> Atlas<2> {
    let shapes: Vec<Shape<2>> = (0..12)
        .map(|k| {
            let a = 1.0 + 0.1 * (k as f64 * 1.7).sin();
            let b = 0.6 + 0.06 * (k as f64 * 2.3).cos();
            let c = 0.05 * (k as f64 * 0.9).cos();
            let d = 0.06 * (k as f64 * 1.3).sin();
            let pts = (0..points)
                .map(|i| {
                    let t = i as f64 / points as f64 * std::f64::consts::TAU;
                    // An egg (no symmetry, so the pose is identifiable) with three modes.
                    let egg = 1.0 + 0.25 * t.cos();
                    [
                        egg * (a * t.cos() + c * (3.0 * t).cos()),
                        egg * (b * t.sin() + d * (2.0 * t).sin()),
                    ]
                })
                .collect();
            Shape::polyline(format!("s{k}"), pts, true)
        })
        .collect();
    Atlas::build(
        &shapes,
        &AtlasParams {
            modes: ModeSelection::Count(3),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap()
}

fn subject(atlas: &Atlas<2>, w: &[f64], sim: &Similarity<2>) -> Shape<2> {
    let pts: Vec<Point<2>> = atlas.instance(w).iter().map(|p| sim.apply(p)).collect();
    // Resample coarser and shifted so that no point coincides with a model point.
    let n = pts.len();
    let sub_pts = (0..n / 2)
        .map(|i| {
            let a = pts[(2 * i) % n];
            let b = pts[(2 * i + 1) % n];
            [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
        })
        .collect();
    Shape::polyline("subject", sub_pts, true)
}

#[test]
fn the_tolerance_means_the_same_at_every_resolution() {
    // The same shapes sampled 8 times finer: `||Δw||` for the same move grows with the
    // root of the points, the updates must not.
    let mut sim = Similarity::<2>::planar_rotation(0.5);
    sim.s = 20.0;
    let mut fits = Vec::new();
    for points in [120, 960] {
        let a = atlas_of(points);
        let w = weights_at(&a, [1.2, -0.8, 0.5]);
        let s = subject(&a, &w, &sim);
        let idx = ClosestPointIndex::from_shape(&s);
        let r = Fitter::new(std::sync::Arc::new(a.clone()))
            .fit(&s, &idx, &FitParams::default())
            .unwrap();
        assert!(r.converged);
        let sigmas: Vec<f64> = r
            .weights
            .iter()
            .zip(&a.eigenvalues)
            .map(|(w, l)| w / l.sqrt())
            .collect();
        fits.push((r.iterations, sigmas));
    }
    let ((coarse, w0), (fine, w1)) = (&fits[0], &fits[1]);
    assert!(
        fine.abs_diff(*coarse) <= 1,
        "{coarse} updates at 120 points, {fine} at 960"
    );
    for (a, b) in w0.iter().zip(w1) {
        assert!((a - b).abs() < 0.05, "weights {w0:?} vs {w1:?} (sigmas)");
    }
}

#[test]
fn fit_recovers_the_weights_and_pose_of_a_model_instance() {
    let a = atlas();
    let w = weights_at(&a, [1.5, -1.0, 0.8]);
    let mut sim = Similarity::<2>::planar_rotation(2.0);
    sim.s = 40.0;
    sim.t = [100.0, -20.0];
    let s = subject(&a, &w, &sim);
    let idx = ClosestPointIndex::from_shape(&s);
    let r = Fitter::new(std::sync::Arc::new(a.clone()))
        .fit(&s, &idx, &FitParams::default())
        .unwrap();
    for (k, (got, want)) in r.weights.iter().zip(&w).enumerate() {
        assert!(
            (got - want).abs() < 0.05 * a.eigenvalues[0].sqrt(),
            "mode {k}: {got} vs {want}"
        );
    }
    assert!(
        (r.similarity.s - 40.0).abs() < 0.4,
        "scale {}",
        r.similarity.s
    );
}

#[test]
fn fit_is_invariant_to_the_subject_units() {
    let a = atlas();
    let w = weights_at(&a, [-1.0, 1.0, 0.5]);
    let mut small = Similarity::<2>::identity();
    small.s = 1.0;
    let mut big = small;
    big.s = 1000.0;
    let fa = Fitter::new(std::sync::Arc::new(a.clone()));
    let s1 = subject(&a, &w, &small);
    let s2 = subject(&a, &w, &big);
    let r1 = fa
        .fit(
            &s1,
            &ClosestPointIndex::from_shape(&s1),
            &FitParams::default(),
        )
        .unwrap();
    let r2 = fa
        .fit(
            &s2,
            &ClosestPointIndex::from_shape(&s2),
            &FitParams::default(),
        )
        .unwrap();
    for (x, y) in r1.weights.iter().zip(&r2.weights) {
        assert!(
            (x - y).abs() < 1e-6 * a.eigenvalues[0].sqrt() + 1e-9,
            "{x} vs {y}"
        );
    }
}

#[test]
fn symmetric_fit_recovers_a_far_instance() {
    let a = atlas();
    let w = weights_at(&a, [2.8, -2.5, 2.5]);
    let s = subject(&a, &w, &Similarity::identity());
    let idx = ClosestPointIndex::from_shape(&s);
    let r = Fitter::new(std::sync::Arc::new(a.clone()))
        .fit(&s, &idx, &FitParams::default())
        .unwrap();
    let err: f64 = r
        .weights
        .iter()
        .zip(&w)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(err < 0.1 * a.eigenvalues[0].sqrt(), "weight error {err}");
}

/// Landmarks alone: points of a model instance under a known similarity, observed with a
/// tiny noise at a dozen points, give back the instance and the similarity (the posterior
/// mean of eq. 4 and `t_{R,T,s}`), with no spread left; noisier landmarks leave more.
#[test]
fn a_dozen_exact_landmarks_give_back_the_instance_and_its_pose() {
    let a = atlas();
    let w = weights_at(&a, [1.5, -1.0, 0.5]);
    let truth = Similarity::centred(
        40.0,
        crate::geometry::rotation_exp::<2>(&[0.4]),
        &[0.0, 0.0],
        &[100.0, -20.0],
    );
    let shape: Vec<Point<2>> = a.instance(&w).iter().map(|p| truth.apply(p)).collect();
    let points: Vec<usize> = (0..12).map(|k| k * 10).collect();
    let observed: Vec<(usize, Point<2>)> = points.iter().map(|&i| (i, shape[i])).collect();
    let fit = fit_landmarks(&a, &observed, 1e-6).unwrap();
    let err = shape
        .iter()
        .zip(&fit.mean)
        .map(|(p, q)| crate::geometry::dist2(*p, *q).sqrt())
        .fold(0.0, f64::max);
    assert!(err < 1e-3, "largest error {err} (shape about 80 across)");
    assert!(
        (fit.similarity.s - 40.0).abs() < 1e-3,
        "{}",
        fit.similarity.s
    );
    // Twelve exact landmarks leave nothing of three modes open; one noisier leaves more.
    let tight = fit.point_sd.iter().fold(0.0, |m: f64, &v| m.max(v));
    assert!(tight < 1e-4, "{tight}");
    let loose = fit_landmarks(&a, &observed, 1.0).unwrap();
    assert!(loose.point_sd.iter().all(|&v| v > tight));
    // Too few landmarks, a bad sd: refused.
    assert!(fit_landmarks(&a, &observed[..1], 1.0).is_err());
    assert!(fit_landmarks(&a, &observed, f64::NAN).is_err());
    // Landmarks at one place fix no pose; one landmark thrown far off asks the model for a
    // shape no population holds: refused with the reason, not fitted.
    let same: Vec<(usize, Point<2>)> = points.iter().map(|&i| (i, [3.0, 4.0])).collect();
    let e = fit_landmarks(&a, &same, 1.0).unwrap_err().to_string();
    assert!(e.contains("all at one place"), "{e}");
    let mut far = observed.clone();
    far[3].1 = [1e6, 1e6];
    let e = fit_landmarks(&a, &far, 1.0).unwrap_err().to_string();
    assert!(e.contains("far outside the model"), "{e}");
}

#[test]
fn landmarks_on_one_line_fix_no_pose_in_3d() {
    use super::landmarks::check_spread;
    let line: Vec<Point<3>> = vec![[0.0, 0.0, 0.0], [10.0, 20.0, 30.0], [5.0, 10.0, 15.0]];
    let e = check_spread(&line).unwrap_err().to_string();
    assert!(e.contains("one line"), "{e}");
    let ok: Vec<Point<3>> = vec![[0.0, 0.0, 0.0], [10.0, 20.0, 30.0], [5.0, 11.0, 15.0]];
    assert!(check_spread(&ok).is_ok());
    assert!(check_spread(&[[1.0, 2.0, 3.0]; 4]).is_err());
}

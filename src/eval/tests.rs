use super::*;
use crate::geometry::Point;

#[test]
fn normals_correlate_perfectly_with_a_rotated_copy_and_not_with_noise() {
    let x: Vec<Point<2>> = (0..100)
        .map(|i| {
            let t = i as f64 * 0.1;
            [t.cos(), t.sin()]
        })
        .collect();
    let (s, c) = 0.8f64.sin_cos();
    let y: Vec<Point<2>> = x
        .iter()
        .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
        .collect();
    assert!((normal_correlation(&x, &y) - 1.0).abs() < 1e-9);
    let z: Vec<Point<2>> = (0..100)
        .map(|i| {
            let t = (i * 7919 % 101) as f64;
            [t.cos(), t.sin()]
        })
        .collect();
    assert!(normal_correlation(&x, &z) < 0.4);
}

/// Outlines that differ in one dimension only: PCA keeps fewer modes than shapes less one
/// (the others are round-off), and the measures stop at the modes there are instead of
/// reading past them (a panic once).
#[test]
fn measures_of_a_population_with_fewer_modes_than_shapes() {
    let shapes: Vec<crate::geometry::Shape<2>> = (0..5)
        .map(|k| {
            let a = 1.0 + 0.05 * k as f64;
            let pts = (0..60)
                .map(|i| {
                    let t = i as f64 / 60.0 * std::f64::consts::TAU;
                    [a * t.cos(), 0.6 * t.sin()]
                })
                .collect();
            crate::geometry::Shape::polyline(format!("e{k}"), pts, true)
        })
        .collect();
    let m = crate::eval::shape_model_measures(&shapes, 30, 20, 0).unwrap();
    assert!(!m.modes.is_empty() && m.modes.len() <= 3, "{:?}", m.modes);
    assert_eq!(m.generalization.len(), m.modes.len());
    assert_eq!(m.specificity.len(), m.modes.len());
    assert!(*m.compactness.last().unwrap() <= 1.0 + 1e-12);
}

/// The generalization of [`shape_model_measures`], built on the model's vocabulary
/// (`build_model`, `truncate(M).project`), equals the same measure computed by hand (GPA,
/// PCA, the left-out shape aligned in tangent space and reconstructed mode by mode) to 1e-9;
/// and `project` of a training shape (aligned) equals the instance of its coefficients.
#[test]
fn generalization_by_the_model_vocabulary_equals_the_computation_by_hand() {
    use crate::model::{align_to_mean, generalized_procrustes, pca};
    let shapes = crate::study::demo_population(9, 80, 11);
    let mm = 5;
    let m = shape_model_measures(&shapes, mm, 10, 3).unwrap();
    let ns = shapes.len();
    let raw: Vec<Vec<Point<2>>> = shapes.iter().map(|s| s.points.clone()).collect();
    let unit = raw
        .iter()
        .map(|s| crate::geometry::centroid_size(s))
        .sum::<f64>()
        / ns as f64;
    let dist = |a: &[Point<2>], b: &[Point<2>]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| crate::geometry::dist2(*p, *q).sqrt())
            .sum::<f64>()
            / a.len() as f64
            * unit
    };
    let mut by_hand = vec![0.0; mm];
    for i in 0..ns {
        let rest: Vec<Vec<Point<2>>> = (0..ns)
            .filter(|&k| k != i)
            .map(|k| raw[k].clone())
            .collect();
        let g = generalized_procrustes(&rest).unwrap();
        let p = pca(&g.aligned, &g.mean).unwrap();
        let x = align_to_mean(&raw[i], &g.mean);
        let mut recon = g.mean.clone();
        for (k, acc) in by_hand.iter_mut().enumerate() {
            let col = p.modes.col(k);
            let w: f64 = (0..x.len())
                .map(|j| {
                    (0..2)
                        .map(|d| col[j * 2 + d] * (x[j][d] - g.mean[j][d]))
                        .sum::<f64>()
                })
                .sum();
            for (j, r) in recon.iter_mut().enumerate() {
                for d in 0..2 {
                    r[d] += w * col[j * 2 + d];
                }
            }
            *acc += dist(&recon, &x) / ns as f64;
        }
    }
    for k in 0..mm {
        let rel = (m.generalization[k] - by_hand[k]).abs() / by_hand[k];
        assert!(
            rel < 1e-9,
            "{} modes: {} by the vocabulary, {} by hand",
            k + 1,
            m.generalization[k],
            by_hand[k]
        );
    }
    // project(x) = instance(coefficients(x)) for an aligned training shape.
    let atlas = crate::model::Atlas::build_model(&shapes, &Default::default()).unwrap();
    let r = atlas
        .mean
        .iter()
        .map(|p| p[0] * p[0] + p[1] * p[1])
        .sum::<f64>()
        .sqrt();
    let unit_mean: Vec<Point<2>> = atlas.mean.iter().map(|p| p.map(|c| c / r)).collect();
    let x: Vec<Point<2>> = align_to_mean(&raw[0], &unit_mean)
        .iter()
        .map(|p| p.map(|c| c * r))
        .collect();
    let a = atlas.project(&x);
    let b = atlas.instance(&atlas.coefficients(&x));
    assert!(
        a.iter()
            .zip(&b)
            .all(|(p, q)| crate::geometry::dist2(*p, *q) < 1e-24)
    );
}

/// A population of more than `LEAVE_ONE_OUT_UP_TO` shapes measures its generalization by 10
/// folds (10 models, not one per shape); on the same shapes, within 5 % of the leave-one-out's
/// (each fold's model has a tenth fewer shapes and its groups are consecutive, not random).
#[test]
fn a_large_population_generalizes_by_ten_folds() {
    let shapes = crate::model::tests::ellipses(LEAVE_ONE_OUT_UP_TO + 10);
    let large = shape_model_measures(&shapes, 4, 20, 1).unwrap();
    assert_eq!(large.generalization_folds, Some(GENERALIZATION_FOLDS));
    let small = shape_model_measures(&shapes[..LEAVE_ONE_OUT_UP_TO], 4, 20, 1).unwrap();
    assert_eq!(small.generalization_folds, None);
    let every = model_measures::measures_with_folds(&shapes, 4, 20, 1, None).unwrap();
    assert_eq!(large.modes, every.modes);
    assert!(large.modes.len() >= 2);
    for m in 0..large.modes.len() {
        let (k, l) = (large.generalization[m], every.generalization[m]);
        eprintln!(
            "{} modes: 10-fold {k:.6}, leave-one-out {l:.6} ± {:.6}",
            m + 1,
            every.generalization_sd[m]
        );
        assert!(k.is_finite() && k >= 0.0);
        assert!(
            (k - l).abs() <= 0.05 * l + 1e-12,
            "{} modes: 10-fold {k} against leave-one-out {l}",
            m + 1
        );
        if m > 0 {
            assert!(k <= large.generalization[m - 1] * (1.0 + 1e-9));
        }
    }
    assert_eq!(large.compactness, every.compactness);
    assert_eq!(large.specificity, every.specificity);
}

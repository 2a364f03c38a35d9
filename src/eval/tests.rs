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

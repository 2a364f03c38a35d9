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

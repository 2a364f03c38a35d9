//! Uniform cubic B-spline bases (eq. 1).

/// The four uniform cubic B-spline bases on a span at local parameter `t ∈ [0, 1]`, and
/// their first and second derivatives (`order` 0, 1, 2).
#[inline]
pub fn cubic_bases(t: f64, order: usize) -> [f64; 4] {
    let s = 1.0 - t;
    match order {
        0 => [
            s * s * s / 6.0,
            (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
            (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
            t * t * t / 6.0,
        ],
        1 => [
            -s * s / 2.0,
            (3.0 * t * t - 4.0 * t) / 2.0,
            (-3.0 * t * t + 2.0 * t + 1.0) / 2.0,
            t * t / 2.0,
        ],
        2 => [s, 3.0 * t - 2.0, 1.0 - 3.0 * t, t],
        _ => [0.0; 4],
    }
}

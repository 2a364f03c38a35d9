//! Draws of the standard normal distribution (the model's samples and the randomized PCA's
//! test matrices), from a seeded stream.

/// Standard normal deviate (Box-Muller) from a seeded generator: the draws of the model's
/// prior (eq. 4, `w ~ N(0, Lambda)`) and the randomized PCA's test matrix.
pub(crate) fn standard_normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::RngExt;
    let u: f64 = rng.random_range(1e-12..1.0);
    let v: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

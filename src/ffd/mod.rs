//! Cubic B-spline free-form deformation (eq. 1) on a regular lattice, its exact smoothing
//! energy `E_smooth` (section 2.1), and the regularized least-squares fit of eq. 9.
//!
//! Lattice convention: `size[d]` control points along axis `d`, spacing `h_d`; control point
//! `j` rests at `origin + (j - 1) h`, and the lattice's domain (where every point has its full
//! 4^D supporting control points) is `[origin, origin + (size - 3) h]`. With the control points
//! at rest the deformation is the identity (uniform cubic B-splines reproduce linear functions).
//!
//! | file | what it computes |
//! |---|---|
//! | `bases` | the cubic B-spline bases and their derivatives |
//! | `lattice` | [`Lattice`]: control points at rest, tensor bases at a point |
//! | `smoothing` | `E_smooth` as a banded quadratic form ([`smoothing_energy`]) |
//! | `deformation` | [`Ffd`]: `f(u)` and its Jacobian |
//! | `system` | [`FfdSystem`]: the sparse normal equations of eq. 2 and 9, factored |
//! | `least_squares` | [`FfdFit`]: eq. 9 solved for many right-hand sides |

mod bases;
mod deformation;
mod lattice;
mod least_squares;
mod smoothing;
mod system;

pub use bases::cubic_bases;
pub use deformation::Ffd;
pub use lattice::Lattice;
pub use smoothing::smoothing_energy;
pub use system::FfdFit;
pub use system::{FfdParams, FfdSystem};

#[cfg(test)]
mod tests;

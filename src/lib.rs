//! # atlasmesh
//!
//! Subject-specific finite element meshes from a statistical shape atlas, after
//! "A statistical atlas based approach to automated subject-specific FE modeling"
//! (the paper; equation numbers in the docs refer to it).
//!
//! The modules follow the pipeline: [`io`] reads shapes, [`geometry`] holds shapes, normals
//! and closest points, [`resample`] puts outlines in correspondence, [`procrustes`] and
//! [`pca`] build the shape model in [`model`] (with the mean mesh from [`fe`]), [`fit`]
//! instantiates the model on a subject (Algorithm 1), [`ffd`] and [`morph`] carry the mean
//! mesh to the subject, [`eval`] measures the result, [`export`] and [`report`] write it,
//! and [`pipeline`] strings the stages together for the command-line tool.

// Index loops over small fixed dimensions read like the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod batch;
pub mod error;
pub mod eval;
pub mod export;
pub mod fe;
pub mod ffd;
pub mod fit;
pub mod geometry;
pub mod io;
pub mod model;
pub mod morph;
pub mod pca;
pub mod procrustes;
pub mod register;
pub mod resample;

pub use error::{Error, Result};
pub mod pipeline;
pub mod repair;
pub mod report;

/// Clears the upper halves of the vector registers (x86-64 `vzeroupper`) on CPUs with AVX.
///
/// faer's dense and sparse kernels run AVX/AVX-512 code and can return with those halves in
/// use; the rest of atlasmesh is compiled for baseline x86-64 (legacy SSE encodings), and
/// every SSE instruction then pays a state-transition penalty until something clears them.
/// Measured on the femurs: the hex mesher of the mean ran 2.6 s after an atlas build against
/// 0.9 s with the state clear, a femur fit 45 ms against 40 ms. Called after the faer calls
/// that precede long non-faer loops (the fit's update, the FFD solves, the SVDs of GPA and
/// PCA) and at the start of the hex mesher and the repair. Nothing happens elsewhere.
#[inline]
pub(crate) fn clear_simd_upper_state() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked), so `vzeroupper` exists; it zeroes bits 128 and
        // up of the vector registers 0-15, which are all declared clobbered here, so no
        // value the compiler keeps in them lives across it. No memory, stack or flags use.
        unsafe {
            std::arch::asm!(
                "vzeroupper",
                out("xmm0") _, out("xmm1") _, out("xmm2") _, out("xmm3") _,
                out("xmm4") _, out("xmm5") _, out("xmm6") _, out("xmm7") _,
                out("xmm8") _, out("xmm9") _, out("xmm10") _, out("xmm11") _,
                out("xmm12") _, out("xmm13") _, out("xmm14") _, out("xmm15") _,
                options(nomem, nostack, preserves_flags)
            )
        };
    }
}

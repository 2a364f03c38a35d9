//! Clearing the vector registers' upper halves after faer's kernels (x86-64 `vzeroupper`).

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

//! Run-time choice of the SIMD level, as Embree makes it: the core's traversal is portable
//! code over `[f32; W]` lanes that the compiler vectorises for whatever target features the
//! calling function has. The default x86-64 target guarantees SSE2 only; on a CPU with AVX2
//! and FMA, [`x86_avx2_fma`] lets the frontend run the same (inlined) code compiled for them.

/// `true` when the CPU running this process has AVX2 and FMA (x86-64 only; checked once by
/// `is_x86_feature_detected!`, which caches the answer).
#[inline]
#[must_use]
pub fn x86_avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The AVX2 + FMA token of the core's node kernels when the CPU has both (x86-64 only).
#[cfg(target_arch = "x86_64")]
#[inline]
#[must_use]
pub fn avx2_fma() -> Option<halfray_core::simd_level::Avx2Fma> {
    // SAFETY: made only after the run-time check that this CPU supports AVX2 and FMA, the
    // token's one requirement.
    x86_avx2_fma().then(|| unsafe { halfray_core::simd_level::Avx2Fma::new_unchecked() })
}

/// The SIMD level queries run with on this CPU, for reports: `"avx2+fma"` or `"sse2"`
/// (x86-64), or `"portable"` elsewhere.
#[must_use]
pub fn level_name() -> &'static str {
    if x86_avx2_fma() {
        "avx2+fma"
    } else if cfg!(target_arch = "x86_64") {
        "sse2"
    } else {
        "portable"
    }
}

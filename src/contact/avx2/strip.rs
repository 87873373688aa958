//! The dense part of a strip product on AVX2 (`contact::column_sums`, which holds the blocks
//! and their contract): its vector operations in 8 `f32` or 4 `f64` lanes, and the two entry
//! points compiled for AVX2. A block of four vectors keeps eight accumulators, two source
//! values and two kernel vectors in the sixteen registers.

use crate::contact::column_sums::{lanes, sums, Group, Sums};
use std::arch::x86_64::{
    __m256, __m256d, _mm256_add_pd, _mm256_add_ps, _mm256_loadu_pd, _mm256_loadu_ps, _mm256_mul_pd,
    _mm256_mul_ps, _mm256_set1_pd, _mm256_set1_ps, _mm256_setzero_pd, _mm256_setzero_ps,
    _mm256_storeu_pd, _mm256_storeu_ps, _mm256_sub_pd, _mm256_sub_ps,
};

lanes!(
    F32x8,
    "avx2",
    f32,
    8,
    __m256,
    _mm256_setzero_ps,
    _mm256_set1_ps,
    _mm256_loadu_ps,
    _mm256_storeu_ps,
    _mm256_add_ps,
    _mm256_sub_ps,
    _mm256_mul_ps
);
lanes!(
    F64x4,
    "avx2",
    f64,
    4,
    __m256d,
    _mm256_setzero_pd,
    _mm256_set1_pd,
    _mm256_loadu_pd,
    _mm256_storeu_pd,
    _mm256_add_pd,
    _mm256_sub_pd,
    _mm256_mul_pd
);

/// The sums in single precision.
///
/// # Safety
/// `contact::column_sums`' contract, on a CPU with AVX2.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn sums_f32(a: Sums<'_, f32>, groups: &[Group]) {
    // SAFETY: the caller's contract.
    unsafe { sums::<F32x8>(a, groups) }
}

/// The sums in double precision.
///
/// # Safety
/// `contact::column_sums`' contract, on a CPU with AVX2.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn sums_f64(a: Sums<'_, f64>, groups: &[Group]) {
    // SAFETY: the caller's contract.
    unsafe { sums::<F64x4>(a, groups) }
}

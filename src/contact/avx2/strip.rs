//! The dense part of a strip product on AVX2 (`contact::column_sums`, which holds the blocks
//! and their contract): its vector operations in 8 `f32` or 4 `f64` lanes, each with its entry
//! point compiled for AVX2 (`Lanes::run`). A block of four vectors keeps eight accumulators, two source
//! values and two kernel vectors in the sixteen registers.

use crate::contact::column_sums::lanes;
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

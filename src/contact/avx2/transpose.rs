//! The tiled transpose of `contact::influence::transpose`. Safety: the CPU must support AVX2 and every element of the block
//! (`rows × cols` with the strides) must lie inside both buffers (`contact::influence::transpose` checks both).

use std::arch::x86_64::{
    __m256d, _mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd, _mm256_unpackhi_pd,
    _mm256_unpacklo_pd,
};

/// The transpose of the block's whole tiles for elements of `W` f64 words: 8-byte
/// elements (`W = 1`) in 4 × 4 tiles, 16-byte ones (`W = 2`) in 2 × 2 tiles. Returns the
/// tiled corner's rows and columns; the caller moves the rest.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn tiles<const W: usize>(
    src: *const f64,
    ss: usize,
    dst: *mut f64,
    ds: usize,
    rows: usize,
    cols: usize,
) -> (usize, usize) {
    // SAFETY: this function's contract (module docs): AVX2 is present and the tiles lie inside both buffers.
    unsafe {
        let t = 4 / W;
        let (rt, ct) = (rows - rows % t, cols - cols % t);
        for i in (0..rt).step_by(t) {
            for j in (0..ct).step_by(t) {
                let ld = |k: usize| _mm256_loadu_pd(src.add(W * ((i + k) * ss + j)));
                let st =
                    |k: usize, v: __m256d| _mm256_storeu_pd(dst.add(W * ((j + k) * ds + i)), v);
                if W == 1 {
                    let (a, b, c, d) = (ld(0), ld(1), ld(2), ld(3));
                    let t0 = _mm256_unpacklo_pd(a, b);
                    let t1 = _mm256_unpackhi_pd(a, b);
                    let t2 = _mm256_unpacklo_pd(c, d);
                    let t3 = _mm256_unpackhi_pd(c, d);
                    st(0, _mm256_permute2f128_pd::<0x20>(t0, t2));
                    st(1, _mm256_permute2f128_pd::<0x20>(t1, t3));
                    st(2, _mm256_permute2f128_pd::<0x31>(t0, t2));
                    st(3, _mm256_permute2f128_pd::<0x31>(t1, t3));
                } else {
                    let (a, b) = (ld(0), ld(1));
                    st(0, _mm256_permute2f128_pd::<0x20>(a, b));
                    st(1, _mm256_permute2f128_pd::<0x31>(a, b));
                }
            }
        }
        (rt, ct)
    }
}

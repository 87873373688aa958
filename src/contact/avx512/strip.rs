//! The dense part of a strip product on AVX-512 (`contact::influence::strip`'s `Dense`): for
//! one frequency, the field spectra `y_r = Σ_s S_rs x_s` on a run of rows, as a sum of kernel
//! columns scaled by the source spectra, in blocks of four vectors of rows (three, two or one
//! for the last rows) whose sums stay in registers over all the sources: the kernel's columns
//! are read once per block, so few blocks per run keep them in the nearest cache.
//!
//! Safety (both kernels): the CPU must support AVX-512F; every source `s` of `sources` must
//! have its column `s · cn` with `s · cn + r1 + 4 · lanes ≤ spec.len()` (a last block reads
//! less than one vector past the run, into lanes it does not store; the bound keeps a margin), `s < src.len()`, and
//! `r1 ≤ acc.len()`.

use std::arch::x86_64::{
    __m512, __m512d, _mm512_add_pd, _mm512_add_ps, _mm512_loadu_pd, _mm512_loadu_ps, _mm512_mul_pd,
    _mm512_mul_ps, _mm512_set1_pd, _mm512_set1_ps, _mm512_setzero_pd, _mm512_setzero_ps,
    _mm512_storeu_pd, _mm512_storeu_ps, _mm512_sub_pd, _mm512_sub_ps,
};

/// The kernel's spectra of one frequency and the source spectra, real and imaginary parts
/// apart (`spec[s · cn + r]`, `src[s]`), and the field spectra's accumulators (`acc[r]`).
pub(crate) struct Sums<'a, T> {
    pub spec_re: &'a [T],
    pub spec_im: &'a [T],
    pub src_re: &'a [T],
    pub src_im: &'a [T],
    pub acc_re: &'a mut [T],
    pub acc_im: &'a mut [T],
    /// The length of a kernel column (`c · ny`).
    pub cn: usize,
    /// The field rows `r0..r1`.
    pub rows: (usize, usize),
}

/// The vector operations the kernels need, for `f32` (16 lanes) and `f64` (8 lanes).
trait Lanes: Copy + Default {
    const L: usize;
    type V: Copy;
    unsafe fn zero() -> Self::V;
    unsafe fn splat(x: Self) -> Self::V;
    unsafe fn load(p: *const Self) -> Self::V;
    unsafe fn store(p: *mut Self, v: Self::V);
    /// `y + (a·xr − b·xi)`, rounded after each operation.
    unsafe fn acc_re(y: Self::V, a: Self::V, b: Self::V, xr: Self::V, xi: Self::V) -> Self::V;
    /// `y + (a·xi + b·xr)`, rounded after each operation.
    unsafe fn acc_im(y: Self::V, a: Self::V, b: Self::V, xr: Self::V, xi: Self::V) -> Self::V;
}

impl Lanes for f32 {
    const L: usize = 16;
    type V = __m512;
    #[inline(always)]
    unsafe fn zero() -> __m512 {
        // SAFETY: AVX-512F, the kernels' contract.
        unsafe { _mm512_setzero_ps() }
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m512 {
        // SAFETY: as above.
        unsafe { _mm512_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> __m512 {
        // SAFETY: as above, and `p` points to 16 readable values (the caller's bounds).
        unsafe { _mm512_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: __m512) {
        // SAFETY: as above, and `p` points to 16 writable values.
        unsafe { _mm512_storeu_ps(p, v) }
    }
    #[inline(always)]
    unsafe fn acc_re(y: __m512, a: __m512, b: __m512, xr: __m512, xi: __m512) -> __m512 {
        // SAFETY: AVX-512F.
        unsafe { _mm512_add_ps(y, _mm512_sub_ps(_mm512_mul_ps(a, xr), _mm512_mul_ps(b, xi))) }
    }
    #[inline(always)]
    unsafe fn acc_im(y: __m512, a: __m512, b: __m512, xr: __m512, xi: __m512) -> __m512 {
        // SAFETY: AVX-512F.
        unsafe { _mm512_add_ps(y, _mm512_add_ps(_mm512_mul_ps(a, xi), _mm512_mul_ps(b, xr))) }
    }
}

impl Lanes for f64 {
    const L: usize = 8;
    type V = __m512d;
    #[inline(always)]
    unsafe fn zero() -> __m512d {
        // SAFETY: AVX-512F, the kernels' contract.
        unsafe { _mm512_setzero_pd() }
    }
    #[inline(always)]
    unsafe fn splat(x: f64) -> __m512d {
        // SAFETY: as above.
        unsafe { _mm512_set1_pd(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f64) -> __m512d {
        // SAFETY: as above, and `p` points to 8 readable values (the caller's bounds).
        unsafe { _mm512_loadu_pd(p) }
    }
    #[inline(always)]
    unsafe fn store(p: *mut f64, v: __m512d) {
        // SAFETY: as above, and `p` points to 8 writable values.
        unsafe { _mm512_storeu_pd(p, v) }
    }
    #[inline(always)]
    unsafe fn acc_re(y: __m512d, a: __m512d, b: __m512d, xr: __m512d, xi: __m512d) -> __m512d {
        // SAFETY: AVX-512F.
        unsafe { _mm512_add_pd(y, _mm512_sub_pd(_mm512_mul_pd(a, xr), _mm512_mul_pd(b, xi))) }
    }
    #[inline(always)]
    unsafe fn acc_im(y: __m512d, a: __m512d, b: __m512d, xr: __m512d, xi: __m512d) -> __m512d {
        // SAFETY: AVX-512F.
        unsafe { _mm512_add_pd(y, _mm512_add_pd(_mm512_mul_pd(a, xi), _mm512_mul_pd(b, xr))) }
    }
}

/// One block of `B` vectors of rows from row `r`: its sums over the sources into `acc`
/// (the rows below `r1` only).
#[inline(always)]
unsafe fn block<T: Lanes, const B: usize>(
    a: &mut Sums<'_, T>,
    sources: impl Iterator<Item = usize>,
    r: usize,
) {
    let (l, cn, r1) = (T::L, a.cn, a.rows.1);
    // SAFETY: AVX-512F and the bounds are the kernels' contract (module docs).
    unsafe {
        let mut yr = [T::zero(); B];
        let mut yi = [T::zero(); B];
        for s in sources {
            let (xr, xi) = (
                T::splat(*a.src_re.get_unchecked(s)),
                T::splat(*a.src_im.get_unchecked(s)),
            );
            let (pr, pi) = (
                a.spec_re.as_ptr().add(s * cn + r),
                a.spec_im.as_ptr().add(s * cn + r),
            );
            for v in 0..B {
                let (ar, ai) = (T::load(pr.add(v * l)), T::load(pi.add(v * l)));
                yr[v] = T::acc_re(yr[v], ar, ai, xr, xi);
                yi[v] = T::acc_im(yi[v], ar, ai, xr, xi);
            }
        }
        let mut out = [T::default(); 128];
        let p = out.as_mut_ptr();
        for v in 0..B {
            T::store(p.add(v * l), yr[v]);
            T::store(p.add((B + v) * l), yi[v]);
        }
        let n = (B * l).min(r1 - r);
        a.acc_re[r..r + n].copy_from_slice(&out[..n]);
        a.acc_im[r..r + n].copy_from_slice(&out[B * l..B * l + n]);
    }
}

/// `acc[r] = Σ_s spec[s·cn + r] · src[s]` (complex, in the order of `sources`) for `r` in the
/// run, as the plain loop: blocks of four vectors, the last rows in the smallest block of
/// three, two or one that holds them. Safety: the module's.
#[inline(always)]
unsafe fn sums<T: Lanes>(mut a: Sums<'_, T>, sources: impl Iterator<Item = usize> + Clone) {
    let (l, (r0, r1)) = (T::L, a.rows);
    let mut r = r0;
    while r < r1 {
        // SAFETY: the module's contract.
        unsafe {
            let rest = r1 - r;
            if rest > 3 * l {
                block::<T, 4>(&mut a, sources.clone(), r);
                r += 4 * l;
            } else if rest > 2 * l {
                block::<T, 3>(&mut a, sources.clone(), r);
                r += 3 * l;
            } else if rest > l {
                block::<T, 2>(&mut a, sources.clone(), r);
                r += 2 * l;
            } else {
                block::<T, 1>(&mut a, sources.clone(), r);
                r += l;
            }
        }
    }
}

/// [`sums`] in single precision. Safety: the module's.
#[target_feature(enable = "avx512f")]
pub(crate) unsafe fn sums_f32(a: Sums<'_, f32>, sources: impl Iterator<Item = usize> + Clone) {
    // SAFETY: the module's contract.
    unsafe { sums(a, sources) }
}

/// [`sums`] in double precision. Safety: the module's.
#[target_feature(enable = "avx512f")]
pub(crate) unsafe fn sums_f64(a: Sums<'_, f64>, sources: impl Iterator<Item = usize> + Clone) {
    // SAFETY: the module's contract.
    unsafe { sums(a, sources) }
}

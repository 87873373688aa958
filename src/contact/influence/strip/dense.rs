//! The dense part of a strip product (`super::StripConvolver`): per frequency along x, the
//! field spectra as a sum of the kernel's spectral columns scaled by the source spectra, in
//! double or single precision, on AVX-512 where the CPU has it (`contact::avx512::strip`),
//! else as plain loops pulp compiles for the CPU's instruction set; every route gives the
//! plain loops' bits.

use rustfft::num_complex::Complex;

#[cfg(target_arch = "x86_64")]
use crate::contact::avx512::strip::Sums;

/// The spectra of a strip product in one precision `T`, real and imaginary parts apart.
#[derive(Clone)]
pub(super) struct Spectra<T> {
    /// The kernel's `m/2 + 1` spectra, each a `(c·ny) × (c·ny)` matrix (row: field component
    /// and column `a·ny + j`; column: source `b·ny + j'`) stored column by column
    /// (`[k][source][row]`), divided by `m`; then [`PAD`] zeros.
    pub(super) spec_re: Vec<T>,
    pub(super) spec_im: Vec<T>,
    /// The source spectra `[k][b·ny + j']`.
    pub(super) src_re: Vec<T>,
    pub(super) src_im: Vec<T>,
    /// The field spectra of one frequency, `c·ny` each (accumulators).
    pub(super) acc_re: Vec<T>,
    pub(super) acc_im: Vec<T>,
}

/// The real type of a strip product's dense part: `f64`, or `f32` for the inner loops.
pub(super) trait DenseReal:
    Copy
    + Default
    + Into<f64>
    + std::ops::Mul<Output = Self>
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::AddAssign
{
    /// `v` rounded to this precision.
    fn from_f64(v: f64) -> Self;
    /// The values in an AVX-512 vector.
    const LANES_512: usize;
    /// `contact::avx512::strip`'s sums in this precision.
    ///
    /// # Safety
    /// That module's contract: AVX-512F, and the bounds it states.
    #[cfg(target_arch = "x86_64")]
    unsafe fn sums_avx512(sums: Sums<'_, Self>, sources: impl Iterator<Item = usize> + Clone);
}

impl DenseReal for f32 {
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    const LANES_512: usize = 16;
    #[cfg(target_arch = "x86_64")]
    unsafe fn sums_avx512(sums: Sums<'_, f32>, sources: impl Iterator<Item = usize> + Clone) {
        // SAFETY: the caller's contract is the kernel's.
        unsafe { crate::contact::avx512::strip::sums_f32(sums, sources) }
    }
}
impl DenseReal for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
    const LANES_512: usize = 8;
    #[cfg(target_arch = "x86_64")]
    unsafe fn sums_avx512(sums: Sums<'_, f64>, sources: impl Iterator<Item = usize> + Clone) {
        // SAFETY: the caller's contract is the kernel's.
        unsafe { crate::contact::avx512::strip::sums_f64(sums, sources) }
    }
}

/// The dense part of a strip product, in precision `T`: per frequency `k`, the field spectra
/// of the columns `d0..d1` of every component (computed as one run of rows from the first
/// component's `d0` to the last one's `d1`, or on AVX-512 one run per component where that
/// takes fewer vectors), `y = S_k x` over the source columns `c0..c1`
/// of every component, as a sum of columns of `S_k` (stored source-major, `[k][s][r]`) scaled
/// by the source spectrum `x_s`: contiguous element-wise updates, no reductions, so any
/// vector width gives the same bits. Into `field[(a·ny + j)·nk + k]`.
pub(super) struct Dense<'a, T> {
    spectra: &'a mut Spectra<T>,
    field: &'a mut [Complex<T>],
    /// `(nk, comps, ny)`
    dims: (usize, usize, usize),
    cols: (usize, usize),
    field_cols: (usize, usize),
}

/// The kernel's spectra below this fraction of their largest are zero in single precision
/// (`to_single`): far below its resolution (6e-8). They are the round-off of the imaginary
/// parts of kernel rows even in x (about 1e-16 of the largest), and their products with the
/// sources' spectra would be subnormal, which the CPU computes many times slower (the box
/// product of `strip_bench` took about three times as long with them).
const FLUSH: f64 = 1e-12;

/// `v` rounded to `f32`, the values below [`FLUSH`] times `largest` made zero.
pub(super) fn to_single(v: &[f64], largest: f64) -> Vec<f32> {
    let tiny = FLUSH * largest;
    v.iter()
        .map(|&x| if x.abs() < tiny { 0.0 } else { x as f32 })
        .collect()
}

/// Zeros after the kernel's spectra: the AVX-512 sums' last block reads less than one vector
/// (16 `f32`, 8 `f64`) past a column's run (`contact::avx512::strip`); the margin is four.
pub(super) const PAD: usize = 64;

impl<T: DenseReal> Dense<'_, T> {
    /// [`Self::run_reference`] on AVX-512 (`contact::avx512::strip`): per frequency, the sums
    /// over the sources in blocks of rows held in registers, the same operations in the same
    /// order per element, so the same bits.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[cfg(target_arch = "x86_64")]
    unsafe fn run_avx512(mut self) {
        let (nk, c, ny) = self.dims;
        let ((c0, c1), (d0, d1)) = (self.cols, self.field_cols);
        let cn = c * ny;
        // the sources' columns inside the kernel's (the kernel reads them unchecked)
        assert!(c0 <= c1 && c1 <= ny && d1 <= ny);
        let Some((r0, r1)) = self.run_rows() else {
            return;
        };
        // one run across the components, or one per component where that takes fewer
        // vectors (a box narrower than the grid: the columns between are not computed)
        let vectors = |n: usize| n.div_ceil(T::LANES_512);
        let per_component = c * vectors(d1 - d0) < vectors(r1 - r0);
        let runs = (0..if per_component { c } else { 1 }).map(|a| {
            if per_component {
                (a * ny + d0, a * ny + d1)
            } else {
                (r0, r1)
            }
        });
        let sources = (0..c).flat_map(|b| (c0..c1).map(move |jp| b * ny + jp));
        for k in 0..nk {
            for rows in runs.clone() {
                let s = &mut *self.spectra;
                let sums = Sums {
                    spec_re: &s.spec_re[k * cn * cn..],
                    spec_im: &s.spec_im[k * cn * cn..],
                    src_re: &s.src_re[k * cn..(k + 1) * cn],
                    src_im: &s.src_im[k * cn..(k + 1) * cn],
                    acc_re: &mut s.acc_re[..cn],
                    acc_im: &mut s.acc_im[..cn],
                    cn,
                    rows,
                };
                // the kernel's contract: every column's run and the margin beyond lie inside
                assert!((cn - 1) * cn + rows.1 + PAD <= sums.spec_re.len().min(sums.spec_im.len()));
                assert!(rows.1 <= cn);
                // SAFETY: AVX-512F is the caller's contract; the bounds are checked above.
                unsafe { T::sums_avx512(sums, sources.clone()) };
            }
            self.store(k);
        }
    }

    /// The loops, for any instruction set ([`pulp::WithSimd`] compiles them for each), and the
    /// scalar reference the AVX-512 kernel's bits are tested against: per frequency `k`, the
    /// field spectra of the run of rows, a sum of kernel columns scaled by the source spectra.
    #[inline(always)]
    fn run_reference(mut self) {
        let (nk, c, ny) = self.dims;
        let (c0, c1) = self.cols;
        let cn = c * ny;
        let Some((r0, r1)) = self.run_rows() else {
            return;
        };
        for k in 0..nk {
            let Spectra {
                spec_re,
                spec_im,
                src_re,
                src_im,
                acc_re: yr,
                acc_im: yi,
            } = &mut *self.spectra;
            yr.fill(T::default());
            yi.fill(T::default());
            for b in 0..c {
                for jp in c0..c1 {
                    let s = b * ny + jp;
                    let (xr, xi) = (src_re[k * cn + s], src_im[k * cn + s]);
                    let col = (k * cn + s) * cn;
                    let (sr, si) = (&spec_re[col + r0..col + r1], &spec_im[col + r0..col + r1]);
                    for ((yr, yi), (ar, ai)) in yr[r0..r1]
                        .iter_mut()
                        .zip(&mut yi[r0..r1])
                        .zip(sr.iter().zip(si))
                    {
                        *yr += *ar * xr - *ai * xi;
                        *yi += *ar * xi + *ai * xr;
                    }
                }
            }
            self.store(k);
        }
    }

    /// The run of field rows the plain loops' sums cover: from the first component's first
    /// field column to the last one's last (the columns between, outside the field, are
    /// computed and unused); `None` if empty.
    fn run_rows(&self) -> Option<(usize, usize)> {
        let (_, c, ny) = self.dims;
        let (d0, d1) = self.field_cols;
        let (r0, r1) = (d0, (c - 1) * ny + d1);
        (r0 < r1).then_some((r0, r1))
    }

    /// The accumulators' field spectra of the field columns into frequency `k` of `field`.
    fn store(&mut self, k: usize) {
        let (nk, c, ny) = self.dims;
        let (d0, d1) = self.field_cols;
        let (acc_re, acc_im) = (&self.spectra.acc_re, &self.spectra.acc_im);
        for a in 0..c {
            for j in d0..d1 {
                let r = a * ny + j;
                self.field[r * nk + k] = Complex::new(acc_re[r], acc_im[r]);
            }
        }
    }
}

impl<T: DenseReal> Dense<'_, T> {
    /// The dense part of `spectra` into `field` (`dims` = `(nk, comps, ny)`,
    /// the source and field columns), compiled for the CPU's instruction set (`dispatch`), or
    /// the scalar reference [`Self::run_reference`].
    pub(super) fn apply(
        spectra: &mut Spectra<T>,
        field: &mut [Complex<T>],
        dims: (usize, usize, usize),
        (cols, field_cols): ((usize, usize), (usize, usize)),
        dispatch: bool,
    ) {
        let dense = Dense {
            spectra,
            field,
            dims,
            cols,
            field_cols,
        };
        if !dispatch {
            dense.run_reference();
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, checked on the line above.
            unsafe { dense.run_avx512() };
            return;
        }
        pulp::Arch::new().dispatch(dense);
    }
}

impl<T: DenseReal> pulp::WithSimd for Dense<'_, T> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.run_reference();
    }
}

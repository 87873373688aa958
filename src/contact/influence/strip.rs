//! Influence products for a kernel that is translation-invariant along the rail only: FFTs
//! along x, dense blocks across (theory §6.9).
//!
//! The half-space kernel of [`super::Convolver`] depends on the offset in both directions, so
//! its products are two-dimensional cyclic convolutions. A kernel condensed from an FE model
//! of an extruded rail head (and a tread of revolution) is invariant along the rolling
//! direction only: across the rail the field and source columns `j, j'` enter separately,
//!
//! ```text
//! u_a(i, j) = Σ_{i', j', b} K_ab(i − i', j, j') f_b(i', j'),   a, b ∈ components,
//! ```
//!
//! a Toeplitz structure along x with dense `(c·ny) × (c·ny)` blocks (`c` components: 1 for the
//! normal problem, 2 for the tangential, 3 for the coupled one). The product is a cyclic
//! convolution along x on a zero-padded length `m ≥ 2nx − 1` (exact for the linear
//! convolution on rows `0..nx`): a real FFT of every source column, per frequency a dense
//! complex matrix–vector product with the kernel's spectrum, an inverse real FFT.
//! Assumption: the kernel is real; its spectra are computed once.

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;
use rustfft::FftNum;
use std::sync::Arc;

use super::{coefficients, next_fast_len};
#[cfg(target_arch = "x86_64")]
use crate::contact::avx512::strip::Sums;

/// The quasi-identical half-space's kernel ([`coefficients`]; element `dx × dy` in m, `E*`,
/// `G` in Pa, ν) in the form [`StripConvolver::new`] takes, for `comps` components: 1 → the
/// normal term; 2 → the tangential block (x, y); 3 → x, y and the normal, uncoupled. For
/// checks and benchmarks of the strip products against [`super::Convolver`].
pub fn half_space_kernel(
    (dx, dy): (f64, f64),
    (e_star, g, nu): (f64, f64, f64),
    comps: usize,
) -> impl Fn(isize, usize, usize) -> [[f64; 3]; 3] {
    move |o, j, jp| {
        let c = coefficients(
            o as f64 * dx,
            (j as f64 - jp as f64) * dy,
            dx,
            dy,
            e_star,
            g,
            nu,
        );
        match comps {
            1 => [[c.zz, 0.0, 0.0], [0.0; 3], [0.0; 3]],
            2 => [[c.xx, c.xy, 0.0], [c.xy, c.yy, 0.0], [0.0; 3]],
            _ => [[c.xx, c.xy, 0.0], [c.xy, c.yy, 0.0], [0.0, 0.0, c.zz]],
        }
    }
}

/// FFT-along-x, dense-across influence products on an `nx × ny` grid (element `i * ny + j`,
/// `i` along x) with `c` components per element. A clone shares the FFT plans.
///
/// Layout: the kernel spectra and the source spectra are stored as separate real and
/// imaginary arrays, frequency-major and source-major (`[k][source][row]` and `[k][source]`),
/// so that the dense product of one frequency is a sum of contiguous kernel columns, one per
/// source column that carries traction, each scaled by its source spectrum (`Dense`).
#[derive(Clone)]
pub struct StripConvolver {
    nx: usize,
    ny: usize,
    comps: usize,
    m: usize,
    /// The kernel's and the sources' spectra in double precision, for
    /// [`Self::product_cols`], and their FFTs.
    double: Spectra<f64>,
    fft64: Ffts<f64>,
    /// [`Self::double`]'s kernel spectra rounded to single precision, and FFTs in single
    /// precision, for [`Precision::Single`].
    single: Spectra<f32>,
    fft32: Ffts<f32>,
}

/// The FFTs along x of a strip product in one precision `T` and their buffers.
#[derive(Clone)]
struct Ffts<T: FftNum> {
    forward: Arc<dyn RealToComplex<T>>,
    inverse: Arc<dyn ComplexToReal<T>>,
    line: Vec<T>,
    /// One column's spectrum (`m/2 + 1`).
    spectrum: Vec<Complex<T>>,
    /// Field spectra, one row of `m/2 + 1` per field column `a·ny + j`.
    field: Vec<Complex<T>>,
    scratch: Vec<Complex<T>>,
}

impl<T: FftNum + DenseReal> Ffts<T> {
    /// The plans of length `m` and the buffers for `cn` field columns.
    fn new(m: usize, cn: usize) -> Self {
        let mut planner = RealFftPlanner::<T>::new();
        let forward = planner.plan_fft_forward(m);
        let inverse = planner.plan_fft_inverse(m);
        let nk = m / 2 + 1;
        let zero = Complex::new(T::default(), T::default());
        let scratch_len = forward
            .get_scratch_len()
            .max(inverse.get_scratch_len())
            .max(1);
        Ffts {
            line: forward.make_input_vec(),
            spectrum: vec![zero; nk],
            field: vec![zero; cn * nk],
            scratch: vec![zero; scratch_len],
            forward,
            inverse,
        }
    }

    /// The spectra along x of the source columns `c0..c1` of every component, `nx` rows of
    /// `ny` columns each, into `spectra`'s source spectra (`[k][b·ny + j']`).
    fn forward(
        &mut self,
        f: &[&[f64]],
        (nx, ny): (usize, usize),
        (c0, c1): (usize, usize),
        spectra: &mut Spectra<T>,
    ) {
        let cn = f.len() * ny;
        for (b, fb) in f.iter().enumerate() {
            for jp in c0..c1 {
                self.line.fill(T::default());
                for i in 0..nx {
                    self.line[i] = <T as DenseReal>::from_f64(fb[i * ny + jp]);
                }
                self.forward
                    .process_with_scratch(&mut self.line, &mut self.spectrum, &mut self.scratch)
                    .expect("lengths from the plan");
                let s = b * ny + jp;
                for (k, v) in self.spectrum.iter().enumerate() {
                    spectra.src_re[k * cn + s] = v.re;
                    spectra.src_im[k * cn + s] = v.im;
                }
            }
        }
    }

    /// The inverse FFTs of the field spectra of the columns `d0..d1` into the field rows
    /// `shift..shift + rows` of `u` (`ny` columns each).
    fn inverse(
        &mut self,
        u: &mut [&mut [f64]],
        ny: usize,
        (shift, rows): (usize, usize),
        (d0, d1): (usize, usize),
    ) {
        let nk = self.spectrum.len();
        let even = self.line.len().is_multiple_of(2);
        for (a, ua) in u.iter_mut().enumerate() {
            for j in d0..d1 {
                let row = &mut self.field[(a * ny + j) * nk..(a * ny + j + 1) * nk];
                // the imaginary parts of the zero and Nyquist bins are round-off of a real kernel
                row[0].im = T::default();
                if even {
                    row[nk - 1].im = T::default();
                }
                self.inverse
                    .process_with_scratch(row, &mut self.line, &mut self.scratch)
                    .expect("lengths from the plan");
                for i in 0..rows {
                    ua[i * ny + j] = self.line[i + shift].into();
                }
            }
        }
    }
}

/// The precision of a strip product's dense part (`StripConvolver::product_cols_in`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Precision {
    /// Everything in `f64`.
    Double,
    /// The per-frequency products with the kernel's spectra in `f32` (the FFTs in `f64`).
    Single,
}

/// The spectra of a strip product in one precision `T`, real and imaginary parts apart.
#[derive(Clone)]
struct Spectra<T> {
    /// The kernel's `m/2 + 1` spectra, each a `(c·ny) × (c·ny)` matrix (row: field component
    /// and column `a·ny + j`; column: source `b·ny + j'`) stored column by column
    /// (`[k][source][row]`), divided by `m`; then [`PAD`] zeros.
    spec_re: Vec<T>,
    spec_im: Vec<T>,
    /// The source spectra `[k][b·ny + j']`.
    src_re: Vec<T>,
    src_im: Vec<T>,
    /// The field spectra of one frequency, `c·ny` each (accumulators).
    acc_re: Vec<T>,
    acc_im: Vec<T>,
}

/// The real type of a strip product's dense part: `f64`, or `f32` for the inner loops.
trait DenseReal:
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
    #[cfg(target_arch = "x86_64")]
    unsafe fn sums_avx512(sums: Sums<'_, f64>, sources: impl Iterator<Item = usize> + Clone) {
        // SAFETY: the caller's contract is the kernel's.
        unsafe { crate::contact::avx512::strip::sums_f64(sums, sources) }
    }
}

/// The dense part of a strip product, in precision `T`: per frequency `k`, the field spectra
/// of the columns `d0..d1` of every component (computed as one run of rows from the first
/// component's `d0` to the last one's `d1`), `y = S_k x` over the source columns `c0..c1`
/// of every component, as a sum of columns of `S_k` (stored source-major, `[k][s][r]`) scaled
/// by the source spectrum `x_s`: contiguous element-wise updates, no reductions, so any
/// vector width gives the same bits. Into `field[(a·ny + j)·nk + k]`.
struct Dense<'a, T> {
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
/// product of `strip_bench` took 3.5 times as long with them).
const FLUSH: f64 = 1e-12;

/// `v` rounded to `f32`, the values below [`FLUSH`] times the largest made zero.
fn to_single(v: &[f64]) -> Vec<f32> {
    let tiny = FLUSH * v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    v.iter()
        .map(|&x| if x.abs() < tiny { 0.0 } else { x as f32 })
        .collect()
}

/// Zeros after the kernel's spectra: the AVX-512 sums' last block reads up to four vectors
/// (64 `f32`, 32 `f64`) past a column's run (`contact::avx512::strip`).
const PAD: usize = 64;

impl<T: DenseReal> Dense<'_, T> {
    /// [`Self::run_reference`] on AVX-512 (`contact::avx512::strip`): per frequency, the sums
    /// over the sources in blocks of rows held in registers, the same operations in the same
    /// order per element, so the same bits.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[cfg(target_arch = "x86_64")]
    unsafe fn run_avx512(self) {
        let (nk, c, ny) = self.dims;
        let ((c0, c1), (d0, d1)) = (self.cols, self.field_cols);
        let cn = c * ny;
        let Spectra {
            spec_re,
            spec_im,
            src_re,
            src_im,
            acc_re,
            acc_im,
        } = self.spectra;
        let (r0, r1) = (d0, (c - 1) * ny + d1);
        if r0 >= r1 {
            return;
        }
        let sources = (0..c).flat_map(|b| (c0..c1).map(move |jp| b * ny + jp));
        for k in 0..nk {
            let sums = Sums {
                spec_re: &spec_re[k * cn * cn..],
                spec_im: &spec_im[k * cn * cn..],
                src_re: &src_re[k * cn..(k + 1) * cn],
                src_im: &src_im[k * cn..(k + 1) * cn],
                acc_re: &mut acc_re[..cn],
                acc_im: &mut acc_im[..cn],
                cn,
                rows: (r0, r1),
            };
            // the kernel's contract: every column's run and two vectors beyond lie inside
            assert!((cn - 1) * cn + r1 + PAD <= sums.spec_re.len().min(sums.spec_im.len()));
            assert!(r1 <= cn);
            // SAFETY: AVX-512F is the caller's contract; the bounds are checked above.
            unsafe { T::sums_avx512(sums, sources.clone()) };
            for a in 0..c {
                for j in d0..d1 {
                    let r = a * ny + j;
                    self.field[r * nk + k] = Complex::new(acc_re[r], acc_im[r]);
                }
            }
        }
    }

    /// The loops, for any instruction set ([`pulp::WithSimd`] compiles them for each), and the
    /// scalar reference the AVX-512 kernel's bits are tested against: per frequency `k`, the
    /// field spectra of the run of rows, a sum of kernel columns scaled by the source spectra.
    #[inline(always)]
    fn run_reference(self) {
        let (nk, c, ny) = self.dims;
        let ((c0, c1), (d0, d1)) = (self.cols, self.field_cols);
        let cn = c * ny;
        let Spectra {
            spec_re,
            spec_im,
            src_re,
            src_im,
            acc_re,
            acc_im,
        } = self.spectra;
        let (yr, yi) = (&mut acc_re[..cn], &mut acc_im[..cn]);
        let (r0, r1) = (d0, (c - 1) * ny + d1);
        if r0 >= r1 {
            return;
        }
        for k in 0..nk {
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
            for a in 0..c {
                for j in d0..d1 {
                    let r = a * ny + j;
                    self.field[r * nk + k] = Complex::new(yr[r], yi[r]);
                }
            }
        }
    }
}

impl<T: DenseReal> Dense<'_, T> {
    /// The dense part of `spectra` into `field` ([`Self::run`]; `dims` = `(nk, comps, ny)`,
    /// the source and field columns), compiled for the CPU's instruction set (`dispatch`), or
    /// the scalar reference [`Self::run_reference`].
    fn apply(
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

impl StripConvolver {
    /// The spectra of `kernel(offset, j, j')[a][b]` (m/Pa): the displacement component `a` at
    /// column `j` per unit traction component `b` on an element of column `j'`, `offset` rows
    /// behind it (field row minus source row, `−(nx−1)..=nx`). `comps` is 1 (normal, the
    /// kernel's `[0][0]`), 2 or 3, and `nx, ny ≥ 1`.
    pub fn new(
        nx: usize,
        ny: usize,
        comps: usize,
        kernel: impl Fn(isize, usize, usize) -> [[f64; 3]; 3],
    ) -> Self {
        assert!(nx >= 1 && ny >= 1 && (1..=3).contains(&comps));
        let m = next_fast_len(2 * nx);
        let nk = m / 2 + 1;
        let cn = comps * ny;
        let fft64 = Ffts::<f64>::new(m, cn);
        let forward = fft64.forward.clone();
        // the spectra and `PAD` zeros
        let mut spec_re = vec![0.0; nk * cn * cn + PAD];
        let mut spec_im = vec![0.0; nk * cn * cn + PAD];
        let mut line = forward.make_input_vec();
        let mut out = forward.make_output_vec();
        let scale = 1.0 / m as f64;
        // the offsets a linear convolution of rows 0..nx meets, and +nx (the row beyond the
        // leading edge of transient rolling), at their periodic indices (distinct: m ≥ 2nx)
        let offsets: Vec<(usize, isize)> = (0..m)
            .filter_map(|q| {
                let o = if q <= nx {
                    q as isize
                } else if q + nx > m {
                    q as isize - m as isize
                } else {
                    return None;
                };
                Some((q, o))
            })
            .collect();
        for j in 0..ny {
            for jp in 0..ny {
                let blocks: Vec<(usize, [[f64; 3]; 3])> = offsets
                    .iter()
                    .map(|&(q, o)| (q, kernel(o, j, jp)))
                    .collect();
                for a in 0..comps {
                    for b in 0..comps {
                        line.fill(0.0);
                        for (q, k) in &blocks {
                            line[*q] = k[a][b];
                        }
                        forward
                            .process(&mut line, &mut out)
                            .expect("lengths from the plan");
                        let (row, col) = (a * ny + j, b * ny + jp);
                        for (k, v) in out.iter().enumerate() {
                            let e = (k * cn + col) * cn + row;
                            spec_re[e] = v.re * scale;
                            spec_im[e] = v.im * scale;
                        }
                    }
                }
            }
        }
        StripConvolver {
            nx,
            ny,
            comps,
            m,
            fft64,
            fft32: Ffts::new(m, cn),
            single: Spectra {
                spec_re: to_single(&spec_re),
                spec_im: to_single(&spec_im),
                src_re: vec![0.0; nk * cn],
                src_im: vec![0.0; nk * cn],
                acc_re: vec![0.0; cn],
                acc_im: vec![0.0; cn],
            },
            double: Spectra {
                spec_re,
                spec_im,
                src_re: vec![0.0; nk * cn],
                src_im: vec![0.0; nk * cn],
                acc_re: vec![0.0; cn],
                acc_im: vec![0.0; cn],
            },
        }
    }

    /// Grid size `(nx, ny)` and the components per element.
    pub fn dims(&self) -> (usize, usize, usize) {
        (self.nx, self.ny, self.comps)
    }

    /// The padded length along x.
    pub fn fft_len(&self) -> usize {
        self.m
    }

    /// `u = K f` on the grid: `f[b]` the traction component `b` (Pa, `nx·ny` values each),
    /// `u[a]` the displacement component `a` (m), for the `comps` components; with `shift` = 1
    /// the field rows are `1..=nx` (one row beyond the grid's last, as transient rolling needs;
    /// [`super::Convolver::tangential`]), with 0 the grid's own rows.
    pub fn product(&mut self, f: &[&[f64]], u: &mut [&mut [f64]], shift: usize) {
        assert!(shift <= 1);
        self.product_rows(f, u, shift, self.nx);
    }

    /// `u = K f` on the `rows` field rows from row `shift` on (`shift + rows ≤ nx + 1`; `u[a]`
    /// holds `rows · ny` values): [`Self::product`] with the number of rows free, so that
    /// the extended rows `0..=nx` of transient rolling come from one product. Source columns
    /// without traction (outside the contact) are skipped.
    pub(crate) fn product_rows(
        &mut self,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        shift: usize,
        rows: usize,
    ) {
        let (nx, ny) = (self.nx, self.ny);
        let nonzero = |j: usize| f.iter().any(|fb| (0..nx).any(|i| fb[i * ny + j] != 0.0));
        let src = match (0..ny).find(|&j| nonzero(j)) {
            Some(c0) => (c0, (c0..ny).rev().find(|&j| nonzero(j)).unwrap_or(c0) + 1),
            None => (0, 0),
        };
        self.product_cols(f, u, (shift, rows), src, (0, ny));
    }

    /// `u = K f` for a traction zero outside the source columns `src = (c0, c1)`, on the field
    /// columns `field = (d0, d1)` of the field rows `shift..shift + rows` (`shift + rows ≤
    /// nx + 1`; `u[a]` holds `rows · ny` values; its other columns are left as they are).
    pub(crate) fn product_cols(
        &mut self,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        rows: (usize, usize),
        src: (usize, usize),
        field: (usize, usize),
    ) {
        self.product_in(f, u, (rows, src, field), (Precision::Double, true));
    }

    /// [`Self::product_cols`] with its dense part (the per-frequency products with the kernel's
    /// spectra) in the given precision. [`Precision::Single`]: the kernel's and the sources'
    /// spectra rounded to `f32` and the sums over the sources in `f32`, the FFTs in double
    /// precision; the relative error is of the order of single precision's 6e-8 times the
    /// conditioning of the sums; for the products of an iterative solver's inner loop, as the
    /// half-space's box products ([`super::Convolver::tangential_box`]). Compiled for each
    /// instruction set pulp dispatches to; every one gives the same bits.
    pub(crate) fn product_cols_in(
        &mut self,
        precision: Precision,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (rows, src, field): ((usize, usize), (usize, usize), (usize, usize)),
    ) {
        self.product_in(f, u, (rows, src, field), (precision, true));
    }

    /// [`Self::product_cols_in`], the dense part dispatched to the CPU's instruction set
    /// (`dispatch`) or run by the scalar reference loops (to check the bits).
    fn product_in(
        &mut self,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (rows, src, field): ((usize, usize), (usize, usize), (usize, usize)),
        (precision, dispatch): (Precision, bool),
    ) {
        self.check(f, u, rows, src, field);
        let (nx, ny) = (self.nx, self.ny);
        let dims = (self.m / 2 + 1, self.comps, ny);
        match precision {
            Precision::Single => {
                let ffts = &mut self.fft32;
                ffts.forward(f, (nx, ny), src, &mut self.single);
                Dense::apply(
                    &mut self.single,
                    &mut ffts.field,
                    dims,
                    (src, field),
                    dispatch,
                );
                ffts.inverse(u, ny, rows, field);
            }
            Precision::Double => {
                let ffts = &mut self.fft64;
                ffts.forward(f, (nx, ny), src, &mut self.double);
                Dense::apply(
                    &mut self.double,
                    &mut ffts.field,
                    dims,
                    (src, field),
                    dispatch,
                );
                ffts.inverse(u, ny, rows, field);
            }
        }
    }

    /// The argument checks of [`Self::product_cols`].
    fn check(
        &self,
        f: &[&[f64]],
        u: &[&mut [f64]],
        (shift, rows): (usize, usize),
        (c0, c1): (usize, usize),
        (d0, d1): (usize, usize),
    ) {
        let (nx, ny, c) = (self.nx, self.ny, self.comps);
        assert!(f.len() == c && u.len() == c && shift + rows <= nx + 1);
        assert!(c0 <= c1 && c1 <= ny && d0 <= d1 && d1 <= ny);
    }
}

/// The normal influence operator of a kernel invariant along x only: a one-component
/// [`StripConvolver`] and its largest self-influence, for [`super::NormalInfluence`].
#[derive(Clone)]
pub struct StripNormal {
    conv: StripConvolver,
    diag: f64,
}

impl StripNormal {
    /// The operator of `kernel(offset, j, j')` (m/Pa): the normal displacement at column `j`
    /// per unit pressure on an element of column `j'`, `offset` rows behind it
    /// (`−(nx−1)..=nx`); `nx, ny ≥ 1`.
    pub fn new(nx: usize, ny: usize, kernel: impl Fn(isize, usize, usize) -> f64) -> Self {
        let diag = (0..ny).map(|j| kernel(0, j, j)).fold(f64::MIN, f64::max);
        let conv = StripConvolver::new(nx, ny, 1, |o, j, jp| {
            let mut k = [[0.0; 3]; 3];
            k[0][0] = kernel(o, j, jp);
            k
        });
        StripNormal { conv, diag }
    }
}

impl super::NormalInfluence for StripNormal {
    fn normal(&mut self, p: &[f64], u: &mut [f64]) {
        self.conv.product(&[p], &mut [u], 0);
    }

    fn diag_n(&self) -> f64 {
        self.diag
    }
}

/// The normal and tangential influence operators of a three-component kernel invariant
/// along x only (an FE contact patch, theory §6.9): the normal term `K_nn` for
/// [`super::NormalInfluence`], the tangential block `K_xx, K_xy, K_yx, K_yy` for
/// [`super::TangentialInfluence`]. The normal–tangential couplings `K_xn, K_yn, K_nx, K_ny`
/// are not used: the normal and the tangential problems are solved one after the other, as
/// for quasi-identical bodies (the couplings' size is reported by
/// [`StripInfluence::coupling_ratio`]).
#[derive(Clone)]
pub struct StripInfluence {
    normal: StripNormal,
    tangential: StripConvolver,
    diag: [f64; 2],
    lambda_t: f64,
    coupling: f64,
    asymmetry: f64,
    uniform: [f64; 3],
    /// The symmetrised tangential kernel (x, y) at the offsets `−(nx−1)..=nx−1`,
    /// `[(o + nx − 1)·ny² + j·ny + j'][a][b]` (m/Pa), for [`Self::boxes`].
    kernel_t: Vec<[[f64; 2]; 2]>,
    /// Single-precision box products on fewer rows than the grid's: convolvers of `L` rows on
    /// the padded length `2L` (even, 5-smooth), built when a box first needs one, ascending in
    /// `L` (a box of `L' ≤ L` rows uses the first that holds it).
    boxes: Vec<StripConvolver>,
    /// Scratch of the box and extended products, `(nx + 1) · ny` each.
    bx: Vec<f64>,
    by: Vec<f64>,
    /// Scratch of the box products' sources, `nx · ny` each.
    sx: Vec<f64>,
    sy: Vec<f64>,
}

impl StripInfluence {
    /// The operators of `kernel(offset, j, j')[a][b]` (m/Pa; components x, y, normal; the
    /// displacement difference `a` at column `j` per unit traction `b` on an element of column
    /// `j'`, `offset` rows behind it, `−(nx−1)..=nx`); `nx, ny ≥ 1`. The largest eigenvalue
    /// of the tangential operator is bounded by its largest absolute row sum (Gershgorin).
    pub fn new(
        nx: usize,
        ny: usize,
        kernel: impl Fn(isize, usize, usize) -> [[f64; 3]; 3],
    ) -> Self {
        // The solvers need a symmetric operator (reciprocity, `K_ab(o, j, j') = K_ba(−o, j',
        // j)`); an FE kernel collocated at element centres under uniform element loads holds
        // it only to its discretisation: its symmetric part is used (offsets within the grid;
        // `+nx` reaches the row beyond it only), and the departure is reported.
        let mut asym = 0.0_f64;
        let mut largest = 0.0_f64;
        for o in -(nx as isize - 1)..nx as isize {
            for j in 0..ny {
                for jp in 0..ny {
                    let (k, m) = (kernel(o, j, jp), kernel(-o, jp, j));
                    for a in 0..3 {
                        for b in 0..3 {
                            asym = asym.max((k[a][b] - m[b][a]).abs());
                            largest = largest.max(k[a][b].abs());
                        }
                    }
                }
            }
        }
        let kernel = |o: isize, j: usize, jp: usize| -> [[f64; 3]; 3] {
            let k = kernel(o, j, jp);
            if o.unsigned_abs() >= nx {
                return k;
            }
            let m = kernel(-o, jp, j);
            std::array::from_fn(|a| std::array::from_fn(|b| 0.5 * (k[a][b] + m[b][a])))
        };
        let normal = StripNormal::new(nx, ny, |o, j, jp| kernel(o, j, jp)[2][2]);
        let tangential = StripConvolver::new(nx, ny, 2, kernel);
        let mut kernel_t = Vec::with_capacity((2 * nx - 1) * ny * ny);
        for o in -(nx as isize - 1)..nx as isize {
            for j in 0..ny {
                for jp in 0..ny {
                    let k = kernel(o, j, jp);
                    kernel_t.push([[k[0][0], k[0][1]], [k[1][0], k[1][1]]]);
                }
            }
        }
        let mut diag = [f64::MIN; 2];
        let mut rows = vec![0.0_f64; 2 * ny];
        let (mut coupled, mut direct) = (0.0_f64, 0.0_f64);
        for o in -(nx as isize - 1)..nx as isize {
            for j in 0..ny {
                for jp in 0..ny {
                    let k = kernel(o, j, jp);
                    for a in 0..2 {
                        rows[a * ny + j] += k[a][0].abs() + k[a][1].abs();
                        coupled = coupled.max(k[a][2].abs()).max(k[2][a].abs());
                        direct = direct.max(k[a][a].abs());
                    }
                    if o == 0 && j == jp {
                        diag[0] = diag[0].max(k[0][0]);
                        diag[1] = diag[1].max(k[1][1]);
                    }
                }
            }
        }
        let lambda_t = rows.iter().fold(0.0_f64, |m, &v| m.max(v));
        StripInfluence {
            normal,
            tangential,
            diag,
            lambda_t,
            coupling: if direct > 0.0 { coupled / direct } else { 0.0 },
            asymmetry: if largest > 0.0 { asym / largest } else { 0.0 },
            uniform: [0.0; 3],
            kernel_t,
            boxes: Vec::new(),
            bx: vec![0.0; (nx + 1) * ny],
            by: vec![0.0; (nx + 1) * ny],
            sx: vec![0.0; nx * ny],
            sy: vec![0.0; nx * ny],
        }
    }

    /// The index in [`Self::boxes`] of the convolver for a box of `rows` rows (`1 ≤ rows <
    /// nx`), built if none holds it; `None` when its padded length would be the whole grid's.
    fn box_convolver(&mut self, rows: usize) -> Option<usize> {
        let (nx, ny, _) = self.tangential.dims();
        // an even length: the real FFTs of odd lengths take a complex FFT of the whole length
        let m = (2 * rows..).step_by(2).find(|&m| next_fast_len(m) == m);
        let m = m.expect("a 5-smooth even length exists");
        if m >= self.tangential.fft_len() {
            return None;
        }
        let lb = m / 2;
        if let Some(k) = self.boxes.iter().position(|b| b.nx >= rows) {
            if self.boxes[k].nx == lb {
                return Some(k);
            }
        }
        let kt = &self.kernel_t;
        let kernel = |o: isize, j: usize, jp: usize| -> [[f64; 3]; 3] {
            // offsets up to `lb < nx`; `+lb` reaches beyond a box's rows and is never read
            let k = kt[(o + nx as isize - 1) as usize * ny * ny + j * ny + jp];
            [[k[0][0], k[0][1], 0.0], [k[1][0], k[1][1], 0.0], [0.0; 3]]
        };
        let conv = StripConvolver::new(lb, ny, 2, kernel);
        let at = self.boxes.partition_point(|b| b.nx < lb);
        self.boxes.insert(at, conv);
        Some(at)
    }

    /// These operators with a uniform compliance `c = (c_x, c_y, c_n)` (m/N, finite, of
    /// either sign) under the whole patch: the displacement `c_d F_d` of every element per
    /// total force `F_d`, i.e. `c_d ΔA` added to every coefficient of component `d`. The
    /// contact adds it to its series compliance ([`crate::contact::TransientRolling`]); the
    /// fe-patch's split against the global model is such a term, negative (theory §6.9).
    pub fn with_uniform(mut self, c_m_per_n: [f64; 3]) -> Self {
        self.uniform = c_m_per_n;
        self
    }

    /// The uniform compliance of [`Self::with_uniform`] (m/N; 0 unless set).
    pub fn uniform(&self) -> [f64; 3] {
        self.uniform
    }

    /// The largest departure of the given kernel from reciprocity, `|K_ab(o, j, j') − K_ba(−o,
    /// j', j)|`, over its largest coefficient (−): what symmetrising it changed (0 for the
    /// half-space).
    pub fn asymmetry(&self) -> f64 {
        self.asymmetry
    }

    /// The largest normal–tangential coupling coefficient over the largest direct tangential
    /// one (−): the size of what [`StripInfluence`] leaves out (0 for quasi-identical bodies).
    pub fn coupling_ratio(&self) -> f64 {
        self.coupling
    }
}

impl super::NormalInfluence for StripInfluence {
    fn normal(&mut self, p: &[f64], u: &mut [f64]) {
        self.normal.normal(p, u);
    }

    fn diag_n(&self) -> f64 {
        self.normal.diag_n()
    }
}

impl super::TangentialInfluence for StripInfluence {
    fn dims(&self) -> (usize, usize) {
        let (nx, ny, _) = self.tangential.dims();
        (nx, ny)
    }
    fn diag_xx(&self) -> f64 {
        self.diag[0]
    }
    fn diag_yy(&self) -> f64 {
        self.diag[1]
    }
    fn lambda_max_t(&self) -> f64 {
        self.lambda_t
    }
    fn tangential(&mut self, tx: &[f64], ty: &[f64], ux: &mut [f64], uy: &mut [f64], shift: usize) {
        self.tangential.product(&[tx, ty], &mut [ux, uy], shift);
    }
    fn tangential_ext(&mut self, tx: &[f64], ty: &[f64], ux: &mut [f64], uy: &mut [f64]) {
        let n = (self.tangential.nx + 1) * self.tangential.ny;
        self.tangential.product_rows(
            &[tx, ty],
            &mut [&mut ux[..n], &mut uy[..n]],
            0,
            self.tangential.nx + 1,
        );
    }
    fn tangential_box(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
        (r0, r1): (usize, usize),
        (c0, c1): (usize, usize),
    ) {
        let (nx, ny, _) = self.tangential.dims();
        let (r1, c1) = (r1.min(nx), c1.min(ny));
        let (r0, c0) = (r0.min(r1), c0.min(c1));
        let cols = (c0, c1);
        let rows = r1 - r0;
        let found = if rows > 0 {
            self.box_convolver(rows)
        } else {
            None
        };
        let (bx, by) = (&mut self.bx[..nx * ny], &mut self.by[..nx * ny]);
        let offset = match found {
            Some(k) => {
                // the box's rows first, then zeros to the convolver's rows
                let conv = &mut self.boxes[k];
                let n = conv.nx * ny;
                let (sx, sy) = (&mut self.sx[..n], &mut self.sy[..n]);
                sx[..rows * ny].copy_from_slice(&tx[r0 * ny..r1 * ny]);
                sy[..rows * ny].copy_from_slice(&ty[r0 * ny..r1 * ny]);
                sx[rows * ny..].fill(0.0);
                sy[rows * ny..].fill(0.0);
                conv.product_cols_in(
                    Precision::Single,
                    &[sx, sy],
                    &mut [&mut bx[..n], &mut by[..n]],
                    ((0, rows), cols, cols),
                );
                r0
            }
            None => {
                self.tangential.product_cols_in(
                    Precision::Single,
                    &[tx, ty],
                    &mut [bx, by],
                    ((0, nx), cols, cols),
                );
                0
            }
        };
        for i in r0..r1 {
            for j in 0..ny {
                let (e, b) = (i * ny + j, (i - offset) * ny + j);
                let inside = (c0..c1).contains(&j);
                ux[e] = if inside { self.bx[b] } else { 0.0 };
                uy[e] = if inside { self.by[b] } else { 0.0 };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Precision, StripConvolver, StripInfluence};
    use crate::contact::influence::TangentialInfluence;

    /// A kernel coupling all components, not Toeplitz across the rail, decaying along it.
    fn kernel(o: isize, j: usize, jp: usize) -> [[f64; 3]; 3] {
        let r = 1.0 + (o * o) as f64 + 0.5 * (j as f64 - jp as f64).powi(2);
        let w = 1.0 + 0.1 * j as f64 + 0.03 * (jp * jp) as f64;
        std::array::from_fn(|a| {
            std::array::from_fn(|b| if a == b { w / r } else { 0.2 * w / r.sqrt() } * 1e-11)
        })
    }

    #[test]
    fn dispatched_products_give_the_plain_loops_bits_and_single_precision_is_within_1e_6() {
        // runs of field rows shorter and longer than a chunk, and every kind of last chunk
        for (nx, ny, comps) in [(7, 4, 2), (9, 13, 2), (12, 3, 3), (32, 24, 2), (5, 40, 2)] {
            let mut conv = StripConvolver::new(nx, ny, comps, kernel);
            let n = nx * ny;
            let f: Vec<Vec<f64>> = (0..comps)
                .map(|b| {
                    (0..n)
                        .map(|k| (((k + 3 * b) * 7919) % 13) as f64 * 1e6 - 4e6)
                        .collect()
                })
                .collect();
            let fr: Vec<&[f64]> = f.iter().map(|v| v.as_slice()).collect();
            for (c0, c1) in [(0, ny), (1, ny.min(10)), (ny / 2, ny / 2 + 1)] {
                let mut out = |mode: u8| {
                    let mut u = vec![vec![0.0; n]; comps];
                    let mut ur: Vec<&mut [f64]> = u.iter_mut().map(|v| v.as_mut_slice()).collect();
                    let (rows, cols) = ((0, nx), (c0, c1));
                    match mode {
                        0 => conv.product_in(
                            &fr,
                            &mut ur,
                            (rows, cols, cols),
                            (Precision::Double, true),
                        ),
                        1 => conv.product_in(
                            &fr,
                            &mut ur,
                            (rows, cols, cols),
                            (Precision::Double, false),
                        ),
                        2 => conv.product_in(
                            &fr,
                            &mut ur,
                            (rows, cols, cols),
                            (Precision::Single, true),
                        ),
                        _ => conv.product_in(
                            &fr,
                            &mut ur,
                            (rows, cols, cols),
                            (Precision::Single, false),
                        ),
                    }
                    u
                };
                let (double, double_plain) = (out(0), out(1));
                let (dispatched, plain) = (out(2), out(3));
                let scale = double.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
                for a in 0..comps {
                    for e in 0..n {
                        assert_eq!(
                            double[a][e].to_bits(),
                            double_plain[a][e].to_bits(),
                            "{nx}×{ny}×{comps} cols {c0}..{c1}: {a} {e}"
                        );
                        assert_eq!(
                            dispatched[a][e].to_bits(),
                            plain[a][e].to_bits(),
                            "{nx}×{ny}×{comps} cols {c0}..{c1}: {a} {e}"
                        );
                        let d = (dispatched[a][e] - double[a][e]).abs();
                        assert!(d <= 1e-6 * scale, "{nx}×{ny} {a} {e}: {d:e} of {scale:e}");
                    }
                }
            }
        }
    }

    #[test]
    fn box_products_equal_a_direct_sum_of_the_symmetrised_kernel() {
        // boxes of the whole grid and of fewer rows (their own padded lengths, built in turn,
        // and one reused by a smaller box), against `Σ K_sym(i − i', j, j') τ(i', j')`
        let (nx, ny) = (32, 24);
        let mut op = StripInfluence::new(nx, ny, kernel);
        let sym = |o: isize, j: usize, jp: usize, a: usize, b: usize| {
            0.5 * (kernel(o, j, jp)[a][b] + kernel(-o, jp, j)[b][a])
        };
        let n = nx * ny;
        for (rows, cols) in [
            ((0, nx), (0, ny)),
            ((3, 10), (2, 20)),
            ((5, 26), (4, 19)),
            ((0, 7), (0, 24)),
            ((31, 32), (11, 12)),
            ((2, 30), (6, 18)),
        ] {
            let inside = |e: usize| {
                (rows.0..rows.1).contains(&(e / ny)) && (cols.0..cols.1).contains(&(e % ny))
            };
            let t = |b: usize| -> Vec<f64> {
                (0..n)
                    .map(|e| {
                        let v = (((e + 5 * b) * 7919) % 13) as f64 * 1e6 - 4e6;
                        if inside(e) {
                            v
                        } else {
                            0.0
                        }
                    })
                    .collect()
            };
            let (tx, ty) = (t(0), t(1));
            let (mut ux, mut uy) = (vec![7.0; n], vec![7.0; n]);
            op.tangential_box(&tx, &ty, &mut ux, &mut uy, rows, cols);
            let direct = |e: usize, a: usize| -> f64 {
                let (i, j) = (e / ny, e % ny);
                (0..n)
                    .filter(|&s| inside(s))
                    .map(|s| {
                        let o = i as isize - (s / ny) as isize;
                        sym(o, j, s % ny, a, 0) * tx[s] + sym(o, j, s % ny, a, 1) * ty[s]
                    })
                    .sum()
            };
            let expect: Vec<[f64; 2]> = (0..n).map(|e| [direct(e, 0), direct(e, 1)]).collect();
            let scale = expect.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
            for e in 0..n {
                let got = [ux[e], uy[e]];
                for a in 0..2 {
                    if inside(e) {
                        let d = (got[a] - expect[e][a]).abs();
                        assert!(
                            d <= 1e-6 * scale,
                            "{rows:?} {cols:?} {e} {a}: {d:e} of {scale:e}"
                        );
                    } else if (rows.0..rows.1).contains(&(e / ny)) {
                        assert_eq!(
                            got[a], 0.0,
                            "{rows:?} {cols:?} {e} {a}: outside the columns"
                        );
                    } else {
                        assert_eq!(
                            got[a], 7.0,
                            "{rows:?} {cols:?} {e} {a}: a row outside the box"
                        );
                    }
                }
            }
        }
    }
}

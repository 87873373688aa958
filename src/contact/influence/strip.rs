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
use rustfft::num_complex::Complex64;
use std::sync::Arc;

use super::{coefficients, next_fast_len};

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
    /// [`Self::product_cols`].
    double: Spectra<f64>,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
    line: Vec<f64>,
    /// One column's spectrum (`m/2 + 1`).
    spectrum: Vec<Complex64>,
    /// Field spectra, one row of `m/2 + 1` per field column `a·ny + j`.
    field: Vec<Complex64>,
    scratch: Vec<Complex64>,
    /// [`Self::double`] rounded to single precision, for [`Precision::Single`].
    single: Spectra<f32>,
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
    /// (`[k][source][row]`), divided by `m`.
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
}

impl DenseReal for f32 {}
impl DenseReal for f64 {}

/// The dense part of a strip product, in precision `T`: per frequency `k`, the field spectra
/// of the columns `d0..d1` of every component (computed as one run of rows from the first
/// component's `d0` to the last one's `d1`), `y = S_k x` over the source columns `c0..c1`
/// of every component, as a sum of columns of `S_k` (stored source-major, `[k][s][r]`) scaled
/// by the source spectrum `x_s`: contiguous element-wise updates, no reductions, so any
/// vector width gives the same bits. Into `field[(a·ny + j)·nk + k]`.
struct Dense<'a, T> {
    spectra: &'a mut Spectra<T>,
    field: &'a mut [Complex64],
    /// `(nk, comps, ny)`
    dims: (usize, usize, usize),
    cols: (usize, usize),
    field_cols: (usize, usize),
}

impl<T: DenseReal> Dense<'_, T> {
    /// The loops, for any instruction set ([`pulp::WithSimd`] compiles them for each).
    #[inline(always)]
    fn run(self) {
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
        // one contiguous run of rows from the first component's first field column to the
        // last one's last (the columns between, outside the field, are computed and unused)
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
                    self.field[r * nk + k] = Complex64::new(yr[r].into(), yi[r].into());
                }
            }
        }
    }
}

impl<T: DenseReal> Dense<'_, T> {
    /// The dense part of `spectra` into `field` ([`Self::run`]; `dims` = `(nk, comps, ny)`,
    /// the source and field columns), compiled for the CPU's instruction set (`dispatch`) or
    /// for the baseline target only.
    fn apply(
        spectra: &mut Spectra<T>,
        field: &mut [Complex64],
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
            dense.run();
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, checked on the line above.
            unsafe { run_avx512(dense) };
            return;
        }
        pulp::Arch::new().dispatch(dense);
    }
}

/// [`Dense::run`] compiled for AVX-512 (pulp 0.22 dispatches up to AVX2 on stable Rust; the
/// loops are element-wise, so the wider vectors give the same bits).
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn run_avx512<T: DenseReal>(dense: Dense<'_, T>) {
    dense.run();
}

impl<T: DenseReal> pulp::WithSimd for Dense<'_, T> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.run();
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
        let mut planner = RealFftPlanner::<f64>::new();
        let forward = planner.plan_fft_forward(m);
        let inverse = planner.plan_fft_inverse(m);
        let cn = comps * ny;
        let mut spec_re = vec![0.0; nk * cn * cn];
        let mut spec_im = vec![0.0; nk * cn * cn];
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
        let scratch_len = forward
            .get_scratch_len()
            .max(inverse.get_scratch_len())
            .max(1);
        StripConvolver {
            nx,
            ny,
            comps,
            m,
            line,
            spectrum: vec![Complex64::new(0.0, 0.0); nk],
            single: Spectra {
                spec_re: spec_re.iter().map(|&v| v as f32).collect(),
                spec_im: spec_im.iter().map(|&v| v as f32).collect(),
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
            field: vec![Complex64::new(0.0, 0.0); cn * nk],
            scratch: vec![Complex64::new(0.0, 0.0); scratch_len],
            forward,
            inverse,
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
    /// (`dispatch`) or compiled for the baseline target only (to check the bits).
    fn product_in(
        &mut self,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (rows, src, field): ((usize, usize), (usize, usize), (usize, usize)),
        (precision, dispatch): (Precision, bool),
    ) {
        self.check(f, u, rows, src, field);
        self.forward(f, src);
        let dims = (self.m / 2 + 1, self.comps, self.ny);
        let out = &mut self.field[..];
        if precision == Precision::Single {
            let (nk, c, ny) = dims;
            let cn = c * ny;
            let (d, f32s) = (&self.double, &mut self.single);
            for k in 0..nk {
                for b in 0..c {
                    let e = k * cn + b * ny;
                    for e in e + src.0..e + src.1 {
                        f32s.src_re[e] = d.src_re[e] as f32;
                        f32s.src_im[e] = d.src_im[e] as f32;
                    }
                }
            }
            Dense::apply(&mut self.single, out, dims, (src, field), dispatch);
        } else {
            Dense::apply(&mut self.double, out, dims, (src, field), dispatch);
        }
        self.inverse(u, rows, field);
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

    /// The spectra along x of the source columns `c0..c1` of every component, into
    /// the double-precision source spectra (`[k][b·ny + j']`).
    fn forward(&mut self, f: &[&[f64]], (c0, c1): (usize, usize)) {
        let (nx, ny, c) = (self.nx, self.ny, self.comps);
        let cn = c * ny;
        for b in 0..c {
            for jp in c0..c1 {
                self.line.fill(0.0);
                for i in 0..nx {
                    self.line[i] = f[b][i * ny + jp];
                }
                self.forward
                    .process_with_scratch(&mut self.line, &mut self.spectrum, &mut self.scratch)
                    .expect("lengths from the plan");
                let s = b * ny + jp;
                for (k, v) in self.spectrum.iter().enumerate() {
                    self.double.src_re[k * cn + s] = v.re;
                    self.double.src_im[k * cn + s] = v.im;
                }
            }
        }
    }

    /// The inverse FFTs of the field spectra of the columns `d0..d1` into the field rows
    /// `shift..shift + rows` of `u`.
    fn inverse(
        &mut self,
        u: &mut [&mut [f64]],
        (shift, rows): (usize, usize),
        (d0, d1): (usize, usize),
    ) {
        let (ny, c, m) = (self.ny, self.comps, self.m);
        let nk = m / 2 + 1;
        for a in 0..c {
            for j in d0..d1 {
                let row = &mut self.field[(a * ny + j) * nk..(a * ny + j + 1) * nk];
                // the imaginary parts of the zero and Nyquist bins are round-off of a real kernel
                row[0].im = 0.0;
                if m % 2 == 0 {
                    row[nk - 1].im = 0.0;
                }
                self.inverse
                    .process_with_scratch(row, &mut self.line, &mut self.scratch)
                    .expect("lengths from the plan");
                for i in 0..rows {
                    u[a][i * ny + j] = self.line[i + shift];
                }
            }
        }
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
    /// Scratch of the box and extended products, `(nx + 1) · ny` each.
    bx: Vec<f64>,
    by: Vec<f64>,
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
            bx: vec![0.0; (nx + 1) * ny],
            by: vec![0.0; (nx + 1) * ny],
        }
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
        let (bx, by) = (&mut self.bx[..nx * ny], &mut self.by[..nx * ny]);
        let (rows, cols) = ((0, nx), (c0, c1));
        self.tangential.product_cols_in(
            Precision::Single,
            &[tx, ty],
            &mut [bx, by],
            (rows, cols, cols),
        );
        for i in r0..r1 {
            for j in 0..ny {
                let e = i * ny + j;
                let inside = (c0..c1).contains(&j);
                ux[e] = if inside { self.bx[e] } else { 0.0 };
                uy[e] = if inside { self.by[e] } else { 0.0 };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Precision, StripConvolver};

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
        // every remainder of the eight-lane dot products (source widths 1..=9 and the grid's)
        for (nx, ny, comps) in [(7, 4, 2), (9, 13, 2), (12, 3, 3), (32, 24, 2)] {
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
}

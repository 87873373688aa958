//! The dense part of a strip product (`super::StripConvolver`): per frequency along x, the
//! field spectra as a sum of the kernel's spectral columns scaled by the source spectra, in
//! double or single precision, in vector registers on AVX-512 or AVX2 where the CPU has either
//! (`contact::column_sums`), else as plain loops pulp compiles for the CPU's instruction set;
//! every route gives the plain loops' bits.

#[cfg(target_arch = "x86_64")]
use crate::contact::column_sums::{Lanes, Sums};

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
    /// The field spectra `[k][a·ny + j]`, the sums' accumulators: `c·ny` per frequency, then
    /// [`PAD`] values (a vector block's store may reach past its run's last row into rows
    /// not yet computed or not read).
    pub(super) field_re: Vec<T>,
    pub(super) field_im: Vec<T>,
    /// Which parts of the kernel's spectra are not zero, per block of components
    /// (`parts[a·c + b]`, field component `a`, source component `b`), over every frequency.
    pub(super) parts: Vec<Part>,
}

impl<T: DenseReal> Spectra<T> {
    /// The spectra of a kernel (`spec_re`, `spec_im` as [`Spectra::spec_re`], `nk` frequencies,
    /// `c` components of `ny` columns) with the buffers of the products.
    pub(super) fn new(
        spec_re: Vec<T>,
        spec_im: Vec<T>,
        (nk, c, ny): (usize, usize, usize),
    ) -> Self {
        let cn = c * ny;
        let zero = T::default();
        let block_is_zero = |spec: &[T], a: usize, b: usize| {
            (0..nk).all(|k| {
                (0..ny).all(|jp| {
                    let col = (k * cn + b * ny + jp) * cn + a * ny;
                    spec[col..col + ny].iter().all(|v| *v == zero)
                })
            })
        };
        let parts = (0..c * c)
            .map(|ab| {
                let (a, b) = (ab / c, ab % c);
                match (block_is_zero(&spec_re, a, b), block_is_zero(&spec_im, a, b)) {
                    (false, true) => Part::Real,
                    (true, false) => Part::Imaginary,
                    (true, true) => Part::Zero,
                    (false, false) => Part::Complex,
                }
            })
            .collect();
        Spectra {
            spec_re,
            spec_im,
            src_re: vec![zero; nk * cn],
            src_im: vec![zero; nk * cn],
            field_re: vec![zero; nk * cn + PAD],
            field_im: vec![zero; nk * cn + PAD],
            parts,
        }
    }
}

/// Which parts of a block of a kernel's spectra are not zero. A kernel row even in x (the
/// direct terms of a body symmetric about a plane across the rail) has real spectra, one odd
/// in x (the x–y couplings) imaginary ones, an uncoupled pair of components none; the sums
/// skip the zero parts' products.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Part {
    /// Both parts: `y += (a·xr − b·xi) + i (a·xi + b·xr)`.
    Complex,
    /// The real part only (`b = 0`): `y += a·xr + i a·xi`.
    Real,
    /// The imaginary part only (`a = 0`): `y += −b·xi + i b·xr`.
    Imaginary,
    /// Neither: no products.
    Zero,
}

/// The real type of a strip product's dense part: `f64`, or `f32` for the inner loops.
pub(super) trait DenseReal:
    Copy
    + Default
    + PartialEq
    + Into<f64>
    + std::ops::Mul<Output = Self>
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::AddAssign
{
    /// `v` rounded to this precision.
    fn from_f64(v: f64) -> Self;
    /// The vector lanes of this precision on AVX2 and on AVX-512 (`contact::column_sums`).
    #[cfg(target_arch = "x86_64")]
    type Avx2: Lanes<T = Self>;
    #[cfg(target_arch = "x86_64")]
    type Avx512: Lanes<T = Self>;
}

impl DenseReal for f32 {
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[cfg(target_arch = "x86_64")]
    type Avx2 = crate::contact::avx2::strip::F32x8;
    #[cfg(target_arch = "x86_64")]
    type Avx512 = crate::contact::avx512::strip::F32x16;
}
impl DenseReal for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
    #[cfg(target_arch = "x86_64")]
    type Avx2 = crate::contact::avx2::strip::F64x4;
    #[cfg(target_arch = "x86_64")]
    type Avx512 = crate::contact::avx512::strip::F64x8;
}

/// Which code computes the dense part: the plain loops (compiled by pulp for the CPU's
/// instruction set, or as written for the scalar reference) or the register blocks of
/// `contact::column_sums` on AVX2 or AVX-512. Every route gives the same bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Route {
    /// The plain loops.
    Plain,
    /// The register blocks on AVX2 (8 `f32` or 4 `f64` lanes).
    Avx2,
    /// The register blocks on AVX-512F (16 `f32` or 8 `f64` lanes).
    Avx512,
}

impl Route {
    /// The fastest route the CPU supports: AVX-512, else AVX2, else the plain loops.
    pub(crate) fn best() -> Route {
        Route::available().last().unwrap_or(Route::Plain)
    }

    /// The routes the CPU supports, the plain loops first.
    pub(crate) fn available() -> impl Iterator<Item = Route> + Clone {
        #[cfg(target_arch = "x86_64")]
        let (avx2, avx512) = (
            std::arch::is_x86_feature_detected!("avx2"),
            std::arch::is_x86_feature_detected!("avx512f"),
        );
        #[cfg(not(target_arch = "x86_64"))]
        let (avx2, avx512) = (false, false);
        [
            (Route::Plain, true),
            (Route::Avx2, avx2),
            (Route::Avx512, avx512),
        ]
        .into_iter()
        .filter_map(|(r, ok)| ok.then_some(r))
    }

    /// The values of `T` in one of the route's vectors (1 for the plain loops).
    #[cfg(target_arch = "x86_64")]
    fn lanes<T>(self) -> usize {
        let bytes = match self {
            Route::Plain => return 1,
            Route::Avx2 => 32,
            Route::Avx512 => 64,
        };
        bytes / std::mem::size_of::<T>()
    }
}

/// The dense part of a strip product, in precision `T`: per frequency `k`, the field spectra
/// of the columns `d0..d1` of every component (one run of rows per component, or in vector
/// registers one run from the first component's `d0` to the last one's `d1` where that takes
/// no more vectors and every block is complex), `y = S_k x` over the source columns `c0..c1`
/// of every component, as a sum of columns of `S_k` (stored source-major, `[k][s][r]`) scaled
/// by the source spectrum `x_s`: contiguous element-wise updates, no reductions, so any
/// vector width gives the same bits. Into the spectra's field spectra (`[k][a·ny + j]`).
pub(super) struct Dense<'a, T> {
    spectra: &'a mut Spectra<T>,
    /// `(nk, comps, ny)`
    dims: (usize, usize, usize),
    cols: (usize, usize),
    field_cols: (usize, usize),
}

/// The kernel's spectra below this fraction of their largest are zero (`flush`), in both
/// precisions: far below single precision's resolution (6e-8) and double's relative
/// round-off of the largest (1e-16). They are the round-off of the imaginary parts of kernel
/// rows even in x and of the real parts of rows odd in x (about 1e-16 of the largest): made
/// zero, a block of such rows has one part ([`Part`]) and its sums skip the other's products;
/// in single precision their products with the sources' spectra would be subnormal, which the
/// CPU computes many times slower (the box product of `strip_bench` took about three times as
/// long with them).
const FLUSH: f64 = 1e-12;

/// `v`'s values below [`FLUSH`] times `largest` made zero.
pub(super) fn flush(v: &mut [f64], largest: f64) {
    let tiny = FLUSH * largest;
    for x in v.iter_mut().filter(|x| x.abs() < tiny) {
        *x = 0.0;
    }
}

/// `v` rounded to `f32`.
pub(super) fn to_single(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// Zeros after the kernel's spectra: the vector sums' last block reads less than one vector
/// (at most 16 `f32` or 8 `f64`) past a column's run (`contact::column_sums`); the margin is
/// four.
pub(super) const PAD: usize = 64;

impl<T: DenseReal> Dense<'_, T> {
    /// [`Self::run_reference`] in vector registers (`contact::column_sums`) on `isa`: per
    /// frequency, the sums over the sources in blocks of rows held in registers, the same
    /// operations in the same order per element, so the same bits.
    ///
    /// # Safety
    /// The CPU must support `isa`, a vector route ([`Route::Avx2`] or [`Route::Avx512`]).
    #[cfg(target_arch = "x86_64")]
    unsafe fn run_vectors(self, isa: Route) {
        let (nk, c, ny) = self.dims;
        let ((c0, c1), (d0, d1)) = (self.cols, self.field_cols);
        let cn = c * ny;
        // the sources' columns inside the kernel's (the kernel reads them unchecked)
        assert!(c0 <= c1 && c1 <= ny && d1 <= ny);
        let Some((r0, r1)) = self.run_rows() else {
            return;
        };
        // one run across the components if every block of the kernel is complex and that
        // takes no more vectors, else one per component (a box narrower than the grid: the
        // columns between are not computed; a block with a zero part: its products skipped)
        let vectors = |n: usize| n.div_ceil(isa.lanes::<T>());
        let parts = &self.spectra.parts;
        let across =
            parts.iter().all(|p| *p == Part::Complex) && vectors(r1 - r0) <= c * vectors(d1 - d0);
        // the runs, each with its groups of sources (one per source component), on the stack:
        // a product runs in every inner-CG iteration
        let mut runs = [((0, 0), [(Part::Complex, 0, 0); 3]); 3];
        let n_runs = if across { 1 } else { c };
        for (a, (rows, groups)) in runs.iter_mut().enumerate().take(n_runs) {
            *rows = if across {
                (r0, r1)
            } else {
                (a * ny + d0, a * ny + d1)
            };
            for (b, g) in groups.iter_mut().enumerate().take(c) {
                let part = if across {
                    Part::Complex
                } else {
                    parts[a * c + b]
                };
                *g = (part, b * ny + c0, b * ny + c1);
            }
        }
        for k in 0..nk {
            for (rows, groups) in &runs[..n_runs] {
                let groups = &groups[..c];
                let s = &mut *self.spectra;
                let sums = Sums {
                    spec_re: &s.spec_re[k * cn * cn..],
                    spec_im: &s.spec_im[k * cn * cn..],
                    src_re: &s.src_re[k * cn..(k + 1) * cn],
                    src_im: &s.src_im[k * cn..(k + 1) * cn],
                    acc_re: &mut s.field_re[k * cn..],
                    acc_im: &mut s.field_im[k * cn..],
                    cn,
                    rows: *rows,
                };
                // the kernel's contract: every column's run and the margin beyond lie inside
                assert!((cn - 1) * cn + rows.1 + PAD <= sums.spec_re.len().min(sums.spec_im.len()));
                assert!(rows.1 <= cn && groups.iter().all(|g| g.2 <= cn));
                assert!(rows.1 + PAD <= sums.acc_re.len().min(sums.acc_im.len()));
                // SAFETY: the instruction set is the caller's contract; the bounds are checked
                // above.
                unsafe {
                    match isa {
                        Route::Avx512 => T::Avx512::run(sums, groups),
                        Route::Avx2 => T::Avx2::run(sums, groups),
                        Route::Plain => unreachable!("the plain loops have no vector sums"),
                    }
                }
            }
        }
    }

    /// The loops, for any instruction set ([`pulp::WithSimd`] compiles them for each), and the
    /// scalar reference the vector kernels' bits are tested against: per frequency `k`, the
    /// field spectra of the run of rows, a sum of kernel columns scaled by the source spectra,
    /// each element's products those of its block's [`Part`].
    #[inline(always)]
    fn run_reference(self) {
        let (nk, c, ny) = self.dims;
        let ((c0, c1), (d0, d1)) = (self.cols, self.field_cols);
        let cn = c * ny;
        for k in 0..nk {
            let Spectra {
                spec_re,
                spec_im,
                src_re,
                src_im,
                field_re,
                field_im,
                parts,
            } = &mut *self.spectra;
            for a in 0..c {
                let (r0, r1) = (a * ny + d0, a * ny + d1);
                let (yr, yi) = (
                    &mut field_re[k * cn + r0..k * cn + r1],
                    &mut field_im[k * cn + r0..k * cn + r1],
                );
                yr.fill(T::default());
                yi.fill(T::default());
                for b in 0..c {
                    for jp in c0..c1 {
                        let s = b * ny + jp;
                        let (xr, xi) = (src_re[k * cn + s], src_im[k * cn + s]);
                        let col = (k * cn + s) * cn;
                        let (sr, si) = (&spec_re[col + r0..col + r1], &spec_im[col + r0..col + r1]);
                        let elements = yr.iter_mut().zip(yi.iter_mut()).zip(sr.iter().zip(si));
                        match parts[a * c + b] {
                            Part::Complex => {
                                for ((yr, yi), (ar, ai)) in elements {
                                    *yr += *ar * xr - *ai * xi;
                                    *yi += *ar * xi + *ai * xr;
                                }
                            }
                            Part::Real => {
                                for ((yr, yi), (ar, _)) in elements {
                                    *yr += *ar * xr;
                                    *yi += *ar * xi;
                                }
                            }
                            Part::Imaginary => {
                                for ((yr, yi), (_, ai)) in elements {
                                    *yr = *yr - *ai * xi;
                                    *yi += *ai * xr;
                                }
                            }
                            Part::Zero => {}
                        }
                    }
                }
            }
        }
    }

    /// The run of field rows a run across the components covers: from the first component's
    /// first field column to the last one's last (the columns between, outside the field,
    /// are computed and unused); `None` if empty.
    #[cfg(target_arch = "x86_64")]
    fn run_rows(&self) -> Option<(usize, usize)> {
        let (_, c, ny) = self.dims;
        let (d0, d1) = self.field_cols;
        let (r0, r1) = (d0, (c - 1) * ny + d1);
        (r0 < r1).then_some((r0, r1))
    }
}

impl<T: DenseReal> Dense<'_, T> {
    /// The dense part of `spectra` into its field spectra (`dims` = `(nk, comps, ny)`,
    /// the source and field columns) by `route`; `None`: the plain loops as written, the
    /// scalar reference [`Self::run_reference`] (to check the bits), not compiled for the
    /// CPU's instruction set.
    pub(super) fn apply(
        spectra: &mut Spectra<T>,
        dims: (usize, usize, usize),
        (cols, field_cols): ((usize, usize), (usize, usize)),
        route: Option<Route>,
    ) {
        let dense = Dense {
            spectra,
            dims,
            cols,
            field_cols,
        };
        match route {
            None => dense.run_reference(),
            Some(Route::Plain) => pulp::Arch::new().dispatch(dense),
            #[cfg(target_arch = "x86_64")]
            Some(isa) => {
                assert!(
                    Route::available().any(|r| r == isa),
                    "the CPU lacks the instruction set of {isa:?}"
                );
                // SAFETY: the CPU supports `isa`, checked on the line above.
                unsafe { dense.run_vectors(isa) }
            }
            #[cfg(not(target_arch = "x86_64"))]
            Some(_) => unreachable!("no vector routes off x86-64"),
        }
    }
}

impl<T: DenseReal> pulp::WithSimd for Dense<'_, T> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        self.run_reference();
    }
}

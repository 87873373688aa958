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

mod dense;
mod operators;

pub(crate) use dense::Part;
use dense::{flush, to_single, Dense, DenseReal, Route, Spectra, PAD};
pub use operators::{StripInfluence, StripNormal};

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
    scratch: Vec<Complex<T>>,
}

impl<T: FftNum + DenseReal> Ffts<T> {
    /// The plans of length `m` and their buffers.
    fn new(m: usize) -> Self {
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
            scratch: vec![zero; scratch_len],
            forward,
            inverse,
        }
    }

    /// `u = K f` in this precision ([`StripConvolver::product_in`]): the sources' FFTs into
    /// `spectra`, the dense part, the inverse FFTs (`dims` = `(nk, comps, ny)`).
    fn product(
        &mut self,
        spectra: &mut Spectra<T>,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (nx, dims): (usize, (usize, usize, usize)),
        (rows, src, field): ((usize, usize), (usize, usize), (usize, usize)),
        route: Option<Route>,
    ) {
        let ny = dims.2;
        self.forward(f, (nx, ny), src, spectra);
        Dense::apply(spectra, dims, (src, field), route);
        self.inverse(spectra, u, ny, rows, field);
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

    /// The inverse FFTs of `spectra`'s field spectra of the columns `d0..d1` into the field
    /// rows `shift..shift + rows` of `u` (`ny` columns each).
    fn inverse(
        &mut self,
        spectra: &Spectra<T>,
        u: &mut [&mut [f64]],
        ny: usize,
        (shift, rows): (usize, usize),
        (d0, d1): (usize, usize),
    ) {
        let nk = self.spectrum.len();
        let cn = u.len() * ny;
        let even = self.line.len().is_multiple_of(2);
        for (a, ua) in u.iter_mut().enumerate() {
            for j in d0..d1 {
                let r = a * ny + j;
                let row = &mut self.spectrum;
                for (k, v) in row.iter_mut().enumerate() {
                    *v = Complex::new(spectra.field_re[k * cn + r], spectra.field_im[k * cn + r]);
                }
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
    /// The tractions rounded to `f32`, then the FFTs along x and the per-frequency products
    /// with the kernel's spectra in `f32`.
    Single,
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
        let fft64 = Ffts::<f64>::new(m);
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
        // the largest spectral value, real or imaginary: the scale of the flush to zero of
        // the round-off parts (of rows even or odd in x)
        let largest = spec_re
            .iter()
            .chain(&spec_im)
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        flush(&mut spec_re, largest);
        flush(&mut spec_im, largest);
        StripConvolver {
            nx,
            ny,
            comps,
            m,
            fft64,
            fft32: Ffts::new(m),
            single: Spectra::new(to_single(&spec_re), to_single(&spec_im), (nk, comps, ny)),
            double: Spectra::new(spec_re, spec_im, (nk, comps, ny)),
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
        self.product_in(
            f,
            u,
            (rows, src, field),
            (Precision::Double, Some(Route::best())),
        );
    }

    /// [`Self::product_cols`] in the given precision. [`Precision::Single`]: the tractions and
    /// the kernel's spectra rounded to `f32`, the FFTs along x and the sums over the sources
    /// in `f32`; the relative error is of the order of single precision's 6e-8 times the
    /// FFTs' length's logarithm and the conditioning of the sums; for the products of an
    /// iterative solver's inner loop, as the half-space's box products
    /// ([`super::Convolver::tangential_box`]). The dense part runs in vector registers on
    /// AVX-512 or AVX2 where the CPU has either, else compiled for each instruction set pulp
    /// dispatches to ([`Route::best`]); every one gives the same bits.
    pub(crate) fn product_cols_in(
        &mut self,
        precision: Precision,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (rows, src, field): ((usize, usize), (usize, usize), (usize, usize)),
    ) {
        self.product_in(f, u, (rows, src, field), (precision, Some(Route::best())));
    }

    /// [`Self::product_cols_in`], the dense part by `route`, or by the scalar reference loops
    /// (`None`, to check the bits).
    fn product_in(
        &mut self,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (rows, src, field): ((usize, usize), (usize, usize), (usize, usize)),
        (precision, route): (Precision, Option<Route>),
    ) {
        self.check(f, u, rows, src, field);
        let (nx, ny) = (self.nx, self.ny);
        let dims = (self.m / 2 + 1, self.comps, ny);
        let rows_src_field = (rows, src, field);
        match precision {
            Precision::Single => {
                self.fft32
                    .product(&mut self.single, f, u, (nx, dims), rows_src_field, route)
            }
            Precision::Double => {
                self.fft64
                    .product(&mut self.double, f, u, (nx, dims), rows_src_field, route)
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

/// A kernel coupling all components, not Toeplitz across the rail, decaying along it: the
/// tests' (here and in `operators`).
#[cfg(test)]
fn test_kernel(o: isize, j: usize, jp: usize) -> [[f64; 3]; 3] {
    let r = 1.0 + (o * o) as f64 + 0.5 * (j as f64 - jp as f64).powi(2);
    let w = 1.0 + 0.1 * j as f64 + 0.03 * (jp * jp) as f64;
    std::array::from_fn(|a| {
        std::array::from_fn(|b| if a == b { w / r } else { 0.2 * w / r.sqrt() } * 1e-11)
    })
}

#[cfg(test)]
mod tests {
    use super::{Part, Precision, Route, StripConvolver};

    /// A kernel coupling all components, not Toeplitz across the rail, decaying along it
    /// (also the operators' tests').
    pub(super) use super::test_kernel as kernel;

    type Kernel<'a> = &'a dyn Fn(isize, usize, usize) -> [[f64; 3]; 3];

    /// `k` with zeros at the offsets `+nx` and beyond.
    fn zero_beyond(nx: usize, k: Kernel<'_>) -> impl Fn(isize, usize, usize) -> [[f64; 3]; 3] + '_ {
        move |o, j, jp| {
            if o >= nx as isize {
                [[0.0; 3]; 3]
            } else {
                k(o, j, jp)
            }
        }
    }

    #[test]
    fn every_routes_products_give_the_plain_loops_bits_and_single_precision_is_within_1e_6() {
        // runs of field rows shorter and longer than a block of every instruction set, and
        // every kind of last block
        // kernels even in x (real spectra), without couplings (none), with couplings odd in x
        // (imaginary ones) and neither (complex), each zero at the offset +nx (which would break the symmetry in
        // x, as the box products' convolvers have it): the spectra's parts
        let odd = |o: isize, j, jp| {
            let mut k = kernel(o, j, jp);
            for (a, b) in [(0, 1), (1, 0), (0, 2), (2, 0), (1, 2), (2, 1)] {
                k[a][b] *= o.signum() as f64;
            }
            k
        };
        let uncoupled = |o: isize, j, jp| {
            let k = kernel(o, j, jp);
            std::array::from_fn(|a| std::array::from_fn(|b| if a == b { k[a][b] } else { 0.0 }))
        };
        let neither =
            |o: isize, j, jp| kernel(o, j, jp).map(|r| r.map(|v| v * (1.0 + 0.1 * o as f64)));
        let kernels: [(Kernel, [Part; 2]); 4] = [
            (&kernel, [Part::Real, Part::Real]),
            (&uncoupled, [Part::Real, Part::Zero]),
            (&odd, [Part::Real, Part::Imaginary]),
            (&neither, [Part::Complex, Part::Complex]),
        ];
        // (4, 56, 2): per-component runs of four AVX-512 vectors of f32; (6, 5, 1): the normal
        // product's one component
        let grids = [
            (7, 4, 2),
            (9, 13, 2),
            (12, 3, 3),
            (32, 24, 2),
            (5, 40, 2),
            (4, 56, 2),
            (6, 5, 1),
        ];
        for ((nx, ny, comps), (kernel, [direct, coupling])) in grids
            .into_iter()
            .flat_map(|g| kernels.iter().map(move |k| (g, k)))
        {
            let mut conv = StripConvolver::new(nx, ny, comps, zero_beyond(nx, kernel));
            for (ab, (single, double)) in
                conv.single.parts.iter().zip(&conv.double.parts).enumerate()
            {
                let want = if ab / comps == ab % comps {
                    direct
                } else {
                    coupling
                };
                assert_eq!(
                    (*single, *double),
                    (*want, *want),
                    "{nx}×{ny}×{comps} block {ab}"
                );
            }
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
                let mut out = |precision: Precision, route: Option<Route>| {
                    let mut u = vec![vec![0.0; n]; comps];
                    let mut ur: Vec<&mut [f64]> = u.iter_mut().map(|v| v.as_mut_slice()).collect();
                    let cols = (c0, c1);
                    conv.product_in(&fr, &mut ur, ((0, nx), cols, cols), (precision, route));
                    u
                };
                let (double_plain, single_plain) =
                    (out(Precision::Double, None), out(Precision::Single, None));
                let scale = double_plain
                    .iter()
                    .flatten()
                    .fold(0.0_f64, |m, v| m.max(v.abs()));
                for route in Route::available() {
                    let (double, single) = (
                        out(Precision::Double, Some(route)),
                        out(Precision::Single, Some(route)),
                    );
                    for a in 0..comps {
                        for e in 0..n {
                            let at =
                                format!("{route:?} {nx}×{ny}×{comps} cols {c0}..{c1}: {a} {e}");
                            assert_eq!(
                                double[a][e].to_bits(),
                                double_plain[a][e].to_bits(),
                                "{at}"
                            );
                            assert_eq!(
                                single[a][e].to_bits(),
                                single_plain[a][e].to_bits(),
                                "{at}"
                            );
                            let d = (single[a][e] - double[a][e]).abs();
                            assert!(d <= 1e-6 * scale, "{at}: {d:e} of {scale:e}");
                        }
                    }
                }
            }
        }
    }
}

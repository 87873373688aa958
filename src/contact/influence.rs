//! Influence coefficients of the elastic half-space for uniformly loaded rectangles, and
//! FFT-accelerated influence products on the contact grid.
//!
//! For two quasi-identical bodies the displacement *difference* `u = u_wheel − u_rail` at a
//! field point due to a uniform load on a source rectangle is (Johnson 1985, eqs. 3.22
//! Boussinesq and 3.86–3.87 Cerruti, doubled for the two bodies; Love 1929 for the integral):
//!
//! ```text
//! C_zz = 1/(π E*) ∬ 1/r,
//! C_xx = 1/(π G) ∬ [(1−ν)/r + ν X²/r³],   C_yy = 1/(π G) ∬ [(1−ν)/r + ν Y²/r³],
//! C_xy = C_yx = ν/(π G) ∬ X Y / r³,
//! ```
//! with `X, Y` field minus source coordinates. Antiderivatives (corner sums cancel the
//! `X ln|X|` parts): `∬1/r → X asinh(Y/|X|) + Y asinh(X/|Y|)`, `∬X²/r³ → Y asinh(X/|Y|)`,
//! `∬Y²/r³ → X asinh(Y/|X|)`, `∬XY/r³ → −r`.
//!
//! The products `Σ_j C(i − j) f_j` are Toeplitz; they are evaluated as cyclic convolutions on a
//! grid padded to at least `2nx × 2ny` (fast FFT lengths; exact linear convolution for
//! output rows `0..=nx`, which gives also the displacement one cell beyond the leading edge
//! needed by transient rolling — see [`Convolver`] for the one offset that a period of exactly
//! `2nx` cannot hold). Tangential products pack `τx + i τy` into one complex FFT.

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::{Complex, Complex32, Complex64};
use rustfft::num_traits::Zero;
use rustfft::{Fft, FftNum, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;
use transpose::transpose;

mod operators;
pub mod strip;
mod transpose;

pub use operators::{Influence, NormalInfluence, Operators, TangentialInfluence};

fn asinh_ratio(num: f64, den: f64) -> f64 {
    if den == 0.0 {
        0.0
    } else {
        (num / den.abs()).asinh()
    }
}

/// `∬ 1/r dX dY` over `[x1,x2]×[y1,y2]` (m).
fn corner_sum(f: impl Fn(f64, f64) -> f64, x1: f64, x2: f64, y1: f64, y2: f64) -> f64 {
    f(x2, y2) - f(x1, y2) - f(x2, y1) + f(x1, y1)
}

/// Integrals over a source rectangle of half-sizes `hx, hy` (m) centred at the origin, seen from
/// field point `(x, y)`: returns `(∬1/r, ∬X²/r³, ∬Y²/r³, ∬XY/r³)` (units m, m, m, m).
pub(crate) fn rectangle_integrals(x: f64, y: f64, hx: f64, hy: f64) -> (f64, f64, f64, f64) {
    let (x1, x2, y1, y2) = (x - hx, x + hx, y - hy, y + hy);
    let hxx = |xx: f64, yy: f64| yy * asinh_ratio(xx, yy);
    let hyy = |xx: f64, yy: f64| xx * asinh_ratio(yy, xx);
    let i_xx = corner_sum(hxx, x1, x2, y1, y2);
    let i_yy = corner_sum(hyy, x1, x2, y1, y2);
    let i_xy = corner_sum(|xx, yy| -(xx * xx + yy * yy).sqrt(), x1, x2, y1, y2);
    (i_xx + i_yy, i_xx, i_yy, i_xy)
}

/// Dense influence coefficients (m/Pa) between element centres offset by `(ox, oy)` elements.
#[derive(Debug, Clone, Copy)]
pub struct Coefficients {
    /// Normal: u_z per unit pressure.
    pub zz: f64,
    /// u_x per unit τx.
    pub xx: f64,
    /// u_y per unit τy.
    pub yy: f64,
    /// u_x per unit τy (= u_y per unit τx).
    pub xy: f64,
}

/// Influence coefficients for the offset `(x, y)` (m) between field and source centre, element
/// size `dx × dy` (m), combined modulus `E*` and shear modulus `G` (Pa), Poisson ratio ν.
pub fn coefficients(
    x: f64,
    y: f64,
    dx: f64,
    dy: f64,
    e_star: f64,
    g: f64,
    nu: f64,
) -> Coefficients {
    let (i1, ixx, iyy, ixy) = rectangle_integrals(x, y, 0.5 * dx, 0.5 * dy);
    Coefficients {
        zz: i1 / (PI * e_star),
        xx: ((1.0 - nu) * i1 + nu * ixx) / (PI * g),
        yy: ((1.0 - nu) * i1 + nu * iyy) / (PI * g),
        xy: nu * ixy / (PI * g),
    }
}

/// `∬ X/r² dX dY` (m) over a source rectangle of half-sizes `hx, hy` (m) centred at the origin,
/// seen from field point `(x, y)`: the kernel of the normal–tangential coupling of one
/// half-space. Antiderivative `½ Y ln(X² + Y²) + X atan(Y/X)` (the `−Y` term of the exact
/// antiderivative cancels in the corner sum; `X atan(Y/X)` → 0 as `X` → 0).
pub(crate) fn rectangle_integral_x_over_r2(x: f64, y: f64, hx: f64, hy: f64) -> f64 {
    let f = |xx: f64, yy: f64| {
        let r2 = xx * xx + yy * yy;
        let log_part = if r2 > 0.0 { 0.5 * yy * r2.ln() } else { 0.0 };
        let atan_part = if xx != 0.0 {
            xx * (yy / xx).atan()
        } else {
            0.0
        };
        log_part + atan_part
    };
    corner_sum(f, x - hx, x + hx, y - hy, y + hy)
}

/// Influence coefficients (m/Pa) of **one** elastic half-space (Young's modulus `E` in Pa,
/// Poisson ratio ν) for a uniform load on a `dx × dy` (m) rectangle, seen at a surface point
/// offset `(x, y)` (m, field minus source centre): `c[i][j]` is the displacement component `i`
/// per unit traction component `j`, components `(x, y, n)` with `n` the inward normal (the
/// approach under a compressive pressure `p = t_n > 0`). Johnson (1985) eqs. 3.22 (Boussinesq)
/// and 3.86 (Cerruti), integrated over the rectangle:
///
/// ```text
/// c_nn = (1 − ν²)/(π E) ∬ 1/r,
/// c_xx = 1/(2π G) ∬ [(1 − ν)/r + ν X²/r³],   c_yy likewise with Y,   c_xy = c_yx = ν/(2π G) ∬ XY/r³,
/// c_xn = −(1 − 2ν)/(4π G) ∬ X/r²,   c_nx = −c_xn   (and y likewise),
/// ```
///
/// `G = E/(2(1 + ν))`. The coupling terms cancel between two quasi-identical bodies, which is
/// why [`coefficients`] (the pair) has none. This is the closed form the flat block of the
/// local FE contact patch is checked against.
pub fn single_body(x: f64, y: f64, dx: f64, dy: f64, youngs_pa: f64, nu: f64) -> [[f64; 3]; 3] {
    let g = youngs_pa / (2.0 * (1.0 + nu));
    let (hx, hy) = (0.5 * dx, 0.5 * dy);
    let (i1, ixx, iyy, ixy) = rectangle_integrals(x, y, hx, hy);
    let jx = rectangle_integral_x_over_r2(x, y, hx, hy);
    // ∬ Y/r² is the same integral with the axes exchanged
    let jy = rectangle_integral_x_over_r2(y, x, hy, hx);
    let t = 1.0 / (2.0 * PI * g);
    let c = (1.0 - 2.0 * nu) / (4.0 * PI * g);
    let xx = t * ((1.0 - nu) * i1 + nu * ixx);
    let yy = t * ((1.0 - nu) * i1 + nu * iyy);
    let xy = t * nu * ixy;
    let nn = (1.0 - nu * nu) / (PI * youngs_pa) * i1;
    [[xx, xy, -c * jx], [xy, yy, -c * jy], [c * jx, c * jy, nn]]
}

/// 2D FFT of an `m1 × m2` row-major complex array (rows of length `m2`), with preallocated
/// transpose buffer and scratch; in double (`T = f64`) or single precision (`T = f32`, the
/// box products of [`Convolver::tangential_box`]).
#[derive(Clone)]
struct Fft2<T: FftNum> {
    m1: usize,
    m2: usize,
    row_f: Arc<dyn Fft<T>>,
    col_f: Arc<dyn Fft<T>>,
    row_i: Arc<dyn Fft<T>>,
    col_i: Arc<dyn Fft<T>>,
    tbuf: Vec<Complex<T>>,
    scratch: Vec<Complex<T>>,
}

impl<T: FftNum> Fft2<T> {
    fn new(m1: usize, m2: usize) -> Self {
        let mut pl = FftPlanner::<T>::new();
        let row_f = pl.plan_fft_forward(m2);
        let col_f = pl.plan_fft_forward(m1);
        let row_i = pl.plan_fft_inverse(m2);
        let col_i = pl.plan_fft_inverse(m1);
        let ns = [&row_f, &col_f, &row_i, &col_i]
            .iter()
            .map(|f| f.get_inplace_scratch_len())
            .max()
            .unwrap_or(0);
        Fft2 {
            m1,
            m2,
            row_f,
            col_f,
            row_i,
            col_i,
            tbuf: vec![Complex::<T>::zero(); m1 * m2],
            scratch: vec![Complex::<T>::zero(); ns.max(1)],
        }
    }

    /// Forward transform of `data` whose rows `nonzero_rows..` are zero. The result is left
    /// in `self.tbuf` in transposed layout (`m2 × m1`). All-zero rows are not transformed.
    fn forward_to_t(&mut self, data: &mut [Complex<T>], nonzero_rows: usize) {
        let (m1, m2) = (self.m1, self.m2);
        let zero = Complex::<T>::zero();
        for i in 0..nonzero_rows {
            let row = &mut data[i * m2..(i + 1) * m2];
            // the transform of a zero row is zero (rows outside the contact)
            if row.iter().any(|v| *v != zero) {
                self.row_f.process_with_scratch(row, &mut self.scratch);
            }
        }
        // the nonzero rows transposed, the zero rows as one fill per column
        let rows = nonzero_rows.min(m1);
        transpose(data, m2, &mut self.tbuf, m1, (rows, m2));
        for col in self.tbuf.chunks_exact_mut(m1) {
            col[rows..].fill(zero);
        }
        self.col_f
            .process_with_scratch(&mut self.tbuf, &mut self.scratch);
    }

    /// Inverse transform of `self.tbuf` (transposed layout); writes rows `r0..r1` of `data`.
    fn inverse_from_t(&mut self, data: &mut [Complex<T>], r0: usize, r1: usize) {
        let (m1, m2) = (self.m1, self.m2);
        self.col_i
            .process_with_scratch(&mut self.tbuf, &mut self.scratch);
        transpose(
            &self.tbuf[r0..],
            m1,
            &mut data[r0 * m2..],
            m2,
            (m2, r1 - r0),
        );
        self.row_i
            .process_with_scratch(&mut data[r0 * m2..r1 * m2], &mut self.scratch);
    }
}

/// Real-to-complex 2D FFT of an `m1 × m2` row-major real array: real transforms along the rows
/// (length `m2`, spectrum `h2 = m2/2 + 1` long), complex ones along the columns (length `m1`)
/// on the `h2` kept columns only — about half the work of [`Fft2`] for a real field (the other
/// half of the spectrum is the conjugate mirror). Spectra are kept in transposed layout
/// `h2 × m1` (index `k2 · m1 + k1`), the first `h2 m1` entries of [`Fft2`]'s layout.
#[derive(Clone)]
struct RealFft2 {
    m1: usize,
    m2: usize,
    h2: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    col_f: Arc<dyn Fft<f64>>,
    col_i: Arc<dyn Fft<f64>>,
    /// One real row (length `m2`).
    row: Vec<f64>,
    /// One row spectrum (length `h2`).
    spec: Vec<Complex64>,
    /// Spectrum, transposed layout (`h2 × m1`).
    tbuf: Vec<Complex64>,
    scratch: Vec<Complex64>,
}

impl RealFft2 {
    fn new(m1: usize, m2: usize) -> Self {
        let mut rp = RealFftPlanner::<f64>::new();
        let r2c = rp.plan_fft_forward(m2);
        let c2r = rp.plan_fft_inverse(m2);
        let mut pl = FftPlanner::new();
        let col_f = pl.plan_fft_forward(m1);
        let col_i = pl.plan_fft_inverse(m1);
        let ns = r2c
            .get_scratch_len()
            .max(c2r.get_scratch_len())
            .max(col_f.get_inplace_scratch_len())
            .max(col_i.get_inplace_scratch_len());
        let h2 = m2 / 2 + 1;
        let zero = Complex64::new(0.0, 0.0);
        RealFft2 {
            m1,
            m2,
            h2,
            r2c,
            c2r,
            col_f,
            col_i,
            row: vec![0.0; m2],
            spec: vec![zero; h2],
            tbuf: vec![zero; h2 * m1],
            scratch: vec![zero; ns.max(1)],
        }
    }

    /// Forward transform of the field whose rows `0..rows` are `data[i * n2..(i + 1) * n2]`
    /// (zero-padded to `m2`) and whose other rows are zero; result in `self.tbuf`. All-zero rows
    /// are not transformed.
    fn forward(&mut self, data: &[f64], rows: usize, n2: usize) {
        let (m1, h2) = (self.m1, self.h2);
        let zero = Complex64::new(0.0, 0.0);
        for i in 0..m1 {
            let src = if i < rows {
                &data[i * n2..(i + 1) * n2]
            } else {
                &[][..]
            };
            if src.iter().all(|&v| v == 0.0) {
                for k2 in 0..h2 {
                    self.tbuf[k2 * m1 + i] = zero;
                }
                continue;
            }
            self.row[..n2].copy_from_slice(src);
            self.row[n2..].fill(0.0);
            // lengths are fixed at construction: the transform cannot fail
            let r = self
                .r2c
                .process_with_scratch(&mut self.row, &mut self.spec, &mut self.scratch);
            debug_assert!(r.is_ok());
            for (k2, v) in self.spec.iter().enumerate() {
                self.tbuf[k2 * m1 + i] = *v;
            }
        }
        self.col_f
            .process_with_scratch(&mut self.tbuf, &mut self.scratch);
    }

    /// Inverse transform of `self.tbuf` (unnormalised, like [`Fft2`]); writes rows `0..rows`,
    /// columns `0..n2` of the real result to `out[i * n2 + j]`.
    fn inverse(&mut self, out: &mut [f64], rows: usize, n2: usize) {
        let (m1, m2, h2) = (self.m1, self.m2, self.h2);
        self.col_i
            .process_with_scratch(&mut self.tbuf, &mut self.scratch);
        for i in 0..rows {
            for (k2, v) in self.spec.iter_mut().enumerate() {
                *v = self.tbuf[k2 * m1 + i];
            }
            // the spectrum of a real row: the DC (and Nyquist) entries are real; drop the
            // rounding-level imaginary parts that c2r would reject
            self.spec[0].im = 0.0;
            if m2 % 2 == 0 {
                self.spec[h2 - 1].im = 0.0;
            }
            let r = self
                .c2r
                .process_with_scratch(&mut self.spec, &mut self.row, &mut self.scratch);
            debug_assert!(r.is_ok());
            out[i * n2..(i + 1) * n2].copy_from_slice(&self.row[..n2]);
        }
    }
}

/// Smallest `m ≥ n` whose prime factors are 2, 3 and 5 (fast FFT lengths).
pub(crate) fn next_fast_len(n: usize) -> usize {
    let mut m = n.max(1);
    loop {
        let mut r = m;
        for p in [2, 3, 5] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

/// FFT-based influence products on an `nx × ny` grid (element index `i * ny + j`, `i` along x).
///
/// The padded FFT grid is `m1 × m2` with `m1 ≥ 2nx`, `m2 ≥ 2ny` of fast lengths
/// (`next_fast_len`; 64 × 48 for the default 32 × 24 grid, where `2nx + 1` would need 72
/// rows): the offsets that occur (rows `−(nx−1)..=nx`, columns `−(ny−1)..=ny−1`) map to
/// distinct periodic indices, and the periodic kernels are exactly even (zz, xx, yy) or
/// odd–odd (xy), so all four kernel spectra are **real**. The row offset `+nx` (from source
/// row 0 to the extended row `nx` only) sits on the Nyquist index when `m1 = 2nx`: there the
/// even kernels are exact (`C(+nx) = C(−nx)`) but the odd xy kernel must be 0, so that one
/// coupling is added directly (`Convolver::tangential_ext`; O(ny²), and nothing at all when
/// row 0 carries no traction, as in rolling contact where the patch never reaches the grid
/// edge). Hence a real
/// kernel product of a complex field acts on real and imaginary parts separately (two real
/// fields per complex FFT), and the tangential product of `Z = FFT(τx + iτy)` is
/// `W(k) = A(k) Z(k) + B(k) conj Z(−k)` with `A = (K̂xx + K̂yy)/2`, `B = (K̂xx − K̂yy)/2 + i K̂xy`.
#[derive(Clone)]
pub struct Convolver {
    nx: usize,
    ny: usize,
    m1: usize,
    m2: usize,
    fft: Fft2<f64>,
    rfft: RealFft2,
    /// Real spectra in transposed layout, already divided by `m1 m2`.
    kzz: Vec<f64>,
    ka: Vec<f64>,
    kb: Vec<Complex64>,
    buf: Vec<Complex64>,
    work: Vec<Complex64>,
    /// The padded grids of [`Convolver::tangential_box`], one per size ([`box_grids`]; their
    /// kernel spectra sampled from the tangential kernels `(C_xx, C_yy, C_xy)` at the whole
    /// padded grid's periodic offsets).
    boxes: Vec<BoxGrid>,
    /// `C_xy` at row offset `+nx` and column offsets `−(ny−1)..=ny−1` (index `offset + ny − 1`,
    /// m/Pa) when `m1 = 2nx` (the coupling the periodic xy kernel cannot hold); empty otherwise.
    xy_edge: Vec<f64>,
    /// Largest eigenvalue bound of the normal operator (m/Pa).
    pub lambda_max_n: f64,
    /// Largest eigenvalue bound of the tangential operator (m/Pa).
    pub lambda_max_t: f64,
    /// Self-influence (diagonal) of the normal operator (m/Pa).
    pub diag_n: f64,
    /// Self-influence (diagonal, mean of xx and yy) of the tangential operator (m/Pa).
    pub diag_t: f64,
    /// Self-influence `C_xx(0)` of the tangential operator (m/Pa).
    pub diag_xx: f64,
    /// Self-influence `C_yy(0)` of the tangential operator (m/Pa).
    pub diag_yy: f64,
}

impl Convolver {
    /// Build the kernels for element size `dx × dy` (m), moduli `E*`, `G` (Pa) and ν.
    pub fn new(nx: usize, ny: usize, dx: f64, dy: f64, e_star: f64, g: f64, nu: f64) -> Self {
        let (m1, m2) = (next_fast_len(2 * nx), next_fast_len(2 * ny));
        let mut fft = Fft2::new(m1, m2);
        let zero = Complex64::new(0.0, 0.0);
        let mut kz = vec![zero; m1 * m2];
        let mut kx = vec![zero; m1 * m2];
        let mut ky = vec![zero; m1 * m2];
        let mut kc = vec![zero; m1 * m2];
        // periodic offset; the Nyquist entry (k = m/2, never used) gets offset 0 of the
        // odd kernel so that the periodic kernel keeps its exact parity
        let off = |k: usize, m: usize| -> (f64, bool) {
            if 2 * k < m {
                (k as f64, false)
            } else if 2 * k == m {
                (k as f64, true)
            } else {
                (k as f64 - m as f64, false)
            }
        };
        for a in 0..m1 {
            let (ox, nyq_x) = off(a, m1);
            for b in 0..m2 {
                let (oy, nyq_y) = off(b, m2);
                let c = coefficients(ox * dx, oy * dy, dx, dy, e_star, g, nu);
                let idx = a * m2 + b;
                kz[idx] = Complex64::new(c.zz, 0.0);
                kx[idx] = Complex64::new(c.xx, 0.0);
                ky[idx] = Complex64::new(c.yy, 0.0);
                let xy = if nyq_x || nyq_y { 0.0 } else { c.xy };
                kc[idx] = Complex64::new(xy, 0.0);
            }
        }
        let kernels_t: Vec<[f64; 3]> = (0..m1 * m2)
            .map(|q| [kx[q].re, ky[q].re, kc[q].re])
            .collect();
        let diag_n = kz[0].re;
        let (diag_xx, diag_yy) = (kx[0].re, ky[0].re);
        let diag_t = 0.5 * (diag_xx + diag_yy);
        let scale = 1.0 / (m1 * m2) as f64;
        let mut spec = |k: &mut Vec<Complex64>| -> Vec<f64> {
            fft.forward_to_t(k, m1);
            fft.tbuf.iter().map(|v| v.re * scale).collect()
        };
        let kzz = spec(&mut kz);
        let kxx = spec(&mut kx);
        let kyy = spec(&mut ky);
        let kxy = spec(&mut kc);
        let ka: Vec<f64> = kxx.iter().zip(&kyy).map(|(a, b)| 0.5 * (a + b)).collect();
        let kb: Vec<Complex64> = (0..m1 * m2)
            .map(|q| Complex64::new(0.5 * (kxx[q] - kyy[q]), kxy[q]))
            .collect();
        let mut lambda_max_n = 0.0_f64;
        let mut lambda_max_t = 0.0_f64;
        let s = (m1 * m2) as f64;
        for q in 0..m1 * m2 {
            lambda_max_n = lambda_max_n.max(kzz[q].abs() * s);
            // largest eigenvalue (in modulus) of the 2×2 symbol [[xx, xy], [xy, yy]]
            let (a, d, b) = (kxx[q] * s, kyy[q] * s, kxy[q] * s);
            let m = 0.5 * (a + d);
            let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
            lambda_max_t = lambda_max_t.max((m + r).abs()).max((m - r).abs());
        }
        let xy_edge = if m1 == 2 * nx {
            (0..2 * ny - 1)
                .map(|k| {
                    let oy = k as f64 - (ny as f64 - 1.0);
                    coefficients(nx as f64 * dx, oy * dy, dx, dy, e_star, g, nu).xy
                })
                .collect()
        } else {
            Vec::new()
        };
        Convolver {
            nx,
            ny,
            m1,
            m2,
            xy_edge,
            fft,
            rfft: RealFft2::new(m1, m2),
            kzz,
            ka,
            kb,
            buf: vec![zero; m1 * m2],
            work: vec![zero; m1 * m2],
            boxes: box_grids(m1, m2, &kernels_t),
            lambda_max_n,
            lambda_max_t,
            diag_n,
            diag_t,
            diag_xx,
            diag_yy,
        }
    }

    /// Grid size `(nx, ny)`.
    pub fn dims(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// Padded FFT grid `(m1, m2)`.
    pub fn fft_dims(&self) -> (usize, usize) {
        (self.m1, self.m2)
    }

    /// Normal displacement difference `u = C_zz * p` (m) on the grid, `p` in Pa. Real-to-complex
    /// transforms (`RealFft2`: half the work of a complex pair); rows of `p` that are zero
    /// (outside the contact) are not transformed.
    pub fn normal(&mut self, p: &[f64], u: &mut [f64]) {
        let (nx, ny) = (self.nx, self.ny);
        let rf = &mut self.rfft;
        rf.forward(p, nx, ny);
        for (t, k) in rf.tbuf.iter_mut().zip(&self.kzz) {
            *t *= *k;
        }
        rf.inverse(u, nx, ny);
    }

    /// Tangential displacement differences `(ux, uy)` (m) from tractions `(tx, ty)` (Pa),
    /// evaluated at grid rows shifted by `shift` (0 or 1): `u[i] = (C * τ)(i + shift)`.
    pub fn tangential(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
        shift: usize,
    ) {
        debug_assert!(shift <= 1);
        let (nx, ny, m2) = (self.nx, self.ny, self.m2);
        self.tangential_core(tx, ty, shift, nx + shift);
        for i in 0..nx {
            for j in 0..ny {
                let v = self.buf[(i + shift) * m2 + j];
                ux[i * ny + j] = v.re;
                uy[i * ny + j] = v.im;
            }
        }
    }

    /// Tangential displacement differences on the extended rows `0..=nx` (row `nx` lies one
    /// cell beyond the leading edge): `ux, uy` have length `(nx + 1) · ny`.
    pub(crate) fn tangential_ext(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
    ) {
        let (nx, ny, m2) = (self.nx, self.ny, self.m2);
        debug_assert!(ux.len() >= (nx + 1) * ny && uy.len() >= (nx + 1) * ny);
        self.tangential_core(tx, ty, 0, nx + 1);
        for i in 0..=nx {
            for j in 0..ny {
                let v = self.buf[i * m2 + j];
                ux[i * ny + j] = v.re;
                uy[i * ny + j] = v.im;
            }
        }
    }

    /// Tangential displacement differences `(ux, uy)` (m) from tractions `(tx, ty)` (Pa) on
    /// the grid rows `r0..r1` only (`r1 ≤ nx`; the other rows of `ux, uy` are left as they
    /// are): the inverse row transforms of the other rows are skipped.
    pub(crate) fn tangential_rows(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
        r0: usize,
        r1: usize,
    ) {
        let (ny, m2) = (self.ny, self.m2);
        let r1 = r1.min(self.nx);
        let r0 = r0.min(r1);
        self.tangential_core(tx, ty, r0, r1);
        for i in r0..r1 {
            for j in 0..ny {
                let v = self.buf[i * m2 + j];
                ux[i * ny + j] = v.re;
                uy[i * ny + j] = v.im;
            }
        }
    }

    /// Forward transform, kernel product, inverse on the padded rows `r0..r1`.
    fn tangential_core(&mut self, tx: &[f64], ty: &[f64], r0: usize, r1: usize) {
        let (nx, ny, m1, m2) = (self.nx, self.ny, self.m1, self.m2);
        let zero = Complex64::new(0.0, 0.0);
        for i in 0..nx {
            let row = &mut self.buf[i * m2..(i + 1) * m2];
            for j in 0..ny {
                let e = i * ny + j;
                row[j] = Complex64::new(tx[e], ty[e]);
            }
            row[ny..].fill(zero);
        }
        self.fft.forward_to_t(&mut self.buf, nx);
        tangential_kernel_product(&self.fft.tbuf, &self.ka, &self.kb, &mut self.work, m1, m2);
        std::mem::swap(&mut self.fft.tbuf, &mut self.work);
        self.fft.inverse_from_t(&mut self.buf, r0, r1);
        if r1 > nx && !self.xy_edge.is_empty() {
            self.add_xy_edge(tx, ty);
        }
    }

    /// Tangential displacement differences `(ux, uy)` (m) from tractions `(tx, ty)` (Pa) that
    /// are zero outside the box of grid rows `r0..r1` and columns `c0..c1`, on that box
    /// only: a cyclic convolution on a padded grid of the smallest `2^a 3^b` ≥ `2 b − 1` per
    /// direction (`b` the box's extent), exact for the offsets within the box, instead of the
    /// whole grid's `m1 × m2`. Elements of rows `r0..r1` outside the columns `c0..c1` get 0;
    /// the other rows of `ux, uy` are left as they are. The padded grids and their kernel
    /// spectra are built with the convolver (`box_grids`); no allocation here.
    ///
    /// The box product runs in **single precision** (tractions rounded to `f32`, `f32` FFTs
    /// and kernel spectra; about `10⁻⁷ λ_max ‖τ‖₂` of error): it serves the tangential
    /// solver's inner conjugate gradients, which reduce a residual a few hundredfold between
    /// exact double-precision products. A box whose padded grid would not be smaller than the
    /// whole grid's takes the whole grid's rows in double precision.
    pub(crate) fn tangential_box(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
        (r0, r1): (usize, usize),
        (c0, c1): (usize, usize),
    ) {
        let ny = self.ny;
        let (r1, c1) = (r1.min(self.nx), c1.min(ny));
        let (r0, c0) = (r0.min(r1), c0.min(c1));
        let (bx, by) = (r1 - r0, c1 - c0);
        let (p1, p2) = (
            next_smooth3((2 * bx).saturating_sub(1)),
            next_smooth3((2 * by).saturating_sub(1)),
        );
        let found = self.boxes.iter().position(|b| (b.m1, b.m2) == (p1, p2));
        let Some(k) = found.filter(|_| bx > 0 && by > 0) else {
            self.tangential_rows(tx, ty, ux, uy, r0, r1);
            return;
        };
        let bg = &mut self.boxes[k];
        for a in 0..bx {
            let row = &mut bg.buf[a * p2..(a + 1) * p2];
            let e0 = (r0 + a) * ny + c0;
            let (sx, sy) = (&tx[e0..e0 + by], &ty[e0..e0 + by]);
            for ((v, x), y) in row[..by].iter_mut().zip(sx).zip(sy) {
                *v = Complex32::new(*x as f32, *y as f32);
            }
            row[by..].fill(Complex32::zero());
        }
        bg.fft.forward_to_t(&mut bg.buf, bx);
        tangential_kernel_product(&bg.fft.tbuf, &bg.ka, &bg.kb, &mut bg.work, p1, p2);
        std::mem::swap(&mut bg.fft.tbuf, &mut bg.work);
        bg.fft.inverse_from_t(&mut bg.buf, 0, bx);
        for a in 0..bx {
            let row = (r0 + a) * ny;
            let (ux, uy) = (&mut ux[row..row + ny], &mut uy[row..row + ny]);
            for u in [&mut *ux, &mut *uy] {
                u[..c0].fill(0.0);
                u[c1..].fill(0.0);
            }
            let src = &bg.buf[a * p2..a * p2 + by];
            for ((x, y), v) in ux[c0..c1].iter_mut().zip(&mut uy[c0..c1]).zip(src) {
                *x = f64::from(v.re);
                *y = f64::from(v.im);
            }
        }
    }

    /// Adds the xy coupling of source row 0 to the extended row `nx` (padded row `nx` of
    /// `self.buf`), which a period `m1 = 2nx` cannot hold (type doc).
    fn add_xy_edge(&mut self, tx: &[f64], ty: &[f64]) {
        let (nx, ny, m2) = (self.nx, self.ny, self.m2);
        let (tx0, ty0) = (&tx[..ny], &ty[..ny]);
        if tx0.iter().chain(ty0).all(|&v| v == 0.0) {
            return;
        }
        for j in 0..ny {
            let (mut sx, mut sy) = (0.0, 0.0);
            for l in 0..ny {
                let c = self.xy_edge[j + ny - 1 - l];
                sx += c * ty0[l];
                sy += c * tx0[l];
            }
            let v = &mut self.buf[nx * m2 + j];
            v.re += sx;
            v.im += sy;
        }
    }
}

/// `W = A Z + B conj Z(−k)` in the transposed spectral layout (`q = k2 · m1 + k1`) of an
/// `m1 × m2` grid: the tangential kernel product of [`Convolver`] (type doc), in double or
/// single precision. Compiled for each instruction set pulp dispatches to (AVX2, AVX-512 or
/// the baseline, chosen at run time); the same multiplications and additions in the same
/// order (no fused multiply-add: the compiler does not contract them), so every instruction
/// set gives the same bits.
fn tangential_kernel_product<T: FftNum>(
    z: &[Complex<T>],
    ka: &[T],
    kb: &[Complex<T>],
    work: &mut [Complex<T>],
    m1: usize,
    m2: usize,
) {
    pulp::Arch::new().dispatch(KernelProduct {
        z,
        ka,
        kb,
        work,
        m1,
        m2,
    });
}

/// The arguments of [`tangential_kernel_product`], for pulp's dispatch.
struct KernelProduct<'a, T: FftNum> {
    z: &'a [Complex<T>],
    ka: &'a [T],
    kb: &'a [Complex<T>],
    work: &'a mut [Complex<T>],
    m1: usize,
    m2: usize,
}

impl<T: FftNum> pulp::WithSimd for KernelProduct<'_, T> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        tangential_kernel_product_plain(self.z, self.ka, self.kb, self.work, self.m1, self.m2);
    }
}

/// The kernel product of [`tangential_kernel_product`], for any instruction set.
#[inline(always)]
fn tangential_kernel_product_plain<T: FftNum>(
    z: &[Complex<T>],
    ka: &[T],
    kb: &[Complex<T>],
    work: &mut [Complex<T>],
    m1: usize,
    m2: usize,
) {
    for k2 in 0..m2 {
        let n2 = (m2 - k2) % m2;
        let row = &z[k2 * m1..(k2 + 1) * m1];
        let mrow = &z[n2 * m1..(n2 + 1) * m1];
        let a = &ka[k2 * m1..(k2 + 1) * m1];
        let b = &kb[k2 * m1..(k2 + 1) * m1];
        let w = &mut work[k2 * m1..(k2 + 1) * m1];
        w[0] = row[0] * a[0] + b[0] * mrow[0].conj();
        // Z(−k1) runs backwards through the row: zipped iterators, no index checks
        for ((((wv, z), av), bv), zm) in w[1..]
            .iter_mut()
            .zip(&row[1..])
            .zip(&a[1..])
            .zip(&b[1..])
            .zip(mrow[1..].iter().rev())
        {
            *wv = *z * *av + *bv * zm.conj();
        }
    }
}

/// The smallest `2^a 3^b` ≥ `n` (≥ 1).
fn next_smooth3(n: usize) -> usize {
    let mut m = n.max(1);
    loop {
        let mut r = m;
        for p in [2, 3] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

/// The padded grids of [`Convolver::tangential_box`], built with the convolver so that no
/// step allocates: every size `p1 × p2` of the form `2^a 3^b` per direction with `p1 ≤ m1`,
/// `p2 ≤ m2` and `p1 p2 < m1 m2` (a box needs `p ≥ 2b − 1` per direction, so at most a third
/// more than that; a larger box uses the whole grid's rows). For the default 64 × 48 grid:
/// 254 grids, about 6 MB.
fn box_grids(m1: usize, m2: usize, kernels: &[[f64; 3]]) -> Vec<BoxGrid> {
    let sizes = |m: usize| (1..=m).filter(move |&p| next_smooth3(p) == p);
    let mut out = Vec::new();
    for p1 in sizes(m1) {
        for p2 in sizes(m2).filter(|&p2| p1 * p2 < m1 * m2) {
            out.push(BoxGrid::new(p1, p2, m1, m2, kernels));
        }
    }
    out
}

/// A padded grid `m1 × m2` smaller than the [`Convolver`]'s, for products confined to a box
/// ([`Convolver::tangential_box`]): its single-precision FFTs, the tangential kernel spectra
/// sampled from the whole grid's kernels (transformed in double precision, then rounded to
/// single), and scratch.
#[derive(Clone)]
struct BoxGrid {
    m1: usize,
    m2: usize,
    fft: Fft2<f32>,
    ka: Vec<f32>,
    kb: Vec<Complex32>,
    buf: Vec<Complex32>,
    work: Vec<Complex32>,
}

impl BoxGrid {
    /// Kernels at the periodic offsets of `m1 × m2` taken from `kernels` (the `f1 × f2`
    /// padded grid's, `m1 ≤ f1`, `m2 ≤ f2`); the xy kernel is 0 on the Nyquist offsets so
    /// that it keeps its odd parity (real spectra, as in [`Convolver::new`]).
    fn new(m1: usize, m2: usize, f1: usize, f2: usize, kernels: &[[f64; 3]]) -> Self {
        let zero = Complex64::new(0.0, 0.0);
        let mut fft = Fft2::<f64>::new(m1, m2);
        let wrap = |k: usize, m: usize, f: usize| -> (usize, bool) {
            if 2 * k < m {
                (k, false)
            } else if 2 * k == m {
                (k, true)
            } else {
                (f - (m - k), false)
            }
        };
        let mut k3 = [
            vec![zero; m1 * m2],
            vec![zero; m1 * m2],
            vec![zero; m1 * m2],
        ];
        for a in 0..m1 {
            let (fa, nyq_a) = wrap(a, m1, f1);
            for b in 0..m2 {
                let (fb, nyq_b) = wrap(b, m2, f2);
                let c = kernels[fa * f2 + fb];
                let q = a * m2 + b;
                k3[0][q] = Complex64::new(c[0], 0.0);
                k3[1][q] = Complex64::new(c[1], 0.0);
                let xy = if nyq_a || nyq_b { 0.0 } else { c[2] };
                k3[2][q] = Complex64::new(xy, 0.0);
            }
        }
        let scale = 1.0 / (m1 * m2) as f64;
        let [kxx, kyy, kxy] = k3.map(|mut k| {
            fft.forward_to_t(&mut k, m1);
            fft.tbuf.iter().map(|v| v.re * scale).collect::<Vec<f64>>()
        });
        BoxGrid {
            m1,
            m2,
            fft: Fft2::new(m1, m2),
            ka: kxx
                .iter()
                .zip(&kyy)
                .map(|(a, b)| (0.5 * (a + b)) as f32)
                .collect(),
            kb: (0..m1 * m2)
                .map(|q| Complex32::new((0.5 * (kxx[q] - kyy[q])) as f32, kxy[q] as f32))
                .collect(),
            buf: vec![Complex32::zero(); m1 * m2],
            work: vec![Complex32::zero(); m1 * m2],
        }
    }
}

#[cfg(test)]
mod tests;

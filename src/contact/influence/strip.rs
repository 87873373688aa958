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
/// imaginary arrays, frequency-major (`[k][row][source]` and `[k][source]`), so that the
/// dense product of one frequency is a run of contiguous dot products over the source
/// columns that carry traction (four partial sums each).
#[derive(Clone)]
pub struct StripConvolver {
    nx: usize,
    ny: usize,
    comps: usize,
    m: usize,
    /// `m/2 + 1` spectra, each a row-major `(c·ny) × (c·ny)` matrix (row: field component and
    /// column `a·ny + j`; column: source `b·ny + j'`), divided by `m`: real and imaginary parts.
    spec_re: Vec<f64>,
    spec_im: Vec<f64>,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
    line: Vec<f64>,
    /// One column's spectrum (`m/2 + 1`).
    spectrum: Vec<Complex64>,
    /// Source spectra `[k][b·ny + j']`, real and imaginary parts.
    src_re: Vec<f64>,
    src_im: Vec<f64>,
    /// Field spectra, one row of `m/2 + 1` per field column `a·ny + j`.
    field: Vec<Complex64>,
    scratch: Vec<Complex64>,
}

/// `Σ (a_re + i a_im)(b_re + i b_im)` over equal-length slices, in four interleaved partial
/// sums (element `i` to lane `i mod 4`; the last `len mod 4` to lane 0), so that the
/// additions run in independent chains and vector lanes.
fn complex_dot(a_re: &[f64], a_im: &[f64], b_re: &[f64], b_im: &[f64]) -> Complex64 {
    let (mut sr, mut si) = ([0.0_f64; 4], [0.0_f64; 4]);
    let n4 = a_re.len() / 4 * 4;
    let chunks = a_re[..n4]
        .chunks_exact(4)
        .zip(a_im[..n4].chunks_exact(4))
        .zip(b_re[..n4].chunks_exact(4).zip(b_im[..n4].chunks_exact(4)));
    for ((ar, ai), (br, bi)) in chunks {
        for l in 0..4 {
            sr[l] += ar[l] * br[l] - ai[l] * bi[l];
            si[l] += ar[l] * bi[l] + ai[l] * br[l];
        }
    }
    for i in n4..a_re.len() {
        sr[0] += a_re[i] * b_re[i] - a_im[i] * b_im[i];
        si[0] += a_re[i] * b_im[i] + a_im[i] * b_re[i];
    }
    Complex64::new(
        (sr[0] + sr[1]) + (sr[2] + sr[3]),
        (si[0] + si[1]) + (si[2] + si[3]),
    )
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
                            let e = (k * cn + row) * cn + col;
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
            spec_re,
            spec_im,
            line,
            spectrum: vec![Complex64::new(0.0, 0.0); nk],
            src_re: vec![0.0; nk * cn],
            src_im: vec![0.0; nk * cn],
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
    pub fn product_rows(&mut self, f: &[&[f64]], u: &mut [&mut [f64]], shift: usize, rows: usize) {
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
    pub fn product_cols(
        &mut self,
        f: &[&[f64]],
        u: &mut [&mut [f64]],
        (shift, rows): (usize, usize),
        (c0, c1): (usize, usize),
        (d0, d1): (usize, usize),
    ) {
        let (nx, ny, c, m) = (self.nx, self.ny, self.comps, self.m);
        let nk = m / 2 + 1;
        let cn = c * ny;
        assert!(f.len() == c && u.len() == c && shift + rows <= nx + 1);
        assert!(c0 <= c1 && c1 <= ny && d0 <= d1 && d1 <= ny);
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
                    self.src_re[k * cn + s] = v.re;
                    self.src_im[k * cn + s] = v.im;
                }
            }
        }
        for k in 0..nk {
            let (sr, si) = (
                &self.src_re[k * cn..(k + 1) * cn],
                &self.src_im[k * cn..(k + 1) * cn],
            );
            for a in 0..c {
                for j in d0..d1 {
                    let r = a * ny + j;
                    let e = (k * cn + r) * cn;
                    let mut acc = Complex64::new(0.0, 0.0);
                    for b in 0..c {
                        let (s0, s1) = (b * ny + c0, b * ny + c1);
                        acc += complex_dot(
                            &self.spec_re[e + s0..e + s1],
                            &self.spec_im[e + s0..e + s1],
                            &sr[s0..s1],
                            &si[s0..s1],
                        );
                    }
                    self.field[r * nk + k] = acc;
                }
            }
        }
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
        self.tangential
            .product_cols(&[tx, ty], &mut [bx, by], (0, nx), (c0, c1), (c0, c1));
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

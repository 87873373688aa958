//! The normal and tangential influence operators of a kernel invariant along the rail only
//! (`super::StripConvolver`), for the contact solvers (`NormalInfluence`,
//! `TangentialInfluence`): the symmetrised kernel, the bounds the solvers need, and the
//! tangential solver's box products in single precision on a padded length of the box's own.

use super::{next_fast_len, Precision, StripConvolver};

/// The normal influence operator of a kernel invariant along x only: a one-component
/// [`StripConvolver`] and its largest self-influence, for [`crate::contact::influence::NormalInfluence`].
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

impl crate::contact::influence::NormalInfluence for StripNormal {
    fn normal(&mut self, p: &[f64], u: &mut [f64]) {
        self.conv.product(&[p], &mut [u], 0);
    }

    fn diag_n(&self) -> f64 {
        self.diag
    }
}

/// The normal and tangential influence operators of a three-component kernel invariant
/// along x only (an FE contact patch, theory §6.9): the normal term `K_nn` for
/// [`crate::contact::influence::NormalInfluence`], the tangential block `K_xx, K_xy, K_yx, K_yy` for
/// [`crate::contact::influence::TangentialInfluence`]. The normal–tangential couplings `K_xn, K_yn, K_nx, K_ny`
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
    /// the padded length `2L` (even, 5-smooth, below the grid's), ascending in `L`; a box of
    /// `L'` rows uses the one with the smallest such `L ≥ L'`, built when a box first needs it.
    boxes: Vec<StripConvolver>,
    /// Scratch of the box and extended products, `(nx + 1) · ny` each.
    bx: Vec<f64>,
    by: Vec<f64>,
    /// Scratch of the box products' sources (the box's rows, zeros elsewhere), `nx · ny` each.
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
            // offsets up to `lb < nx`; `+lb` reaches beyond a box's rows and is never read:
            // zero, so that the rows even or odd in x keep spectra real or imaginary (the
            // dense sums then skip the other part's products)
            if o == lb as isize {
                return [[0.0; 3]; 3];
            }
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

impl crate::contact::influence::NormalInfluence for StripInfluence {
    fn normal(&mut self, p: &[f64], u: &mut [f64]) {
        self.normal.normal(p, u);
    }

    fn diag_n(&self) -> f64 {
        self.normal.diag_n()
    }
}

impl crate::contact::influence::TangentialInfluence for StripInfluence {
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
        if rows == 0 {
            return;
        }
        // the box's rows of the traction, zeros to the convolver's rows: the rows outside
        // the box may hold anything (the trait's contract is a traction zero there)
        let found = self.box_convolver(rows);
        let (conv, offset) = match found {
            Some(k) => (&mut self.boxes[k], r0),
            None => (&mut self.tangential, 0),
        };
        let n = conv.dims().0 * ny;
        let (sx, sy) = (&mut self.sx[..n], &mut self.sy[..n]);
        sx.fill(0.0);
        sy.fill(0.0);
        let at = (r0 - offset) * ny;
        sx[at..at + rows * ny].copy_from_slice(&tx[r0 * ny..r1 * ny]);
        sy[at..at + rows * ny].copy_from_slice(&ty[r0 * ny..r1 * ny]);
        let (bx, by) = (&mut self.bx[..n], &mut self.by[..n]);
        conv.product_cols_in(
            Precision::Single,
            &[sx, sy],
            &mut [bx, by],
            ((at / ny, rows), cols, cols),
        );
        // the field rows `r0..r1` are the products' rows `0..rows`
        for i in r0..r1 {
            for j in 0..ny {
                let (e, b) = (i * ny + j, (i - r0) * ny + j);
                let inside = (c0..c1).contains(&j);
                ux[e] = if inside { self.bx[b] } else { 0.0 };
                uy[e] = if inside { self.by[b] } else { 0.0 };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::StripInfluence;
    use crate::contact::influence::strip::tests::kernel;
    use crate::contact::influence::strip::Part;
    use crate::contact::influence::TangentialInfluence;

    #[test]
    fn box_products_equal_a_direct_sum_of_the_symmetrised_kernel() {
        box_products_against_direct_sums(kernel);
    }

    #[test]
    fn box_convolvers_of_a_kernel_with_couplings_odd_in_x_have_real_and_imaginary_blocks() {
        // the direct terms even in x, the couplings odd (as a body symmetric about a plane
        // across the rail): the box convolvers' spectra are real and imaginary (their `+lb`
        // offset is zero), so the sums skip half the products; the products stay right
        let odd = |o: isize, j: usize, jp: usize| {
            let mut k = kernel(o, j, jp);
            for (a, b) in [(0, 1), (1, 0)] {
                k[a][b] *= o.signum() as f64;
            }
            k
        };
        let op = box_products_against_direct_sums(odd);
        assert!(
            op.boxes.len() >= 2,
            "box convolvers built: {}",
            op.boxes.len()
        );
        for b in &op.boxes {
            // a box of one row reads the offset 0 only, where odd couplings vanish
            let c = if b.nx == 1 {
                Part::Zero
            } else {
                Part::Imaginary
            };
            let want = [Part::Real, c, c, Part::Real];
            assert_eq!(b.single.parts, want, "box of {} rows", b.nx);
            assert_eq!(b.double.parts, want, "box of {} rows", b.nx);
        }
    }

    /// Boxes of the whole grid and of fewer rows (their own padded lengths, built in turn, and
    /// one reused) against `Σ K_sym(i − i', j, j') τ(i', j')` over the box; the traction
    /// outside the box's rows is not read (it holds other values here). The operators, with
    /// their box convolvers.
    fn box_products_against_direct_sums(
        kernel: impl Fn(isize, usize, usize) -> [[f64; 3]; 3] + Copy,
    ) -> StripInfluence {
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
                        } else if (rows.0..rows.1).contains(&(e / ny)) {
                            0.0
                        } else {
                            9e7 // stale: not part of the box's traction
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
        op
    }
}

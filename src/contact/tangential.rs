//! One tangential contact problem of Kalker's exact theory (one time step of transient rolling,
//! or a static shift).
//!
//! Given the traction bound `g_i = µ p_i` (Pa) and a known shift `e_i` (m, the rigid slip
//! times Δx minus the previous displacement at the same material point), find `τ_i` with
//!
//! ```text
//! S_i = (C τ)_i + e_i         (slip distance in the step, m)
//! |τ_i| ≤ g_i;  |τ_i| < g_i ⇒ S_i = 0;  |τ_i| = g_i ⇒ τ_i = −g_i S_i / |S_i|.
//! ```
//! These are exactly the optimality conditions of the convex programme
//! `min ½ τᵀCτ + eᵀτ  s.t. |τ_i| ≤ g_i` (C symmetric positive definite; Kalker 1990 §2.4:
//! the transient problem is a minimum principle). Its gradient is the slip `S`. It is solved by
//! an active-set conjugate-gradient method with FFT influence products (see `TangentialSolver::solve`).
//!
//! Series compliance: with the uniform compliances `c_x, c_y` (m/N) of the rail surface under
//! the patch the slip gains `c_x F_x(t)` (and `c_y F_y(t)`), `F_x = ΔA Σ τx`, the end-of-step
//! force (implicit); the caller puts the known `−c_x F_x(t − Δt)` into the shift `e`. The operator
//! becomes `C + diag(c_x, c_y) ΔA 1 1ᵀ` (m/Pa), a rank-one term per component that keeps it
//! symmetric positive definite, so the problem stays the same convex programme
//! (`TangentialSolver::uniform_x_m_per_pa`).

use super::influence::TangentialInfluence;
use super::ContactError;

/// Partial sums of the inner CG (`inner_cg.rs` and the AVX2 kernels `contact::avx2::cg`)'s reductions: element `i` of a segment goes to lane `i mod 4`
/// of its blocks of four (the segment's last `n mod 4` elements to lane 0), so that the
/// additions run in four independent chains (and vector lanes) instead of one.
pub(in crate::contact) const LANES: usize = 4;

mod inner_cg;

/// How the slip directions are found (see `TangentialSolver::solve`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TangentialAlgorithm {
    /// Slip elements turn (small turns) inside the inner CG along the tangent of their circle,
    /// with the curvature term `|S_i|/g_i` of the circle in the CG operator: a Newton step on
    /// the manifold of the slip directions (quadratic convergence of the directions).
    #[default]
    Newton,
    /// The alternative: slip directions only by Kalker's element test (a Jacobi-type
    /// fixed-point iteration, one exact product per sweep; slow, and it can stall and fall
    /// back to FISTA). Kept to compare.
    ElementTest,
}

/// The data of one tangential problem: the traction bound `g` (Pa) and the shift `(ex, ey)`
/// (m) per element.
struct Problem<'a> {
    g: &'a [f64],
    ex: &'a [f64],
    ey: &'a [f64],
}

/// Scratch for the tangential solver (allocated once).
#[derive(Clone)]
pub(crate) struct TangentialSolver {
    dx_: Vec<f64>,
    dy_: Vec<f64>,
    qx: Vec<f64>,
    qy: Vec<f64>,
    slip: Vec<bool>,
    px: Vec<f64>,
    py: Vec<f64>,
    rx: Vec<f64>,
    ry: Vec<f64>,
    kap: Vec<f64>,
    /// Inverse diagonal of the inner CG's model Hessian (Jacobi preconditioner), x and y.
    mix: Vec<f64>,
    miy: Vec<f64>,
    /// Elements `lo..hi` hold every element with a positive traction bound (the contact);
    /// the CG loops run over them only.
    lo: usize,
    hi: usize,
    /// Rows and columns of the contact's box, on which the CG's products run.
    rows: (usize, usize),
    cols: (usize, usize),
    /// The box's row segments within `lo..hi` (element ranges, one per row; capacity `nx`
    /// from the start): the inner CG's loops run over them only (elsewhere the search
    /// direction, the residual and the traction bound are zero).
    segs: Vec<(usize, usize)>,
    /// Whether `sx, sy` are the exact product of the current traction (not the CG's
    /// recurrence).
    exact_now: bool,
    /// Adhesion and slip masks of the inner CG (1 or 0 per element; both 0 where `g ≤ 0`),
    /// set with the Jacobi preconditioner: the branch-free CG step.
    wa: Vec<f64>,
    ws: Vec<f64>,
    /// The final traction of the last solve (Pa): with [`Self::ux_ext`] its product, the
    /// start of the next solve by linearity ([`Self::linear_start`]).
    tx_last: Vec<f64>,
    ty_last: Vec<f64>,
    /// Box (rows, columns) of the last solve's contact, and whether `tx_last, ty_last` and
    /// `ux_ext, uy_ext` are a traction and its exact product (with the convolver of
    /// `last_conv`: dims and self-influences).
    last_box: ((usize, usize), (usize, usize)),
    last_valid: bool,
    last_conv: (usize, usize, f64, f64),
    /// The start's slip by linearity (default `true`): `S = C τ_last + C (τ₀ − τ_last) + e`
    /// with `C τ_last` the last solve's exact product and the difference as a box product
    /// ([`TangentialInfluence::tangential_box`]), instead of a whole-grid product of the start `τ₀`.
    /// Every solve still ends on an exact whole-grid product. It needs the same convolver as
    /// the last solve (checked by its dimensions and self-influences; otherwise the whole-grid
    /// product is taken).
    pub linear_start: bool,
    /// The algorithm for the slip directions.
    pub algorithm: TangentialAlgorithm,
    /// Jacobi-precondition the inner CG of [`TangentialAlgorithm::Newton`] (default `true`;
    /// see [`Self::solve`]).
    pub jacobi: bool,
    /// Slip distance S_x of the last solve (m).
    pub sx: Vec<f64>,
    /// Slip distance S_y of the last solve (m).
    pub sy: Vec<f64>,
    /// `(C τ)_x` of the final traction on the extended rows `0..=nx` (m), see
    /// [`TangentialInfluence::tangential_ext`]; rows `1..=nx` are the upstream displacements of the next
    /// transient step.
    pub ux_ext: Vec<f64>,
    /// `(C τ)_y` of the final traction on the extended rows `0..=nx` (m).
    pub uy_ext: Vec<f64>,
    /// Relative stopping tolerance: stick slip distances below `tol · max(g) · C_ii` (i.e. a
    /// traction error of about `tol · µ p_max`), slip directions converged to `tol`.
    pub tol: f64,
    /// Maximum iterations of the FISTA fallback.
    pub max_iterations: usize,
    /// Maximum influence products of the active-set method before falling back to FISTA.
    pub cg_iterations: usize,
    /// Influence products (FFT pairs) used by the last solve.
    pub products: usize,
    /// `c_x ΔA` (m/Pa): uniform x displacement per unit traction summed over the grid
    /// (series compliance times element area, module doc; negative with the fe-patch's split,
    /// the operator then positive definite only with the patch's own compliance); 0 = none.
    pub uniform_x_m_per_pa: f64,
    /// `c_y ΔA` (m/Pa), as [`Self::uniform_x_m_per_pa`] for y.
    pub uniform_y_m_per_pa: f64,
}

impl TangentialSolver {
    /// Scratch for `n` elements on a grid with `nx` rows along x (`n = nx · ny`).
    pub fn new(n: usize, nx: usize) -> Self {
        let ext = n + n.checked_div(nx).unwrap_or(0);
        TangentialSolver {
            dx_: vec![0.0; n],
            dy_: vec![0.0; n],
            qx: vec![0.0; n],
            qy: vec![0.0; n],
            slip: vec![false; n],
            px: vec![0.0; n],
            py: vec![0.0; n],
            rx: vec![0.0; n],
            ry: vec![0.0; n],
            kap: vec![0.0; n],
            mix: vec![0.0; n],
            miy: vec![0.0; n],
            lo: 0,
            hi: n,
            rows: (0, 0),
            cols: (0, 0),
            segs: Vec::with_capacity(nx.max(1)),
            exact_now: false,
            wa: vec![0.0; n],
            ws: vec![0.0; n],
            tx_last: vec![0.0; n],
            ty_last: vec![0.0; n],
            last_box: ((0, 0), (0, 0)),
            last_valid: false,
            last_conv: (0, 0, 0.0, 0.0),
            linear_start: true,
            algorithm: TangentialAlgorithm::Newton,
            jacobi: true,
            sx: vec![0.0; n],
            sy: vec![0.0; n],
            ux_ext: vec![0.0; ext],
            uy_ext: vec![0.0; ext],
            tol: 1e-7,
            max_iterations: 20000,
            cg_iterations: 400,
            products: 0,
            uniform_x_m_per_pa: 0.0,
            uniform_y_m_per_pa: 0.0,
        }
    }

    /// Uniform displacements `(c_x ΔA Σ fx, c_y ΔA Σ fy)` (m) of the series compliance.
    fn uniform(&self, fx: &[f64], fy: &[f64]) -> (f64, f64) {
        let sum = |f: &[f64], c: f64| if c != 0.0 { f.iter().sum::<f64>() } else { 0.0 };
        self.uniform_of_sums(
            sum(fx, self.uniform_x_m_per_pa),
            sum(fy, self.uniform_y_m_per_pa),
        )
    }

    /// Uniform displacements `(c_x ΔA sx, c_y ΔA sy)` (m) of the series compliance for the
    /// traction sums `sx, sy` (Pa); exactly 0 along an axis without series compliance.
    fn uniform_of_sums(&self, sx: f64, sy: f64) -> (f64, f64) {
        let u = |c: f64, s: f64| if c != 0.0 { c * s } else { 0.0 };
        (
            u(self.uniform_x_m_per_pa, sx),
            u(self.uniform_y_m_per_pa, sy),
        )
    }

    /// `S = C τ + c ΔA Σ τ + e` exactly (one FFT pair), with the extended displacement rows
    /// (of `C τ` alone) kept.
    fn exact(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        ex: &[f64],
        ey: &[f64],
        tx: &[f64],
        ty: &[f64],
    ) {
        conv.tangential_ext(tx, ty, &mut self.ux_ext, &mut self.uy_ext);
        let (cux, cuy) = self.uniform(tx, ty);
        let n = ex.len();
        for i in 0..n {
            self.sx[i] = self.ux_ext[i] + ex[i] + cux;
            self.sy[i] = self.uy_ext[i] + ey[i] + cuy;
        }
        self.products += 1;
        self.exact_now = true;
    }

    /// The start's slip `S = C τ_last + C (τ₀ − τ_last) + c ΔA Σ τ₀ + e` on the contact's
    /// elements `lo..hi` ([`Self::linear_start`]): `C τ_last` is the last solve's exact
    /// product (`ux_ext`, kept), the difference's product a box product on the box holding
    /// both contacts (`last_box` and the current one). Not exact (`exact_now` stays false):
    /// the solve's convergence is confirmed by a whole-grid product.
    fn start_by_linearity(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        ex: &[f64],
        ey: &[f64],
        tx: &[f64],
        ty: &[f64],
        (last_rows, last_cols): ((usize, usize), (usize, usize)),
    ) {
        let hull = |a: (usize, usize), b: (usize, usize)| match (a.0 < a.1, b.0 < b.1) {
            (true, true) => (a.0.min(b.0), a.1.max(b.1)),
            (true, false) => a,
            _ => b,
        };
        let rows = hull(self.rows, last_rows);
        let cols = hull(self.cols, last_cols);
        let ny = conv.dims().1;
        let (a, b) = (rows.0 * ny, rows.1 * ny);
        // (rx, ry) are free until the first residual: the traction's change on the box's rows
        for i in a..b {
            self.rx[i] = tx[i] - self.tx_last[i];
            self.ry[i] = ty[i] - self.ty_last[i];
        }
        conv.tangential_box(&self.rx, &self.ry, &mut self.qx, &mut self.qy, rows, cols);
        let (cux, cuy) = self.uniform(tx, ty);
        for i in self.lo..self.hi {
            self.sx[i] = self.ux_ext[i] + self.qx[i] + ex[i] + cux;
            self.sy[i] = self.uy_ext[i] + self.qy[i] + ey[i] + cuy;
        }
        self.products += 1;
        self.exact_now = false;
    }

    /// Slip tractions back onto their circles `|τ_i| = g_i` (after turns along the tangent).
    fn to_circles(&self, g: &[f64], tx: &mut [f64], ty: &mut [f64]) {
        for i in self.lo..self.hi {
            if self.slip[i] && g[i] > 0.0 {
                let s = g[i] / (tx[i] * tx[i] + ty[i] * ty[i]).sqrt();
                tx[i] *= s;
                ty[i] *= s;
            }
        }
    }

    /// Projected residual `r = −P S`. With `into_d` it is written to the search direction
    /// `(dx_, dy_)`, otherwise to `(qx, qy)`. Returns `(r·r, max |r|)`.
    fn residual(&mut self, g: &[f64], into_d: bool) -> (f64, f64) {
        let norot = self.algorithm == TangentialAlgorithm::ElementTest;
        let mut rr = 0.0;
        let mut rmax = 0.0_f64;
        for i in self.lo..self.hi {
            let (rx, ry) = if g[i] <= 0.0 {
                (0.0, 0.0)
            } else if self.slip[i] {
                if norot {
                    (0.0, 0.0)
                } else {
                    let c = -(self.sx[i] * self.px[i] + self.sy[i] * self.py[i]);
                    (c * self.px[i], c * self.py[i])
                }
            } else {
                (-self.sx[i], -self.sy[i])
            };
            rr += rx * rx + ry * ry;
            rmax = rmax.max(rx.abs()).max(ry.abs());
            if into_d {
                self.dx_[i] = rx;
                self.dy_[i] = ry;
            } else {
                self.qx[i] = rx;
                self.qy[i] = ry;
            }
        }
        (rr, rmax)
    }

    /// Solve for `(tx, ty)` (Pa, in/out: warm start). Returns the number of influence
    /// products (FFT pairs) used. On exit `self.sx, self.sy` hold the slip distances
    /// `S = Cτ + e` (m) and `ux_ext, uy_ext` the displacements `Cτ` on rows `0..=nx`.
    ///
    /// Active-set method with inner conjugate gradients (the tangential analogue of Polonsky
    /// & Keer 1999, cf. Vollebregt's TangCG), organised so that it cannot cycle inside a CG
    /// sequence:
    /// 1. *Element test* of the slip elements (Kalker): the trial traction `τ − S/C_ii`
    ///    inside the disc ⇒ release to adhesion; outside ⇒ `τ = g · trial/|trial|` (the
    ///    direction opposite to the slip; a Jacobi-type update, followed by an exact product).
    /// 2. *Inner CG* on the adhesion set with the slip tractions frozen (`S = 0` there). The
    ///    residual is carried by the recurrence: one FFT product per iteration. An adhesion
    ///    element whose traction leaves the disc is projected onto it and joins the slip set;
    ///    the CG then stops and the outer loop restarts from an exact residual.
    ///    With [`TangentialAlgorithm::Newton`] (default) the slip elements also carry one
    ///    degree of freedom each, the turn along the tangent `t_i` of their circle: the CG
    ///    minimises the second-order model of the energy on the set {adhesion τ, slip
    ///    directions}, whose Hessian is `P C P + diag(|S_i|/g_i)` on the slip elements (`P`
    ///    the projection on the tangents; the diagonal is the curvature of the circle times
    ///    the radial slip, without which the CG overshoots along the tangent lines). After the
    ///    (inexact, relative residual 0.01) Newton step the slip tractions return to their
    ///    circles and an exact product restarts the outer loop; turns larger than `0.05 g_i`
    ///    are made by the element test. Once the element test changes nothing (no release,
    ///    no turn: the active set and the directions are settled, as in most steps of a
    ///    passage from the warm start), the CG runs to the final tolerance in one sequence
    ///    instead of restarting at every 100× reduction (each restart throws the Krylov
    ///    space away).
    ///
    ///    *Jacobi preconditioner* ([`Self::jacobi`], Newton only): the model Hessian's diagonal
    ///    is the self-influence `C_xx(0)`, `C_yy(0)` (+ the series term `c ΔA`) on adhesion
    ///    elements, but `t_iᵀ C_ii t_i + κ_i` on the slip elements, and the curvature
    ///    `κ_i = |S_i|/g_i` spreads over orders of magnitude (large where the slip is large
    ///    and the bound `µ p` small, at the trailing edge). Scaling by the inverse diagonal
    ///    removes that spread: on the passage of the default model it halves the influence
    ///    products per step (docs/performance.md). It leaves a slip element's search direction
    ///    along its tangent (a scalar per element), so the CG stays on the same model.
    ///
    /// The outer loop ends when the adhesion residual is below tolerance, no element changes
    /// state and the slip directions are converged. If it has not ended after
    /// `cg_iterations` products, the monotone accelerated projected gradient (FISTA) finishes.
    ///
    /// Phases: `start` (the warm start projected, the slip set and the contact's box) and its
    /// slip (by linearity from the last solve, [`Self::linear_start`]), then per outer
    /// iteration `element_test`, the projected residual and the convergence test, the CG
    /// model (`curvature`, `precondition`) and `inner_cg`; the FISTA fallback last.
    pub fn solve(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        g: &[f64],
        ex: &[f64],
        ey: &[f64],
        tx: &mut [f64],
        ty: &mut [f64],
    ) -> Result<usize, ContactError> {
        let out = self.solve_from_start(conv, g, ex, ey, tx, ty);
        // every successful solve ends on an exact whole-grid product of (tx, ty)
        self.last_valid = out.is_ok();
        if self.last_valid {
            self.tx_last.copy_from_slice(tx);
            self.ty_last.copy_from_slice(ty);
            self.last_conv = Self::fingerprint(conv);
            if g.iter().all(|&v| v <= 0.0) {
                self.last_box = ((0, 0), (0, 0));
            }
        }
        out
    }

    /// The convolver's dimensions and self-influences (m/Pa): the linear start's check that
    /// the last solve's product belongs to the same operator.
    fn fingerprint(conv: &(impl TangentialInfluence + ?Sized)) -> (usize, usize, f64, f64) {
        let (nx, ny) = conv.dims();
        (nx, ny, conv.diag_xx(), conv.diag_yy())
    }

    /// [`Self::solve`] without the bookkeeping of the last solve.
    fn solve_from_start(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        g: &[f64],
        ex: &[f64],
        ey: &[f64],
        tx: &mut [f64],
        ty: &mut [f64],
    ) -> Result<usize, ContactError> {
        self.products = 0;
        let gmax = g.iter().cloned().fold(0.0, f64::max);
        if gmax <= 0.0 {
            tx.fill(0.0);
            ty.fill(0.0);
            self.sx.copy_from_slice(ex);
            self.sy.copy_from_slice(ey);
            self.ux_ext.fill(0.0);
            self.uy_ext.fill(0.0);
            return Ok(0);
        }
        let last_box = self.last_box;
        self.start(conv, g, tx, ty);
        self.last_box = (self.rows, self.cols);
        let norot = self.algorithm == TangentialAlgorithm::ElementTest;
        let s_tol = self.tol * gmax * conv.diag_t();
        if self.linear_start && self.last_valid && self.last_conv == Self::fingerprint(conv) {
            self.start_by_linearity(conv, ex, ey, tx, ty, last_box);
        } else {
            self.exact(conv, ex, ey, tx, ty);
        }
        let pb = Problem { g, ex, ey };
        while self.products < self.cg_iterations {
            // 1. element test of the slip elements: release to adhesion, tangent directions
            let (changed, dmax) = self.element_test(conv, g, gmax, tx, ty);
            if dmax > 0.0 {
                self.exact(conv, ex, ey, tx, ty);
            }
            // 2. projected residual r = −P S (adhesion: both components; slip: the component
            //    along the circle's tangent, which rotates τ towards −S)
            let (mut rr, rmax) = self.residual(g, true);
            if rmax <= s_tol && !changed && (dmax <= self.tol * gmax || !norot) {
                if self.exact_now {
                    return Ok(self.products);
                }
                // confirm with an exact residual (the recurrence drifts)
                self.exact(conv, ex, ey, tx, ty);
                continue;
            }
            // 3. inner CG on adhesion (2 dof) + slip (1 dof) elements: the model residual
            //    (rx, ry) and the curvature κ_i = |S_i|/g_i of the slip elements
            self.rx.copy_from_slice(&self.dx_);
            self.ry.copy_from_slice(&self.dy_);
            if !norot {
                self.curvature(g, tx, ty);
            }
            if self.jacobi && !norot {
                rr = self.precondition(conv, g);
            }
            // settled active set and directions: one CG sequence to the tolerance
            let stop = if norot || (!changed && dmax == 0.0) {
                0.5 * s_tol
            } else {
                (0.01 * rmax).max(0.5 * s_tol)
            };
            self.inner_cg(conv, &pb, tx, ty, rr, stop);
            if !norot && !self.exact_now {
                // radial correction of the turned slip tractions, exact residual
                self.to_circles(g, tx, ty);
                self.exact(conv, ex, ey, tx, ty);
            }
        }
        // active sets cycled: fall back to the (slower, monotone) accelerated projected gradient
        let its = self.solve_fista(conv, g, ex, ey, tx, ty)?;
        self.exact(conv, ex, ey, tx, ty);
        self.products += its;
        Ok(self.products)
    }

    /// The start of a solve: the warm-start traction projected onto the discs, the slip set
    /// (tractions on their circle), the range `lo..hi` of the contact (outside it g = 0, so τ,
    /// the residual and the search direction are zero, and the CG needs neither its slip nor
    /// its displacement: every solve ends with an exact product over the whole grid) and the
    /// box of its rows and columns on which the CG's products run (a padded grid).
    fn start(
        &mut self,
        conv: &(impl TangentialInfluence + ?Sized),
        g: &[f64],
        tx: &mut [f64],
        ty: &mut [f64],
    ) {
        for i in 0..g.len() {
            project(&mut tx[i], &mut ty[i], g[i]);
            self.slip[i] =
                g[i] > 0.0 && tx[i] * tx[i] + ty[i] * ty[i] >= g[i] * g[i] * (1.0 - 1e-12);
        }
        let lo = g.iter().position(|&v| v > 0.0).unwrap_or(0);
        let hi = g.iter().rposition(|&v| v > 0.0).map_or(lo, |k| k + 1);
        (self.lo, self.hi) = (lo, hi);
        let ny = conv.dims().1;
        self.rows = (lo / ny, hi.div_ceil(ny));
        let (mut col0, mut col1) = (ny, 0);
        for (k, _) in g[lo..hi].iter().enumerate().filter(|(_, &v)| v > 0.0) {
            let j = (lo + k) % ny;
            col0 = col0.min(j);
            col1 = col1.max(j + 1);
        }
        self.cols = (col0, col1);
        self.segs.clear();
        for r in self.rows.0..self.rows.1 {
            let (a, b) = ((r * ny + col0).max(lo), (r * ny + col1).min(hi));
            if a < b {
                self.segs.push((a, b));
            }
        }
        for v in [&mut self.dx_, &mut self.dy_] {
            v[..lo].fill(0.0);
            v[hi..].fill(0.0);
        }
    }

    /// Kalker's element test of the slip elements: the trial traction `τ − S/C_ii` inside the
    /// disc ⇒ release to adhesion; outside ⇒ turned onto its circle opposite to the slip when
    /// the turn is large (small turns are left to the CG rotation, except with
    /// [`TangentialAlgorithm::ElementTest`]). Sets the tangents `(px, py)` of the slip
    /// elements. Returns whether an element was released and the largest turn (Pa).
    fn element_test(
        &mut self,
        conv: &(impl TangentialInfluence + ?Sized),
        g: &[f64],
        gmax: f64,
        tx: &mut [f64],
        ty: &mut [f64],
    ) -> (bool, f64) {
        let norot = self.algorithm == TangentialAlgorithm::ElementTest;
        let (cdx, cdy) = (conv.diag_xx(), conv.diag_yy());
        let mut changed = false;
        let mut dmax = 0.0_f64;
        for i in self.lo..self.hi {
            if !self.slip[i] {
                continue;
            }
            let trx = tx[i] - self.sx[i] / cdx;
            let try_ = ty[i] - self.sy[i] / cdy;
            if trx * trx + try_ * try_ < g[i] * g[i] {
                self.slip[i] = false;
                changed = true;
            } else {
                let tm = (trx * trx + try_ * try_).sqrt();
                let (nx, ny) = (g[i] * trx / tm, g[i] * try_ / tm);
                let d = (nx - tx[i]).abs().max((ny - ty[i]).abs());
                // large turns by the element test, small ones by the CG rotation
                let thr = if norot {
                    0.1 * self.tol * gmax
                } else {
                    0.05 * g[i]
                };
                if d > thr {
                    dmax = dmax.max(d);
                    tx[i] = nx;
                    ty[i] = ny;
                }
                let m = (tx[i] * tx[i] + ty[i] * ty[i]).sqrt();
                self.px[i] = -ty[i] / m;
                self.py[i] = tx[i] / m;
            }
        }
        (changed, dmax)
    }

    /// The curvature `κ_i = |S_i|/g_i` of the slip elements' circles (the radial slip over
    /// the radius; 0 on adhesion elements), the diagonal term of the CG's model Hessian.
    fn curvature(&mut self, g: &[f64], tx: &[f64], ty: &[f64]) {
        for i in self.lo..self.hi {
            self.kap[i] = if self.slip[i] && g[i] > 0.0 {
                let m = (tx[i] * tx[i] + ty[i] * ty[i]).sqrt();
                (-(self.sx[i] * tx[i] + self.sy[i] * ty[i]) / m).max(0.0) / g[i]
            } else {
                0.0
            };
        }
    }

    /// The Jacobi preconditioner: the inverse diagonal of the model Hessian into
    /// `(mix, miy)`, the search direction scaled by it (`z = M⁻¹ r`), and the adhesion and
    /// slip masks `(wa, ws)` of the branch-free CG step. Returns `r·z`.
    fn precondition(&mut self, conv: &(impl TangentialInfluence + ?Sized), g: &[f64]) -> f64 {
        let (cdx, cdy) = (conv.diag_xx(), conv.diag_yy());
        let (hx, hy) = (cdx + self.uniform_x_m_per_pa, cdy + self.uniform_y_m_per_pa);
        let mut rr = 0.0;
        for i in self.lo..self.hi {
            let inside = g[i] > 0.0;
            self.wa[i] = f64::from(u8::from(inside && !self.slip[i]));
            self.ws[i] = f64::from(u8::from(inside && self.slip[i]));
            let (mx, my) = if self.slip[i] {
                let (px, py) = (self.px[i], self.py[i]);
                let d = 1.0 / (px * px * hx + py * py * hy + self.kap[i]);
                (d, d)
            } else {
                (1.0 / hx, 1.0 / hy)
            };
            self.mix[i] = mx;
            self.miy[i] = my;
            self.dx_[i] *= mx;
            self.dy_[i] *= my;
            rr += self.rx[i] * self.dx_[i] + self.ry[i] * self.dy_[i];
        }
        rr
    }

    /// FISTA (Beck & Teboulle 2009) with gradient restart (O'Donoghue & Candès 2015): the
    /// robust fallback; step `1/λ_max(C)`, projection onto the discs.
    fn solve_fista(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        g: &[f64],
        ex: &[f64],
        ey: &[f64],
        tx: &mut [f64],
        ty: &mut [f64],
    ) -> Result<usize, ContactError> {
        let n = g.len();
        let gmax = g.iter().cloned().fold(0.0, f64::max);
        // the rank-one terms add at most c ΔA n to the largest eigenvalue (a negative one, the
        // fe-patch's split, only lowers it: the bound without it stays a bound)
        let c_max = self
            .uniform_x_m_per_pa
            .max(self.uniform_y_m_per_pa)
            .max(0.0);
        let step = 1.0 / (conv.lambda_max_t() + c_max * n as f64);
        // reuse the CG scratch: (dx_, dy_) = extrapolated point y, (qx, qy) = new iterate
        self.dx_.copy_from_slice(tx);
        self.dy_.copy_from_slice(ty);
        let mut t = 1.0_f64;
        let mut last = f64::INFINITY;
        for it in 1..=self.max_iterations {
            conv.tangential(&self.dx_, &self.dy_, &mut self.sx, &mut self.sy, 0);
            let (cux, cuy) = self.uniform(&self.dx_, &self.dy_);
            let mut restart_dot = 0.0;
            let mut diff = 0.0_f64;
            let mut tmax = 0.0_f64;
            for i in 0..n {
                let gx = self.sx[i] + ex[i] + cux;
                let gy = self.sy[i] + ey[i] + cuy;
                let mut ax = self.dx_[i] - step * gx;
                let mut ay = self.dy_[i] - step * gy;
                project(&mut ax, &mut ay, g[i]);
                self.qx[i] = ax;
                self.qy[i] = ay;
                restart_dot +=
                    (self.dx_[i] - ax) * (ax - tx[i]) + (self.dy_[i] - ay) * (ay - ty[i]);
                diff = diff.max((ax - tx[i]).abs()).max((ay - ty[i]).abs());
                tmax = tmax.max(ax.abs()).max(ay.abs());
            }
            let t_next = 0.5 * (1.0 + (1.0 + 4.0 * t * t).sqrt());
            let beta = if restart_dot > 0.0 {
                0.0
            } else {
                (t - 1.0) / t_next
            };
            t = if restart_dot > 0.0 { 1.0 } else { t_next };
            for i in 0..n {
                let (ax, ay) = (self.qx[i], self.qy[i]);
                self.dx_[i] = ax + beta * (ax - tx[i]);
                self.dy_[i] = ay + beta * (ay - ty[i]);
                tx[i] = ax;
                ty[i] = ay;
            }
            // FISTA's per-iteration change is ~ step × gradient: use a 100× tighter test
            last = diff / tmax.max(1e-12 * gmax);
            if last < 1e-2 * self.tol {
                conv.tangential(tx, ty, &mut self.sx, &mut self.sy, 0);
                let (cux, cuy) = self.uniform(tx, ty);
                for i in 0..n {
                    self.sx[i] += ex[i] + cux;
                    self.sy[i] += ey[i] + cuy;
                }
                return Ok(it);
            }
        }
        Err(ContactError::NotConverged {
            solver: "tangential solver (active-set CG, then FISTA)",
            iterations: self.max_iterations + self.cg_iterations,
            residual: last,
        })
    }
}

#[inline]
fn project(x: &mut f64, y: &mut f64, g: f64) {
    let m2 = *x * *x + *y * *y;
    if m2 > g * g {
        if g <= 0.0 {
            *x = 0.0;
            *y = 0.0;
        } else {
            let s = g / m2.sqrt();
            *x *= s;
            *y *= s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::influence::Convolver;
    use super::{inner_cg, TangentialInfluence, TangentialSolver};
    /// A 16 × 12 grid (0.5 mm elements, steel) and an elliptic traction bound `µ p` (Pa)
    /// centred `shift` rows from the grid's centre.
    fn grid_and_bound(shift: f64) -> (Convolver, Vec<f64>) {
        let (nx, ny) = (16, 12);
        let conv = Convolver::new(nx, ny, 0.5e-3, 0.5e-3, 115e9, 80e9, 0.28);
        let g = (0..nx * ny)
            .map(|e| {
                let x = ((e / ny) as f64 - 7.5 - shift) / 6.0;
                let y = ((e % ny) as f64 - 5.5) / 4.6;
                0.3 * 1.2e9 * (1.0 - x * x - y * y).max(0.0).sqrt()
            })
            .collect();
        (conv, g)
    }

    #[test]
    fn start_by_linearity_equals_the_whole_grid_product() {
        // Independent check: the start's slip from the last solve's exact product plus the
        // box product of the traction's change, against the whole-grid double-precision
        // product of the start, on the elements of a contact that moved by one row; within
        // the f32 rounding bound of the change's product
        // (influence::tests::box_products_equal_dense_sums)
        let (mut conv, g1) = grid_and_bound(0.0);
        let (_, g2) = grid_and_bound(1.0);
        let n = g1.len();
        let ex: Vec<f64> = (0..n).map(|e| -1.2e-7 + 3e-10 * (e % 7) as f64).collect();
        let ey: Vec<f64> = (0..n).map(|e| 4e-8 - 2e-10 * (e % 5) as f64).collect();
        let mut s = TangentialSolver::new(n, 16);
        s.tol = 1e-9;
        let (mut tx, mut ty) = (vec![0.0; n], vec![0.0; n]);
        s.solve(&mut conv, &g1, &ex, &ey, &mut tx, &mut ty).unwrap();
        assert!(s.last_valid);
        // the next start: the last traction, changed, projected onto the moved discs
        let (mut tx0, mut ty0): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|e| {
                (
                    1.01 * tx[e] + 1e6 * (e % 3) as f64,
                    ty[e] - 2e6 * (e % 4) as f64,
                )
            })
            .unzip();
        let last_box = s.last_box;
        s.start(&conv, &g2, &mut tx0, &mut ty0);
        let mut exact = s.clone();
        s.start_by_linearity(&mut conv, &ex, &ey, &tx0, &ty0, last_box);
        assert!(!s.exact_now);
        exact.exact(&mut conv, &ex, &ey, &tx0, &ty0);
        let change = tx0
            .iter()
            .zip(&tx)
            .chain(ty0.iter().zip(&ty))
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        // the box holds both contacts: rows 0..16 at most, columns 0..12 (padded 32 × 24)
        let bound = 10.0
            * (32.0 * 24.0_f64).log2()
            * f64::from(f32::EPSILON)
            * conv.lambda_max_t()
            * change;
        let (mut worst, mut largest) = (0.0_f64, 0.0_f64);
        // the elements with a positive bound (elsewhere the solver reads no slip)
        for e in (s.lo..s.hi).filter(|&e| g2[e] > 0.0) {
            worst = worst
                .max((s.sx[e] - exact.sx[e]).abs())
                .max((s.sy[e] - exact.sy[e]).abs());
            largest = largest.max(exact.sx[e].abs()).max(exact.sy[e].abs());
        }
        println!(
            "linear start: worst {worst:.3e} m, bound {bound:.3e} m, slip up to {largest:.3e} m"
        );
        assert!(worst <= bound, "{worst} > {bound}");
        // not trivially small: the change's product is part of the slip
        assert!(bound < 1e-3 * largest && change > 0.0);
        // the last solve's product is kept (rows 1..=nx: the next step's upstream displacement)
        assert_eq!(s.ux_ext, exact_ext_of(&mut conv, &tx, &ty).0);
    }

    /// `C τ` on the extended rows `0..=nx` (the solver's `ux_ext, uy_ext`).
    fn exact_ext_of(
        conv: &mut (impl TangentialInfluence + ?Sized),
        tx: &[f64],
        ty: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let (nx, ny) = conv.dims();
        let (mut ux, mut uy) = (vec![0.0; (nx + 1) * ny], vec![0.0; (nx + 1) * ny]);
        conv.tangential_ext(tx, ty, &mut ux, &mut uy);
        (ux, uy)
    }

    /// A solver in the middle of an inner CG on the grid of [`grid_and_bound`]: adhesion and
    /// slip elements (tangents, curvatures, Jacobi scales, masks), a search direction, its
    /// product, the residual; traction and slip. Zero where the bound is zero.
    fn cg_state(g: &[f64]) -> (TangentialSolver, Vec<f64>, Vec<f64>) {
        let n = g.len();
        let mut s = TangentialSolver::new(n, 16);
        let (mut tx, mut ty) = (vec![0.0; n], vec![0.0; n]);
        s.lo = g.iter().position(|&v| v > 0.0).unwrap();
        s.hi = g.iter().rposition(|&v| v > 0.0).unwrap() + 1;
        s.segs = (0..16)
            .map(|r| ((r * 12 + 1).max(s.lo), (r * 12 + 11).min(s.hi)))
            .filter(|(a, b)| a < b)
            .collect();
        let w = |e: usize, k: usize| ((e * 7919 + k * 104729) % 1000) as f64 / 1000.0 - 0.5;
        for e in s.lo..s.hi {
            if g[e] <= 0.0 {
                continue;
            }
            let slip = e % 3 == 0;
            s.slip[e] = slip;
            let phi = 6.0 * w(e, 1);
            if slip {
                (tx[e], ty[e]) = (g[e] * phi.cos(), g[e] * phi.sin());
                (s.px[e], s.py[e]) = (-phi.sin(), phi.cos());
                s.kap[e] = 1e-12 * (1.5 + w(e, 2));
                let d = 1e7 * w(e, 3);
                (s.dx_[e], s.dy_[e]) = (d * s.px[e], d * s.py[e]);
                let m = 1.0 / (1e-11 + s.kap[e]);
                (s.mix[e], s.miy[e]) = (m, m);
            } else {
                (tx[e], ty[e]) = (0.4 * g[e] * w(e, 4), 0.4 * g[e] * w(e, 5));
                (s.dx_[e], s.dy_[e]) = (1e7 * w(e, 6), 1e7 * w(e, 7));
                (s.mix[e], s.miy[e]) = (1e11, 0.9e11);
            }
            s.wa[e] = f64::from(u8::from(!slip));
            s.ws[e] = f64::from(u8::from(slip));
            (s.qx[e], s.qy[e]) = (1e-4 * w(e, 8), 1e-4 * w(e, 9));
            (s.rx[e], s.ry[e]) = (1e-7 * w(e, 10), 1e-7 * w(e, 11));
            (s.sx[e], s.sy[e]) = (1e-6 * w(e, 12), 1e-6 * w(e, 13));
        }
        (s, tx, ty)
    }

    /// The CG step of length `alpha` on `(tx, ty)` over `segs`.
    fn step<'a>(
        g: &'a [f64],
        tx: &'a mut [f64],
        ty: &'a mut [f64],
        alpha: f64,
        segs: &'a [(usize, usize)],
    ) -> inner_cg::CgStep<'a> {
        inner_cg::CgStep {
            g,
            tx,
            ty,
            alpha,
            segs,
        }
    }

    #[test]
    fn avx2_inner_cg_gives_the_bits_of_the_baseline_loops() {
        // Whole solves of a transient sequence (the contact moving by a row per step, load
        // and shift varying, warm starts) with the inner CG's AVX2 kernels and with its
        // baseline loops: the same tractions, slips and products bit for bit
        let run = |plain: bool| {
            inner_cg::tests::PLAIN_CG.with(|p| p.set(plain));
            let mut out = Vec::new();
            let (mut conv, _) = grid_and_bound(0.0);
            let n = conv.dims().0 * conv.dims().1;
            let mut s = TangentialSolver::new(n, 16);
            s.uniform_x_m_per_pa = 1e-13;
            let (mut tx, mut ty) = (vec![0.0; n], vec![0.0; n]);
            for k in 0..6 {
                let (_, g) = grid_and_bound(0.5 * k as f64 - 1.0);
                let ex: Vec<f64> = (0..n)
                    .map(|e| -1.2e-7 * (1.0 + 0.1 * k as f64) + 3e-10 * (e % 7) as f64)
                    .collect();
                let ey: Vec<f64> = (0..n).map(|e| 4e-8 - 2e-10 * (e % 5) as f64).collect();
                let p = s.solve(&mut conv, &g, &ex, &ey, &mut tx, &mut ty).unwrap();
                out.push(p as f64);
                out.extend(tx.iter().chain(&ty).chain(&s.sx).chain(&s.sy));
            }
            inner_cg::tests::PLAIN_CG.with(|p| p.set(false));
            out
        };
        let (simd, plain) = (run(false), run(true));
        assert!(simd.iter().any(|&v| v != 0.0));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&simd), bits(&plain));
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_cg_step_gives_the_bits_of_the_lanes_loop() {
        // The AVX2 kernel of the masked step against the `lanes!` loop from the same state:
        // the same operations per element in the same lanes, so every output bit for bit,
        // with and without an adhesion element leaving its disc
        let (_, g) = grid_and_bound(0.0);
        for alpha in [0.37, 40.0] {
            let (mut a, mut txa, mut tya) = cg_state(&g);
            let (mut b, mut txb, mut tyb) = (a.clone(), txa.clone(), tya.clone());
            let segs = a.segs.clone();
            let Some(va) = a.cg_update_masked_avx2(step(&g, &mut txa, &mut tya, alpha, &segs))
            else {
                println!("no AVX2 on this CPU: nothing to compare");
                return;
            };
            let vb = b.cg_update_masked(step(&g, &mut txb, &mut tyb, alpha, &segs));
            assert_eq!(va.0, vb.0, "alpha {alpha}");
            assert_eq!(
                (va.1.to_bits(), va.2.to_bits()),
                (vb.1.to_bits(), vb.2.to_bits())
            );
            assert_eq!((txa, tya), (txb, tyb));
            assert_eq!(a.slip, b.slip);
            assert_same_step_outputs(&a, &b);
        }
    }

    /// Slip, residual and preconditioned residual of two solvers after a CG step: bit for bit.
    fn assert_same_step_outputs(a: &TangentialSolver, b: &TangentialSolver) {
        for (x, y) in [
            (&a.sx, &b.sx),
            (&a.sy, &b.sy),
            (&a.rx, &b.rx),
            (&a.ry, &b.ry),
            (&a.qx, &b.qx),
            (&a.qy, &b.qy),
        ] {
            assert_eq!(x, y);
        }
    }

    #[test]
    fn branch_free_cg_step_equals_the_branching_one() {
        // Independent check: the masked step against the branching `cg_update` from the same
        // state: every element's traction, slip, residual and preconditioned residual bit
        // for bit, `max |r|` exactly; `r·z` summed in another order, within
        // `n u Σ |r z|` (Higham 2002 §3.1); an adhesion element pushed out of its disc
        // projected and moved to the slip set by both
        let (_, g) = grid_and_bound(0.0);
        for alpha in [0.37, 40.0] {
            let (mut a, mut txa, mut tya) = cg_state(&g);
            let (mut b, mut txb, mut tyb) = (a.clone(), txa.clone(), tya.clone());
            let segs = a.segs.clone();
            let terms: f64 = {
                let (mut c, mut t, mut u) = (b.clone(), txb.clone(), tyb.clone());
                c.cg_update(step(&g, &mut t, &mut u, alpha, &segs));
                segs.iter()
                    .flat_map(|&(p, q)| p..q)
                    .map(|e| (c.rx[e] * c.qx[e]).abs() + (c.ry[e] * c.qy[e]).abs())
                    .sum()
            };
            let (va, rra, rma) = a.cg_update_masked(step(&g, &mut txa, &mut tya, alpha, &segs));
            let (vb, rrb, rmb) = b.cg_update(step(&g, &mut txb, &mut tyb, alpha, &segs));
            assert_eq!(va, vb, "alpha {alpha}");
            assert_eq!(txa, txb);
            assert_eq!(tya, tyb);
            assert_eq!(a.slip, b.slip);
            if va {
                // the step's residual is not used after a violation
                continue;
            }
            assert_eq!(rma.to_bits(), rmb.to_bits());
            assert_same_step_outputs(&a, &b);
            let n = (a.hi - a.lo) as f64;
            assert!(
                (rra - rrb).abs() <= n * f64::EPSILON * terms,
                "{rra} vs {rrb} (bound {})",
                n * f64::EPSILON * terms
            );
            assert!(rra > 0.0);
        }
    }
}

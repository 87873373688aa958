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
//! an active-set conjugate-gradient method with FFT influence products (see [`TangentialSolver::solve`]).

use super::influence::Convolver;
use super::ContactError;

/// Scratch for the tangential solver (allocated once).
pub struct TangentialSolver {
    dx_: Vec<f64>,
    dy_: Vec<f64>,
    qx: Vec<f64>,
    qy: Vec<f64>,
    slip: Vec<bool>,
    /// Slip distance S_x of the last solve (m).
    pub sx: Vec<f64>,
    /// Slip distance S_y of the last solve (m).
    pub sy: Vec<f64>,
    /// Relative stopping tolerance on the traction update, relative to max |τ|.
    pub tol: f64,
    /// Maximum iterations (of each of the two methods).
    pub max_iterations: usize,
    /// Iterations of the active-set CG before falling back to FISTA.
    pub cg_iterations: usize,
}

impl TangentialSolver {
    /// Scratch for `n` elements.
    pub fn new(n: usize) -> Self {
        TangentialSolver {
            dx_: vec![0.0; n],
            dy_: vec![0.0; n],
            qx: vec![0.0; n],
            qy: vec![0.0; n],
            slip: vec![false; n],
            sx: vec![0.0; n],
            sy: vec![0.0; n],
            tol: 1e-7,
            max_iterations: 20000,
            cg_iterations: 400,
        }
    }

    /// Solve for `(tx, ty)` (Pa, in/out: warm start). Returns the number of iterations. On exit
    /// `self.sx, self.sy` hold the slip distances `S = Cτ + e` (m).
    ///
    /// Active-set conjugate gradients (the tangential analogue of Polonsky & Keer 1999, cf.
    /// Vollebregt's TangCG): CG on the adhesion set, elements that exceed the traction bound
    /// are projected onto it and join the slip set, slip elements take the direction
    /// the direction of the local trial traction `τ − S/C_ii` (Kalker's element test) and are
    /// released to adhesion when that trial lies inside the disc; CG restarts whenever the
    /// sets change.
    pub fn solve(
        &mut self,
        conv: &mut Convolver,
        g: &[f64],
        ex: &[f64],
        ey: &[f64],
        tx: &mut [f64],
        ty: &mut [f64],
    ) -> Result<usize, ContactError> {
        let n = g.len();
        let gmax = g.iter().cloned().fold(0.0, f64::max);
        if gmax <= 0.0 {
            tx.fill(0.0);
            ty.fill(0.0);
            self.sx.copy_from_slice(ex);
            self.sy.copy_from_slice(ey);
            return Ok(0);
        }
        for i in 0..n {
            project(&mut tx[i], &mut ty[i], g[i]);
            self.slip[i] =
                g[i] > 0.0 && tx[i] * tx[i] + ty[i] * ty[i] >= g[i] * g[i] * (1.0 - 1e-12);
        }
        self.dx_.fill(0.0);
        self.dy_.fill(0.0);
        let mut rr_old = 0.0;
        let mut restart = true;
        let mut last = f64::INFINITY;
        let cd = conv.diag_t;
        for it in 1..=self.cg_iterations {
            conv.tangential(tx, ty, &mut self.sx, &mut self.sy, 0);
            let mut changed = false;
            let mut diff = 0.0_f64;
            let mut tmax = 0.0_f64;
            let mut rr = 0.0;
            for i in 0..n {
                let (sx, sy) = (self.sx[i] + ex[i], self.sy[i] + ey[i]);
                self.sx[i] = sx;
                self.sy[i] = sy;
                if g[i] <= 0.0 {
                    continue;
                }
                if self.slip[i] {
                    // local element problem (Kalker's Gauss–Seidel test): the traction this
                    // element would take with the others frozen decides stick or slip
                    let trx = tx[i] - sx / cd;
                    let try_ = ty[i] - sy / cd;
                    let tm = (trx * trx + try_ * try_).sqrt();
                    if tm < g[i] {
                        self.slip[i] = false;
                        changed = true;
                    } else {
                        let (nx, ny) = (g[i] * trx / tm, g[i] * try_ / tm);
                        diff = diff.max((nx - tx[i]).abs()).max((ny - ty[i]).abs());
                        tx[i] = nx;
                        ty[i] = ny;
                        continue;
                    }
                }
                rr += sx * sx + sy * sy;
            }
            let beta = if restart || changed || rr_old == 0.0 {
                0.0
            } else {
                rr / rr_old
            };
            rr_old = rr;
            for i in 0..n {
                if g[i] > 0.0 && !self.slip[i] {
                    self.dx_[i] = self.sx[i] + beta * self.dx_[i];
                    self.dy_[i] = self.sy[i] + beta * self.dy_[i];
                } else {
                    self.dx_[i] = 0.0;
                    self.dy_[i] = 0.0;
                }
            }
            conv.tangential(&self.dx_, &self.dy_, &mut self.qx, &mut self.qy, 0);
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                if g[i] > 0.0 && !self.slip[i] {
                    num += self.sx[i] * self.dx_[i] + self.sy[i] * self.dy_[i];
                    den += self.qx[i] * self.dx_[i] + self.qy[i] * self.dy_[i];
                }
            }
            let alpha = if den > 0.0 { num / den } else { 0.0 };
            restart = false;
            for i in 0..n {
                if g[i] > 0.0 && !self.slip[i] {
                    let (ox, oy) = (tx[i], ty[i]);
                    let mut ax = ox - alpha * self.dx_[i];
                    let mut ay = oy - alpha * self.dy_[i];
                    if ax * ax + ay * ay >= g[i] * g[i] {
                        project(&mut ax, &mut ay, g[i]);
                        self.slip[i] = true;
                    }
                    diff = diff.max((ax - ox).abs()).max((ay - oy).abs());
                    tx[i] = ax;
                    ty[i] = ay;
                }
                tmax = tmax.max(tx[i].abs()).max(ty[i].abs());
            }
            restart |= changed;
            last = diff / tmax.max(1e-12 * gmax);
            if last < self.tol && !changed {
                conv.tangential(tx, ty, &mut self.sx, &mut self.sy, 0);
                for i in 0..n {
                    self.sx[i] += ex[i];
                    self.sy[i] += ey[i];
                }
                return Ok(it);
            }
        }
        let _ = last;
        // active sets cycled: fall back to the (slower, monotone) accelerated projected gradient
        let its = self.solve_fista(conv, g, ex, ey, tx, ty)?;
        Ok(self.cg_iterations + its)
    }

    /// FISTA (Beck & Teboulle 2009) with gradient restart (O'Donoghue & Candès 2015): the
    /// robust fallback; step `1/λ_max(C)`, projection onto the discs.
    fn solve_fista(
        &mut self,
        conv: &mut Convolver,
        g: &[f64],
        ex: &[f64],
        ey: &[f64],
        tx: &mut [f64],
        ty: &mut [f64],
    ) -> Result<usize, ContactError> {
        let n = g.len();
        let gmax = g.iter().cloned().fold(0.0, f64::max);
        let step = 1.0 / conv.lambda_max_t;
        // reuse the CG scratch: (dx_, dy_) = extrapolated point y, (qx, qy) = new iterate
        self.dx_.copy_from_slice(tx);
        self.dy_.copy_from_slice(ty);
        let mut t = 1.0_f64;
        let mut last = f64::INFINITY;
        for it in 1..=self.max_iterations {
            conv.tangential(&self.dx_, &self.dy_, &mut self.sx, &mut self.sy, 0);
            let mut restart_dot = 0.0;
            let mut diff = 0.0_f64;
            let mut tmax = 0.0_f64;
            for i in 0..n {
                let gx = self.sx[i] + ex[i];
                let gy = self.sy[i] + ey[i];
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
                for i in 0..n {
                    self.sx[i] += ex[i];
                    self.sy[i] += ey[i];
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

//! Transient (and steady) rolling contact engine, the rail-fixed wear accumulator, and the
//! normal-load frequency response of the longitudinal force.
//!
//! # Discretisation of transient rolling (Kalker 1990 §2.2; CONTACT user guide)
//! The time step is tied to the grid, `Δt = Δx / V`: in one step the material of both bodies
//! moves exactly one cell in `−x` through the contact frame. The slip distance of element `i`
//! during the step is
//! ```text
//! S_i = w_i Δx + u_i(t) − u_{i+1}(t − Δt)
//! ```
//! with `w = (ξ − φ y, η + φ x)` the rigid creepages, `u(t)` the current displacement
//! difference, and `u_{i+1}(t − Δt)` the displacement of the previous step at the position the
//! same material occupied then (one cell downstream, towards the leading edge at `+x`). The
//! previous displacement there is the exact influence product of the previous traction (the FFT
//! convolution delivers row `nx`, one cell beyond the grid). The slip velocity is
//! `s = S / Δt` (m/s). Steady rolling is the fixed point `u(t) = u(t − Δt)`, i.e. the upwind
//! difference `S_i = w_i Δx + u_i − u_{i+1}`, reached by stepping with constant inputs.
//!
//! Normal and tangential problems are decoupled (quasi-identical bodies, see the module root),
//! so each step solves the normal problem first, then the tangential one with `g = µp`.
//!
//! The previous displacement `u(t − Δt)` on rows `1..=nx` is the extended product the
//! tangential solver computes anyway for its final residual, so a step needs no extra FFT.
//!
//! # Frictional work (docs/theory.md §6.6)
//! Per element and step: power density `P_i = −τ̄_i · s_i` (W/m², ≥ 0, zero in stick) and
//! work density `P_i Δt` (J/m²), with `τ̄_i = ½ (τ_i(t) + τ_{i+1}(t − Δt))` the trapezoidal
//! mean of the traction along the material path `x_{i+1} → x_i` of the step (second order;
//! zero contribution from `τ_nx`). Elements just behind the trailing edge keep the work of the
//! path on which their material left the contact (unless the whole contact separated in the
//! step: then the step has no frictional work). Because the influence operator is
//! symmetric and shift-invariant, `Σ τ̄_i · (u_i − u_{i+1}) = 0` in steady rolling, so the
//! patch-integrated power equals `−V (ξ Fx + η Fy)` exactly up to the solver tolerance (with
//! spin up to `O(Δx)`). Pairing the slip with the end-of-step traction alone (backward Euler
//! along the path) loses `(V/Δx) τᵀ(C − C̄)τ ≥ 0` (`C̄` the one-cell shifted operator), a
//! first-order error of relative size ≈ `Δx µ p0 / (G a ξ)`: 24 % on 32 × 24. `WearAccumulator` maps element `(i, j)` at contact position `x_c`
//! to the rail-fixed bin containing `x_c + x_i`.
//!
//! # Series compliance ([`TransientRolling::set_series_compliance`])
//! The residual (static) flexibility of truncated track modes at the contact point enters as
//! a uniform extra displacement `c_d F_d` (m) of the rail surface under the whole patch along
//! each axis `d`, with `F_d` the end-of-step force (implicit). Normal: the effective approach is
//! `δ − c_z F_N` (rank-one term in the normal operator, [`super::normal`]). Tangential: the slip
//! gains `c_x (F_x(t) − F_x(t − Δt))` (and y), `c` the value of the current step; the implicit
//! part is a rank-one term of the operator, the explicit part goes into the shift
//! ([`super::tangential`]). In steady rolling `F(t) = F(t − Δt)`: the forces and the frictional
//! work are unchanged. In transient rolling the uniform slip is part of the true slip of every
//! element, so the local work stays exact; the patch-integrated power then contains, besides
//! `−V (ξ Fx + η Fy + φ Mz)`, the exchange with the series spring: with the path-mean traction
//! `Σ τ̄ ΔA ≈ ½ (F(t) + F(t − Δt))`, its share `−c_x ½ (F(t) + F(t−Δt)) (F(t) − F(t−Δt)) / Δt`
//! is minus the rate of change of the spring energy `½ c_x F_x²` (counted only where the
//! elements slip; it telescopes to zero over a closed force cycle).

use super::influence::{Convolver, Influence};
use super::normal::{NormalMode, NormalSolver};
use super::tangential::{TangentialAlgorithm, TangentialSolver};
use super::{check_positive, combined_modulus, shear_modulus, ContactError};

pub use super::rolling::{
    GridSpec, HertzGridParams, Longitudinal, NormalInput, StepInputs, StepResult, TransientConfig,
};
pub use super::rolling::{STATE_EXTERIOR, STATE_SLIP, STATE_STICK};

/// The transient rolling engine: all scratch allocated in [`TransientRolling::new`];
/// [`TransientRolling::step`] allocates nothing and warm-starts from the previous step.
/// A clone is an independent engine in the same state (the FFT plans are shared, read-only).
#[derive(Clone)]
pub struct TransientRolling {
    pub(super) cfg: TransientConfig,
    pub(super) nx: usize,
    pub(super) ny: usize,
    pub(super) dx: f64,
    da: f64,
    pub(super) xs: Vec<f64>,
    ys: Vec<f64>,
    conv: Influence,
    normal: NormalSolver,
    tang: TangentialSolver,
    h: Vec<f64>,
    p: Vec<f64>,
    g: Vec<f64>,
    tx: Vec<f64>,
    ty: Vec<f64>,
    tx_prev: Vec<f64>,
    ty_prev: Vec<f64>,
    /// Traction two steps back (Pa), for the extrapolated warm start.
    tx_pp: Vec<f64>,
    ty_pp: Vec<f64>,
    upx: Vec<f64>,
    upy: Vec<f64>,
    ex: Vec<f64>,
    ey: Vec<f64>,
    sx: Vec<f64>,
    sy: Vec<f64>,
    pub(super) power: Vec<f64>,
    state: Vec<u8>,
    xi_last: f64,
    steps: usize,
    g_mod: f64,
    /// Series compliances `(c_x, c_y, c_z)` (m/N).
    series_c: [f64; 3],
    /// Whether the warm start puts the last step's slip elements on their new circle
    /// ([`Self::set_circle_start`]).
    circle_start: bool,
}

impl TransientRolling {
    /// Allocate the engine and its influence kernels: Kalker's quasi-identical half-spaces.
    pub fn new(cfg: TransientConfig) -> Result<Self, ContactError> {
        cfg.validate()?;
        let (dx, dy) = (cfg.grid.dx(), cfg.grid.dy());
        let es = combined_modulus(cfg.youngs_pa, cfg.poisson);
        let gm = shear_modulus(cfg.youngs_pa, cfg.poisson);
        let conv = Convolver::new(cfg.grid.nx, cfg.grid.ny, dx, dy, es, gm, cfg.poisson);
        Self::with_influence(cfg, Influence::HalfSpace(conv))
    }

    /// Allocate the engine on the given influence operators (an FE contact patch's,
    /// [`Influence::Strip`], or the half-spaces'), refused unless they are on the grid of
    /// `cfg` (`nx × ny`).
    pub fn with_influence(cfg: TransientConfig, conv: Influence) -> Result<Self, ContactError> {
        cfg.validate()?;
        let (nx, ny) = (cfg.grid.nx, cfg.grid.ny);
        if conv.dims() != (nx, ny) {
            return Err(ContactError::InvalidParameter {
                name: "influence grid",
                value: (conv.dims().0 * conv.dims().1) as f64,
                reason: "the influence operators must be on the contact grid (nx × ny elements)",
            });
        }
        let n = nx * ny;
        let (dx, dy) = (cfg.grid.dx(), cfg.grid.dy());
        let gm = shear_modulus(cfg.youngs_pa, cfg.poisson);
        let mut normal = NormalSolver::new(n);
        normal.tol = cfg.normal_tol;
        let mut tang = TangentialSolver::new(n, nx);
        tang.tol = cfg.tangential_tol;
        let mut engine = TransientRolling {
            nx,
            ny,
            dx,
            da: dx * dy,
            xs: (0..nx).map(|i| cfg.grid.x(i)).collect(),
            ys: (0..ny).map(|j| cfg.grid.y(j)).collect(),
            conv,
            normal,
            tang,
            h: vec![0.0; n],
            p: vec![0.0; n],
            g: vec![0.0; n],
            tx: vec![0.0; n],
            ty: vec![0.0; n],
            tx_prev: vec![0.0; n],
            ty_prev: vec![0.0; n],
            tx_pp: vec![0.0; n],
            ty_pp: vec![0.0; n],
            upx: vec![0.0; n],
            upy: vec![0.0; n],
            ex: vec![0.0; n],
            ey: vec![0.0; n],
            sx: vec![0.0; n],
            sy: vec![0.0; n],
            power: vec![0.0; n],
            state: vec![0; n],
            xi_last: 0.0,
            steps: 0,
            g_mod: gm,
            series_c: [0.0; 3],
            circle_start: true,
            cfg,
        };
        engine.apply_series_compliance();
        Ok(engine)
    }

    /// Set the uniform series compliance `c = (c_x, c_y, c_z)` (m/N; contact frame: x rolling,
    /// y lateral, z normal; each finite and ≥ 0; default 0) of the rail surface under the patch:
    /// the residual static flexibility of truncated track modes at the contact point (module
    /// doc, "Series compliance"). It acts from the next [`Self::step`] on; cheap enough to call
    /// every step (no allocation, no product).
    pub fn set_series_compliance(&mut self, c_m_per_n: [f64; 3]) -> Result<(), ContactError> {
        for (name, v) in [
            ("series_compliance_x_m_per_n", c_m_per_n[0]),
            ("series_compliance_y_m_per_n", c_m_per_n[1]),
            ("series_compliance_z_m_per_n", c_m_per_n[2]),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ContactError::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite and ≥ 0 (m/N)",
                });
            }
        }
        self.series_c = c_m_per_n;
        self.apply_series_compliance();
        Ok(())
    }

    /// The uniform compliance under the patch the solvers see (m/N): the series compliance
    /// plus the influence operators' own uniform term ([`Influence::uniform`]; the fe-patch's
    /// split, negative). The sum may be negative; the operator with it must stay positive
    /// definite on the contact (the global model's compliance the split was taken from is
    /// part of the series compliance), which the solvers check.
    fn effective_series(&self) -> [f64; 3] {
        let u = self.conv.uniform();
        [0, 1, 2].map(|d| self.series_c[d] + u[d])
    }

    fn apply_series_compliance(&mut self) {
        let c = self.effective_series();
        self.normal.series_compliance_m_per_n = c[2];
        self.tang.uniform_x_m_per_pa = c[0] * self.da;
        self.tang.uniform_y_m_per_pa = c[1] * self.da;
    }

    /// Choose the tangential algorithm (default [`TangentialAlgorithm::Newton`];
    /// [`TangentialAlgorithm::ElementTest`] is the alternative, kept to compare).
    pub fn set_tangential_algorithm(&mut self, algorithm: TangentialAlgorithm) {
        self.tang.algorithm = algorithm;
    }

    /// Switch the Jacobi preconditioner of the tangential solver's inner CG (default on; see
    /// `TangentialSolver::solve`); off only to compare.
    pub fn set_tangential_jacobi(&mut self, on: bool) {
        self.tang.jacobi = on;
    }

    /// Whether the warm start of a step puts the elements that slipped in the last step on the
    /// circle of their new traction bound (default on); off only to compare. The solution is
    /// the same within the solver's tolerance; the start needs fewer influence products.
    pub fn set_circle_start(&mut self, on: bool) {
        self.circle_start = on;
    }

    /// Whether the tangential solver takes the slip of a step's start by linearity from the
    /// last step's exact product (default on; `TangentialSolver::linear_start`); off only to
    /// compare. The solution is the same within the solver's tolerance.
    pub fn set_linear_start(&mut self, on: bool) {
        self.tang.linear_start = on;
    }

    /// Sets the rolling speed `V` (m/s, finite and > 0) from the next step on: it fixes the
    /// time step `Δt = Δx / V` and converts the slip distances of a step into slip velocities
    /// (the frictional power). The contact state itself does not depend on `V` — a step moves
    /// the material by one element whatever the speed — so a state brought to steady rolling
    /// at one speed is the steady state at any other.
    pub fn set_speed(&mut self, speed_m_per_s: f64) -> Result<(), ContactError> {
        check_positive("speed_m_per_s", speed_m_per_s)?;
        self.cfg.speed_m_per_s = speed_m_per_s;
        Ok(())
    }

    /// The influence operators' own uniform compliance (m/N; x, y, normal): 0 on the
    /// half-space, the fe-patch's split (negative) on its operators ([`Influence::uniform`]);
    /// the solvers add it to the series compliance.
    pub fn uniform_compliance(&self) -> [f64; 3] {
        self.conv.uniform()
    }

    /// The series compliance `(c_x, c_y, c_z)` (m/N) set by [`Self::set_series_compliance`].
    pub fn series_compliance(&self) -> [f64; 3] {
        self.series_c
    }

    /// The configuration.
    pub fn config(&self) -> &TransientConfig {
        &self.cfg
    }
    /// Time step `Δt = Δx / V` (s).
    pub fn time_step_s(&self) -> f64 {
        self.dx / self.cfg.speed_m_per_s
    }
    /// Element area (m²).
    pub fn element_area_m2(&self) -> f64 {
        self.da
    }
    /// Element-centre x coordinates (m), length nx.
    pub fn x_m(&self) -> &[f64] {
        &self.xs
    }
    /// Element-centre y coordinates (m), length ny.
    pub fn y_m(&self) -> &[f64] {
        &self.ys
    }
    /// Pressure per element (Pa), index `i * ny + j`.
    pub fn pressure_pa(&self) -> &[f64] {
        &self.p
    }
    /// Tangential traction on the wheel, x component (Pa).
    pub(crate) fn traction_x_pa(&self) -> &[f64] {
        &self.tx
    }
    /// Tangential traction on the wheel, y component (Pa).
    pub(crate) fn traction_y_pa(&self) -> &[f64] {
        &self.ty
    }
    /// Slip velocity of wheel relative to rail, x (m/s).
    pub(crate) fn slip_x_m_per_s(&self) -> &[f64] {
        &self.sx
    }
    /// Slip velocity of wheel relative to rail, y (m/s).
    pub(crate) fn slip_y_m_per_s(&self) -> &[f64] {
        &self.sy
    }
    /// Frictional power density `−τ̄·s` (W/m²) with the path-mean traction `τ̄` (module doc),
    /// zero in stick.
    pub(crate) fn power_density_w_per_m2(&self) -> &[f64] {
        &self.power
    }
    /// Element states ([`STATE_EXTERIOR`], [`STATE_STICK`], [`STATE_SLIP`]).
    pub fn states(&self) -> &[u8] {
        &self.state
    }
    /// Deformed gap of the last step (m).
    pub fn gap_m(&self) -> &[f64] {
        self.normal.gap()
    }
    /// Number of steps taken since construction / [`Self::reset`].
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Forget the traction history (start from rest) while keeping the kernels.
    pub fn reset(&mut self) {
        for v in [
            &mut self.p,
            &mut self.tx,
            &mut self.ty,
            &mut self.tx_prev,
            &mut self.tx_pp,
            &mut self.ty_pp,
            &mut self.ty_prev,
        ] {
            v.fill(0.0);
        }
        self.xi_last = 0.0;
        self.steps = 0;
        self.normal.invalidate();
    }

    /// One transient step (no allocation). Forces and fields refer to the end of the step.
    ///
    /// Phases: the inputs checked, the undeformed gap, the normal problem (and the check
    /// that the patch stays inside the grid), the traction bound `µ p`, the previous
    /// displacement at the upstream material positions and the warm start, the tangential
    /// problem at the given creepage or force, and the outputs (forces, states, frictional
    /// power).
    pub fn step(&mut self, inp: &StepInputs) -> Result<StepResult, ContactError> {
        self.check_inputs(inp)?;
        self.undeformed_gap(inp.rail_height_m);
        let mode = normal_mode(inp.normal)?;
        let nres = self
            .normal
            .solve(self.conv.ops_mut(), &self.h, self.da, mode, &mut self.p)?;
        let contact = self.contact_elements(nres.load_n)?;
        let mu = self.cfg.friction;
        for (g, p) in self.g.iter_mut().zip(&self.p) {
            *g = mu * p;
        }
        self.upstream_displacement();
        self.warm_start();
        let (xi, tang_its) = self.solve_longitudinal(inp, nres.load_n, contact)?;
        self.xi_last = xi;
        let sums = self.outputs(contact);
        if !(sums.fx.is_finite()
            && sums.fy.is_finite()
            && sums.power.is_finite()
            && nres.load_n.is_finite())
        {
            return Err(ContactError::NotConverged {
                solver: "contact step (non-finite result; refine the grid or loosen the load)",
                iterations: tang_its,
                residual: 1.0,
            });
        }
        std::mem::swap(&mut self.tx_pp, &mut self.tx_prev);
        std::mem::swap(&mut self.ty_pp, &mut self.ty_prev);
        self.tx_prev.copy_from_slice(&self.tx);
        self.ty_prev.copy_from_slice(&self.ty);
        self.steps += 1;
        Ok(StepResult {
            normal_force_n: nres.load_n,
            approach_m: nres.approach_m,
            fx_n: sums.fx * self.da,
            fy_n: sums.fy * self.da,
            mz_nm: sums.mz * self.da,
            creepage: xi,
            contact_elements: contact,
            slip_elements: sums.slip_elements,
            area_m2: contact as f64 * self.da,
            frictional_power_w: sums.power * self.da,
            normal_iterations: nres.iterations,
            tangential_iterations: tang_its,
            influence_products: tang_its + self.normal.products,
        })
    }

    /// The step's inputs: the rail heights one per grid column, the lateral creepage and the
    /// spin finite.
    fn check_inputs(&self, inp: &StepInputs) -> Result<(), ContactError> {
        if let Some(r) = inp.rail_height_m {
            if r.len() != self.nx {
                return Err(ContactError::WrongLength {
                    name: "rail_height_m",
                    got: r.len(),
                    expected: self.nx,
                    per: "column (x)",
                });
            }
        }
        for (name, v) in [
            ("lateral_creepage", inp.lateral_creepage),
            ("spin_per_m", inp.spin_per_m),
        ] {
            if !v.is_finite() {
                return Err(ContactError::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite",
                });
            }
        }
        Ok(())
    }

    /// The undeformed gap `h` (m): the wheel's and the rail crown's curvatures less the rail
    /// heights per column (m; `None` = smooth).
    fn undeformed_gap(&mut self, rail_height_m: Option<&[f64]>) {
        let (nx, ny) = (self.nx, self.ny);
        let (cx, cy) = (0.5 / self.cfg.radius_x_m, 0.5 / self.cfg.radius_y_m);
        for i in 0..nx {
            let hx = cx * self.xs[i] * self.xs[i] - rail_height_m.map_or(0.0, |r| r[i]);
            for j in 0..ny {
                self.h[i * ny + j] = hx + cy * self.ys[j] * self.ys[j];
            }
        }
    }

    /// The number of elements in contact after the normal solve; an error (carrying the
    /// normal solve's force `normal_n`, N) when the patch touches the edge of the grid.
    fn contact_elements(&self, normal_n: f64) -> Result<usize, ContactError> {
        let (nx, ny) = (self.nx, self.ny);
        let mut contact = 0usize;
        for i in 0..nx {
            for j in 0..ny {
                if self.p[i * ny + j] > 0.0 {
                    contact += 1;
                    if i == 0 || i == nx - 1 {
                        return Err(ContactError::PatchAtGridEdge {
                            edge: "x",
                            normal_n,
                        });
                    }
                    if ny > 1 && (j == 0 || j == ny - 1) {
                        return Err(ContactError::PatchAtGridEdge {
                            edge: "y",
                            normal_n,
                        });
                    }
                }
            }
        }
        Ok(contact)
    }

    /// The previous displacement at the upstream material positions: rows `1..=nx` of the
    /// extended product of the previous step's final traction (zero from rest).
    fn upstream_displacement(&mut self) {
        if self.steps > 0 {
            let (ny, n) = (self.ny, self.nx * self.ny);
            self.upx.copy_from_slice(&self.tang.ux_ext[ny..ny + n]);
            self.upy.copy_from_slice(&self.tang.uy_ext[ny..ny + n]);
        } else {
            self.upx.fill(0.0);
            self.upy.fill(0.0);
        }
    }

    /// The warm start of the tangential solve: the traction extrapolated linearly in time
    /// from the last two steps (the solver projects it onto the new traction bound) where it
    /// changed by more than the solver tolerance; elsewhere the last traction (so that steady
    /// rolling stays an exact fixed point of the step). With [`Self::set_circle_start`] (the
    /// default) an element that slipped in the last step starts on the circle of its new bound
    /// `|τ| = µ p` in the extrapolated direction: the slip/adhesion split is carried over as
    /// well as the traction, so a slip element whose bound grew does not start inside its
    /// disc as an adhesion element that the solver must push out again (docs/theory.md §6.5).
    fn warm_start(&mut self) {
        if self.steps < 2 {
            return;
        }
        let thr = self.cfg.tangential_tol * self.g.iter().cloned().fold(0.0, f64::max);
        for e in 0..self.nx * self.ny {
            let (dx, dy) = (
                self.tx_prev[e] - self.tx_pp[e],
                self.ty_prev[e] - self.ty_pp[e],
            );
            let (mut tx, mut ty) = if dx.abs().max(dy.abs()) > thr {
                (self.tx_prev[e] + dx, self.ty_prev[e] + dy)
            } else {
                (self.tx_prev[e], self.ty_prev[e])
            };
            let g = self.g[e];
            if self.circle_start && self.state[e] == STATE_SLIP && g > 0.0 {
                // inside the new disc by more than the solver's slip test: onto the circle
                // (outside it, the solver's projection does the same)
                let m2 = tx * tx + ty * ty;
                if m2 > 0.0 && m2 < g * g * (1.0 - 1e-12) {
                    let s = g / m2.sqrt();
                    (tx, ty) = (tx * s, ty * s);
                }
            }
            self.tx[e] = tx;
            self.ty[e] = ty;
        }
    }

    /// The tangential problem at the prescribed creepage, or at the creepage that gives the
    /// prescribed longitudinal force (with the normal load `load_n`, N, and `contact`
    /// elements in contact). Returns the creepage (−) and the influence products used.
    fn solve_longitudinal(
        &mut self,
        inp: &StepInputs,
        load_n: f64,
        contact: usize,
    ) -> Result<(f64, usize), ContactError> {
        let (eta, phi) = (inp.lateral_creepage, inp.spin_per_m);
        let mut tang_its = 0usize;
        let xi = match inp.longitudinal {
            Longitudinal::Creepage(xi) => {
                if !xi.is_finite() {
                    return Err(ContactError::InvalidParameter {
                        name: "creepage",
                        value: xi,
                        reason: "must be finite",
                    });
                }
                tang_its += self.tangential(xi, eta, phi)?;
                xi
            }
            Longitudinal::Force(fx) => {
                let limit = self.cfg.friction * load_n;
                if !fx.is_finite() || fx.abs() >= limit * (1.0 - 1e-9) && fx != 0.0 {
                    return Err(ContactError::TractionExceedsFriction {
                        fx_n: fx,
                        limit_n: limit,
                    });
                }
                if load_n == 0.0 {
                    self.tangential(0.0, eta, phi)?;
                    0.0
                } else {
                    self.solve_creepage_for_force(fx, limit, contact, eta, phi, &mut tang_its)?
                }
            }
        };
        Ok((xi, tang_its))
    }

    /// The outputs of the step: element states, slip velocities and frictional power
    /// densities (stored), and the sums of traction, moment and power over the grid.
    fn outputs(&mut self, contact: usize) -> StepSums {
        let (nx, ny) = (self.nx, self.ny);
        let v_over_dx = self.cfg.speed_m_per_s / self.dx;
        let (mut fx, mut fy, mut mz, mut pw) = (0.0, 0.0, 0.0, 0.0);
        let mut nslip = 0usize;
        for i in 0..nx {
            for j in 0..ny {
                let e = i * ny + j;
                let (tx, ty) = (self.tx[e], self.ty[e]);
                // traction averaged along the material path of the step (trapezoidal rule):
                // the material now at x_i was at x_{i+1} one step ago
                let (tpx, tpy) = if i + 1 < nx {
                    (self.tx_prev[e + ny], self.ty_prev[e + ny])
                } else {
                    (0.0, 0.0)
                };
                let (tmx, tmy) = (0.5 * (tx + tpx), 0.5 * (ty + tpy));
                fx += tx;
                fy += ty;
                mz += self.xs[i] * ty - self.ys[j] * tx;
                let sx = self.tang.sx[e] * v_over_dx;
                let sy = self.tang.sy[e] * v_over_dx;
                let st = if self.p[e] <= 0.0 {
                    STATE_EXTERIOR
                } else if tx * tx + ty * ty >= self.g[e] * self.g[e] * (1.0 - 1e-9) {
                    STATE_SLIP
                } else {
                    STATE_STICK
                };
                self.state[e] = st;
                if st == STATE_SLIP {
                    nslip += 1;
                    self.sx[e] = sx;
                    self.sy[e] = sy;
                    let d = -(tmx * sx + tmy * sy);
                    self.power[e] = d.max(0.0);
                    pw += self.power[e];
                } else if st == STATE_EXTERIOR && contact > 0 && (tmx != 0.0 || tmy != 0.0) {
                    // material that left the contact during this step: the work of the part
                    // of its path that was still in contact (traction falls to zero)
                    self.sx[e] = 0.0;
                    self.sy[e] = 0.0;
                    let d = -(tmx * sx + tmy * sy);
                    self.power[e] = d.max(0.0);
                    pw += self.power[e];
                } else {
                    self.sx[e] = 0.0;
                    self.sy[e] = 0.0;
                    self.power[e] = 0.0;
                }
            }
        }
        StepSums {
            fx,
            fy,
            mz,
            power: pw,
            slip_elements: nslip,
        }
    }

    fn tangential(&mut self, xi: f64, eta: f64, phi: f64) -> Result<usize, ContactError> {
        let ny = self.ny;
        // uniform displacement of the series compliance at the start of the step,
        // −c F(t − Δt) (zero from rest: tx_prev is zero after a reset)
        let (ucx, ucy) = if self.steps > 0 {
            let c = self.effective_series();
            (
                c[0] * self.tx_prev.iter().sum::<f64>() * self.da,
                c[1] * self.ty_prev.iter().sum::<f64>() * self.da,
            )
        } else {
            (0.0, 0.0)
        };
        for i in 0..self.nx {
            for j in 0..ny {
                let e = i * ny + j;
                self.ex[e] = (xi - phi * self.ys[j]) * self.dx - self.upx[e] - ucx;
                self.ey[e] = (eta + phi * self.xs[i]) * self.dx - self.upy[e] - ucy;
            }
        }
        self.tang.solve(
            self.conv.ops_mut(),
            &self.g,
            &self.ex,
            &self.ey,
            &mut self.tx,
            &mut self.ty,
        )
    }

    fn force_x(&self) -> f64 {
        self.tx.iter().sum::<f64>() * self.da
    }

    /// Solve ξ such that Fx(ξ) = target (Fx decreasing in ξ): secant steps safeguarded by a
    /// bracket (Illinois regula falsi).
    fn solve_creepage_for_force(
        &mut self,
        target: f64,
        limit: f64,
        contact: usize,
        eta: f64,
        phi: f64,
        its: &mut usize,
    ) -> Result<f64, ContactError> {
        let ftol = 1e-6 * limit;
        // linear-theory stiffness estimate: Fx ≈ −G c² C11 ξ, c² ≈ area/π, C11 ≈ 4.5
        let k_est = self.g_mod * (contact as f64 * self.da / std::f64::consts::PI) * 4.5;
        let mut a = self.xi_last;
        *its += self.tangential(a, eta, phi)?;
        let mut fa = self.force_x() - target;
        if fa.abs() < ftol {
            return Ok(a);
        }
        let mut b = a + fa / k_est;
        *its += self.tangential(b, eta, phi)?;
        let mut fb = self.force_x() - target;
        let mut side = 0i32;
        for _ in 0..80 {
            if fb.abs() < ftol {
                return Ok(b);
            }
            let c = if fa * fb < 0.0 {
                // bracketed: Illinois
                (a * fb - b * fa) / (fb - fa)
            } else {
                let slope = (fb - fa) / (b - a);
                if slope < -1e-3 * k_est && slope.is_finite() {
                    b - fb / slope
                } else {
                    // flat (saturated) part: step further with the initial stiffness
                    b + 2.0 * fb / k_est
                }
            };
            *its += self.tangential(c, eta, phi)?;
            let fc = self.force_x() - target;
            if fa * fb < 0.0 {
                if fc * fb < 0.0 {
                    a = b;
                    fa = fb;
                    side = 0;
                } else {
                    side += 1;
                    if side >= 1 {
                        fa *= 0.5;
                    }
                }
            } else {
                a = b;
                fa = fb;
            }
            b = c;
            fb = fc;
        }
        // The force is known only to the tangential solver's precision (a traction error of
        // about `tangential_tol · µ p_max` per element, of order `tangential_tol · µN` summed;
        // a passage solves at 1e-5): a secant that stalls within it, as it did on the
        // fe-patch's operators on a coarse 12 × 10 grid (at 1.7e-6), has found the creepage
        // as well as the force allows. The state is the last iterate's.
        if fb.abs() <= self.cfg.tangential_tol * limit {
            return Ok(b);
        }
        Err(ContactError::NotConverged {
            solver: "creepage for prescribed Fx (secant)",
            iterations: 80,
            residual: fb.abs() / limit,
        })
    }

    /// Steady rolling: step with constant inputs until the forces change by less than
    /// `rel_tol · µ N` between steps and the traction field by less than `rel_tol · µ p_max`
    /// (at most `max_steps` steps). Starts from the current state (warm).
    pub(crate) fn solve_steady(
        &mut self,
        inp: &StepInputs,
        rel_tol: f64,
        max_steps: usize,
    ) -> Result<StepResult, ContactError> {
        let mut last = self.step(inp)?;
        for _ in 1..max_steps {
            let r = self.step(inp)?;
            let scale = r
                .fx_n
                .abs()
                .max(r.fy_n.abs())
                .max(1e-9 * self.cfg.friction * r.normal_force_n)
                .max(1e-300);
            let df = (r.fx_n - last.fx_n)
                .abs()
                .max((r.fy_n - last.fy_n).abs())
                .max((r.creepage - last.creepage).abs() / r.creepage.abs().max(1e-12) * scale);
            last = r;
            if df < rel_tol * scale || r.normal_force_n == 0.0 {
                return Ok(r);
            }
        }
        Err(ContactError::NotConverged {
            solver: "steady rolling (transient stepping)",
            iterations: max_steps,
            residual: 1.0,
        })
    }
}

/// Sums over the grid of one step: tractions (Pa), moment (Pa·m) and frictional power
/// density (W/m²), each to be multiplied by the element area; slip elements.
struct StepSums {
    fx: f64,
    fy: f64,
    mz: f64,
    power: f64,
    slip_elements: usize,
}

/// The normal problem of a step: the approach (finite) or the force (finite, ≥ 0).
fn normal_mode(normal: NormalInput) -> Result<NormalMode, ContactError> {
    match normal {
        NormalInput::Approach(d) if d.is_finite() => Ok(NormalMode::Approach(d)),
        NormalInput::Force(f) if f.is_finite() && f >= 0.0 => Ok(NormalMode::Load(f)),
        NormalInput::Approach(d) => Err(ContactError::InvalidParameter {
            name: "approach",
            value: d,
            reason: "must be finite",
        }),
        NormalInput::Force(f) => Err(ContactError::InvalidParameter {
            name: "normal force",
            value: f,
            reason: "must be finite and ≥ 0",
        }),
    }
}

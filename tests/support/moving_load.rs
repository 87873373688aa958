//! Verification harness of the integration tests (not part of the library).
//!
//! Validation of the modal synthesis against the full FE matrices (docs/theory.md §7.9): a
//! constant load moving along the rail's contact line, solved
//! (a) by the reduced-order path of the passage and (b) by direct time integration of the
//! full sparse `K`, `M`, `C`; and the static deflection under the wheel load, modal vs a
//! direct sparse solve.
//!
//! # The load
//! A constant force `F = (F_x, F_t, F_n)` (N, components in the contact frame
//! [`ContactFrame`]: rolling direction, lateral tangent, outward normal of the rail head)
//! acts **on the rail** at `x(t) = x₀ + V t` on the running-surface contact line. It is
//! distributed exactly as the passage distributes the contact force
//! ([`RailContactLine`]): across the rail over the weighted contact nodes of a node plane,
//! along the rail by the hexahedron's linear shape function between the two planes around
//! `x`. The full-DOF load vector is `f(x) = Σ_d F_d b_d(x)` with
//! `b_d(x) = Σ_p N_p(x) Σ_k w_k e_d ⊗ node_k` (constrained DOFs dropped); its modal
//! projection `Φᵀ b_d(x)` is exactly the row that [`RailContactLine::rows_at`] returns
//! (interpolation and projection commute), so the two paths see the same load.
//!
//! # Modal path (the passage's)
//! `q̈ + C_q q̇ + Ω² q = Φᵀ f(x(t))` with [`ModalSystem`] (full projected damping
//! `C_q = Φᵀ C Φ`, or its diagonal for the comparison) integrated by [`ModalVerlet`]
//! (velocity Verlet, damping implicit); displacements `u = Φ q` at the probes.
//!
//! # Direct path
//! `M ü + C u̇ + K u = f(x(t))` on all free DOFs, Newmark average acceleration
//! (β = ¼, γ = ½; Hughes, *The Finite Element Method*, 2000, §9.1.1, eqs. 9.1.3–9.1.5):
//!
//! ```text
//! K̂ = K + (2/Δt) C + (4/Δt²) M                     (SPD: factorised once, sparse LLᵀ)
//! K̂ u_{n+1} = f_{n+1} + M (4/Δt² u_n + 4/Δt v_n + a_n) + C (2/Δt u_n + v_n)
//! a_{n+1} = 4/Δt² (u_{n+1} − u_n) − 4/Δt v_n − a_n
//! v_{n+1} = v_n + Δt/2 (a_n + a_{n+1})
//! ```
//!
//! Unconditionally stable, second order, no numerical damping (the highest FE modes, far
//! above f_max, are not excited by the slow load and stay negligible).
//!
//! # Initial state
//! Both paths start at rest in their own static equilibrium under the load at `x₀`
//! (modal: `q₀ = Ω⁻² Φᵀ f(x₀)`; direct: `u₀ = K⁻¹ f(x₀)`), as the passage does, so that no
//! start-up transient is excited: the difference of the two is the truncation error alone
//! (quasi-static and dynamic).
//!
//! # Static deflection and residual flexibility
//! [`static_comparison`] compares the modal static deflection `Φ Ω⁻² Φᵀ f` with `K⁻¹ f` at
//! the probes, and the flexibility of the contact point in the normal direction,
//! `b_nᵀ K⁻¹ b_n` vs `Σ_i (φ_iᵀ b_n)² / ω_i²`. The difference is the residual (truncated)
//! flexibility `b_nᵀ (K⁻¹ − Φ Ω⁻² Φᵀ) b_n ≥ 0` (m/N) — the local flexibility of the mesh
//! under the distributed contact load that the truncated basis misses (Craig & Kurdila,
//! *Fundamentals of Structural Dynamics*, 2006, §14.4, residual flexibility / static
//! correction). It is compared by the caller with the linearised Hertz compliance
//! `dδ/dF = 2δ/(3F)`.

// Numerical kernels index several parallel arrays with one loop index (as in the library).
#![allow(clippy::needless_range_loop)]
#![allow(dead_code)]

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Par, Side, Spec};

use corrugation::dynamics::integrator::ModalVerlet;
use corrugation::dynamics::reduced::{
    add_line_load, modal_rows, ContactFrame, ModalSystem, RailContactLine,
};
use corrugation::dynamics::residual::{for_each_plane_solution, nodes_dot, plane_range};
use corrugation::dynamics::DynamicsError;
use corrugation::fe::assembly::FeMatrices;
use corrugation::structure::TrackStructure;

/// `Σ_i a_i b_i`.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Errors of the moving-load validation. Each variant says what to change.
#[derive(Debug, thiserror::Error)]
pub enum MovingLoadError {
    /// An input is out of range (message says which and what to change).
    #[error("moving load: {0}")]
    Input(String),
    /// The load leaves the rail during the run.
    #[error("the load at x = {x_m:.4} m is off the rail [{start_m:.3}, {end_m:.3}] m: lower the speed, the number of steps or x₀, or lengthen the track (track.bays)")]
    OffRail {
        /// Position (m).
        x_m: f64,
        /// Rail start (m).
        start_m: f64,
        /// Rail end (m).
        end_m: f64,
    },
    /// The reduced-order path failed (e.g. unstable time step for the highest mode).
    #[error(transparent)]
    Modal(#[from] DynamicsError),
    /// The passage's shared machinery failed (contact line, load spreading).
    #[error(transparent)]
    Passage(#[from] corrugation::passage::PassageError),
    /// A sparse factorisation failed.
    #[error("sparse LLᵀ of {what} failed ({detail}): the matrix is not positive definite; the track must be supported (ballast stiffness > 0) and Δt > 0")]
    Factorisation {
        /// Which matrix.
        what: &'static str,
        /// faer's message.
        detail: String,
    },
    /// The direct solution became non-finite.
    #[error("the direct Newmark solution is not finite at step {step}: check the matrices")]
    Diverged {
        /// Step index.
        step: usize,
    },
}

/// A constant load moving along the rail's contact line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingLoad {
    /// Force **on the rail** in the contact frame (x, t, n) (N). A downward wheel load `W`
    /// is `[0, 0, −W/cos α]` (the normal points out of the rail head).
    pub force_n: [f64; 3],
    /// Start position along the rail (m).
    pub x_start_m: f64,
    /// Speed (m/s), ≥ 0.
    pub speed_m_per_s: f64,
    /// Time step (s), > 0.
    pub dt_s: f64,
    /// Number of steps (−).
    pub steps: usize,
}

impl MovingLoad {
    fn check(&self, line: &RailContactLine) -> Result<(), MovingLoadError> {
        let bad = |s: String| Err(MovingLoadError::Input(s));
        if !(self.dt_s > 0.0 && self.dt_s.is_finite()) {
            return bad(format!("time step {} s must be finite and > 0", self.dt_s));
        }
        if !(self.speed_m_per_s >= 0.0 && self.speed_m_per_s.is_finite()) {
            return bad(format!(
                "speed {} m/s must be finite and ≥ 0",
                self.speed_m_per_s
            ));
        }
        if self.force_n.iter().any(|f| !f.is_finite()) {
            return bad(format!("force {:?} N must be finite", self.force_n));
        }
        let px = &line.planes_x_m;
        let (a, b) = (px[0], px[px.len() - 1]);
        for x in [self.x_at(0), self.x_at(self.steps)] {
            if !(x >= a && x <= b) {
                return Err(MovingLoadError::OffRail {
                    x_m: x,
                    start_m: a,
                    end_m: b,
                });
            }
        }
        Ok(())
    }

    /// Load position at step `n` (m).
    pub fn x_at(&self, n: usize) -> f64 {
        self.x_start_m + self.speed_m_per_s * self.dt_s * n as f64
    }
}

/// A rail observation point: a weighted set of nodes whose weighted global displacement
/// `Σ w_k u_k` (x, y, z) (m) is recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// Name for reports.
    pub name: String,
    /// Global node indices and weights (−).
    pub nodes: Vec<(usize, f64)>,
}

impl Probe {
    /// The contact-line node with the largest lateral weight at node plane `plane` (the
    /// passage's rail-point node).
    pub fn contact_node(line: &RailContactLine, plane: usize) -> Result<Probe, MovingLoadError> {
        let set = line.nodes.get(plane).ok_or_else(|| {
            MovingLoadError::Input(format!(
                "plane {plane} out of range ({} planes)",
                line.nodes.len()
            ))
        })?;
        let (node, _) = set
            .iter()
            .copied()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or_else(|| MovingLoadError::Input("empty contact line".into()))?;
        Ok(Probe {
            name: "contact node".into(),
            nodes: vec![(node, 1.0)],
        })
    }

    /// The weighted contact nodes of plane `plane` (the contact point as the load sees it).
    pub fn contact_patch(line: &RailContactLine, plane: usize) -> Result<Probe, MovingLoadError> {
        let set = line.nodes.get(plane).ok_or_else(|| {
            MovingLoadError::Input(format!(
                "plane {plane} out of range ({} planes)",
                line.nodes.len()
            ))
        })?;
        Ok(Probe {
            name: "contact patch".into(),
            nodes: set.clone(),
        })
    }

    /// The foot-underside node nearest the section's centre line (y = 0 before inclination)
    /// at plane `plane`.
    pub fn foot_centre(track: &TrackStructure, plane: usize) -> Result<Probe, MovingLoadError> {
        let sec = &track.rail.section;
        let j = sec
            .foot_underside
            .iter()
            .zip(&sec.foot_underside_s_m)
            .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map(|(&j, _)| j)
            .ok_or_else(|| MovingLoadError::Input("the section has no foot nodes".into()))?;
        Self::check_plane(track, plane)?;
        Ok(Probe {
            name: "foot centre".into(),
            nodes: vec![(track.rail.node(plane, j), 1.0)],
        })
    }

    /// Mean of the foot-underside nodes at plane `plane` (the section's deflection away
    /// from the local indentation under the load).
    pub fn foot_mean(track: &TrackStructure, plane: usize) -> Result<Probe, MovingLoadError> {
        Self::check_plane(track, plane)?;
        let nodes = track.rail.foot_underside_nodes(plane);
        let w = 1.0 / nodes.len().max(1) as f64;
        Ok(Probe {
            name: "foot mean".into(),
            nodes: nodes.into_iter().map(|n| (n, w)).collect(),
        })
    }

    fn check_plane(track: &TrackStructure, plane: usize) -> Result<(), MovingLoadError> {
        if plane >= track.rail.n_planes() {
            return Err(MovingLoadError::Input(format!(
                "plane {plane} out of range ({} planes)",
                track.rail.n_planes()
            )));
        }
        Ok(())
    }

    /// Displacement (x, y, z) (m) from a full-free-DOF vector.
    fn displacement_of(&self, track: &TrackStructure, u: &[f64]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for &(node, w) in &self.nodes {
            for (c, o) in out.iter_mut().enumerate() {
                if let Some(f) = track.dofmap.free_index(3 * node + c) {
                    *o += w * u[f];
                }
            }
        }
        out
    }
}

/// Index of the node plane nearest `x` (m).
pub fn nearest_plane(line: &RailContactLine, x: f64) -> usize {
    (0..line.planes_x_m.len())
        .min_by(|&a, &b| {
            (line.planes_x_m[a] - x)
                .abs()
                .total_cmp(&(line.planes_x_m[b] - x).abs())
        })
        .unwrap_or(0)
}

/// Displacement histories of the probes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResponseHistory {
    /// Time (s), step 0 (the static start) included.
    pub t_s: Vec<f64>,
    /// Load position (m).
    pub x_m: Vec<f64>,
    /// `displacement_m[probe][step]` = (x, y, z) (m).
    pub displacement_m: Vec<Vec<[f64; 3]>>,
    /// `load_point_m[step]`: displacement of the contact line *at the load*, along the
    /// contact-frame axes (x, t, n) (m) — `b_d(x_c)ᵀ u` with `b_d(x_c)` the load vector of a
    /// unit force in direction d at the load position (modal: `rows_d(x_c) · q`). This is
    /// the rail displacement the passage's contact sees (before any series compliance).
    pub load_point_m: Vec<[f64; 3]>,
    /// Wall time of the time stepping (s).
    pub seconds: f64,
}

impl ResponseHistory {
    fn new(probes: usize, steps: usize) -> Self {
        ResponseHistory {
            t_s: Vec::with_capacity(steps + 1),
            x_m: Vec::with_capacity(steps + 1),
            displacement_m: (0..probes).map(|_| Vec::with_capacity(steps + 1)).collect(),
            load_point_m: Vec::with_capacity(steps + 1),
            seconds: 0.0,
        }
    }

    /// `max_t |u_self − u_ref| / max_t |u_ref|` for component `c` (0 = x, 1 = y, 2 = z) of
    /// probe `p` (−): the error norm of the comparisons. `reference` is the direct solution.
    pub fn relative_max_error(&self, reference: &ResponseHistory, p: usize, c: usize) -> f64 {
        let a = &self.displacement_m[p];
        let b = &reference.displacement_m[p];
        let n = a.len().min(b.len());
        let diff = (0..n)
            .map(|i| (a[i][c] - b[i][c]).abs())
            .fold(0.0, f64::max);
        let scale = (0..n).map(|i| b[i][c].abs()).fold(0.0, f64::max);
        if scale > 0.0 {
            diff / scale
        } else {
            diff
        }
    }

    /// Same as [`Self::relative_max_error`] for the *dynamic part*: both histories minus
    /// their own value at step 0 (the static deflection under the load at x₀) (−).
    pub fn relative_max_change_error(
        &self,
        reference: &ResponseHistory,
        p: usize,
        c: usize,
    ) -> f64 {
        let a = &self.displacement_m[p];
        let b = &reference.displacement_m[p];
        let n = a.len().min(b.len());
        if n == 0 {
            return 0.0;
        }
        let diff = (0..n)
            .map(|i| ((a[i][c] - a[0][c]) - (b[i][c] - b[0][c])).abs())
            .fold(0.0, f64::max);
        let scale = (0..n)
            .map(|i| (b[i][c] - b[0][c]).abs())
            .fold(0.0, f64::max);
        if scale > 0.0 {
            diff / scale
        } else {
            diff
        }
    }
}

/// The global frame (x, y, z) used for the probes' modal rows.
const GLOBAL: ContactFrame = ContactFrame {
    x: [1.0, 0.0, 0.0],
    t: [0.0, 1.0, 0.0],
    n: [0.0, 0.0, 1.0],
};

/// Modal rows (global x, y, z blocks of m values) of each probe.
fn probe_rows(track: &TrackStructure, modes: &Mat<f64>, probes: &[Probe]) -> Vec<Vec<f64>> {
    let m = modes.ncols();
    probes
        .iter()
        .map(|p| {
            let mut r = vec![0.0; 3 * m];
            modal_rows(&p.nodes, &track.dofmap, modes, &GLOBAL, &mut r);
            r
        })
        .collect()
}

/// The first modes of a basis (frequencies ascending) up to `f_max_hz` (Hz): frequencies
/// and the corresponding columns. Truncating a basis solved to a higher f_max gives the
/// basis of the lower f_max (up to the order of degenerate pairs at the cut).
pub fn truncate_basis(
    frequencies_hz: &[f64],
    modes: &Mat<f64>,
    f_max_hz: f64,
) -> (Vec<f64>, Mat<f64>) {
    let m = frequencies_hz.partition_point(|&f| f <= f_max_hz);
    let f = frequencies_hz[..m].to_vec();
    let phi = modes.subcols(0, m).to_owned();
    (f, phi)
}

/// The modal system with the off-diagonal damping terms dropped (modal damping
/// `2 ζ_i ω_i = (Φᵀ C Φ)_ii`), for measuring what the coupling does.
pub fn diagonal_damping(sys: &ModalSystem) -> ModalSystem {
    let m = sys.len();
    let mut c = Mat::<f64>::zeros(m, m);
    for i in 0..m {
        c[(i, i)] = sys.damping[(i, i)];
    }
    ModalSystem {
        omega2: sys.omega2.clone(),
        damping: c,
    }
}

/// Moving-load response of the reduced model: the passage's path ([`RailContactLine::rows_at`],
/// [`ModalSystem`], [`ModalVerlet`]), started at rest in the modal static equilibrium under
/// the load at x₀. `modes` (n_free × m, mass-normalised, m/√kg) are those of `sys` and
/// `line`; the probes are reconstructed as `u = Φ q`.
pub fn modal_response(
    track: &TrackStructure,
    modes: &Mat<f64>,
    sys: &ModalSystem,
    line: &RailContactLine,
    load: &MovingLoad,
    probes: &[Probe],
) -> Result<ResponseHistory, MovingLoadError> {
    modal_response_corrected(track, modes, sys, line, load, probes, None)
}

/// [`modal_response`] with the static correction of the truncated modes at the probes,
/// `u = Φ q + T(x_c) F` ([`ProbeCorrection`], built for the same probes), when given.
pub fn modal_response_corrected(
    track: &TrackStructure,
    modes: &Mat<f64>,
    sys: &ModalSystem,
    line: &RailContactLine,
    load: &MovingLoad,
    probes: &[Probe],
    correction: Option<&ProbeCorrection>,
) -> Result<ResponseHistory, MovingLoadError> {
    load.check(line)?;
    let m = sys.len();
    if modes.ncols() != m || line.modes != m {
        return Err(MovingLoadError::Input(format!(
            "the modal system has {m} modes, the basis {} and the contact line {}: build all three from the same basis",
            modes.ncols(),
            line.modes
        )));
    }
    if let Some(i) = sys.omega2.iter().position(|&w| w <= 0.0) {
        return Err(MovingLoadError::Input(format!(
            "mode {i} has ω² = {} ≤ 0: the track must be supported",
            sys.omega2[i]
        )));
    }
    let prow = probe_rows(track, modes, probes);
    let mut it = ModalVerlet::new(sys, load.dt_s)?;
    let mut rows = vec![0.0; 3 * m];
    let mut f = vec![0.0; m];
    let gen = |rows: &[f64], f: &mut [f64]| {
        for i in 0..m {
            f[i] = load.force_n[0] * rows[i]
                + load.force_n[1] * rows[m + i]
                + load.force_n[2] * rows[2 * m + i];
        }
    };
    let x0 = load.x_at(0);
    line.rows_at(x0, &mut rows)?;
    gen(&rows, &mut f);
    let q0: Vec<f64> = (0..m).map(|i| f[i] / sys.omega2[i]).collect();
    it.set_state(&q0, &vec![0.0; m], &f);
    let mut h = ResponseHistory::new(probes.len(), load.steps);
    let record = |h: &mut ResponseHistory, q: &[f64], rows: &[f64], n: usize| {
        h.t_s.push(n as f64 * load.dt_s);
        h.x_m.push(load.x_at(n));
        h.load_point_m
            .push([0, 1, 2].map(|d| dot(&rows[d * m..(d + 1) * m], q)));
        for (p, r) in prow.iter().enumerate() {
            let mut u = [0.0; 3];
            for (c, uc) in u.iter_mut().enumerate() {
                *uc = dot(&r[c * m..(c + 1) * m], q);
            }
            if let Some(corr) = correction {
                corr.add(line, load.x_at(n), load.force_n, p, &mut u);
            }
            h.displacement_m[p].push(u);
        }
    };
    record(&mut h, &it.q, &rows, 0);
    let t = std::time::Instant::now();
    for n in 1..=load.steps {
        it.advance_displacement();
        line.rows_at(load.x_at(n), &mut rows)?;
        gen(&rows, &mut f);
        it.complete(&f);
        if !it.q.iter().all(|v| v.is_finite()) {
            return Err(
                DynamicsError::Passage(corrugation::passage::PassageError::Diverged {
                    t_s: n as f64 * load.dt_s,
                    x_m: load.x_at(n),
                    what: "modal coordinates of the moving-load run".into(),
                })
                .into(),
            );
        }
        record(&mut h, &it.q, &rows, n);
    }
    h.seconds = t.elapsed().as_secs_f64();
    Ok(h)
}

/// Static correction of the probes for the truncated modes (the residual flexibility of
/// [`corrugation::dynamics::residual`], extended from the contact point to any probe): for every plane `p`
/// of the load's path and direction `d` of the frame, the probe's residual displacement
/// under the unit contact load `b_{p,d}`,
/// `T_{P,p,d} = e_Pᵀ K⁻¹ b_{p,d} − (e_Pᵀ Φ) Ω⁻² (Φᵀ b_{p,d})` (m/N, global x, y, z).
/// The corrected response is `u_P = e_Pᵀ Φ q + Σ_d F_d T_{P,d}(x_c)`, with `T` interpolated
/// by the load's own shape functions (exact static response of the interpolated load).
#[derive(Clone, Debug)]
pub struct ProbeCorrection {
    first_plane: usize,
    /// `transfer[i][probe][d]` = (x, y, z) residual displacement (m/N).
    transfer: Vec<Vec<[[f64; 3]; 3]>>,
}

impl ProbeCorrection {
    /// Computes the transfers of the planes the load of `load` travels over, with `K`
    /// factorised in `factor`, the kept `modes` of `sys` and the contact line built from
    /// them.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        track: &TrackStructure,
        factor: &corrugation::dynamics::residual::StiffnessFactor,
        modes: &Mat<f64>,
        sys: &ModalSystem,
        line: &RailContactLine,
        frame: &ContactFrame,
        load: &MovingLoad,
        probes: &[Probe],
    ) -> Result<Self, MovingLoadError> {
        load.check(line)?;
        let m = sys.len();
        if modes.ncols() != m || line.modes != m || sys.omega2.iter().any(|&w| w <= 0.0) {
            return Err(MovingLoadError::Input(
                "the modes, the modal system (all ω² > 0) and the contact line must come from one basis of a supported track".into(),
            ));
        }
        let (a, b) = (load.x_at(0), load.x_at(load.steps));
        let (p0, p1) = plane_range(line, a.min(b), a.max(b))?;
        let np = p1 - p0 + 1;
        let mut transfer = vec![vec![[[0.0; 3]; 3]; probes.len()]; np];
        // Static part: e_Pᵀ K⁻¹ b.
        for_each_plane_solution(track, factor, line, frame, p0, p1, &mut |i, d, u| {
            for (k, pr) in probes.iter().enumerate() {
                for &(node, w) in &pr.nodes {
                    for c in 0..3 {
                        if let Some(f) = track.dofmap.free_index(3 * node + c) {
                            transfer[i][k][d][c] += w * u(f);
                        }
                    }
                }
            }
        });
        // Modal part.
        let prow = probe_rows(track, modes, probes);
        let mut rows = vec![0.0; 3 * m];
        for i in 0..np {
            line.rows_at(line.planes_x_m[p0 + i], &mut rows)?;
            for (k, pr) in prow.iter().enumerate() {
                for d in 0..3 {
                    for c in 0..3 {
                        let modal: f64 = (0..m)
                            .map(|j| pr[c * m + j] * rows[d * m + j] / sys.omega2[j])
                            .sum();
                        transfer[i][k][d][c] -= modal;
                    }
                }
            }
        }
        Ok(ProbeCorrection {
            first_plane: p0,
            transfer,
        })
    }

    /// Adds the correction of probe `k` for `force` (N, frame) at `x` (m) into `u` (m).
    fn add(&self, line: &RailContactLine, x: f64, force: [f64; 3], k: usize, u: &mut [f64; 3]) {
        let Some((p, s)) = line.locate(x) else {
            return;
        };
        for (plane, w) in [(p, 1.0 - s), (p + 1, s)] {
            if w == 0.0 || plane < self.first_plane {
                continue;
            }
            if let Some(t) = self.transfer.get(plane - self.first_plane) {
                for d in 0..3 {
                    for c in 0..3 {
                        u[c] += w * force[d] * t[k][d][c];
                    }
                }
            }
        }
    }
}

/// Sparse `y = A x` (CSC, full storage), no allocation.
fn spmv(a: SparseColMatRef<'_, usize, f64>, x: &[f64], y: &mut [f64]) {
    y.iter_mut().for_each(|v| *v = 0.0);
    let cp = a.symbolic().col_ptr();
    let ri = a.symbolic().row_idx();
    let val = a.val();
    for j in 0..a.ncols() {
        let xj = x[j];
        if xj == 0.0 {
            continue;
        }
        for p in cp[j]..cp[j + 1] {
            y[ri[p]] += val[p] * xj;
        }
    }
}

/// A sparse SPD matrix factorised once (LLᵀ, AMD ordering), with its solve workspace.
struct SparseLlt {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    buf: MemBuffer,
    rhs: Mat<f64>,
}

impl SparseLlt {
    fn new(
        a: SparseColMatRef<'_, usize, f64>,
        what: &'static str,
    ) -> Result<Self, MovingLoadError> {
        let err = |detail: String| MovingLoadError::Factorisation { what, detail };
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| err(format!("{e:?}")))?;
        let mut values = vec![0.0; symbolic.len_val()];
        let par = Par::Seq;
        let mut mem =
            MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Spec::default()))
                .map_err(|e| err(format!("{e:?}")))?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Spec::default(),
            )
            .map_err(|e| err(format!("{e:?}")))?;
        let buf = MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(1, par))
            .map_err(|e| err(format!("{e:?}")))?;
        let n = a.nrows();
        Ok(SparseLlt {
            symbolic,
            values,
            buf,
            rhs: Mat::zeros(n, 1),
        })
    }

    /// Overwrites `x` with `A⁻¹ x`. No allocation.
    fn solve(&mut self, x: &mut [f64]) {
        for (i, v) in x.iter().enumerate() {
            self.rhs[(i, 0)] = *v;
        }
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            self.rhs.as_mut(),
            Par::Seq,
            MemStack::new(&mut self.buf),
        );
        for (i, v) in x.iter_mut().enumerate() {
            *v = self.rhs[(i, 0)];
        }
    }
}

fn same_pattern(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> bool {
    a.symbolic().col_ptr() == b.symbolic().col_ptr()
        && a.symbolic().row_idx() == b.symbolic().row_idx()
}

/// Direct Newmark (average acceleration) integration of the full track matrices under the
/// moving load, started at rest in the static equilibrium `u₀ = K⁻¹ f(x₀)`. `frame` is the
/// contact frame the line was built with (the load's components are along its axes).
pub fn direct_response(
    track: &TrackStructure,
    mats: &FeMatrices,
    line: &RailContactLine,
    frame: &ContactFrame,
    load: &MovingLoad,
    probes: &[Probe],
) -> Result<ResponseHistory, MovingLoadError> {
    load.check(line)?;
    let n = mats.k.nrows();
    if n != track.dofmap.n_free() {
        return Err(MovingLoadError::Input(format!(
            "the matrices have {n} rows but the track has {} free DOFs: assemble this track",
            track.dofmap.n_free()
        )));
    }
    if !(same_pattern(&mats.k, &mats.m) && same_pattern(&mats.k, &mats.c)) {
        return Err(MovingLoadError::Input(
            "K, M and C must share one sparsity pattern (as assembled by TrackStructure::assemble)"
                .into(),
        ));
    }
    let dt = load.dt_s;
    let (a0, a1, a2) = (4.0 / (dt * dt), 2.0 / dt, 4.0 / dt);
    let kv = mats.k.val();
    let mv = mats.m.val();
    let cv = mats.c.val();
    let eff: Vec<f64> = (0..kv.len())
        .map(|p| kv[p] + a1 * cv[p] + a0 * mv[p])
        .collect();
    let sym: SymbolicSparseColMatRef<'_, usize> = mats.k.symbolic();
    let k_eff = SparseColMatRef::new(sym, &eff);
    let mut eff_llt = SparseLlt::new(k_eff, "K + 2/Δt C + 4/Δt² M")?;

    // Static start.
    let mut u = vec![0.0; n];
    add_line_load(track, line, frame, load.x_at(0), load.force_n, &mut u)?;
    {
        let mut k_llt = SparseLlt::new(mats.k.as_ref(), "K")?;
        k_llt.solve(&mut u);
    }
    let mut v = vec![0.0; n];
    let mut a = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut tmp = vec![0.0; n];
    let mut u_new = vec![0.0; n];

    let mut h = ResponseHistory::new(probes.len(), load.steps);
    let axes = [frame.x, frame.t, frame.n];
    let record = |h: &mut ResponseHistory, u: &[f64], step: usize| -> Result<(), MovingLoadError> {
        h.t_s.push(step as f64 * dt);
        let x = load.x_at(step);
        h.x_m.push(x);
        // b_d(x)ᵀu with b(x) = (1−s) b_p + s b_{p+1} (the line's interpolation).
        let (p, s) = line.locate(x).ok_or(MovingLoadError::OffRail {
            x_m: x,
            start_m: line.planes_x_m[0],
            end_m: line.planes_x_m[line.planes_x_m.len() - 1],
        })?;
        h.load_point_m.push([0, 1, 2].map(|d| {
            let at = |q: usize| nodes_dot(&line.nodes[q], &track.dofmap, axes[d], |i| u[i]);
            (1.0 - s) * at(p) + s * at(p + 1)
        }));
        for (p, pr) in probes.iter().enumerate() {
            h.displacement_m[p].push(pr.displacement_of(track, u));
        }
        Ok(())
    };
    record(&mut h, &u, 0)?;
    let t = std::time::Instant::now();
    for step in 1..=load.steps {
        // rhs = f_{n+1} + M (a0 u + a2 v + a) + C (a1 u + v)
        rhs.iter_mut().for_each(|x| *x = 0.0);
        add_line_load(track, line, frame, load.x_at(step), load.force_n, &mut rhs)?;
        for i in 0..n {
            w[i] = a0 * u[i] + a2 * v[i] + a[i];
        }
        spmv(mats.m.as_ref(), &w, &mut tmp);
        for i in 0..n {
            rhs[i] += tmp[i];
            w[i] = a1 * u[i] + v[i];
        }
        spmv(mats.c.as_ref(), &w, &mut tmp);
        for i in 0..n {
            rhs[i] += tmp[i];
        }
        u_new.copy_from_slice(&rhs);
        eff_llt.solve(&mut u_new);
        for i in 0..n {
            let a_new = a0 * (u_new[i] - u[i]) - a2 * v[i] - a[i];
            v[i] += 0.5 * dt * (a[i] + a_new);
            a[i] = a_new;
        }
        std::mem::swap(&mut u, &mut u_new);
        if !u.iter().all(|x| x.is_finite()) {
            return Err(MovingLoadError::Diverged { step });
        }
        record(&mut h, &u, step)?;
    }
    h.seconds = t.elapsed().as_secs_f64();
    Ok(h)
}

/// Static deflection under a load at one contact position: modal vs direct.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticComparison {
    /// Load position (m).
    pub x_m: f64,
    /// Number of modes (−).
    pub modes: usize,
    /// Probe displacements (x, y, z) (m), modal `Φ Ω⁻² Φᵀ f`.
    pub modal_m: Vec<[f64; 3]>,
    /// Probe displacements (x, y, z) (m), direct `K⁻¹ f`.
    pub direct_m: Vec<[f64; 3]>,
    /// Normal flexibility of the contact point, direct `b_nᵀ K⁻¹ b_n` (m/N).
    pub contact_flexibility_direct_m_per_n: f64,
    /// Normal flexibility of the contact point, modal `Σ (φ_iᵀ b_n)²/ω_i²` (m/N).
    pub contact_flexibility_modal_m_per_n: f64,
}

impl StaticComparison {
    /// Residual (truncated) normal flexibility at the contact
    /// `b_nᵀ (K⁻¹ − Φ Ω⁻² Φᵀ) b_n` (m/N).
    pub fn residual_flexibility_m_per_n(&self) -> f64 {
        self.contact_flexibility_direct_m_per_n - self.contact_flexibility_modal_m_per_n
    }

    /// `modal / direct − 1` for component `c` of probe `p` (−).
    pub fn relative_error(&self, p: usize, c: usize) -> f64 {
        self.modal_m[p][c] / self.direct_m[p][c] - 1.0
    }
}

/// The direct static solver of a track: `K` factorised once, for many load cases.
pub struct StaticDirect {
    llt: SparseLlt,
    scratch: Vec<f64>,
}

impl StaticDirect {
    /// Factorises `K` (N/m, free DOFs).
    pub fn new(mats: &FeMatrices) -> Result<Self, MovingLoadError> {
        Ok(StaticDirect {
            llt: SparseLlt::new(mats.k.as_ref(), "K")?,
            scratch: vec![0.0; mats.k.nrows()],
        })
    }

    /// Modal vs direct static response to `force_n` (N, on the rail, contact frame) at `x`
    /// (m), with the modes `modes` (m/√kg) of `sys` (ω² > 0) and the contact line built
    /// from them.
    #[allow(clippy::too_many_arguments)]
    pub fn compare(
        &mut self,
        track: &TrackStructure,
        modes: &Mat<f64>,
        sys: &ModalSystem,
        line: &RailContactLine,
        frame: &ContactFrame,
        x: f64,
        force_n: [f64; 3],
        probes: &[Probe],
    ) -> Result<StaticComparison, MovingLoadError> {
        let m = sys.len();
        if modes.ncols() != m || line.modes != m {
            return Err(MovingLoadError::Input(format!(
                "the modal system has {m} modes, the basis {} and the contact line {}",
                modes.ncols(),
                line.modes
            )));
        }
        if sys.omega2.iter().any(|&w| w <= 0.0) {
            return Err(MovingLoadError::Input(
                "a mode with ω² ≤ 0: the track must be supported".into(),
            ));
        }
        // Direct: u = K⁻¹ f, and the unit-normal flexibility.
        let n = self.scratch.len();
        let mut u = vec![0.0; n];
        add_line_load(track, line, frame, x, force_n, &mut u)?;
        self.llt.solve(&mut u);
        let direct_m = probes
            .iter()
            .map(|p| p.displacement_of(track, &u))
            .collect();
        let mut bn = vec![0.0; n];
        add_line_load(track, line, frame, x, [0.0, 0.0, 1.0], &mut bn)?;
        self.scratch.copy_from_slice(&bn);
        self.llt.solve(&mut self.scratch);
        let flex_direct = dot(&bn, &self.scratch);
        // Modal: q = Ω⁻² Φᵀ f (Φᵀ f from the contact line's rows, as in the passage).
        let mut rows = vec![0.0; 3 * m];
        line.rows_at(x, &mut rows)?;
        let q: Vec<f64> = (0..m)
            .map(|i| {
                (force_n[0] * rows[i] + force_n[1] * rows[m + i] + force_n[2] * rows[2 * m + i])
                    / sys.omega2[i]
            })
            .collect();
        let flex_modal: f64 = (0..m)
            .map(|i| rows[2 * m + i] * rows[2 * m + i] / sys.omega2[i])
            .sum();
        let modal_m = probes
            .iter()
            .map(|p| {
                let mut r = vec![0.0; 3 * m];
                modal_rows(&p.nodes, &track.dofmap, modes, &GLOBAL, &mut r);
                [
                    dot(&r[..m], &q),
                    dot(&r[m..2 * m], &q),
                    dot(&r[2 * m..], &q),
                ]
            })
            .collect();
        Ok(StaticComparison {
            x_m: x,
            modes: m,
            modal_m,
            direct_m,
            contact_flexibility_direct_m_per_n: flex_direct,
            contact_flexibility_modal_m_per_n: flex_modal,
        })
    }
}

/// One-shot [`StaticDirect::compare`] (factorises `K` each call).
#[allow(clippy::too_many_arguments)]
pub fn static_comparison(
    track: &TrackStructure,
    mats: &FeMatrices,
    modes: &Mat<f64>,
    sys: &ModalSystem,
    line: &RailContactLine,
    frame: &ContactFrame,
    x: f64,
    force_n: [f64; 3],
    probes: &[Probe],
) -> Result<StaticComparison, MovingLoadError> {
    StaticDirect::new(mats)?.compare(track, modes, sys, line, frame, x, force_n, probes)
}

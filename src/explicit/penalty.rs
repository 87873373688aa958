//! The penalty contact between two FE bodies on the central-difference step (theory §6.10),
//! and its first rolling case: steady rolling of the refined tread over the refined rail head
//! (validation/contact_patch.md, P4c).
//!
//! What it models: [`PenaltyPair`] holds the slave nodes of one body, each with the master
//! nodes and bilinear weights of the point below it on the other body's surface, and applies
//! the penalty law of [`crate::contact::penalty`] per slave from the two bodies' displacements:
//! the gap is the rigid gap (given per slave and step) plus the normal displacements of the
//! slave and its master point, the tangential increment the slave's relative to the master
//! point plus the step's rigid slip. Forces are on the slave and, shared by the weights and
//! reversed, on the master nodes, each turned into its mesh's axes.
//!
//! [`RollingCase`] runs the rail-head segment and the tread prism of the local contact patch
//! (`structure::contact_patch`, both at `refine` 1: FE faces of the grid's size) as two
//! explicitly integrated bodies: the Hertzian gap moves along x at the speed, the bodies'
//! approach is held at the static penalty solution's for the load at the start (displacement
//! control), the tread slides rigidly by `ξ V Δt` per step relative to the rail (the creepage),
//! and the run starts from the static normal solution at rest, without traction.
//!
//! Assumptions: small sliding (a slave keeps its master point: the rigid slip over a run is
//! `ξ` times the travel, micrometres) and the contact frame's normal; the tread is unrolled
//! (its curvature enters only through the gap); both bodies are held 0.1 m away from the
//! contact, so the track's and the wheel's dynamics are not in it.

use faer::Mat;

use super::operator::ExplicitOperator;
use super::stable::StableStep;
use super::ExplicitError;
use crate::contact::penalty::{
    segment_stiffness, solve_static_normal, PenaltyLaw, TangentialState,
};
use crate::contact::report::{solve_case, ContactCase, ContactSolution, TangentialLoading};
use crate::contact::{ContactError, HertzContact};
use crate::fe::assembly::DofMap;
use crate::fe::material::IsotropicElastic;
use crate::structure::contact_patch::rail_head::RailHeadPatch;
use crate::structure::contact_patch::tread::TreadPatch;
use crate::structure::contact_patch::{FactorisedSurface, SurfacePoint};

/// One slave node and the master point below it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slave {
    /// The slave body's node.
    pub node: usize,
    /// The master body's surface nodes carrying the point, with their bilinear weights.
    pub master: [(usize, f64); 4],
}

/// One body as the contact sees it: its DOF map and its mesh axes in the contact frame
/// (`±1` per component; the contact frame's z points from the master into the slave).
#[derive(Clone, Copy)]
pub struct Side<'a> {
    /// The body's DOF map.
    pub dofmap: &'a DofMap,
    /// The mesh's axes in the contact frame.
    pub axes: [f64; 3],
}

impl Side<'_> {
    /// The contact-frame displacement of `node` (m) from the free-DOF vector `u`.
    fn displacement(&self, u: &[f64], node: usize) -> [f64; 3] {
        std::array::from_fn(|d| {
            self.dofmap
                .free_index(3 * node + d)
                .map_or(0.0, |f| self.axes[d] * u[f])
        })
    }

    /// Adds the contact-frame force `force` (N) at `node` to the free-DOF load `f`.
    fn add(&self, f: &mut [f64], node: usize, force: [f64; 3]) {
        for d in 0..3 {
            if let Some(k) = self.dofmap.free_index(3 * node + d) {
                f[k] += self.axes[d] * force[d];
            }
        }
    }
}

/// The contact's totals at one evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactTotals {
    /// Normal force on the slave body (N, contact frame +z).
    pub normal_n: f64,
    /// Tangential force on the slave body (N, contact frame x and y).
    pub tangential_n: [f64; 2],
    /// Slaves in contact.
    pub nodes: usize,
}

/// The penalty contact of a set of slave nodes on a master surface (module docs).
pub struct PenaltyPair {
    law: PenaltyLaw,
    slaves: Vec<Slave>,
    states: Vec<TangentialState>,
    /// Each slave's relative displacement (slave less master point, contact x and y) at the
    /// last evaluation (m).
    relative: Vec<[f64; 2]>,
    /// Each slave's penetration at the last evaluation (m).
    penetration: Vec<f64>,
    /// Friction's dissipation so far (J).
    dissipated_j: f64,
    /// The springs' energy in the central difference's cross form between the last two
    /// evaluations (J): `Σ k_n ⟨p_k⟩⟨p_{k+1}⟩ / 2 + f_k · f_{k+1} / 2 k_t`, the penalty's
    /// counterpart of the step's `u_kᵀ K u_{k+1} / 2`.
    cross_j: f64,
}

impl PenaltyPair {
    /// The pair with every spring unloaded; the first evaluation takes the displacements it
    /// is given as the tangential springs' reference.
    pub fn new(law: PenaltyLaw, slaves: Vec<Slave>) -> Self {
        let n = slaves.len();
        PenaltyPair {
            law,
            slaves,
            states: vec![TangentialState::default(); n],
            relative: Vec::new(),
            penetration: vec![f64::NEG_INFINITY; n],
            dissipated_j: 0.0,
            cross_j: 0.0,
        }
    }

    /// The pair with the slaves' tangential springs loaded by `forces_n` (N on each slave,
    /// contact x and y; one per slave): a start in a steady traction.
    pub fn with_tangential_forces(mut self, forces_n: &[[f64; 2]]) -> Result<Self, ContactError> {
        if forces_n.len() != self.slaves.len() {
            return Err(ContactError::WrongLength {
                name: "forces_n",
                got: forces_n.len(),
                expected: self.slaves.len(),
                per: "slave",
            });
        }
        for (state, f) in self.states.iter_mut().zip(forces_n) {
            state.force_n = *f;
        }
        Ok(self)
    }

    /// The law.
    pub fn law(&self) -> &PenaltyLaw {
        &self.law
    }

    /// The slaves.
    pub fn slaves(&self) -> &[Slave] {
        &self.slaves
    }

    /// An upper bound on the highest `ω²` (1/s²) the penalty springs add to the two bodies'
    /// (their lumped masses `slave_mass`, `master_mass`, kg per free DOF): Gershgorin's on
    /// `M⁻¹ K_p`, a slave's row `k (1 + Σ|w|) / m_s`, a master node's `k Σ |w| (|w| + Σ|w'|)
    /// / m_m` bounded by `k Σ |w| (1 + W) / m_m` (`W` the largest `Σ|w|` of a slave), `k`
    /// the larger of the normal and tangential penalties. The
    /// stable step takes it on top of the bodies' own (`λ_max(A + B) ≤ λ_max(A) + λ_max(B)`
    /// for the symmetric mass-scaled operators).
    pub fn omega2_bound(
        &self,
        (slave, slave_mass): (Side<'_>, &[f64]),
        (master, master_mass): (Side<'_>, &[f64]),
    ) -> f64 {
        let k = self.law.normal_n_per_m.max(self.law.tangential_n_per_m);
        let mass = |side: &Side<'_>, m: &[f64], node: usize| {
            (0..3)
                .filter_map(|d| side.dofmap.free_index(3 * node + d))
                .map(|f| m[f])
                .fold(f64::INFINITY, f64::min)
        };
        let mut carried: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
        let mut bound: f64 = 0.0;
        let mut widest: f64 = 0.0;
        for s in &self.slaves {
            let sum: f64 = s.master.iter().map(|m| m.1.abs()).sum();
            widest = widest.max(sum);
            bound = bound.max(k * (1.0 + sum) / mass(&slave, slave_mass, s.node));
            for &(node, w) in &s.master {
                *carried.entry(node).or_insert(0.0) += w.abs();
            }
        }
        for (node, w) in carried {
            bound = bound.max(k * w * (1.0 + widest) / mass(&master, master_mass, node));
        }
        bound
    }

    /// Friction's dissipation so far (J).
    pub fn dissipated_j(&self) -> f64 {
        self.dissipated_j
    }

    /// The springs' energy between the last two evaluations, in the central difference's
    /// cross form (J).
    pub fn cross_energy_j(&self) -> f64 {
        self.cross_j
    }

    /// The contact forces at the bodies' displacements into the loads `f_slave`, `f_master`
    /// (N, free DOFs; overwritten): `gap_m(s)` the rigid gap of slave `s` now (m), `slip_m`
    /// the slave body's rigid tangential displacement relative to the master over the step
    /// (m, contact x and y). Updates the springs, the dissipation and the cross energy.
    pub fn forces(
        &mut self,
        gap_m: impl Fn(usize) -> f64,
        slip_m: [f64; 2],
        (slave, u_slave, f_slave): (Side<'_>, &[f64], &mut [f64]),
        (master, u_master, f_master): (Side<'_>, &[f64], &mut [f64]),
    ) -> ContactTotals {
        f_slave.fill(0.0);
        f_master.fill(0.0);
        self.cross_j = 0.0;
        let first = self.relative.is_empty();
        if first {
            self.relative = vec![[0.0; 2]; self.slaves.len()];
        }
        let mut totals = ContactTotals::default();
        let (kn, kt) = (self.law.normal_n_per_m, self.law.tangential_n_per_m);
        for (s, sl) in self.slaves.iter().enumerate() {
            let us = slave.displacement(u_slave, sl.node);
            let mut um = [0.0; 3];
            for &(node, w) in &sl.master {
                let d = master.displacement(u_master, node);
                for c in 0..3 {
                    um[c] += w * d[c];
                }
            }
            let penetration = -(gap_m(s) + us[2] - um[2]);
            let rel = [us[0] - um[0], us[1] - um[1]];
            let inc = if first {
                slip_m
            } else {
                [
                    rel[0] - self.relative[s][0] + slip_m[0],
                    rel[1] - self.relative[s][1] + slip_m[1],
                ]
            };
            self.relative[s] = rel;
            let old = self.states[s].force_n;
            let f = self.law.update(penetration, inc, &mut self.states[s]);
            let new = self.states[s].force_n;
            self.dissipated_j += f.dissipated_j;
            self.cross_j += 0.5 * kn * self.penetration[s].max(0.0) * penetration.max(0.0)
                + (old[0] * new[0] + old[1] * new[1]) / (2.0 * kt);
            self.penetration[s] = penetration;
            if f.normal_n == 0.0 {
                continue;
            }
            let force = [f.tangential_n[0], f.tangential_n[1], f.normal_n];
            slave.add(f_slave, sl.node, force);
            for &(node, w) in &sl.master {
                master.add(f_master, node, force.map(|c| -w * c));
            }
            totals.normal_n += f.normal_n;
            totals.tangential_n[0] += f.tangential_n[0];
            totals.tangential_n[1] += f.tangential_n[1];
            totals.nodes += 1;
        }
        totals
    }
}

/// How a rolling case starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RollingStart {
    /// From the static normal solution at rest, without traction: the traction builds up
    /// over the travel, and with it the submodels' structural wind-up (their global
    /// compliance under the creep force, about 1e-9 m/N along x), which takes a travel of
    /// about `F_x C / ξ`.
    Normal,
    /// From the static solution under the normal forces and Kalker's steady traction on the
    /// half-space at the same load and creepage, carried by the tangential springs: the
    /// structure starts wound up, and the run shows whether the penalty contact holds that
    /// traction (a steady state of its own drifts away from it).
    KalkerTraction,
}

/// Steady rolling with the penalty contact on the refined rail head and tread (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollingCase {
    /// FE face size at the contact (m), the grid element of the submodels (`refine` 1);
    /// 0.8 mm in the reference study. Range 2e-4–5e-3.
    pub element_m: f64,
    /// Normal load at the start (N, above 0).
    pub load_n: f64,
    /// Longitudinal creepage ξ (−; positive braking, |ξ| ≤ 0.05).
    pub creepage: f64,
    /// Coulomb friction µ (−, 0–2).
    pub friction: f64,
    /// Segment-stiffness scale of the penalty (−, above 0; the codes' default 0.1).
    pub scale: f64,
    /// Rolling speed (m/s, above 0).
    pub speed_m_per_s: f64,
    /// Distance the contact travels (m, above 0).
    pub travel_m: f64,
    /// Wheel rolling radius (m) and rail crown radius (m): the Hertzian gap.
    pub wheel_radius_m: f64,
    /// Rail crown radius (m).
    pub crown_radius_m: f64,
    /// Both bodies' material.
    pub material: IsotropicElastic,
    /// Fraction of the critical step used (0–1].
    pub safety: f64,
    /// How the run starts.
    pub start: RollingStart,
}

impl RollingCase {
    /// The case of P4c: 0.8 mm faces, 15 kN, ξ = 5e-4, µ 0.3, s = 10, 140 km/h, 12 mm of
    /// travel, the default model's wheel on the R300 crown, steel, 0.9 of the critical step.
    pub fn p4c() -> Self {
        RollingCase {
            element_m: 0.8e-3,
            load_n: 15e3,
            creepage: 5e-4,
            friction: 0.3,
            scale: 10.0,
            speed_m_per_s: 140.0 / 3.6,
            travel_m: 12e-3,
            wheel_radius_m: 0.46,
            crown_radius_m: 0.3,
            material: IsotropicElastic::STEEL,
            safety: 0.9,
            start: RollingStart::Normal,
        }
    }
}

impl RollingCase {
    /// Checks the ranges (names the key out of range).
    pub fn check(&self) -> Result<(), ContactError> {
        let bad = |name: &'static str, value: f64, reason: &'static str| {
            Err(ContactError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if !(2e-4..=5e-3).contains(&self.element_m) {
            return bad("element_m", self.element_m, "2e-4 to 5e-3 m");
        }
        if self.creepage.is_nan() || self.creepage.abs() > 0.05 {
            return bad("creepage", self.creepage, "|ξ| at most 0.05");
        }
        if !(self.safety > 0.0 && self.safety <= 1.0) {
            return bad("safety", self.safety, "above 0, at most 1");
        }
        if !(self.travel_m >= 2.0 * self.element_m && self.travel_m <= 0.1) {
            return bad("travel_m", self.travel_m, "two elements to 0.1 m");
        }
        for (name, v) in [
            ("load_n", self.load_n),
            ("scale", self.scale),
            ("speed_m_per_s", self.speed_m_per_s),
            ("wheel_radius_m", self.wheel_radius_m),
            ("crown_radius_m", self.crown_radius_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, v, "finite, above 0");
            }
        }
        PenaltyLaw {
            normal_n_per_m: 1.0,
            tangential_n_per_m: 1.0,
            friction: self.friction,
        }
        .check()
    }
}

/// The contact at one step of a rolling case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollingSample {
    /// Contact position along the rail (m).
    pub x_m: f64,
    /// Normal force on the wheel (N).
    pub normal_n: f64,
    /// Longitudinal force on the wheel (N; negative braking).
    pub fx_n: f64,
    /// Friction's dissipation since the start (J).
    pub dissipated_j: f64,
    /// Slave nodes in contact.
    pub nodes: usize,
}

/// What a rolling case gives.
#[derive(Debug, Clone, PartialEq)]
pub struct RollingResult {
    /// Time step (s).
    pub dt_s: f64,
    /// Steps run.
    pub steps: usize,
    /// Free DOFs of the rail head and the tread.
    pub dofs: [usize; 2],
    /// Normal penalty per slave (N/m).
    pub k_n_per_m: f64,
    /// The contact at every step.
    pub history: Vec<RollingSample>,
    /// Mean normal force over the last third of the travel (N).
    pub steady_normal_n: f64,
    /// Mean `F_x / F_n` over the last third of the travel (−).
    pub steady_traction: f64,
    /// Frictional power over the last third (W).
    pub steady_power_w: f64,
    /// Kalker's steady solution on the half-space at the steady normal force and the
    /// creepage: `F_x / F_n` (−) and the frictional power (W).
    pub kalker_traction: f64,
    /// Kalker's frictional power (W).
    pub kalker_power_w: f64,
    /// Hertz at the start load.
    pub hertz: HertzContact,
}

/// Runs a rolling case (module docs): builds and factorises both submodels, the static
/// normal start, then the central difference over the travel.
pub fn run_rolling(case: &RollingCase) -> Result<RollingResult, ExplicitError> {
    case.check()?;
    let hertz = contact_case(case, case.load_n).hertz()?;
    let h = case.element_m;
    // the refined zone covers the travel and 1.4 semi-axes beyond either end
    let reach_x = 0.5 * case.travel_m + 1.4 * hertz.a_m;
    let reach_y = 1.4 * hertz.b_m;
    let nx = (reach_x / h).ceil() as usize;
    let ny = (2.0 * reach_y / h).ceil() as usize;
    let mut rail = RailHeadPatch::steel(h, nx, ny);
    rail.material = case.material;
    rail.refine = 1;
    let mut tread = TreadPatch::steel(h, nx, ny);
    tread.material = case.material;
    tread.refine = 1;
    let rail = rail.factorised_surface()?;
    let tread = tread.factorised_surface()?;
    let points: Vec<SurfacePoint> = tread.surface_points(reach_x, reach_y);
    let at: Vec<[f64; 2]> = points.iter().map(|p| p.at).collect();
    let area = points
        .iter()
        .map(|p| p.area_m2)
        .fold(f64::INFINITY, f64::min);
    let layer = tread.layer_m().min(rail.layer_m());
    let k_n = segment_stiffness(
        case.material.youngs_modulus,
        case.material.poisson_ratio,
        area,
        area * layer,
        case.scale,
    )?;
    // the rigid gap of slave s with the contact centred at x_c, less the approach δ
    let (rw, rc) = (case.wheel_radius_m, case.crown_radius_m);
    let shape = |p: [f64; 2], xc: f64| (p[0] - xc).powi(2) / (2.0 * rw) + p[1] * p[1] / (2.0 * rc);
    let x0 = -0.5 * case.travel_m;
    // the static start: the penalty's normal solution on the condensed point compliances
    let c = rail.point_compliance(&at)? + tread.point_compliance(&at)?;
    let gap0: Vec<f64> = at.iter().map(|&p| shape(p, x0)).collect();
    let start = solve_static_normal(&c, &gap0, k_n, case.load_n)?;
    let slaves: Vec<Slave> = points
        .iter()
        .map(|p| Slave {
            node: p.node,
            master: rail.weights(p.at),
        })
        .collect();
    // the start's tangential forces on the slaves (N, on the wheel)
    let traction: Vec<[f64; 2]> = match case.start {
        RollingStart::Normal => vec![[0.0; 2]; slaves.len()],
        RollingStart::KalkerTraction => {
            let steady = kalker(case, case.load_n)?;
            let total_k = steady.result.fx_n;
            let mut f: Vec<[f64; 2]> = points
                .iter()
                .zip(&start.forces_n)
                .map(|(p, &fz)| {
                    let tx = if fz > 0.0 {
                        nearest(
                            &steady.x_m,
                            &steady.y_m,
                            &steady.traction_x_pa,
                            [p.at[0] - x0, p.at[1]],
                        )
                    } else {
                        0.0
                    };
                    [tx * p.area_m2, 0.0]
                })
                .collect();
            let total: f64 = f.iter().map(|v| v[0]).sum();
            if total != 0.0 {
                for v in &mut f {
                    v[0] *= total_k / total;
                }
            }
            f
        }
    };
    let rail_side = Side {
        dofmap: rail.dofmap(),
        axes: rail.axes(),
    };
    let tread_side = Side {
        dofmap: tread.dofmap(),
        axes: tread.axes(),
    };
    // the static displacement of a body under the start's contact forces: on the slaves as
    // they are, on the master nodes shared by the weights and reversed
    let static_state = |body: &FactorisedSurface, side: Side<'_>, is_slave: bool| {
        let mut f = Mat::<f64>::zeros(body.dofmap().n_free(), 1);
        let mut load = vec![0.0; body.dofmap().n_free()];
        for ((sl, &fz), t) in slaves.iter().zip(&start.forces_n).zip(&traction) {
            let force = [t[0], t[1], fz];
            if is_slave {
                side.add(&mut load, sl.node, force);
            } else {
                for &(node, w) in &sl.master {
                    side.add(&mut load, node, force.map(|c| -w * c));
                }
            }
        }
        for (i, v) in load.iter().enumerate() {
            f[(i, 0)] = *v;
        }
        body.solve_in_place(&mut f)?;
        Ok::<Vec<f64>, ExplicitError>((0..f.nrows()).map(|i| f[(i, 0)]).collect())
    };
    let mut u_t = static_state(&tread, tread_side, true)?;
    let mut u_r = static_state(&rail, rail_side, false)?;
    let op = |b: &FactorisedSurface| {
        let m = b.matrices();
        ExplicitOperator::new(m.k.as_ref(), m.m.as_ref(), m.c.as_ref())
    };
    let (op_t, op_r) = (op(&tread)?, op(&rail)?);
    let law = PenaltyLaw {
        normal_n_per_m: k_n,
        tangential_n_per_m: k_n,
        friction: case.friction,
    };
    let mut pair = PenaltyPair::new(law, slaves).with_tangential_forces(&traction)?;
    let w2 = |o: &ExplicitOperator| -> Result<f64, ExplicitError> {
        Ok(StableStep::estimate(o)?.omega_max_estimate.powi(2))
    };
    // the bodies' highest frequency and a bound on what the penalty adds
    let omega2 = w2(&op_t)?.max(w2(&op_r)?)
        + pair.omega2_bound((tread_side, op_t.mass()), (rail_side, op_r.mass()));
    let dt = case.safety * 2.0 / omega2.sqrt();
    let (mut v_t, mut v_r) = (vec![0.0; op_t.n()], vec![0.0; op_r.n()]);
    let (mut f_t, mut f_r) = (vec![0.0; op_t.n()], vec![0.0; op_r.n()]);
    let (mut s_t, mut s_r) = (op_t.scratch(), op_r.scratch());
    let steps = (case.travel_m / (case.speed_m_per_s * dt)).ceil() as usize;
    let slip = [case.creepage * case.speed_m_per_s * dt, 0.0];
    let delta = start.approach_m;
    let mut history = Vec::with_capacity(steps + 1);
    for step in 0..=steps {
        let xc = x0 + case.speed_m_per_s * dt * step as f64;
        let totals = pair.forces(
            |s| shape(at[s], xc) - delta,
            if step == 0 { [0.0; 2] } else { slip },
            (tread_side, &u_t, &mut f_t),
            (rail_side, &u_r, &mut f_r),
        );
        history.push(RollingSample {
            x_m: xc,
            normal_n: totals.normal_n,
            fx_n: totals.tangential_n[0],
            dissipated_j: pair.dissipated_j(),
            nodes: totals.nodes,
        });
        // a diverged state shows in the contact forces at once; the states are scanned only
        // then, not every step (a pass over both bodies' DOFs)
        let forces_finite = totals.normal_n.is_finite() && totals.tangential_n[0].is_finite();
        if !forces_finite || (step == steps && !u_t.iter().chain(&u_r).all(|x| x.is_finite())) {
            return Err(ExplicitError::Diverged {
                t_s: dt * step as f64,
                x_m: xc,
                part: "penalty contact",
            });
        }
        if step == steps {
            break;
        }
        op_t.step(dt, &mut u_t, &mut v_t, &f_t, &mut s_t);
        op_r.step(dt, &mut u_r, &mut v_r, &f_r, &mut s_r);
    }
    // the last third of the travel
    let tail = &history[2 * history.len() / 3..];
    let n = tail.len() as f64;
    let steady_normal_n = tail.iter().map(|h| h.normal_n).sum::<f64>() / n;
    let steady_fx = tail.iter().map(|h| h.fx_n).sum::<f64>() / n;
    let (first, last) = (tail[0], tail[tail.len() - 1]);
    let steady_power_w = (last.dissipated_j - first.dissipated_j) / ((tail.len() - 1) as f64 * dt);
    let kalker = kalker(case, steady_normal_n)?;
    Ok(RollingResult {
        dt_s: dt,
        steps,
        dofs: [rail.n_dofs(), tread.n_dofs()],
        k_n_per_m: k_n,
        history,
        steady_normal_n,
        steady_traction: steady_fx / steady_normal_n,
        steady_power_w,
        kalker_traction: kalker.result.fx_n / kalker.result.normal_force_n,
        kalker_power_w: kalker.result.frictional_power_w,
        hertz,
    })
}

/// The rolling case as a contact case on the half-space at the normal load `load_n` (N):
/// Hertz and Kalker's steady rolling for the same bodies and creepage.
fn contact_case(case: &RollingCase, load_n: f64) -> ContactCase {
    ContactCase {
        wheel_radius_m: case.wheel_radius_m,
        crown_radius_m: case.crown_radius_m,
        wheel_lateral_radius_m: f64::INFINITY,
        youngs_pa: case.material.youngs_modulus,
        poisson: case.material.poisson_ratio,
        normal_load_n: load_n,
        friction: case.friction,
        tangential: TangentialLoading::Creepage(case.creepage),
        speed_m_per_s: case.speed_m_per_s,
        ..ContactCase::default()
    }
}

/// Kalker's steady rolling on the half-space for the case at the normal load `load_n` (N).
fn kalker(case: &RollingCase, load_n: f64) -> Result<ContactSolution, ExplicitError> {
    Ok(solve_case(&contact_case(case, load_n))?)
}

/// The value of the element-centre field `v` (index `i · y.len() + j`) of the element
/// nearest to `p` (m); zero beyond the grid.
fn nearest(x: &[f64], y: &[f64], v: &[f64], p: [f64; 2]) -> f64 {
    let index = |c: &[f64], q: f64| -> Option<usize> {
        let h = if c.len() > 1 {
            c[1] - c[0]
        } else {
            return None;
        };
        let i = ((q - c[0]) / h).round();
        (i >= 0.0 && (i as usize) < c.len()).then_some(i as usize)
    };
    match (index(x, p[0]), index(y, p[1])) {
        (Some(i), Some(j)) => v[i * y.len() + j],
        _ => 0.0,
    }
}

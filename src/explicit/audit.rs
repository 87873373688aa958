//! The energy audit of an explicit passage (docs/theory.md §8.8): every contact step is
//! replayed from its start state with the force history the structures actually carried
//! (the predictor's held force plus the corrector's share of the change, sub-step by
//! sub-step), and the work of the nodal forces is summed as the central difference defines
//! it, `Σ_k f_k · (u_{k+1} − u_{k−1})/2`. That work, the dampers' and the change of the
//! central difference's conserved energy `½ v_{k+½}ᵀ M v_{k+½} + ½ u_kᵀ K u_{k+1}` close
//! exactly (a conservation law of the scheme), so the audit tells which term of the
//! `super::ledger::Ledger` carries an energy error: the structures' accounting, or the
//! contact's (the contact force's work on the relative displacement against the friction,
//! the Hertz energy and the series spring). It doubles the structural cost of a passage and
//! is off unless asked for ([`super::ExplicitOptions::audit`]).

use super::ledger::State;
use super::model::ExplicitModel;
use super::operator::{ExplicitOperator, StepScratch};
use super::response::Hold;
use super::start::add_line_force;
use crate::passage::contact_line::add_nodes_load;
use crate::passage::planes::PlaneWeights;

/// The audit's sums over a passage (J unless stated).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct EnergyAudit {
    /// Work of the contact load on the rail's nodes, `Σ_k f_k · (u_{k+1} − u_{k−1})/2`.
    pub rail_nodal_work_j: f64,
    /// Work of the contact load on the wheel's nodes (same sum).
    pub wheel_contact_nodal_work_j: f64,
    /// Work of the constant wheel loads on the wheel's nodes (same sum).
    pub wheel_load_nodal_work_j: f64,
    /// Work of the dampers over every replayed sub-step.
    pub damper_work_j: f64,
    /// Change of the central difference's conserved energy of both substructures.
    pub discrete_energy_change_j: f64,
    /// `work in − dampers − discrete energy change`: zero to rounding (the scheme's
    /// conservation law; a check of the audit itself).
    pub scheme_residual_j: f64,
    /// Largest difference between a replayed and the corrected displacement over the
    /// largest displacement (−): zero to rounding when the corrector's superposition is exact.
    pub replay_mismatch: f64,
    /// The ledger's contact work on the rail: the mean force over the step times the rail's
    /// displacement increment under the patch.
    pub ledger_rail_work_j: f64,
    /// The ledger's contact work on the wheel (same, at the wheel's contact point).
    pub ledger_wheel_work_j: f64,
    /// The ledger's contact work per contact-frame direction (x, t, n): the mean force over
    /// the step times the contact points' relative displacement increment.
    pub ledger_contact_work_j: [f64; 3],
    /// The ledger's convective work per direction (x, t, n).
    pub ledger_convective_work_j: [f64; 3],
    /// The series spring's energy change per direction (x, t, n) (with the normal
    /// direction's rolling term, which the ledger books as convective work, included here).
    pub ledger_spring_j: [f64; 3],
}

/// Replays contact steps and keeps the [`EnergyAudit`]'s structural sums. Buffers are
/// allocated once per passage.
pub(super) struct Audit {
    saved: State,
    load: Vec<f64>,
    load_w: Vec<f64>,
    ref_u: Vec<f64>,
    sc_t: StepScratch,
    sc_w: StepScratch,
    pub(super) sums: EnergyAudit,
    scale_u: f64,
}

/// One contact step's force history: the predictor's first and held force, the change
/// applied by the corrector (N, on the wheel, contact frame) and the hold's shares.
pub(super) struct StepForces<'a> {
    /// The predictor's first sub-step load: at the previous contact position (patch
    /// `previous`) and at this one.
    pub(super) first: [[f64; 3]; 2],
    pub(super) previous: &'a PlaneWeights,
    pub(super) held: [f64; 3],
    pub(super) change: [f64; 3],
    /// `None` without a corrector.
    pub(super) hold: Option<Hold>,
    /// The wheel's constant loads over the step (N; [`ExplicitModel::wheel_loads`]).
    pub(super) wheel_loads: &'a [f64],
}

impl StepForces<'_> {
    /// The load of sub-step `k` of `steps` at this contact position (N).
    fn at(&self, k: usize, steps: usize) -> [f64; 3] {
        let base = if k == 0 { self.first[1] } else { self.held };
        let a = self.hold.map_or(0.0, |h| h.share(k, steps));
        [0, 1, 2].map(|d| base[d] + a * self.change[d])
    }

    /// The load of sub-step `k` at the previous contact position (N).
    fn at_previous(&self, k: usize) -> [f64; 3] {
        if k == 0 {
            self.first[0]
        } else {
            [0.0; 3]
        }
    }
}

impl Audit {
    pub(super) fn new(m: &ExplicitModel, s: &State) -> Self {
        Audit {
            saved: State {
                ut: s.ut.clone(),
                vt: s.vt.clone(),
                uw: s.uw.clone(),
                vw: s.vw.clone(),
            },
            load: vec![0.0; s.ut.len()],
            load_w: vec![0.0; s.uw.len()],
            ref_u: vec![0.0; s.ut.len().max(s.uw.len())],
            sc_t: m.track.op.scratch(),
            sc_w: m.wheel.op.scratch(),
            sums: EnergyAudit::default(),
            scale_u: 0.0,
        }
    }

    /// The discrete energy of the state at the start (`dt`: the track's and wheel's steps).
    pub(super) fn start(&mut self, m: &ExplicitModel, s: &State, dt: [f64; 2]) {
        self.sums.discrete_energy_change_j = -discrete_energy(m, s, dt, &mut self.ref_u);
    }

    /// Keeps the state at a contact step's start.
    pub(super) fn save(&mut self, s: &State) {
        self.saved.ut.copy_from_slice(&s.ut);
        self.saved.vt.copy_from_slice(&s.vt);
        self.saved.uw.copy_from_slice(&s.uw);
        self.saved.vw.copy_from_slice(&s.vw);
    }

    /// Replays the step from the saved state with the forces `f` at the patch `pw`, with
    /// `(steps, dt)` of the track and the wheel, and compares with the corrected state `s`.
    pub(super) fn replay(
        &mut self,
        m: &ExplicitModel,
        pw: &PlaneWeights,
        f: &StepForces,
        [track, wheel]: [(usize, f64); 2],
        s: &State,
    ) {
        let State { ut, vt, uw, vw } = &mut self.saved;
        let (n, dt) = track;
        for k in 0..n {
            self.load.iter_mut().for_each(|x| *x = 0.0);
            for (g, w) in [(f.at_previous(k), f.previous), (f.at(k, n), pw)] {
                let neg = [-g[0], -g[1], -g[2]];
                add_line_force(
                    &m.line,
                    &m.track_structure,
                    &m.frame,
                    w,
                    neg,
                    &mut self.load,
                );
            }
            let r = m.track.op.step(dt, ut, vt, &self.load, &mut self.sc_t);
            self.sums.rail_nodal_work_j += r.external_work_j;
            self.sums.damper_work_j += r.damper_work_j;
        }
        let (n, dt) = wheel;
        let dm = &m.wheel_structure.dofmap;
        for k in 0..n {
            let (a, b) = (f.at_previous(k), f.at(k, n));
            let g = [0, 1, 2].map(|d| a[d] + b[d]);
            let fc = f.wheel_loads;
            self.load_w.copy_from_slice(fc);
            add_nodes_load(&m.wheel_nodes, dm, &m.frame, 1.0, g, &mut self.load_w);
            // The constant loads' share of the step's work, `f_c · (u_{k+1} − u_{k−1})/2`.
            let before = dot(fc, uw) - 0.5 * dt * dot(fc, vw);
            let r = m.wheel.op.step(dt, uw, vw, &self.load_w, &mut self.sc_w);
            let after = dot(fc, uw) - 0.5 * dt * dot(fc, vw);
            let w_const = after - before;
            self.sums.wheel_load_nodal_work_j += w_const;
            self.sums.wheel_contact_nodal_work_j += r.external_work_j - w_const;
            self.sums.damper_work_j += r.damper_work_j;
        }
        let mut worst: f64 = 0.0;
        for (a, b) in [(&self.saved.ut, &s.ut), (&self.saved.uw, &s.uw)] {
            for (x, y) in a.iter().zip(b.iter()) {
                worst = worst.max((x - y).abs());
                self.scale_u = self.scale_u.max(y.abs());
            }
        }
        self.sums.replay_mismatch = self
            .sums
            .replay_mismatch
            .max(worst / self.scale_u.max(f64::MIN_POSITIVE));
    }

    /// The sums at the end of the passage, state `s`.
    pub(super) fn finish(mut self, m: &ExplicitModel, s: &State, dt: [f64; 2]) -> EnergyAudit {
        self.sums.discrete_energy_change_j += discrete_energy(m, s, dt, &mut self.ref_u);
        let a = &mut self.sums;
        a.scheme_residual_j =
            a.rail_nodal_work_j + a.wheel_contact_nodal_work_j + a.wheel_load_nodal_work_j
                - a.damper_work_j
                - a.discrete_energy_change_j;
        self.sums
    }
}

/// The central difference's conserved energy `½ v_{k+½}ᵀ M v_{k+½} + ½ u_kᵀ K u_{k+1}` of
/// both substructures (J), written with the state `(u_{k+1}, v_{k+½})` as
/// `½ vᵀ M v + ½ (u − Δt v)ᵀ K u`.
fn discrete_energy(m: &ExplicitModel, s: &State, [dtt, dtw]: [f64; 2], ku: &mut [f64]) -> f64 {
    let mut e = 0.0;
    for (op, u, v, dt) in [
        (&m.track.op, &s.ut, &s.vt, dtt),
        (&m.wheel.op, &s.uw, &s.vw, dtw),
    ] {
        e += energy_of(op, u, v, dt, &mut ku[..u.len()]);
    }
    e
}

fn energy_of(op: &ExplicitOperator, u: &[f64], v: &[f64], dt: f64, ku: &mut [f64]) -> f64 {
    op.apply_k(u, ku);
    let strain: f64 = u
        .iter()
        .zip(v)
        .zip(ku.iter())
        .map(|((x, w), k)| 0.5 * (x - dt * w) * k)
        .sum();
    strain + op.kinetic_energy(v)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

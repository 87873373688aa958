//! The step loop of an explicit passage: the plan, the static start, and the state carried
//! from one contact step to the next with its phases (predictor, contact, corrector, energy
//! ledger, recorder); the scheme is in the parent module's documentation.

use std::time::Instant;

use super::{ExplicitInfo, ExplicitRecord};
use crate::contact::{
    Longitudinal, NormalInput, StepInputs, StepResult, TransientRolling, WearAccumulator,
};
use crate::explicit::audit::{Audit, StepForces};
use crate::explicit::ledger::{Ledger, LedgerStep, State};
use crate::explicit::model::ExplicitModel;
use crate::explicit::operator::StepScratch;
use crate::explicit::response::{advance_held, Hold, RailResponses, UnitResponse};
use crate::explicit::rotating::RotatingWheel;
use crate::explicit::start::add_line_force;
use crate::explicit::ExplicitError;
use crate::passage::contact_line::add_nodes_load;
use crate::passage::planes::{max_planes, PlaneWeights};
use crate::passage::setup::{start_longitudinal_force_n, torque_onset_m};
use crate::passage::{
    record::{Histories, PassageRecord, RailPointRecord},
    setup::{rigid_least_norm, steady_contact},
    PassageOptions,
};
use crate::passage::{PassageError, RailProfile};

impl ExplicitModel {
    /// The plan of a passage at `v` (m/s) with the passage's contact engine: the contact step
    /// `Δx/V`, the structures' sub-steps, and the contact steps from the start until the
    /// patch has left the solution zone.
    pub(super) fn plan(&self, v: f64, contact: &TransientRolling) -> Plan {
        let dt_c = contact.time_step_s();
        let dx = v * dt_c;
        let (nt, dtt) = self.track.substeps(dt_c);
        let (nw, dtw) = self.wheel.substeps(dt_c);
        let x0 = self.x_start_m;
        let [z0, z1] = self.zone_m;
        let half_grid = contact.config().grid.half_length_x_m;
        let x_end = z1 + half_grid + 2.0 * dx;
        Plan {
            v,
            dt_c,
            dx,
            nt,
            dtt,
            nw,
            dtw,
            spin: self.frame.n[1] / self.wheel_radius_m,
            x0,
            half_grid,
            n_steps: ((x_end - x0) / dx).ceil() as usize,
            nbins: ((z1 - z0) / dx).round().max(1.0) as usize,
        }
    }

    /// The estimated time and memory of a passage of `plan`
    /// ([`crate::explicit::estimate::ExplicitEstimate`]).
    pub(super) fn estimate(&self, plan: &Plan) -> crate::explicit::estimate::ExplicitEstimate {
        crate::explicit::estimate::ExplicitEstimate::new(
            plan.n_steps,
            [plan.nt, plan.nw],
            self.dofs(),
        )
    }

    /// The static start: the contact brought to steady rolling at the static load, the
    /// structures' static state with the wheel's rigid modes placed and turned to match it,
    /// and the rotating wheel (`None` for the fixed one) with its rolling velocity added.
    pub(super) fn static_start(
        &self,
        plan: &Plan,
        contact: &mut TransientRolling,
        heights: &mut RailHeights<'_>,
    ) -> Result<Start, ExplicitError> {
        let w_load = self.model.vehicle.wheel_load;
        let f_l0 = start_longitudinal_force_n(&self.model);
        let f_n0 = w_load / self.frame.n[2];
        let x_torque = torque_onset_m(&self.model, plan.x0, self.zone_m[0])?;
        let st = steady_contact(contact, f_n0, f_l0, plan.spin, heights.at(plan.x0), plan.x0)?;
        let mut state = self.start_state(plan.v, st.creepage, st.approach_m)?;
        // The rotating wheel (rotating.rs); `None` for the fixed wheel.
        let rot = self.rotating_wheel(plan.v, plan.nw, plan.dtw)?;
        if let Some(r) = &rot {
            r.check_coverage(plan.n_steps as f64 * plan.dt_c)?;
            r.add_rolling_velocity(&self.wheel_structure, &state.uw, &mut state.vw);
            // The wheel's material velocity at the contact back to the steady creepage's.
            let dv = st.creepage * plan.v - r.contact_velocity_x(&state.uw, &state.vw);
            let c = rigid_least_norm(&self.rigid_obs, [dv, 0.0, 0.0]);
            for (k, m) in self.rigid.iter().enumerate() {
                state.vw.iter_mut().zip(m).for_each(|(x, y)| *x += c[k] * y);
            }
        }
        Ok(Start {
            st,
            state,
            rot,
            x_torque,
        })
    }
}

/// The fixed quantities of one passage: speed, contact step and sub-steps, range.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plan {
    /// Speed (m/s).
    v: f64,
    /// Contact step `Δx/V` (s).
    dt_c: f64,
    /// Contact step length `Δx` (m).
    dx: f64,
    /// Track sub-steps per contact step (−) and their length (s).
    nt: usize,
    dtt: f64,
    /// Wheel sub-steps per contact step (−) and their length (s).
    nw: usize,
    dtw: f64,
    /// Spin creepage of the tread (1/m).
    spin: f64,
    /// Contact position at the start (m).
    x0: f64,
    /// Half length of the contact grid along x (m).
    half_grid: f64,
    /// Contact steps of the passage (−).
    pub(super) n_steps: usize,
    /// Wear bins over the solution zone (−).
    nbins: usize,
}

/// The rail profile's heights under the contact grid's columns (m), refreshed per step.
pub(super) struct RailHeights<'a> {
    /// The rail profile (`None` = smooth rail: no heights).
    profile: Option<&'a RailProfile>,
    /// The grid columns' x relative to the contact point (m).
    xs: Vec<f64>,
    /// The heights of the last position (m).
    h: Vec<f64>,
}

impl<'a> RailHeights<'a> {
    /// Heights over `profile` (`None` = smooth) under the grid of `contact`.
    pub(super) fn new(profile: Option<&'a RailProfile>, contact: &TransientRolling) -> Self {
        RailHeights {
            profile,
            xs: contact.x_m().to_vec(),
            h: vec![0.0; contact.config().grid.nx],
        }
    }

    /// The heights under the grid at contact position `xc` (m); `None` on a smooth rail.
    fn at(&mut self, xc: f64) -> Option<&[f64]> {
        let p = self.profile?;
        for (hi, &xi) in self.h.iter_mut().zip(&self.xs) {
            *hi = p.height_at(xc + xi);
        }
        Some(&self.h)
    }
}

/// The static start of a passage.
pub(super) struct Start {
    /// The contact in steady rolling at the static load.
    st: StepResult,
    /// The structures' state.
    state: State,
    /// The rotating wheel (`None` for the fixed wheel).
    rot: Option<RotatingWheel>,
    /// Position from which the driving torque and the resistance act (m; −∞ for the static
    /// start).
    x_torque: f64,
}

/// The predictor's load vectors (N), allocated once per passage: the first sub-step's and
/// the other sub-steps' on the track, and on the wheel (with the wheel's constant loads).
struct HeldLoads {
    track0: Vec<f64>,
    track: Vec<f64>,
    wheel0: Vec<f64>,
    wheel: Vec<f64>,
}

/// What the predictor of one contact step yields.
struct Predicted {
    /// Rail under the patch and wheel at the contact, at the step's start (m, contact frame).
    old: [[f64; 3]; 2],
    /// Without a corrector: the rail under the previous contact position, where the held
    /// force acts, at the step's start (m, contact frame).
    old_at_previous: Option<[f64; 3]>,
    /// The same after the predictor (m).
    new: [[f64; 3]; 2],
    /// The first sub-step's load at the previous and at this contact position (N).
    split: [[f64; 3]; 2],
    /// Work of the dampers over the step (J).
    damper_j: f64,
    /// The wheel's contact-point displacement at the step's start as the structure sees it
    /// ([`LedgerStep::uw_turned`], m).
    uw_turned: [f64; 3],
    /// Work of the rotating wheel's suspension turned to the ground vertical (J).
    frame_j: f64,
    /// The wheel's one-step compliance at the contact (m/N per direction).
    g_wheel: [f64; 3],
}

/// What the contact solve of one contact step yields.
struct Solved {
    /// The contact's step result.
    r: StepResult,
    /// The longitudinal creepage from the predicted kinematics (−).
    xi: f64,
    /// The approach given to the contact (m).
    delta: f64,
    /// The removed local compliance variation at the position (m/N per direction): the
    /// rail's and the rotating tread's, and the tread's share.
    dg: [f64; 3],
    dg_wheel: [f64; 3],
    /// The rotating tread's convective deflection taken out of the creepage (m, contact
    /// frame; zero on the fixed wheel).
    conv: [f64; 3],
}

/// The state of an explicit passage carried from one contact step to the next: the
/// structures, the contact, the coupling's force history, the energy ledger and the records.
pub(super) struct Stepper<'a> {
    m: &'a ExplicitModel,
    plan: Plan,
    contact: TransientRolling,
    heights: RailHeights<'a>,
    /// Static creepage (−) and approach (m) of the start.
    static_creepage: f64,
    static_approach_m: f64,
    s: State,
    rot: Option<RotatingWheel>,
    /// Position from which the driving torque and the resistance act (m), and whether they
    /// do at the current step.
    x_torque: f64,
    drive: bool,
    corrected: bool,
    hold: Hold,
    sc_t: StepScratch,
    sc_w: StepScratch,
    /// The fixed wheel's unit responses over a contact step and its one-step compliance (m/N).
    wheel_resp: UnitResponse,
    g_wheel: [f64; 3],
    rail_resp: RailResponses,
    loads: HeldLoads,
    /// The last contact force and the one before (N, on the wheel, contact frame).
    f: [f64; 3],
    f_prev: [f64; 3],
    /// The patch of the previous contact step.
    pw_prev: PlaneWeights,
    /// The one-step compliance (m/N) and the contact's series compliance (less the local
    /// variation, clamped at 0).
    series: [f64; 3],
    series_c: [f64; 3],
    /// Contact steps at which the series compliance was clamped.
    clamped: usize,
    last_delta: f64,
    /// Whether the energy ledger is kept.
    keep: bool,
    ledger: Ledger<'a>,
    audit: Option<Audit>,
    h: Histories,
    rail_point: Option<(usize, RailPointRecord)>,
    wear: WearAccumulator,
}

impl<'a> Stepper<'a> {
    /// The set-up of the step loop: the unit responses and scratch of the coupling, the
    /// energy ledger (and audit), the records, and the force history at the static start.
    pub(super) fn new(
        m: &'a ExplicitModel,
        plan: Plan,
        contact: TransientRolling,
        heights: RailHeights<'a>,
        start: Start,
        popts: &PassageOptions,
    ) -> Result<Self, ExplicitError> {
        let Start {
            st,
            state: s,
            mut rot,
            x_torque,
        } = start;
        // Before the torque's onset (a start from rest) the wheel carries gravity only.
        let drive = x_torque == f64::NEG_INFINITY;
        if let Some(r) = rot.as_mut() {
            r.set_drive(drive);
        }
        let sc_t = m.track.op.scratch();
        let mut sc_w = m.wheel.op.scratch();
        let hold = m.opts.coupling.hold();
        let (wheel_resp, g_wheel) = m.wheel_response(plan.dtw, plan.nw, &mut sc_w);
        let slots = max_planes(&m.line.planes_x_m, m.patch_a_m) + 1;
        let rail_resp = RailResponses::new(m.track.op.n(), (plan.dtt, plan.nt, hold), slots);
        let rail_point = m.rail_point(popts, plan.n_steps);
        let wear = WearAccumulator::new(&contact, m.zone_m[0], plan.nbins);
        let keep = popts.energy;
        let ledger = Ledger::new(m, keep, &s, &st, plan.x0, rot.as_ref())?;
        let mut audit = (keep && m.opts.audit && rot.is_none()).then(|| Audit::new(m, &s));
        if let Some(a) = audit.as_mut() {
            a.start(m, &s, [plan.dtt, plan.dtw]);
        }
        // The start's force on the structures is the static one (lateral 0).
        let f = [st.fx_n, 0.0, st.normal_force_n];
        // The patch of the previous contact step (at the start: the static one).
        let pw_prev = m.weights(plan.x0)?;
        let ftrack = vec![0.0; m.track.op.n()];
        Ok(Stepper {
            m,
            plan,
            contact,
            heights,
            static_creepage: st.creepage,
            static_approach_m: st.approach_m,
            s,
            rot,
            x_torque,
            drive,
            corrected: m.opts.coupling.corrected(),
            hold,
            sc_t,
            sc_w,
            wheel_resp,
            g_wheel,
            rail_resp,
            loads: HeldLoads {
                track0: ftrack.clone(),
                track: ftrack,
                wheel0: m.wheel_loads(drive).to_vec(),
                wheel: m.wheel_loads(drive).to_vec(),
            },
            f,
            f_prev: f,
            pw_prev,
            series: [0.0; 3],
            series_c: [0.0; 3],
            clamped: 0,
            last_delta: st.approach_m,
            keep,
            ledger,
            audit,
            h: Histories::default(),
            rail_point,
            wear,
        })
    }

    /// Contact step `n` (1-based) from `t_{n-1}` to `t_n`: predictor, contact, corrector,
    /// then the audit, the wear, the energy ledger and the records.
    pub(super) fn step(&mut self, n: usize) -> Result<(), ExplicitError> {
        let p = self.plan;
        let t = n as f64 * p.dt_c;
        let xc = p.x0 + p.v * t;
        // The driving torque and the resistance (a start from rest) act from the contact
        // step after the one whose end reached their onset, held over it and every later
        // one: the reduced passage's loads at a step's end are held over the next step.
        if !self.drive && xc - p.dx >= self.x_torque {
            self.drive = true;
            if let Some(r) = self.rot.as_mut() {
                r.set_drive(true);
            }
        }
        let pw = self.m.weights(xc)?;
        let pred = self.predict(t, &pw);
        let sol = self.solve_contact(t, xc, &pw, &pred)?;
        let f = self.f;
        let f_new = [sol.r.fx_n, sol.r.fy_n, sol.r.normal_force_n];
        let df = [f_new[0] - f[0], f_new[1] - f[1], f_new[2] - f[2]];
        self.correct(&pw, df);
        self.s.check_finite(t, xc)?;
        if let Some(a) = self.audit.as_mut() {
            let forces = StepForces {
                first: pred.split,
                previous: &self.pw_prev,
                held: f,
                change: df,
                hold: self.corrected.then_some(self.hold),
                wheel_loads: self.m.wheel_loads(self.drive),
            };
            a.replay(
                self.m,
                if self.corrected { &pw } else { &self.pw_prev },
                &forces,
                [(p.nt, p.dtt), (p.nw, p.dtw)],
                &self.s,
            );
        }
        let [z0, z1] = self.m.zone_m;
        if xc - p.half_grid < z1 && xc + p.half_grid > z0 {
            self.wear.add_step(&self.contact, xc);
        }
        // With the corrector the structures carry the mean of F_n and F_{n+1} (exactly, with
        // the mean hold; as the ramp's mean, with the first-order hold); without it F_n.
        let f_work = if self.corrected {
            [0, 1, 2].map(|d| 0.5 * (f[d] + f_new[d]))
        } else {
            f
        };
        self.ledger.after_step(
            &self.s,
            LedgerStep {
                xc,
                dt_c: p.dt_c,
                v: p.v,
                spin: p.spin,
                f_work,
                old: pred.old,
                held_at_previous: pred
                    .old_at_previous
                    .map(|o| [o, self.m.rail_under(&self.s.ut, &self.pw_prev)]),
                forces: [f, f_new],
                dg: sol.dg,
                dg_wheel: sol.dg_wheel,
                damper_j: pred.damper_j,
                t: [t - p.dt_c, t],
                uw_end: match &self.rot {
                    Some(r) => r.wheel_at(&self.s.uw, t, t),
                    None => self.m.wheel_at(&self.s.uw),
                },
                uw_turned: pred.uw_turned,
                conv: sol.conv,
                frame_j: pred.frame_j,
            },
            &sol.r,
            self.rot.as_ref(),
        )?;
        self.f_prev = f;
        self.f = f_new;
        self.pw_prev = pw;
        self.last_delta = sol.r.approach_m;
        self.record(t, xc, &sol);
        Ok(())
    }

    /// The predictor: the last force `F_n` held over the step at `x_{n+1}` (patch `pw`), the
    /// first sub-step also carrying the previous step's share where the previous step's
    /// force acted (on the rail and on the rotating wheel); without a corrector
    /// ([`super::Coupling::HeldForce`]) `F_n` held at `x_n` in every sub-step. The track and
    /// the wheel advanced over their sub-steps.
    fn predict(&mut self, t: f64, pw: &PlaneWeights) -> Predicted {
        let (m, p, f) = (self.m, self.plan, self.f);
        let frame = m.frame;
        let ur_old = m.rail_under(&self.s.ut, pw);
        let (uw_old, uw_turned) = match &self.rot {
            Some(r) => (
                r.wheel_at(&self.s.uw, t - p.dt_c, t),
                r.wheel_at(&self.s.uw, t, t),
            ),
            None => {
                let w = m.wheel_at(&self.s.uw);
                (w, w)
            }
        };
        let f0 = m.opts.coupling.first_load(f, self.f_prev);
        let split = m.opts.coupling.boundary_split(f, self.f_prev);
        // Without a corrector the force is held where it was computed, at x_n (as the
        // reduced passage holds it); with one, at x_{n+1}.
        let held_at = if self.corrected { pw } else { &self.pw_prev };
        let old_at_previous = (!self.corrected).then(|| m.rail_under(&self.s.ut, held_at));
        let loads = &mut self.loads;
        loads.track0.iter_mut().for_each(|x| *x = 0.0);
        for (g, w) in [(split[0], &self.pw_prev), (split[1], held_at)] {
            let neg = [-g[0], -g[1], -g[2]];
            add_line_force(
                &m.line,
                &m.track_structure,
                &frame,
                w,
                neg,
                &mut loads.track0,
            );
        }
        loads.track.iter_mut().for_each(|x| *x = 0.0);
        let neg = [-f[0], -f[1], -f[2]];
        add_line_force(
            &m.line,
            &m.track_structure,
            &frame,
            held_at,
            neg,
            &mut loads.track,
        );
        self.ledger.before_step(&self.s.uw, self.drive);
        if let Some(a) = self.audit.as_mut() {
            a.save(&self.s);
        }
        let State { ut, vt, uw, vw } = &mut self.s;
        let mut damper_j = advance_held(
            &m.track.op,
            (p.dtt, p.nt),
            [&loads.track0, &loads.track],
            ut,
            vt,
            &mut self.sc_t,
        );
        let mut frame_j = 0.0;
        let (uw_new, g_wheel) = match self.rot.as_mut() {
            Some(r) => {
                let [d, fr] = r.advance(&m.wheel.op, uw, vw, (split, f), t);
                damper_j += d;
                frame_j = fr;
                let g = if self.corrected {
                    r.compliance(&m.wheel.op)
                } else {
                    self.g_wheel
                };
                (r.wheel_at(uw, t, t), g)
            }
            None => {
                for (buf, g) in [(&mut loads.wheel0, f0), (&mut loads.wheel, f)] {
                    buf.copy_from_slice(m.wheel_loads(self.drive));
                    add_nodes_load(
                        &m.wheel_nodes,
                        &m.wheel_structure.dofmap,
                        &frame,
                        1.0,
                        g,
                        buf,
                    );
                }
                damper_j += advance_held(
                    &m.wheel.op,
                    (p.dtw, p.nw),
                    [&loads.wheel0, &loads.wheel],
                    uw,
                    vw,
                    &mut self.sc_w,
                );
                (m.wheel_at(uw), self.g_wheel)
            }
        };
        let ur_new = m.rail_under(&self.s.ut, pw);
        Predicted {
            old: [ur_old, uw_old],
            old_at_previous,
            new: [ur_new, uw_new],
            split,
            damper_j,
            uw_turned,
            frame_j,
            g_wheel,
        }
    }

    /// The contact at `x_{n+1}` (`xc`, m; time `t`, s) with the one-step compliance as the
    /// series compliance (less the mesh's element-scale local compliance variation where
    /// that is removed, clamped at 0), the approach and the creepages from the predicted
    /// kinematics.
    fn solve_contact(
        &mut self,
        t: f64,
        xc: f64,
        pw: &PlaneWeights,
        pred: &Predicted,
    ) -> Result<Solved, ExplicitError> {
        let (m, p, f) = (self.m, self.plan, self.f);
        if self.corrected {
            self.series =
                m.one_step_compliance(&mut self.rail_resp, &mut self.sc_t, pw, pred.g_wheel);
        }
        let to_contact = |source| PassageError::Contact {
            t_s: t,
            x_m: xc,
            source,
        };
        let mut dg = m.local_variation(xc, pw);
        let dg_wheel = self.rot.as_ref().map_or([0.0; 3], |r| r.local_variation());
        if self.rot.is_some() {
            dg = [0, 1, 2].map(|d| dg[d] + dg_wheel[d]);
        }
        for d in 0..3 {
            self.series_c[d] = self.series[d] - dg[d];
            if self.series_c[d] < 0.0 {
                self.series_c[d] = 0.0;
                self.clamped += 1;
            }
        }
        self.contact
            .set_series_compliance(self.series_c)
            .map_err(to_contact)?;
        let [ur_old, uw_old] = pred.old;
        let [ur_new, uw_new] = pred.new;
        let delta = ur_new[2] - uw_new[2] + self.series[2] * f[2];
        // The rotating wheel's contact is relieved of the faceted tread's convective static
        // deflection, as the fixed wheel's contact (which does not move on the wheel) is.
        let conv = self.rot.as_ref().map_or([0.0; 3], |r| r.convective(f));
        let xi = ((uw_new[0] - uw_old[0] - conv[0]) - (ur_new[0] - ur_old[0])) / (p.v * p.dt_c);
        let eta = ((uw_new[1] - uw_old[1] - conv[1]) - (ur_new[1] - ur_old[1])) / (p.v * p.dt_c);
        let r = self
            .contact
            .step(&StepInputs {
                normal: NormalInput::Approach(delta),
                longitudinal: Longitudinal::Creepage(xi),
                lateral_creepage: eta,
                spin_per_m: p.spin,
                rail_height_m: self.heights.at(xc),
            })
            .map_err(to_contact)?;
        Ok(Solved {
            r,
            xi,
            delta,
            dg,
            dg_wheel,
            conv,
        })
    }

    /// The corrector: both structures get the response to the force change `df` (N) applied
    /// as the coupling's hold (nothing without a corrector).
    fn correct(&mut self, pw: &PlaneWeights, df: [f64; 3]) {
        if !self.corrected {
            return;
        }
        for (j, wj) in pw.iter() {
            self.rail_resp
                .response(j)
                .add_to(wj, df, &mut self.s.ut, &mut self.s.vt);
        }
        match &self.rot {
            Some(r) => r.correct(df, &mut self.s.uw, &mut self.s.vw),
            None => self
                .wheel_resp
                .add_to(1.0, df, &mut self.s.uw, &mut self.s.vw),
        }
    }

    /// The recorder: the step's histories (the force already the new one) and the rail
    /// point's displacement.
    fn record(&mut self, t: f64, xc: f64, sol: &Solved) {
        let approach = sol.delta - self.series[2] * self.f[2];
        self.h.push_step(
            &self.contact,
            &sol.r,
            [t, xc, sol.xi, approach],
            self.plan.dx,
        );
        if let Some((node, rec)) = self.rail_point.as_mut() {
            let dm_t = &self.m.track_structure.dofmap;
            let ut = &self.s.ut;
            rec.displacement_m
                .push([0, 1, 2].map(|c| dm_t.free_index(3 * *node + c).map_or(0.0, |i| ut[i])));
        }
    }

    /// The passage's record and report after the last step; the dynamic phase started at
    /// `t_wall` with the process's CPU seconds `cpu0`.
    pub(super) fn finish(self, t_wall: Instant, cpu0: Option<f64>) -> ExplicitRecord {
        let (m, p) = (self.m, self.plan);
        let (by_direction, rail_wheel) = (self.ledger.by_direction, self.ledger.rail_wheel);
        let eb = self.ledger.finish(
            &self.s,
            (self.f[2], self.last_delta, self.series_c[2]),
            self.rot.as_ref(),
            p.n_steps as f64 * p.dt_c,
        );
        let audit = self.audit.map(|a| {
            let mut r = a.finish(m, &self.s, [p.dtt, p.dtw]);
            [
                r.ledger_contact_work_j,
                r.ledger_convective_work_j,
                r.ledger_spring_j,
            ] = by_direction;
            [r.ledger_rail_work_j, r.ledger_wheel_work_j] = rail_wheel;
            r
        });
        let mut w = vec![0.0; p.nbins];
        self.wear.work_x(&mut w);
        let seconds = t_wall.elapsed().as_secs_f64();
        let info = ExplicitInfo {
            dt_s: p.dtt,
            dt_wheel_s: p.dtw,
            contact_dt_s: p.dt_c,
            track_substeps: p.nt,
            wheel_substeps: p.nw,
            omega_max_estimate: m.track.step.omega_max_estimate,
            omega_max_wheel_estimate: m.wheel.step.omega_max_estimate,
            omega_max_bound: m.track.step.omega_max_bound,
            steps: p.n_steps * p.nt,
            contact_steps: p.n_steps,
            energy_error: if self.keep {
                eb.relative_error()
            } else {
                f64::NAN
            },
            seconds,
            cpu_seconds: match (cpu0, crate::progress::cpu_seconds()) {
                (Some(a), Some(b)) => Some(b - a),
                _ => None,
            },
            dofs: m.dofs(),
            setup_seconds: m.setup_seconds,
            clamped_steps: self.clamped,
            wheel: m.opts.wheel.as_str(),
            spin_rate_rad_s: self.rot.as_ref().map_or(0.0, |r| r.omega()),
            wheel_local_seconds: m.wheel_local_seconds,
            audit,
        };
        ExplicitRecord {
            record: PassageRecord {
                speed_m_per_s: p.v,
                dt_s: p.dt_c,
                substeps: [p.nt, p.nw],
                x_start_m: p.x0,
                zone_m: m.zone_m,
                histories: self.h,
                wear_x_m: self.wear.x_m(),
                wear_j_per_m: w,
                rail_point: self.rail_point.map(|(_, r)| r),
                energy: eb,
                static_creepage: self.static_creepage,
                static_approach_m: self.static_approach_m,
                steps: p.n_steps,
                seconds,
                split_steps: 0,
                contact_grid_widened: None,
            },
            info,
        }
    }
}

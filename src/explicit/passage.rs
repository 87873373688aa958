//! The explicit passage (E1: the wheel as the reduced model has it, not rotating, its
//! contact point fixed on the wheel); docs/theory.md §8.4.
//!
//! # One contact step `t_n → t_{n+1}` (`Δt_c = Δx/V`, the transient contact's step)
//! 1. **Predictor.** The last contact force `F_n` (contact frame x, t, n; on the wheel, its
//!    opposite on the rail) is held over the step at the end-of-step contact position
//!    `x_{n+1}`; the track runs `N_t` central-difference steps of `Δt_c/N_t`, the wheel `N_w`
//!    of `Δt_c/N_w`, each below its own stable step.
//! 2. **Contact.** The contact is solved at `x_{n+1}` with the predicted kinematics and the
//!    structures' one-contact-step compliance `G = G_rail + G_wheel` as its series
//!    compliance (`G`: the contact-point displacement at the end of a contact step under a
//!    unit force ramped from 0 to 1 over the step, from rest): approach `δ_pred + G_n F_{n,N}`,
//!    creepages from the predicted relative displacement increments over the step. The
//!    solver then returns the force `F_{n+1}` that is consistent with the end-of-step
//!    kinematics.
//! 3. **Corrector.** Both structures get the response to the change `F_{n+1} − F_n`
//!    applied as the coupling's hold (`response.rs`; unit-load response fields: the wheel's once per
//!    passage, the rail's per node plane of the contact line, interpolated like the load).
//!    Since the FE is linear, the state is then exactly the one under the hold's force
//!    history. With the default mean hold that is `(F_n + F_{n+1})/2` held over the step:
//!    its work is exactly that force times the contact-point displacement increment, so the
//!    energy balances, and the coupling stays stable however stiff the contact is against
//!    the mass under it (on a contact mass it is the trapezoidal rule).
//!
//! The first-order hold ([`Coupling::RampCorrector`](super::coupling::Coupling::RampCorrector), the force interpolated linearly from
//! `F_n` to `F_{n+1}`) is Newmark's linear-acceleration method on a contact mass: unstable
//! once the contact–mass frequency times `Δt_c` exceeds 2√3, within reach of the grams of a
//! fine mesh under the patch at the default contact step. The plain alternative, holding `F_n`
//! without the corrector ([`Coupling::HeldForce`](super::coupling::Coupling::HeldForce)), is explicit in the contact stiffness:
//! with `k_contact · G` of order one it is at the edge of stability. Both are kept to show
//! that in tests. The held force acts where it was computed, at `x_n`, as in the reduced
//! passage, which the all-modes comparison uses it for (docs/theory.md §8.6).
//!
//! # Start
//! As the reduced passage: the contact brought to steady rolling at the static load; the
//! track and the wheel's elastic deformation by static solves of the full `K` under the
//! static contact force and the wheel loads (no dynamic relaxation); the wheel's rigid
//! modes placed so that the approach is the steady one and turned so that the creepage is.
//! With `run.start = "rest"` the same in free rolling: no longitudinal force and no driving
//! torque or resistance in the static solves; both step on at the contact step whose end
//! reaches `run.rest_start_distance` before the zone
//! ([`crate::passage::setup::torque_onset_m`]), as in the reduced
//! passage (docs/theory.md §7.5).

mod stepper;

use std::time::Instant;

use stepper::{RailHeights, Stepper};

use super::audit::EnergyAudit;
use super::estimate::{ExplicitEstimate, MAX_EXPLICIT_SECONDS};
use super::ledger::State;
use super::model::ExplicitModel;
use super::operator::StepScratch;
use super::response::{RailResponses, UnitResponse};
use super::rotating::{RotatingWheel, WheelParts};
use super::start::static_contact_force;
use super::ExplicitError;
use crate::model::ExplicitWheel;
use crate::passage::contact_line::add_nodes_load;
use crate::passage::planes::PlaneWeights;
use crate::passage::{
    record::{PassageRecord, RailPointRecord, WidenedGrid},
    setup::{
        check_profile_on_travel, contact_config_for, passage_contact, passage_grid,
        rail_under_contact_m, rigid_least_norm, run_widening_grid, GridWidening, ProfileOnRail,
    },
    PassageOptions,
};
use crate::passage::{PassageError, PassageSummary, RailProfile};
use crate::progress::{Cancelled, Progress};

/// What the explicit path reports besides the passage record.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ExplicitInfo {
    /// Track time step (s).
    pub dt_s: f64,
    /// Wheel time step (s).
    pub dt_wheel_s: f64,
    /// Contact step `Δx/V` (s).
    pub contact_dt_s: f64,
    /// Track sub-steps per contact step (−).
    pub track_substeps: usize,
    /// Wheel sub-steps per contact step (−).
    pub wheel_substeps: usize,
    /// Estimated ω_max of the track (rad/s).
    pub omega_max_estimate: f64,
    /// Estimated ω_max of the wheel (rad/s).
    pub omega_max_wheel_estimate: f64,
    /// Gershgorin bound on the track's ω_max (rad/s).
    pub omega_max_bound: f64,
    /// Track FE steps of the passage (−).
    pub steps: usize,
    /// Contact steps of the passage (−).
    pub contact_steps: usize,
    /// Relative energy error of the passage (−; see `EnergyBalance::relative_error`); not
    /// a number when the ledger is not kept (no energy option, or the rotating wheel).
    pub energy_error: f64,
    /// Wall time of the dynamic phase (s).
    pub seconds: f64,
    /// CPU time (user + system) of the dynamic phase (s), where the OS reports it.
    pub cpu_seconds: Option<f64>,
    /// Track and wheel DOFs.
    pub dofs: [usize; 2],
    /// Wall time of the set-up: assembly, static solves, stable steps (s).
    pub setup_seconds: f64,
    /// Contact steps at which the series compliance `G − Δg` was negative and clamped to 0
    /// (−; docs/theory.md §8.6).
    pub clamped_steps: usize,
    /// The wheel treatment: `"fixed"` or `"rotating"` (`explicit.wheel`).
    pub wheel: &'static str,
    /// The rotating wheel's spin rate (rad/s; 0 for the fixed wheel).
    pub spin_rate_rad_s: f64,
    /// Wall time of computing the rotating wheel's tread compliance over the angles of the
    /// travel, part of `setup_seconds` (s; 0 when it is not computed).
    pub wheel_local_seconds: f64,
    /// The energy audit (when [`super::ExplicitOptions::audit`] asks for it and the ledger
    /// is kept).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub audit: Option<EnergyAudit>,
}

/// A passage of the explicit path.
#[derive(Clone, Debug)]
pub struct ExplicitRecord {
    /// The passage, in the same form as the reduced one.
    pub record: PassageRecord,
    /// Step sizes, counts, timing.
    pub info: ExplicitInfo,
}

impl ExplicitModel {
    /// Runs one passage at `speed_m_per_s` (m/s) over the rail profile (`None` = smooth);
    /// `progress` learns the number of contact steps ([`Progress::total`]) and the steps done
    /// every few contact steps ([`Progress::done`]; the caller names the stage), and stops the
    /// passage with [`ExplicitError::Cancelled`] when it is [cancelled](Progress::cancelled).
    ///
    /// Phases: the plan (steps and range), the static start, the set-up of the step loop
    /// (unit responses, scratch, energy ledger, recorder), the contact steps (predictor,
    /// contact, corrector, ledger, records) and the record.
    ///
    /// When the contact patch reaches the boundary of the contact grid the passage is run
    /// again from the start on a widened grid, as the reduced passage does
    /// ([`run_widening_grid`]; the record's `contact_grid_widened` then names the grid).
    pub fn passage(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
        popts: &PassageOptions,
        progress: Option<&dyn Progress>,
    ) -> Result<ExplicitRecord, ExplicitError> {
        self.check_profile(speed_m_per_s, profile)?;
        let (mut rec, w) = run_widening_grid(
            self.model.vehicle.wheel_load,
            |w| self.passage_on_grid(speed_m_per_s, profile, popts, progress, w),
            |e: &ExplicitError| match e {
                ExplicitError::Passage(d) => Some(d),
                _ => None,
            },
            ExplicitError::Passage,
            |_, _| {},
        )?;
        if w.any() {
            let cfg = contact_config_for(&self.model, speed_m_per_s)?;
            let grid = passage_grid(
                &cfg,
                ProfileOnRail::of(profile, self.hertz_approach_m, || {
                    self.rail_under_contact_m(speed_m_per_s)
                })?,
                w,
            )?;
            rec.record.contact_grid_widened = Some(WidenedGrid::new(&grid, w));
        }
        Ok(rec)
    }

    /// The estimated time and memory of a passage at `speed_m_per_s` (m/s) over `profile`
    /// on the model's contact grid ([`ExplicitEstimate`]), before it runs.
    pub fn passage_estimate(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
    ) -> Result<ExplicitEstimate, ExplicitError> {
        let contact = passage_contact(
            &self.model,
            speed_m_per_s,
            ProfileOnRail::of(profile, self.hertz_approach_m, || {
                self.rail_under_contact_m(speed_m_per_s)
            })?,
            GridWidening::default(),
        )?;
        let e = self.estimate(&self.plan(speed_m_per_s, &contact));
        self.check_estimate(speed_m_per_s, &e)?;
        Ok(e)
    }

    /// Refuses a passage whose estimate `e` is beyond [`MAX_EXPLICIT_SECONDS`], naming the
    /// key that drives its sub-steps: `explicit.time_step` when one is given, else the speed.
    fn check_estimate(
        &self,
        speed_m_per_s: f64,
        e: &ExplicitEstimate,
    ) -> Result<(), ExplicitError> {
        if e.within_bound() {
            return Ok(());
        }
        let (key, value, advice) = match self.opts.time_step_s {
            Some(dt) => (
                "explicit.time_step",
                format!("{dt:e} s"),
                "leave explicit.time_step out (the stable step is then computed) or raise it",
            ),
            None => (
                "run.speed_kmh",
                format!("{:.4} km/h", crate::units::ms_to_kmh(speed_m_per_s)),
                "raise run.speed_kmh (the sub-steps per contact step grow as 1/V) or coarsen the mesh (mesh.element_length, track.bays)",
            ),
        };
        Err(ExplicitError::TooLong {
            key,
            value,
            estimate: e.to_string(),
            limit_h: MAX_EXPLICIT_SECONDS / 3600.0,
            advice,
        })
    }

    /// The rail the contact grid passes over in a passage at `v` (m/s), as the reduced
    /// passage's ([`rail_under_contact_m`] of the model's grid).
    pub fn rail_under_contact_m(&self, v: f64) -> Result<[f64; 2], ExplicitError> {
        let cfg = contact_config_for(&self.model, v)?;
        Ok(rail_under_contact_m(
            self.x_start_m,
            self.zone_m[1],
            &cfg.grid,
        ))
    }

    /// Checks `profile` against the rail a passage at `v` (m/s) passes over
    /// ([`check_profile_on_travel`]): an error when it lies entirely off it, the warning to
    /// give when it only partly overlaps it.
    pub fn check_profile(
        &self,
        v: f64,
        profile: Option<&RailProfile>,
    ) -> Result<Option<String>, ExplicitError> {
        match profile {
            Some(p) => Ok(check_profile_on_travel(p, self.rail_under_contact_m(v)?)?),
            None => Ok(None),
        }
    }

    /// One passage (as [`Self::passage`]) on the contact grid widened by `widening`.
    fn passage_on_grid(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
        popts: &PassageOptions,
        progress: Option<&dyn Progress>,
        widening: GridWidening,
    ) -> Result<ExplicitRecord, ExplicitError> {
        let mut contact = passage_contact(
            &self.model,
            speed_m_per_s,
            ProfileOnRail::of(profile, self.hertz_approach_m, || {
                self.rail_under_contact_m(speed_m_per_s)
            })?,
            widening,
        )?;
        let plan = self.plan(speed_m_per_s, &contact);
        self.check_estimate(speed_m_per_s, &self.estimate(&plan))?;
        let mut heights = RailHeights::new(profile, &contact);
        let start = self.static_start(&plan, &mut contact, &mut heights)?;
        let mut run = Stepper::new(self, plan, contact, heights, start, popts)?;
        let t_wall = Instant::now();
        let cpu0 = crate::progress::cpu_seconds();
        if let Some(p) = progress {
            p.total(plan.n_steps as u64);
            p.done(0);
        }
        // every 16 contact steps, and at least once a second when a step is slow (a small
        // explicit.time_step), so that the progress shows its rate and ETA from the start
        let mut reported = Instant::now();
        for n in 1..=plan.n_steps {
            run.step(n)?;
            if n % 16 == 0 || n == plan.n_steps || reported.elapsed().as_secs_f64() >= 1.0 {
                if let Some(p) = progress {
                    p.done(n as u64);
                    if p.cancelled() {
                        return Err(Cancelled.into());
                    }
                }
                reported = Instant::now();
            }
        }
        Ok(run.finish(t_wall, cpu0))
    }

    /// The rotating wheel of a passage at `v` (m/s) with `steps` wheel sub-steps of `dt` (s)
    /// per contact step (spin rate `V/R` unless the options set one); `None` for the fixed
    /// wheel.
    fn rotating_wheel(
        &self,
        v: f64,
        steps: usize,
        dt: f64,
    ) -> Result<Option<RotatingWheel>, ExplicitError> {
        if self.opts.wheel == ExplicitWheel::Fixed {
            return Ok(None);
        }
        let parts = WheelParts {
            structure: &self.wheel_structure,
            op: &self.wheel.op,
            contact_nodes: &self.wheel_nodes,
            frame: self.frame,
            loads: &self.loads,
            wheel_const: &self.wheel_const,
            local: self.wheel_local.as_ref(),
        };
        let omega = self.opts.spin_rate_rad_s.unwrap_or(v / self.wheel_radius_m);
        RotatingWheel::new(&parts, omega, (steps, dt, self.opts.coupling.hold())).map(Some)
    }

    /// The start: the static deflections, the wheel's rigid modes placed so that the
    /// approach is the steady one `delta0` (m) with the axle and the contact point at x = 0,
    /// and turning so that the creepage is `xi0` (−) at `v` (m/s).
    fn start_state(&self, v: f64, xi0: f64, delta0: f64) -> Result<State, ExplicitError> {
        let mut st = State {
            ut: self.track_static.clone(),
            vt: vec![0.0; self.track.op.n()],
            uw: self.wheel_static.clone(),
            vw: vec![0.0; self.wheel.op.n()],
        };
        let w0 = self.weights(self.x_start_m)?;
        let mut u_rail = self.rail_under(&st.ut, &w0);
        // The contact sees the rail without the mesh's local compliance variation.
        u_rail[2] += self.local_variation(self.x_start_m, &w0)[2]
            * static_contact_force(&self.model, &self.frame)[2];
        let u_wheel_el = self.wheel_at(&st.uw);
        let target_n = u_rail[2] - delta0 - u_wheel_el[2];
        let c = rigid_least_norm(&self.rigid_obs, [0.0, target_n, 0.0]);
        let cv = rigid_least_norm(&self.rigid_obs, [xi0 * v, 0.0, 0.0]);
        for (k, r) in self.rigid.iter().enumerate() {
            st.uw.iter_mut().zip(r).for_each(|(x, y)| *x += c[k] * y);
            st.vw.iter_mut().zip(r).for_each(|(x, y)| *x += cv[k] * y);
        }
        Ok(st)
    }

    /// The wheel's unit responses over one contact step (`steps` of `dt`, s) and its
    /// one-step compliance at the contact point per contact-frame direction (m/N).
    fn wheel_response(
        &self,
        dt: f64,
        steps: usize,
        scratch: &mut StepScratch,
    ) -> (UnitResponse, [f64; 3]) {
        let r = UnitResponse::compute(
            &self.wheel.op,
            dt,
            steps,
            self.opts.coupling.hold(),
            |d, f| {
                let mut force = [0.0; 3];
                force[d] = 1.0;
                add_nodes_load(
                    &self.wheel_nodes,
                    &self.wheel_structure.dofmap,
                    &self.frame,
                    1.0,
                    force,
                    f,
                )
            },
            scratch,
        );
        let g = [0, 1, 2].map(|d| self.wheel_at(&r.u[d])[d]);
        (r, g)
    }

    /// The rail's one-step compliance under the patch of plane weights `w` plus the wheel's
    /// `g_wheel` (m/N per direction); the planes' unit responses are made ready in `rail`.
    fn one_step_compliance(
        &self,
        rail: &mut RailResponses,
        scratch: &mut StepScratch,
        w: &PlaneWeights,
        g_wheel: [f64; 3],
    ) -> [f64; 3] {
        for (q, _) in w.iter() {
            let load = |d: usize, f: &mut [f64]| {
                let mut force = [0.0; 3];
                force[d] = -1.0;
                add_nodes_load(
                    &self.line.nodes[q],
                    &self.track_structure.dofmap,
                    &self.frame,
                    1.0,
                    force,
                    f,
                )
            };
            rail.ensure(&self.track.op, q, w.first, load, scratch);
        }
        [0, 1, 2].map(|d| {
            // Rail displacement under the patch along axis d under the spread unit load −e_d:
            // the quadratic form Σ_jk w_j w_k g_jk.
            let gr: f64 = -w
                .iter()
                .map(|(k, wk)| wk * self.rail_under(&rail.response(k).u[d], w)[d])
                .sum::<f64>();
            (gr + g_wheel[d]).max(0.0)
        })
    }

    /// The rail-top node recorded by a passage (`popts.rail_point_offset_m` into the
    /// solution zone), with room for `n_steps` records.
    fn rail_point(
        &self,
        popts: &PassageOptions,
        n_steps: usize,
    ) -> Option<(usize, RailPointRecord)> {
        let x = self.zone_m[0] + popts.rail_point_offset_m?;
        let px = &self.line.planes_x_m;
        let p = (0..px.len()).min_by(|&a, &b| (px[a] - x).abs().total_cmp(&(px[b] - x).abs()))?;
        let (node, _) = self.line.nodes[p]
            .iter()
            .copied()
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        Some((
            node,
            RailPointRecord {
                position_m: self.track_structure.mesh.nodes[node],
                displacement_m: Vec::with_capacity(n_steps),
            },
        ))
    }
}

impl crate::passage::PassageRecorder for ExplicitModel {
    fn record(
        &self,
        speed: crate::units::Speed,
        profile: Option<&RailProfile>,
    ) -> Result<PassageRecord, PassageError> {
        let speed_m_per_s = speed.m_per_s();
        let opts = PassageOptions {
            energy: false,
            rail_point_offset_m: None,
            overlap: false,
        };
        self.passage(speed_m_per_s, profile, &opts, None)
            .map(|r| r.record)
            .map_err(|e| match e {
                ExplicitError::Passage(d) => d,
                other => PassageError::Engine {
                    engine: "explicit",
                    source: Box::new(other),
                },
            })
    }

    fn hertz_b_m(&self) -> f64 {
        self.hertz_b_m
    }
}

/// Runs explicit passages of one model behind the [`crate::passage::PassageRunner`]
/// interface, so that sweeps, growth and studies take `--engine explicit`.
pub struct ExplicitRunner {
    /// The explicit model.
    pub model: ExplicitModel,
}

impl crate::passage::PassageRunner for ExplicitRunner {
    fn run(
        &self,
        speed: crate::units::Speed,
        profile: Option<&RailProfile>,
    ) -> Result<PassageSummary, PassageError> {
        use crate::passage::PassageRecorder;
        let rec = self.model.record(speed, profile)?;
        crate::passage::analysis::summarise_at(&rec, speed)
    }
}

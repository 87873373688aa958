//! One passage's time loop ([`PassageEngine::passage`]): the static start placed in the modal
//! states, then per contact step the rail rows at the contact, the contact step (with the
//! track's damping product beside it when [`PassageOptions::overlap`] is on), the modal
//! forces, the energy ledger and the records (docs/theory.md §7.3). The engine and its
//! set-up are in the parent module.

use super::super::record::RailPointRecord;
use super::spin::SpinPair;
use super::{
    check_finite, step, CreepageKind, DampingOverlap, DynamicsError, GridWidening, Histories,
    Instant, Ledger, LedgerStep, ModalVerlet, PassageEngine, PassageOptions, PassageRecord,
    RailProfile, RoadAhead, StartKind, TransientRolling, WearAccumulator,
};

impl PassageEngine {
    /// Runs one passage at `speed_m_per_s` (m/s) over the rail profile (`None` = smooth) on
    /// the contact grid widened by `widening` ([`PassageEngine::passage`] chooses it).
    pub(super) fn passage_on_grid(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
        opts: &PassageOptions,
        progress: Option<&dyn crate::progress::Progress>,
        widening: GridWidening,
    ) -> Result<PassageRecord, DynamicsError> {
        let (mut s, k) = self.passage_start(speed_m_per_s, profile, opts, widening)?;
        let t_wall = Instant::now();
        if let Some(p) = progress {
            p.total(k.n_steps as u64);
            p.done(0);
        }
        // with the overlap and a second thread allowed, a worker thread takes the damping
        // product beside each contact step while it has a core (module `spin`: bounded
        // spinning, then parking; a job not started in time is taken back; one thread while
        // the machine is oversubscribed)
        let two_cores = s.overlap.is_some() && rayon::current_num_threads() >= 2;
        let mut run = |pair: Option<&SpinPair>| -> Result<(), DynamicsError> {
            for n in 1..=k.n_steps {
                self.passage_step(&mut s, &k, n, pair)?;
                if let Some(p) = progress.filter(|_| n % 64 == 0) {
                    p.done(n as u64);
                    if p.cancelled() {
                        return Err(crate::progress::Cancelled.into());
                    }
                }
            }
            Ok(())
        };
        let split_steps = if two_cores {
            std::thread::scope(|sc| {
                let pair = SpinPair::start(sc);
                run(pair.as_ref()).map(|()| pair.map_or(0, |p| p.counts().split as usize))
            })?
        } else {
            run(None)?;
            0
        };
        let mut rec = self.passage_record(s, &k, t_wall.elapsed().as_secs_f64());
        rec.split_steps = split_steps;
        Ok(rec)
    }

    /// The start of a passage at `speed_m_per_s` (m/s) over `profile` on the contact grid
    /// widened by `widening`: the contact at the static start (steady rolling at the static
    /// load) placed in the modal states of track and wheel, the step loop's state
    /// (integrators, buffers, records, the energy ledger, the damping product's scratch when
    /// [`PassageOptions::overlap`] is on) and constants.
    fn passage_start<'a>(
        &self,
        speed_m_per_s: f64,
        profile: Option<&'a RailProfile>,
        opts: &PassageOptions,
        widening: GridWidening,
    ) -> Result<(StepState<'a>, StepConstants), DynamicsError> {
        let v = speed_m_per_s;
        let (contact, st) = self.started_contact(v, profile, widening)?;
        let dt = contact.time_step_s();
        let dx = v * dt;
        let mut tr = ModalVerlet::new(&self.track_sys, dt)?;
        let mut wh = ModalVerlet::new(&self.wheel_sys, dt)?;
        let (mt, mw) = (tr.len(), wh.len());
        let substepped = tr.substeps() > 1 || wh.substeps() > 1;
        let (f_n0, f_l0, spin) = self.static_loads();
        let x_torque = self.torque_onset_m()?;
        let x0 = self.x_start_m;
        let [z0, z1] = self.zone_m;
        let half_grid = contact.config().grid.half_length_x_m;
        let n_steps = self.step_count(half_grid, dx);
        let road = RoadAhead::new(&contact, profile);
        let increment = self.model.run.creepage == CreepageKind::Increment;

        // --- Static start (steady rolling at the static load): `st`, above.
        let (xi0, delta0) = (st.creepage, st.approach_m);

        let mut rr = vec![0.0; 3 * mt];
        let slopes = vec![0.0; 3 * mt];
        self.rail_line.rows_at(x0, &mut rr)?;
        // Force on the wheel in frame components (x, t, n).
        let f0 = [f_l0, 0.0, f_n0];
        let mut ft = vec![0.0; mt];
        let mut fw = vec![0.0; mw];
        // The torque and the resistance act with weight `drive`: always for the static start;
        // from rest, not in the initial state and from the first step at their onset on.
        let drive = match self.model.run.start {
            StartKind::Static => 1.0,
            StartKind::Rest => 0.0,
        };
        let mut fw_const = vec![0.0; mw];
        self.wheel_constant_loads(drive, &mut fw_const);
        self.generalised_forces(&f0, &fw_const, &rr, (&mut ft, &mut fw));
        self.place_at_static_start(v, (xi0, delta0), &rr, (&ft, &fw), (&mut tr, &mut wh));

        // --- Records.
        let h = Histories::with_capacity(n_steps);
        let rail_point = self.rail_point_record(n_steps);
        let nbins = ((z1 - z0) / dx).round().max(1.0) as usize;
        let wear = WearAccumulator::new(&contact, z0, nbins);
        let ledger = Ledger::start(
            self,
            (&tr, &wh),
            &st,
            (opts.energy, contact.uniform_compliance()),
            f0[0],
        );
        // the damping product's planes up to the last step's interval, with two steps to
        // spare against rounding
        let overlap = (opts.overlap && tr.splits())
            .then(|| self.damping_overlap(mt, x0, x0 + v * dt * (n_steps + 2) as f64));
        let k = StepConstants {
            dt,
            dx,
            v,
            spin,
            x0,
            half_grid,
            x_torque,
            increment,
            substepped,
            energy: opts.energy,
            n_steps,
            nbins,
            static_start: [xi0, delta0],
        };
        let s = StepState {
            contact,
            road,
            tr,
            wh,
            rr,
            slopes,
            ft,
            fw,
            fw_const,
            drive,
            f_last: f0,
            last_delta: st.approach_m,
            overlap,
            wear,
            ledger,
            h,
            rail_point,
        };
        Ok((s, k))
    }

    /// Scratch of the track's damping product beside the contact step for a passage of a
    /// track with `mt` modes whose contact runs from `x_first` to `x_last` (m).
    fn damping_overlap(&self, mt: usize, x_first: f64, x_last: f64) -> DampingOverlap {
        let line = &self.rail_line;
        let last_plane = line.planes_x_m.len().saturating_sub(2);
        let p_first = line.locate(x_first).map_or(0, |(p, _)| p);
        let p_last = line.locate(x_last).map_or(last_plane, |(p, _)| p);
        DampingOverlap::new(mt, p_first, p_last)
    }

    /// The passage's record after its `k.n_steps` steps, the loop having taken `seconds`
    /// (s, wall): histories, wear, the energy balance (closed when the ledger is kept).
    fn passage_record(&self, s: StepState<'_>, k: &StepConstants, seconds: f64) -> PassageRecord {
        let StepState {
            tr,
            wh,
            f_last,
            last_delta,
            wear,
            ledger,
            h,
            rail_point,
            ..
        } = s;
        // the last step's force, or the static start's when no step ran
        let f_end = if k.n_steps > 0 {
            f_last
        } else {
            ledger.f_start
        };
        let eb = if k.energy {
            ledger.finish((&tr, &wh), f_end, last_delta)
        } else {
            ledger.eb
        };
        let mut w = vec![0.0; k.nbins];
        wear.work_x(&mut w);
        let [static_creepage, static_approach_m] = k.static_start;
        PassageRecord {
            speed_m_per_s: k.v,
            dt_s: k.dt,
            substeps: [tr.substeps(), wh.substeps()],
            x_start_m: k.x0,
            zone_m: self.zone_m,
            histories: h,
            wear_x_m: wear.x_m(),
            wear_j_per_m: w,
            rail_point,
            energy: eb,
            static_creepage,
            static_approach_m,
            steps: k.n_steps,
            seconds,
            split_steps: 0,
            contact_grid_widened: None,
        }
    }
}

/// The fixed quantities of one passage's step loop.
struct StepConstants {
    /// Contact step (s).
    dt: f64,
    /// Contact step's travel `v Δt` (m).
    dx: f64,
    /// Speed (m/s).
    v: f64,
    /// Spin creepage per metre (1/m).
    spin: f64,
    /// Contact position at the start (m).
    x0: f64,
    /// Half length of the contact grid along x (m).
    half_grid: f64,
    /// Contact position where the torque and the resistance come on (m).
    x_torque: f64,
    /// Creepages from the displacement increments (`run.creepage = "increment"`).
    increment: bool,
    /// Either modal system sub-steps.
    substepped: bool,
    /// The energy ledger is kept.
    energy: bool,
    /// Contact steps of the passage.
    n_steps: usize,
    /// Wear bins over the solution zone.
    nbins: usize,
    /// Creepage ξ₀ (−) and approach δ₀ (m) of the static start.
    static_start: [f64; 2],
}

/// What one passage's step loop carries from step to step: the contact, the modal states,
/// the force buffers, the last forces and the records (allocated once per passage).
struct StepState<'a> {
    contact: TransientRolling,
    road: RoadAhead<'a>,
    tr: ModalVerlet,
    wh: ModalVerlet,
    /// The rail's contact rows at the contact (3 × the track's mode count).
    rr: Vec<f64>,
    /// Scratch of the energy ledger (3 × the track's mode count).
    slopes: Vec<f64>,
    /// Generalised forces of track and wheel (N·√kg⁻¹ per mode).
    ft: Vec<f64>,
    fw: Vec<f64>,
    /// The wheel's constant loads (gravity, torque, resistance) in its modes.
    fw_const: Vec<f64>,
    /// Weight of the torque and the resistance (0 before their onset, 1 after).
    drive: f64,
    /// Contact force on the wheel of the last step (x, t, n; N; before the first step the
    /// static loads').
    f_last: [f64; 3],
    /// Approach of the last step (m).
    last_delta: f64,
    overlap: Option<DampingOverlap>,
    wear: WearAccumulator,
    ledger: Ledger,
    h: Histories,
    rail_point: Option<RailPointRecord>,
}

impl PassageEngine {
    /// Step `n` of a passage: the rail rows at the contact, the displacements advanced, the
    /// contact step (with the track's damping product beside it when the overlap is on), the
    /// wear, the loads' onset, the modal forces, the steps completed, the energy ledger and
    /// the records.
    fn passage_step(
        &self,
        s: &mut StepState<'_>,
        k: &StepConstants,
        n: usize,
        pair: Option<&SpinPair>,
    ) -> Result<(), DynamicsError> {
        let (dt, v, spin) = (k.dt, k.v, k.spin);
        let [z0, z1] = self.zone_m;
        let t = n as f64 * dt;
        let xc = k.x0 + v * t;
        self.rail_line.rows_at(xc, &mut s.rr)?;
        // With the increment creepage, the contact points' displacements at `t_n` read with
        // the rows of `x_{n+1}`: the same material points at both ends of the step.
        let start = k.increment.then(|| {
            [
                step::contact_displacement(&s.rr, &s.tr),
                step::contact_displacement(&self.wheel_contact.rows, &s.wh),
            ]
        });
        s.tr.advance_displacement();
        s.wh.advance_displacement();
        let mut at = (0, 0.0);
        let (contact, road, rr, tr, wh) = (&mut s.contact, &mut s.road, &s.rr, &s.tr, &s.wh);
        let mut solve = || self.contact_step(contact, road, (rr, tr, wh), start, [t, xc, v, spin]);
        let (r, [xi, delta]) = if let Some(ov) = s.overlap.as_mut() {
            at = self
                .rail_line
                .locate(xc)
                .ok_or_else(|| self.rail_line.off_rail("contact point", xc))?;
            let f_last = &s.f_last;
            let mut begin = || ov.begin(tr, &self.rail_line, at.0, f_last, rr);
            let (res, ()) = match pair {
                Some(p) => p.join(solve, begin),
                None => (solve(), begin()),
            };
            res?
        } else {
            solve()?
        };
        if xc - k.half_grid < z1 && xc + k.half_grid > z0 {
            s.wear.add_step(&s.contact, xc);
        }
        let f = [r.fx_n, r.fy_n, r.normal_force_n];
        // The driving torque and the resistance come on as a step at their onset.
        let drive_prev = s.drive;
        if s.drive == 0.0 && xc >= k.x_torque {
            s.drive = 1.0;
            self.wheel_constant_loads(s.drive, &mut s.fw_const);
        }
        self.generalised_forces(&f, &s.fw_const, &s.rr, (&mut s.ft, &mut s.fw));
        match s.overlap.as_mut() {
            Some(ov) => ov.finish(&mut s.tr, &f, &s.f_last, &s.rr, at),
            None => s.tr.complete(&s.ft),
        }
        s.f_last = f;
        s.wh.complete(&s.fw);
        check_finite((&s.tr, &s.wh), t, xc)?;
        if k.energy {
            s.ledger.add_step(
                self,
                (&s.tr, &s.wh),
                &LedgerStep {
                    dt,
                    v,
                    spin,
                    xc,
                    d_mean: 0.5 * (s.drive + drive_prev),
                    f,
                    frictional_power_w: r.frictional_power_w,
                    mz_nm: r.mz_nm,
                    substepped: k.substepped,
                },
                &s.rr,
                &mut s.slopes,
            )?;
        }
        s.last_delta = r.approach_m;
        s.h.push_step(&s.contact, &r, [t, xc, xi, delta], k.dx);
        self.record_rail_point(s.rail_point.as_mut(), &s.tr);
        Ok(())
    }
}

//! One passage's time loop ([`PassageEngine::passage`]): the static start placed in the modal
//! states, then per contact step the rail rows at the contact, the contact step (with the
//! track's damping product beside it when [`PassageOptions::overlap`] is on), the modal
//! forces, the energy ledger and the records (docs/theory.md §7.3). The engine and its
//! set-up are in the parent module.

use super::*;

impl PassageEngine {
    /// Runs one passage at `speed_m_per_s` (m/s) over the rail profile (`None` = smooth).
    pub fn passage(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
        opts: &PassageOptions,
        progress: Option<&dyn crate::progress::Progress>,
    ) -> Result<PassageRecord, DynamicsError> {
        let v = speed_m_per_s;
        let (mut contact, st) = self.started_contact(v, profile)?;
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
        let mut road = RoadAhead::new(&contact, profile);
        let increment = self.model.run.creepage == CreepageKind::Increment;

        // --- Static start (steady rolling at the static load): `st`, above.
        let (xi0, delta0) = (st.creepage, st.approach_m);

        let mut rr = vec![0.0; 3 * mt];
        let mut slopes = vec![0.0; 3 * mt];
        self.rail_line.rows_at(x0, &mut rr)?;
        // Force on the wheel in frame components (x, t, n).
        let f0 = [f_l0, 0.0, f_n0];
        let mut ft = vec![0.0; mt];
        let mut fw = vec![0.0; mw];
        // The torque and the resistance act with weight `drive`: always for the static start;
        // from rest, not in the initial state and from the first step at their onset on.
        let mut drive = match self.model.run.start {
            StartKind::Static => 1.0,
            StartKind::Rest => 0.0,
        };
        let mut fw_const = vec![0.0; mw];
        self.wheel_constant_loads(drive, &mut fw_const);
        self.generalised_forces(&f0, &fw_const, &rr, (&mut ft, &mut fw));
        self.place_at_static_start(v, (xi0, delta0), &rr, (&ft, &fw), (&mut tr, &mut wh));

        // --- Records.
        let mut h = Histories::with_capacity(n_steps);
        let mut rail_point = self.rail_point_record(n_steps);
        let nbins = ((z1 - z0) / dx).round().max(1.0) as usize;
        let mut wear = WearAccumulator::new(&contact, z0, nbins);
        let mut ledger = Ledger::start(self, (&tr, &wh), &st, opts.energy, f0[0]);
        let mut f_end = ledger.f_start;
        let mut last_delta = st.approach_m;
        let mut overlap = if opts.overlap && tr.splits() {
            let line = &self.rail_line;
            let last_plane = line.planes_x_m.len().saturating_sub(2);
            let p_first = line.locate(x0).map_or(0, |(p, _)| p);
            // the last step's interval, with two steps to spare against rounding
            let p_last = line
                .locate(x0 + v * dt * (n_steps + 2) as f64)
                .map_or(last_plane, |(p, _)| p);
            Some(DampingOverlap::new(mt, p_first, p_last))
        } else {
            None
        };
        let mut f_last = f0;
        let t_wall = Instant::now();
        if let Some(p) = progress {
            p.total(n_steps as u64);
            p.done(0);
        }
        // with the overlap, the loop runs on a worker of the thread pool, so that its
        // `rayon::join`s do not cross into the pool at every step
        let in_pool = overlap.is_some();
        let mut run = || -> Result<(), DynamicsError> {
            for n in 1..=n_steps {
                let t = n as f64 * dt;
                let xc = x0 + v * t;
                self.rail_line.rows_at(xc, &mut rr)?;
                // With the increment creepage, the contact points' displacements at `t_n`
                // read with the rows of `x_{n+1}`: the same material points at both ends of
                // the step.
                let start = increment.then(|| {
                    [
                        step::contact_displacement(&rr, &tr),
                        step::contact_displacement(&self.wheel_contact.rows, &wh),
                    ]
                });
                tr.advance_displacement();
                wh.advance_displacement();
                let mut at = (0, 0.0);
                let mut solve = || {
                    self.contact_step(
                        &mut contact,
                        &mut road,
                        (&rr, &tr, &wh),
                        start,
                        [t, xc, v, spin],
                    )
                };
                let (r, [xi, delta]) = if let Some(ov) = overlap.as_mut() {
                    at = self
                        .rail_line
                        .locate(xc)
                        .ok_or_else(|| self.rail_line.off_rail("contact point", xc))?;
                    let (res, ()) =
                        rayon::join(solve, || ov.begin(&tr, &self.rail_line, at.0, &f_last, &rr));
                    res?
                } else {
                    solve()?
                };
                if xc - half_grid < z1 && xc + half_grid > z0 {
                    wear.add_step(&contact, xc);
                }
                let f = [r.fx_n, r.fy_n, r.normal_force_n];
                f_end = f;
                // The driving torque and the resistance come on as a step at their onset.
                let drive_prev = drive;
                if drive == 0.0 && xc >= x_torque {
                    drive = 1.0;
                    self.wheel_constant_loads(drive, &mut fw_const);
                }
                self.generalised_forces(&f, &fw_const, &rr, (&mut ft, &mut fw));
                match overlap.as_mut() {
                    Some(ov) => ov.finish(&mut tr, &f, &f_last, &rr, at),
                    None => tr.complete(&ft),
                }
                f_last = f;
                wh.complete(&fw);
                check_finite((&tr, &wh), t, xc)?;
                if opts.energy {
                    ledger.add_step(
                        self,
                        (&tr, &wh),
                        &LedgerStep {
                            dt,
                            v,
                            spin,
                            xc,
                            d_mean: 0.5 * (drive + drive_prev),
                            f,
                            frictional_power_w: r.frictional_power_w,
                            mz_nm: r.mz_nm,
                            substepped,
                        },
                        &rr,
                        &mut slopes,
                    )?;
                }
                last_delta = r.approach_m;
                h.push_step(&contact, &r, [t, xc, xi, delta], dx);
                self.record_rail_point(rail_point.as_mut(), &tr);
                if let Some(p) = progress.filter(|_| n % 64 == 0) {
                    p.done(n as u64);
                }
            }
            Ok(())
        };
        if in_pool {
            rayon::scope(|_| run())?;
        } else {
            run()?;
        }
        let eb = if opts.energy {
            ledger.finish((&tr, &wh), f_end, last_delta)
        } else {
            ledger.eb
        };
        let mut w = vec![0.0; nbins];
        wear.work_x(&mut w);
        Ok(PassageRecord {
            speed_m_per_s: v,
            dt_s: dt,
            substeps: [tr.substeps(), wh.substeps()],
            x_start_m: x0,
            zone_m: self.zone_m,
            histories: h,
            wear_x_m: wear.x_m(),
            wear_j_per_m: w,
            rail_point,
            energy: eb,
            static_creepage: xi0,
            static_approach_m: delta0,
            steps: n_steps,
            seconds: t_wall.elapsed().as_secs_f64(),
        })
    }
}

//! The energy ledger of an explicit passage (docs/theory.md §8.8): the same terms as the
//! reduced passage's [`EnergyBalance`] (§7.8), from the state at contact-step boundaries.

use super::model::ExplicitModel;
use super::rotating::RotatingWheel;
use super::ExplicitError;
use crate::passage::record::EnergyBalance;

/// The state of both substructures: displacements (m) and half-step velocities (m/s).
pub(super) struct State {
    pub(super) ut: Vec<f64>,
    pub(super) vt: Vec<f64>,
    pub(super) uw: Vec<f64>,
    pub(super) vw: Vec<f64>,
}

impl State {
    pub(super) fn check_finite(&self, t: f64, xc: f64) -> Result<(), ExplicitError> {
        for (part, u) in [("track", &self.ut), ("wheel", &self.uw)] {
            if !u.iter().all(|x| x.is_finite()) {
                return Err(ExplicitError::Diverged {
                    t_s: t,
                    x_m: xc,
                    part,
                });
            }
        }
        Ok(())
    }
}

/// One step's inputs to the energy ledger.
pub(super) struct LedgerStep {
    /// Contact position (m).
    pub(super) xc: f64,
    /// Contact step (s).
    pub(super) dt_c: f64,
    /// Speed (m/s).
    pub(super) v: f64,
    /// Spin creepage (1/m).
    pub(super) spin: f64,
    /// The contact force that did the work over the step (N, on the wheel).
    pub(super) f_work: [f64; 3],
    /// Rail and wheel contact-point displacement at the step's start (m).
    pub(super) old: [[f64; 3]; 2],
    /// When the force was held at the previous contact position (no corrector): the rail's
    /// displacement there at the step's start and end (m); `None` when it acted at `xc`.
    pub(super) held_at_previous: Option<[[f64; 3]; 2]>,
    /// The contact force at the step's start and end (N, on the wheel).
    pub(super) forces: [[f64; 3]; 2],
    /// The removed local compliance variation `Δg` at the step's end position (m/N): the
    /// rail's and the rotating tread's.
    pub(super) dg: [f64; 3],
    /// The rotating tread's share of `dg` (m/N; zero on the fixed wheel).
    pub(super) dg_wheel: [f64; 3],
    /// Work of the dampers over the predictor's sub-steps (J). The corrector's response
    /// starts at the contact and does not reach the dampers (pads, ballast, suspension)
    /// within the step, so this is the step's dissipation.
    pub(super) damper_j: f64,
    /// The step's start and end times (s).
    pub(super) t: [f64; 2],
    /// The wheel's contact-point displacement at the step's end (m, contact frame).
    pub(super) uw_end: [f64; 3],
    /// The wheel's contact-point displacement of the step's start state as the structure
    /// sees it (m, contact frame): on the rotating wheel turned to the ground with the
    /// step's end rotation, where `old` turns it with the start rotation (the material
    /// point's increment the contact reads); on the fixed wheel `old`'s.
    pub(super) uw_turned: [f64; 3],
    /// The rotating tread's convective deflection taken out of the creepage's wheel
    /// increment (m, contact frame; zero on the fixed wheel).
    pub(super) conv: [f64; 3],
    /// Work of the rotating wheel's suspension turned to the ground vertical over the
    /// predictor's sub-steps (J; zero on the fixed wheel).
    pub(super) frame_j: f64,
}

/// The energy ledger of an explicit passage (the same terms as the reduced passage's,
/// [`EnergyBalance`]); inactive (no cost) when the passage does not keep it.
pub(super) struct Ledger<'a> {
    m: &'a ExplicitModel,
    on: bool,
    eb: EnergyBalance,
    e_start: f64,
    e_contact_start: f64,
    ur_prev: [f64; 3],
    /// The removed normal local compliance variation at the last position (m/N), and the
    /// rotating tread's share of it.
    dg_prev: f64,
    dg_wheel_prev: f64,
    /// Wheel-load work potentials `f·u` at the step's start: all, torque, gravity.
    before: [f64; 3],
    /// Whether the driving torque and the resistance act over the current step.
    drive: bool,
    ku: Vec<f64>,
    /// The wheel's state at the step's start (m; rotating wheel only).
    uw_start: Vec<f64>,
    /// The suspension's energy correction at the last step's end (J; rotating wheel only).
    sus_prev: f64,
    /// The wheel's contact-point displacement at the last step's end (m; rotating wheel).
    uw_prev: [f64; 3],
    /// Contact work, convective work and series-spring energy per contact-frame direction
    /// (J), for the audit.
    pub(super) by_direction: [[f64; 3]; 3],
    /// The contact work on the rail and on the wheel (J), for the audit.
    pub(super) rail_wheel: [f64; 2],
}

impl<'a> Ledger<'a> {
    pub(super) fn new(
        m: &'a ExplicitModel,
        on: bool,
        s: &State,
        st: &crate::contact::StepResult,
        x0: f64,
        rot: Option<&RotatingWheel>,
    ) -> Result<Self, ExplicitError> {
        let nw = if on && rot.is_some() {
            m.wheel.op.n()
        } else {
            0
        };
        let mut l = Ledger {
            m,
            on,
            eb: EnergyBalance::default(),
            e_start: 0.0,
            e_contact_start: hertz_energy(st.normal_force_n, st.approach_m, 0.0),
            ur_prev: m.rail_at(&s.ut, x0)?,
            dg_prev: m.local_variation(x0, &m.weights(x0)?)[2],
            // The tread's variation is zero at the start's angle, its reference.
            dg_wheel_prev: 0.0,
            before: [0.0; 3],
            drive: true,
            by_direction: [[0.0; 3]; 3],
            rail_wheel: [0.0; 2],
            ku: if on {
                vec![0.0; m.track.op.n().max(m.wheel.op.n())]
            } else {
                Vec::new()
            },
            uw_start: vec![0.0; nw],
            uw_prev: rot.map_or([0.0; 3], |r| r.wheel_at(&s.uw, 0.0, 0.0)),
            sus_prev: rot.map_or(0.0, |r| r.suspension_energy_correction(&s.uw, 0.0)),
        };
        if on {
            l.e_start = l.stored(s, rot, 0.0);
        }
        Ok(l)
    }

    /// Kinetic + strain energy of both substructures (J) at time `t` (s); the rotating
    /// wheel's in its spinning frame ([`RotatingWheel::stored`]).
    fn stored(&mut self, s: &State, rot: Option<&RotatingWheel>, t: f64) -> f64 {
        let plain = |op: &super::operator::ExplicitOperator, u: &[f64], v, ku: &mut [f64]| {
            op.apply_k(u, ku);
            0.5 * dot(u, ku) + op.kinetic_energy(v)
        };
        let (track, wheel) = (&self.m.track.op, &self.m.wheel.op);
        let e = plain(track, &s.ut, &s.vt, &mut self.ku[..s.ut.len()]);
        let ku = &mut self.ku[..s.uw.len()];
        e + match rot {
            Some(r) => r.stored(wheel, &s.uw, &s.vw, t, ku),
            None => plain(wheel, &s.uw, &s.vw, ku),
        }
    }

    /// Before a step whose wheel loads include the driving torque and the resistance when
    /// `drive` (the wheel's state `uw` at the step's start).
    pub(super) fn before_step(&mut self, uw: &[f64], drive: bool) {
        self.drive = drive;
        if self.on {
            if !self.uw_start.is_empty() {
                self.uw_start.copy_from_slice(uw);
            }
            let l = &self.m.loads;
            self.before = [
                dot(self.m.wheel_loads(drive), uw),
                if drive { dot(&l.torque, uw) } else { 0.0 },
                dot(&l.gravity, uw),
            ];
        }
    }

    pub(super) fn after_step(
        &mut self,
        s: &State,
        k: LedgerStep,
        r: &crate::contact::StepResult,
        rot: Option<&RotatingWheel>,
    ) -> Result<(), ExplicitError> {
        if !self.on {
            return Ok(());
        }
        let (m, eb) = (self.m, &mut self.eb);
        // Constant wheel loads: exact work f·Δu. On the rotating wheel the ground-fixed ones
        // (gravity, resistance) turn in the spinning frame: their turn's work is added.
        eb.external_work_j += dot(m.wheel_loads(self.drive), &s.uw) - self.before[0];
        if self.drive {
            eb.torque_work_j += dot(&m.loads.torque, &s.uw) - self.before[1];
        }
        eb.gravity_work_j += dot(&m.loads.gravity, &s.uw) - self.before[2];
        if let Some(rw) = rot {
            // The ground-fixed loads turn in the spinning frame: the scheme's energy sees
            // their work on the spinning frame's increments; the input is their work on the
            // ground frame's, the difference is the frame's.
            let u = [self.uw_start.as_slice(), s.uw.as_slice()];
            let [sg, gg] = rw.load_work(&m.loads.gravity, u, k.t);
            // The resistance acts only with the driving torque (a start from rest).
            let [sd, gd, d_du] = if self.drive {
                let [sd, gd] = rw.load_work(&m.loads.drawbar, u, k.t);
                let d_du = dot(&m.loads.drawbar, &s.uw) - dot(&m.loads.drawbar, &self.uw_start);
                [sd, gd, d_du]
            } else {
                [0.0; 3]
            };
            // Less the non-turning g · Δu counted above.
            let g_du = dot(&m.loads.gravity, &s.uw) - self.before[2];
            eb.external_work_j += gg + gd - (g_du + d_du);
            eb.gravity_work_j += gg - g_du;
            eb.frame_work_j += sg + sd - (gg + gd);
            // The suspension's spring along the ground vertical in the stored energy.
            let e = rw.suspension_energy_correction(&s.uw, k.t[1]);
            eb.frame_work_j += e - self.sus_prev;
            self.sus_prev = e;
        }
        eb.damper_dissipation_j += k.damper_j;
        // Work of the contact force on the two structures, with the corrected end-of-step
        // displacements. On the rotating wheel the contact reads the material point's
        // increment, the structure carries the force over the spinning frame's increment:
        // the difference, the force's work through the frame's turn of the wheel's
        // displacement under the contact, is fed by the rotation.
        let ur_end = m.rail_at(&s.ut, k.xc)?;
        let [ur_old, _] = k.old;
        let (uw_end, uw_old) = (k.uw_end, k.uw_turned);
        // The rail's displacement increment where the force acted.
        let du_rail = match k.held_at_previous {
            Some([a, b]) => [0, 1, 2].map(|d| b[d] - a[d]),
            None => [0, 1, 2].map(|d| ur_end[d] - ur_old[d]),
        };
        eb.frame_work_j += k.frame_j;
        for d in 0..3 {
            eb.frame_work_j += k.f_work[d] * (k.old[1][d] - uw_old[d]);
        }
        // The contact moving round the wheel: the change of the wheel's normal displacement
        // under it as the contact moves from its place of t_n to that of t_{n+1} on the state
        // at t_n (as on the rail; the approach has the opposite sign). Normal only: the
        // approach is a state, but the creepages read the material point's increment at the
        // step's end place, which contains no change of place (docs/theory.md §8.8).
        if rot.is_some() {
            let w = -k.f_work[2] * (k.old[1][2] - self.uw_prev[2]);
            eb.convective_work_j += w;
            self.by_direction[1][2] += w;
            self.uw_prev = uw_end;
        }
        // The tread's convective deflection taken out of the creepages (§8.7): an input of
        // the contact law.
        for d in 0..2 {
            eb.tread_correction_work_j += k.f_work[d] * k.conv[d];
        }
        for d in 0..3 {
            let [on_rail, on_wheel] = [
                -k.f_work[d] * du_rail[d],
                k.f_work[d] * (uw_end[d] - uw_old[d]),
            ];
            self.rail_wheel[0] += on_rail;
            self.rail_wheel[1] += on_wheel;
            let w = on_rail + on_wheel;
            eb.contact_work_j += w;
            self.by_direction[0][d] += w;
        }
        eb.frictional_work_j += r.frictional_power_w * k.dt_c;
        eb.spin_work_j -= k.v * k.spin * r.mz_nm * k.dt_c;
        // Convective work: the force rolling over the deflected rail, the change of the rail's
        // normal displacement under the contact as the contact moves from x_n to x_{n+1} on
        // the state at t_n; with the force held at x_n, the move on the state at t_{n+1}, the
        // rest of the change from `u(x_n, t_n)` to `u(x_{n+1}, t_{n+1})`. Normal only: the
        // approach is the difference of the two surfaces' displacements where the contact is,
        // a state, so its change holds the move; the creepages are the displacement
        // increments at the step's end position (rail and wheel), whose work is the contact
        // work and holds none (docs/theory.md §8.8).
        let moved = match k.held_at_previous {
            Some(_) => ur_end[2] - self.ur_prev[2] - du_rail[2],
            None => ur_old[2] - self.ur_prev[2],
        };
        let w = k.f_work[2] * moved;
        eb.convective_work_j += w;
        self.by_direction[1][2] += w;
        self.ur_prev = ur_end;
        // The removed local compliance variation acts as a series spring of compliance
        // −Δg (docs/theory.md §8.6, §8.8). Tangential: on the creepage increments at the
        // step's end position, energy −Δg F̄ ΔF. Normal: in the approach, energy −½ Δg F²;
        // the contact's approach is the structures' plus Δg F, so the mean force's work on
        // that shift, F̄ Δ(Δg F), is the energy change ½ Δ(Δg F²) plus the work of the
        // spring's explicit dependence on the contact's place, ½ F_n F_{n+1} (Δg_{n+1} − Δg_n),
        // an input: the rail's share (Δg(x)) as convective work, the rotating tread's
        // (Δg(φ)) as the tread corrections' work.
        let [fo, fnew] = k.forces;
        for d in 0..2 {
            let e = k.dg[d] * 0.5 * (fo[d] + fnew[d]) * (fnew[d] - fo[d]);
            eb.residual_spring_energy_change_j -= e;
            self.by_direction[2][d] -= e;
        }
        let e = 0.5 * (k.dg[2] * fnew[2] * fnew[2] - self.dg_prev * fo[2] * fo[2]);
        let dg_rail = [k.dg[2] - k.dg_wheel[2], self.dg_prev - self.dg_wheel_prev];
        let roll = varying_spring_work([dg_rail[1], dg_rail[0]], [fo[2], fnew[2]]);
        let tread = varying_spring_work([self.dg_wheel_prev, k.dg_wheel[2]], [fo[2], fnew[2]]);
        eb.residual_spring_energy_change_j -= e;
        eb.convective_work_j += roll;
        eb.tread_correction_work_j += tread;
        self.by_direction[2][2] -= e + roll + tread;
        self.dg_prev = k.dg[2];
        self.dg_wheel_prev = k.dg_wheel[2];
        Ok(())
    }

    /// The balance at the end: `f_n` the last normal force (N), `delta` the contact
    /// solver's last approach (m), `c_n` the last normal series compliance (m/N).
    /// `rot` the rotating wheel (`None`: fixed) and `t` the passage's end time (s).
    pub(super) fn finish(
        mut self,
        s: &State,
        (f_n, delta, c_n): (f64, f64, f64),
        rot: Option<&RotatingWheel>,
        t: f64,
    ) -> EnergyBalance {
        if self.on {
            self.eb.stored_change_j = self.stored(s, rot, t) - self.e_start;
            // The half-space part of the approach: the solver's approach less the series
            // compliance's share (the structures' own compliance, whose energy is in the
            // stored energy: no separate spring).
            self.eb.contact_energy_change_j = hertz_energy(f_n, delta, c_n) - self.e_contact_start;
        }
        self.eb
    }
}

/// The trapezoidal work (J) of the explicit time dependence of a series compliance that
/// changes from `g[0]` to `g[1]` (m/N) while its force changes from `f[0]` to `f[1]` (N):
/// the mean force times the change of the spring's stretch `g F`, less the change of its
/// energy `½ g F²`, which is `½ f₀ f₁ (g₁ − g₀)`.
fn varying_spring_work(g: [f64; 2], f: [f64; 2]) -> f64 {
    0.5 * f[0] * f[1] * (g[1] - g[0])
}

/// Hertz estimate of the contact's elastic energy `(2/5) F (δ − c F)` (J) for the normal
/// force `f` (N), the approach `d` (m) and a series compliance `c` (m/N) whose share of the
/// approach is not in the half-space.
fn hertz_energy(f: f64, d: f64, c: f64) -> f64 {
    0.4 * f * (d - c * f).max(0.0)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::varying_spring_work;

    /// The work of a varying series compliance is the mean force times the change of the
    /// spring's stretch `g F` less the change of its energy `½ g F²` (closed form by hand),
    /// and differs from the force-at-the-start form `½ Δg F_n²` by `½ Δg F_n ΔF` (numbers
    /// chosen so that the difference is not small).
    #[test]
    fn varying_spring_work_is_the_trapezoid_less_the_energy_change() {
        let (g0, g1, f0, f1) = (-2.0e-10, 1.5e-10, 1.0e5, 1.1e5);
        let direct = 0.5 * (f0 + f1) * (g1 * f1 - g0 * f0) - 0.5 * (g1 * f1 * f1 - g0 * f0 * f0);
        let w = varying_spring_work([g0, g1], [f0, f1]);
        assert!((w - direct).abs() < 1e-12 * direct.abs(), "{w} vs {direct}");
        let rail_form = 0.5 * (g1 - g0) * f0 * f0;
        assert!((w - rail_form - 0.5 * (g1 - g0) * f0 * (f1 - f0)).abs() < 1e-9 * w.abs());
        assert!((w - rail_form).abs() > 0.05 * w.abs());
    }
}

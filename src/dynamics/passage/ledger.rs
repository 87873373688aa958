//! The energy balance of the reduced passage (docs/theory.md §7.8): the work of the wheel's
//! loads, the contact, the dampers, friction, spin and the convective term, advanced once
//! per contact step, and the stored, contact and residual-spring energy changes at the end.

use super::super::integrator::ModalVerlet;
use super::super::record::EnergyBalance;
use super::super::reduced::dot;
use super::super::DynamicsError;
use super::PassageEngine;

/// What one contact step hands to the energy ledger.
pub(super) struct LedgerStep {
    /// Contact step (s).
    pub(super) dt: f64,
    /// Speed (m/s).
    pub(super) v: f64,
    /// Spin creepage per metre (1/m).
    pub(super) spin: f64,
    /// Contact position (m).
    pub(super) xc: f64,
    /// Mean weight of the torque and resistance over the step (0 to 1).
    pub(super) d_mean: f64,
    /// Contact force on the wheel (x, t, n; N).
    pub(super) f: [f64; 3],
    /// Frictional power of the step (W).
    pub(super) frictional_power_w: f64,
    /// Spin moment (N·m).
    pub(super) mz_nm: f64,
    /// True when either modal system sub-steps (no unit).
    pub(super) substepped: bool,
}

/// The passage's energy balance (docs/theory.md §7.8), advanced once per contact step.
pub(super) struct Ledger {
    /// The work terms accumulated so far (each in J).
    pub(super) eb: EnergyBalance,
    /// Stored energy of track and wheel at the static start, kinetic + strain (J).
    pub(super) e_start: f64,
    /// Elastic energy of the half-space at the static start, Hertz estimate (J).
    pub(super) e_contact_start: f64,
    /// Contact force at the static start (x, y, n; N).
    pub(super) f_start: [f64; 3],
    /// Compliance of the residual springs in series with the contact (x, y, n; m/N).
    pub(super) series_c: [f64; 3],
    /// Damper power of both systems at the end of the previous contact step (W).
    pub(super) p_damp_prev: f64,
    /// Contact power F · (v_wheel − v_rail) at the end of the previous contact step (W).
    pub(super) p_contact_prev: f64,
    /// Wheel modal coordinates at the end of the previous contact step (√kg·m: the
    /// coordinates of mass-normalised modes).
    pub(super) qw_prev: Vec<f64>,
}

/// Elastic energy of the half-space (Hertz estimate, J) at the load `f` (N) on the approach
/// `d` (m) without the residual spring's share `cz f`.
fn hertz_energy(f: f64, d: f64, cz: f64) -> f64 {
    0.4 * f * (d - cz * f).max(0.0)
}

impl Ledger {
    /// The ledger at the static start `st`; `f_l0` (N) the static longitudinal force;
    /// `uniform` (m/N) the contact operators' own uniform compliance (the fe-patch's split,
    /// [`crate::contact::TransientRolling::uniform_compliance`]), part of the series springs.
    pub(super) fn start(
        e: &PassageEngine,
        (tr, wh): (&ModalVerlet, &ModalVerlet),
        st: &crate::contact::StepResult,
        (energy, uniform): (bool, [f64; 3]),
        f_l0: f64,
    ) -> Self {
        let series_c = [0, 1, 2].map(|d| e.series_compliance[d] + uniform[d]);
        let mw = wh.len();
        Ledger {
            eb: EnergyBalance::default(),
            e_start: tr.kinetic_energy()
                + tr.strain_energy()
                + wh.kinetic_energy()
                + wh.strain_energy(),
            e_contact_start: hertz_energy(st.normal_force_n, st.approach_m, series_c[2]),
            f_start: [st.fx_n, st.fy_n, st.normal_force_n],
            series_c,
            p_damp_prev: if energy {
                tr.damping_power() + wh.damping_power()
            } else {
                0.0
            },
            // contact power at the start: F · (v_w − v_r)
            p_contact_prev: f_l0 * dot(&e.wheel_contact.rows[..mw], &wh.v),
            qw_prev: wh.q.clone(),
        }
    }

    /// Adds the work of one contact step (after both systems completed it).
    pub(super) fn add_step(
        &mut self,
        e: &PassageEngine,
        (tr, wh): (&ModalVerlet, &ModalVerlet),
        s: &LedgerStep,
        rr: &[f64],
        slopes: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (mt, mw) = (tr.len(), wh.len());
        let wr = &e.wheel_contact.rows;
        let eb = &mut self.eb;
        // Constant wheel loads: work g · Δq (exact); a load switched on in this step
        // counts by the trapezoidal rule of the integrator, ½(g_n + g_{n+1}) · Δq.
        for i in 0..mw {
            let dq = wh.q[i] - self.qw_prev[i];
            eb.gravity_work_j += e.wheel_gravity[i] * dq;
            eb.torque_work_j += s.d_mean * e.wheel_torque[i] * dq;
            eb.external_work_j +=
                (e.wheel_gravity[i] + s.d_mean * (e.wheel_torque[i] + e.wheel_drawbar[i])) * dq;
        }
        self.qw_prev.copy_from_slice(&wh.q);
        let p_damp = tr.damping_power() + wh.damping_power();
        eb.damper_dissipation_j += if s.substepped {
            tr.step_damper_work() + wh.step_damper_work()
        } else {
            0.5 * s.dt * (p_damp + self.p_damp_prev)
        };
        self.p_damp_prev = p_damp;
        // Contact power with the corrected velocities.
        let mut p_c = 0.0;
        for d in 0..3 {
            let vr = dot(&rr[d * mt..(d + 1) * mt], &tr.v);
            let vw = dot(&wr[d * mw..(d + 1) * mw], &wh.v);
            p_c += s.f[d] * (vw - vr);
        }
        eb.contact_work_j += 0.5 * s.dt * (p_c + self.p_contact_prev);
        self.p_contact_prev = p_c;
        eb.frictional_work_j += s.frictional_power_w * s.dt;
        eb.spin_work_j -= s.v * s.spin * s.mz_nm * s.dt;
        e.rail_line.row_slopes_at(s.xc, slopes)?;
        let dun = dot(&slopes[2 * mt..], &tr.q);
        let dut = dot(&slopes[mt..2 * mt], &tr.q);
        eb.convective_work_j += s.v * (s.f[2] * dun + s.f[1] * dut) * s.dt;
        Ok(())
    }

    /// The balance at the end: the stored, contact and residual-spring energy changes from
    /// the final state, force `f_end` (N) and approach `last_delta` (m).
    pub(super) fn finish(
        mut self,
        (tr, wh): (&ModalVerlet, &ModalVerlet),
        f_end: [f64; 3],
        last_delta: f64,
    ) -> EnergyBalance {
        let e_end =
            tr.kinetic_energy() + tr.strain_energy() + wh.kinetic_energy() + wh.strain_energy();
        let c = self.series_c;
        let f0 = self.f_start;
        self.eb.stored_change_j = e_end - self.e_start;
        self.eb.contact_energy_change_j =
            hertz_energy(f_end[2], last_delta, c[2]) - self.e_contact_start;
        self.eb.residual_spring_energy_change_j = (0..3)
            .map(|d| 0.5 * c[d] * (f_end[d] * f_end[d] - f0[d] * f0[d]))
            .sum();
        self.eb
    }
}

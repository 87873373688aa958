//! What a passage records (docs/theory.md §7): the per-step histories of the contact, the
//! wear along the rail, the energy ledger and the rail points' displacements. Produced by
//! the reduced passage ([`crate::dynamics::passage`]) and the explicit FE path alike, and read by the
//! summary analysis ([`super::analysis`]).

use crate::contact::TransientRolling;

/// Time histories of a passage, one value per step.
#[derive(Clone, Debug, Default)]
pub struct Histories {
    /// Time since the start (s).
    pub t_s: Vec<f64>,
    /// Contact centre along the rail (m).
    pub x_m: Vec<f64>,
    /// Normal force on the wheel (N).
    pub normal_n: Vec<f64>,
    /// Longitudinal force on the wheel, + forward (N).
    pub longitudinal_n: Vec<f64>,
    /// Lateral force on the wheel along t (N).
    pub lateral_n: Vec<f64>,
    /// Longitudinal creepage ξ (−).
    pub creepage: Vec<f64>,
    /// Rigid approach δ (m).
    pub approach_m: Vec<f64>,
    /// Contact length along the rail: grid columns with contact × Δx (m).
    pub contact_length_m: Vec<f64>,
    /// Largest element pressure of the patch (Pa).
    pub peak_pressure_pa: Vec<f64>,
    /// Slip-area fraction (−).
    pub slip_fraction: Vec<f64>,
    /// Frictional power (W).
    pub frictional_power_w: Vec<f64>,
}

impl Histories {
    /// Empty histories with room for `n` steps in each series.
    pub fn with_capacity(n: usize) -> Self {
        let mut h = Histories::default();
        for vct in [
            &mut h.t_s,
            &mut h.x_m,
            &mut h.normal_n,
            &mut h.longitudinal_n,
            &mut h.lateral_n,
            &mut h.creepage,
            &mut h.approach_m,
            &mut h.contact_length_m,
            &mut h.peak_pressure_pa,
            &mut h.slip_fraction,
            &mut h.frictional_power_w,
        ] {
            vct.reserve(n);
        }
        h
    }

    /// Appends one contact step: `[t (s), x_c (m), ξ (−), approach (m)]`, the contact
    /// result, the contact length (grid columns along x with any pressure × `dx`, m) and the
    /// peak pressure.
    pub fn push_step(
        &mut self,
        contact: &TransientRolling,
        r: &crate::contact::StepResult,
        [t, xc, xi, approach]: [f64; 4],
        dx: f64,
    ) {
        let ny = contact.config().grid.ny;
        self.t_s.push(t);
        self.x_m.push(xc);
        self.normal_n.push(r.normal_force_n);
        self.longitudinal_n.push(r.fx_n);
        self.lateral_n.push(r.fy_n);
        self.creepage.push(xi);
        self.approach_m.push(approach);
        let cols = contact
            .pressure_pa()
            .chunks_exact(ny)
            .filter(|row| row.iter().any(|&p| p > 0.0))
            .count();
        self.contact_length_m.push(cols as f64 * dx);
        let peak = contact.pressure_pa().iter().copied().fold(0.0, f64::max);
        self.peak_pressure_pa.push(peak);
        self.slip_fraction.push(r.slip_area_fraction());
        self.frictional_power_w.push(r.frictional_power_w);
    }
}

/// The displacement history of one rail-top node.
#[derive(Clone, Debug, Default)]
pub struct RailPointRecord {
    /// Node position (x, y, z) (m).
    pub position_m: [f64; 3],
    /// Displacements (x, y, z) over time (m), one triple per step.
    pub displacement_m: Vec<[f64; 3]>,
}

/// The energy balance of a passage (J), all over the dynamic phase.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct EnergyBalance {
    /// Work of the constant wheel loads: driving torque, gravity, train resistance (J).
    pub external_work_j: f64,
    /// Of which the driving torque (J).
    pub torque_work_j: f64,
    /// Of which gravity (J).
    pub gravity_work_j: f64,
    /// Work of the spin creepage of the coned wheel, `−∫ V φ M_z dt` (J): the spin is
    /// kinematic (from the nominal rolling), so its frictional dissipation is fed by the
    /// nominal motion, not by the modal perturbation; it is counted as an input.
    pub spin_work_j: f64,
    /// Work of the contact force through the convective change of the rail displacement
    /// under the moving contact, `∫ V (F_N ∂u_n/∂x + F_t ∂u_t/∂x) dt` (J): the wheel rolling
    /// over a deflected rail (climbing out of the damped deflection bowl). It is fed by the
    /// nominal forward motion and counted as an input.
    pub convective_work_j: f64,
    /// Change of kinetic + strain energy of both substructures (J).
    pub stored_change_j: f64,
    /// Dissipated by the discrete dampers (J).
    pub damper_dissipation_j: f64,
    /// Frictional work in the contact (J).
    pub frictional_work_j: f64,
    /// Change of the elastic energy of the contact (Hertz estimate 2/5·F_N·δ_H, δ_H the
    /// approach less the residual spring's share) (J).
    pub contact_energy_change_j: f64,
    /// Change of the energy `½ c F²` of the residual (static-correction) spring in series
    /// with the contact, summed over x, t, n (J); `c` is constant along the rail (see
    /// `PassageEngine::series_compliance`).
    pub residual_spring_energy_change_j: f64,
    /// Work of the contact forces on the two structures (J): = −(friction + contact energy).
    pub contact_work_j: f64,
    /// Work fed by the rotating wheel's spinning frame (J; zero for a wheel that does not
    /// rotate, docs/theory.md §8.8): the contact force through the frame's turn of the
    /// wheel's displacement under the contact over a contact step, and the primary
    /// suspension's turn to the ground vertical. Counted as an input.
    pub frame_work_j: f64,
    /// Work fed into the contact by the rotating wheel's tread corrections (J; zero for a
    /// wheel that does not rotate and with `explicit.local_compliance = "mesh"`,
    /// docs/theory.md §8.8): the contact force through the convective deflection taken
    /// out of the creepage, and the explicit time dependence of the removed normal
    /// compliance variation `−Δg(φ)` as the contact runs round the faceted tread. Both are
    /// inputs of the contact law, not of the structures. Counted as an input.
    pub tread_correction_work_j: f64,
}

impl EnergyBalance {
    /// `input + spin, convective, frame and tread-correction work − (stored + dampers +
    /// friction + contact and residual-spring energy)` over the input (−).
    pub fn relative_error(&self) -> f64 {
        let out = self.stored_change_j
            + self.damper_dissipation_j
            + self.frictional_work_j
            + self.contact_energy_change_j
            + self.residual_spring_energy_change_j;
        let scale = self
            .external_work_j
            .abs()
            .max(self.frictional_work_j.abs() + self.damper_dissipation_j.abs())
            .max(f64::MIN_POSITIVE);
        (self.external_work_j
            + self.spin_work_j
            + self.convective_work_j
            + self.frame_work_j
            + self.tread_correction_work_j
            - out)
            / scale
    }
}

/// Everything one passage produces.
#[derive(Clone, Debug)]
pub struct PassageRecord {
    /// Speed (m/s).
    pub speed_m_per_s: f64,
    /// Time step: the contact step `Δx / V` (s).
    pub dt_s: f64,
    /// Structural sub-steps per contact step, `[track, wheel]` (−; 1 = none): the reduced
    /// passage's modal sub-steps, the explicit path's central-difference steps.
    pub substeps: [usize; 2],
    /// Wheel start position (m).
    pub x_start_m: f64,
    /// Solution zone [start, end] (m).
    pub zone_m: [f64; 2],
    /// Time histories.
    pub histories: Histories,
    /// Bin centres of the wear along the rail in the solution zone (m).
    pub wear_x_m: Vec<f64>,
    /// Frictional work per metre of rail `W_f(x) = Σ τ·s Δt` integrated across the rail head
    /// (J/m). The wear is proportional to it (docs/theory.md §6.6); the wear coefficient
    /// (`wear.coefficient`, m³/J) converts it to a worn depth only in the iterative growth.
    pub wear_j_per_m: Vec<f64>,
    /// The rail-point record.
    pub rail_point: Option<RailPointRecord>,
    /// Energy balance (zeros unless `PassageOptions::energy`).
    pub energy: EnergyBalance,
    /// Static state: steady creepage ξ₀ (−) and approach δ₀ (m).
    pub static_creepage: f64,
    /// Static approach (m).
    pub static_approach_m: f64,
    /// Number of time steps.
    pub steps: usize,
    /// Wall time of the dynamic phase (s).
    pub seconds: f64,
    /// Steps whose track damping product ran on a second thread beside the contact step (−;
    /// 0 without [`super::PassageOptions::overlap`], with one thread, on the
    /// explicit path, or while the machine was oversubscribed). The results do not depend on it.
    pub split_steps: usize,
    /// The contact grid the passage ran on when its contact patch reached the boundary of
    /// the model's grid and it was rerun on a wider one
    /// ([`super::setup::run_widening_grid`]); `None` on the model's grid.
    pub contact_grid_widened: Option<WidenedGrid>,
}

/// The contact grid a passage ran on when it was widened ([`super::setup::run_widening_grid`]): the
/// patch reached the boundary of the grid of [`super::setup::passage_contact`] (under a dynamic load above
/// what `contact.grid_margin` leaves room for, e.g. over a deep corrugation) and the passage
/// was rerun on this one.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WidenedGrid {
    /// Widenings along x and y (−), each by `super::setup::GRID_WIDENING` in half-length.
    pub widenings: [u32; 2],
    /// Elements along x and y (−).
    pub elements: [usize; 2],
    /// Half-lengths along x and y (m).
    pub half_lengths_m: [f64; 2],
}

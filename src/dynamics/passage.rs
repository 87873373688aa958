//! One passage of the wheel over the track (docs/theory.md §7).
//!
//! # The coupled problem
//! Track modes `q_t` and wheel modes `q_w` (see [`super::reduced`]) each obey
//! `q̈ + C_q q̇ + Ω² q = Φᵀ f`, integrated by [`super::integrator::ModalVerlet`] with the
//! time step of the contact grid, `Δt = Δx / V` (docs/theory.md §6.5: material moves one grid
//! element per step in Kalker's transient theory). At each step:
//!
//! 1. both substructures advance their displacements to `t_{n+1}`;
//! 2. the contact point moves to `x_c = x_0 + V t_{n+1}` on the rail; the rail's
//!    displacement and (predicted) velocity there, and the wheel's at its tread contact
//!    point, are interpolated from the modes (frame x, t, n);
//! 3. the contact inputs: rigid approach `δ = (u_rail − u_wheel)·n` (the rail-top profile
//!    enters the contact solver's gap, column by column); creepages
//!    `ξ = (u̇_wheel,x − u̇_rail,x)/V`, `η = (u̇_wheel,t − u̇_rail,t)/V` — the rail's
//!    longitudinal vibration at the contact enters here — and the spin of the coned wheel on
//!    the inclined rail `φ = −sin α / R` (1/m);
//! 4. the transient rolling contact step ([`crate::contact::TransientRolling`]) gives the
//!    forces on the wheel (F_L = Fx, lateral, F_N) and the frictional power density, which
//!    is accumulated in rail-fixed bins: `W_f(x) = Σ τ·s Δt` integrated across the rail
//!    head (J/m, docs/theory.md §6.6 with k = 1: the coefficient scales, it does not shape);
//! 5. the forces act on the wheel and, opposite, on the rail at `x_c`; both substructures
//!    complete the step.
//!
//! # Loads and rigid-body motion of the wheel
//! Gravity acts on every wheel mass and the sprung mass (total = `vehicle.wheel_load`). The
//! driving torque is constant, `T = μ_t W R` (traction coefficient μ_t), applied as
//! tangential forces on the journal nodes; a constant torque is preferred to a
//! feedback controller (it does not itself excite the kHz band). A constant longitudinal
//! force `−μ_t W` on the journal nodes stands for the train resisting the traction (the
//! vehicle's inertia keeps the speed). The wheel's three rigid modes (x, z, rotation) are
//! free: their mean motion is balanced by these loads and the contact.
//!
//! # Static start
//! The contact is first brought to steady rolling at the static load (normal force
//! `W / cos α`, longitudinal force `μ_t W`), which gives the steady creepage ξ₀ and approach
//! δ₀; the track and the wheel's elastic modes take their static deflection under these
//! forces (exact modal static solution), the wheel's rigid modes are placed so that the
//! approach is δ₀ and turned so that the creepage is ξ₀. Results are read in the solution
//! zone, from `run.solution_zone_offset` after the start.

use std::time::Instant;

use faer::Mat;

use super::integrator::ModalVerlet;
use super::reduced::{dot, ContactFrame, ModalSystem, RailContactLine, WheelContact};
use super::residual::ResidualFlexibility;
use super::{DynamicsError, RailProfile};
use crate::contact::WearAccumulator;
use crate::contact::{
    GridSpec, Longitudinal, NormalInput, StepInputs, TransientConfig, TransientRolling,
};
use crate::model::{Model, ResidualVariation};
use crate::structure::{TrackStructure, WheelStructure};

/// Frequencies below this are rigid-body modes (Hz).
pub const RIGID_HZ: f64 = 0.5;

/// Relative tolerance of the tangential contact solver in a passage (traction error ≈ this ×
/// µ p_max; the contact module's default is 1e-6). Measured on the default model (140 km/h,
/// 2 and 5 kHz) against the former plain CG at 1e-6: the force histories move by
/// ≤ 6e-5 of the mean F_L (≤ 5e-6 of the mean F_N), the band RMS of F_L and of the wear by
/// ≤ 6e-4 (relative), the dominant wavelength by < 1e-5 — no more than with the Jacobi CG at
/// 1e-6 (most of it is a start transient: the static start's creepage moves by ~4e-5
/// relative, and the difference decays through the run-in). The Jacobi CG then needs 12
/// instead of 16 tangential products per step.
pub const PASSAGE_TANGENTIAL_TOL: f64 = 1e-5;

/// What a passage records besides the wear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassageOptions {
    /// Keep the energy balance (O(modes) per step: the damper power comes with the
    /// integrator's implicit solve).
    pub energy: bool,
    /// Distance after the solution-zone start of the rail-top node whose displacement is
    /// recorded (m); `None` = no rail-point record. Default 0.6 m.
    pub rail_point_offset_m: Option<f64>,
}

impl Default for PassageOptions {
    fn default() -> Self {
        Self {
            energy: true,
            rail_point_offset_m: Some(0.6),
        }
    }
}

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
    /// Slip-area fraction (−).
    pub slip_fraction: Vec<f64>,
    /// Frictional power (W).
    pub frictional_power_w: Vec<f64>,
}

impl Histories {
    /// Appends one contact step: `[t (s), x_c (m), ξ (−), approach (m)]`, the contact
    /// result, and the contact length (grid columns along x with any pressure × `dx`, m).
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
    /// [`PassageEngine::series_compliance`]).
    pub residual_spring_energy_change_j: f64,
    /// Work of the contact forces on the two structures (J): = −(friction + contact energy).
    pub contact_work_j: f64,
}

impl EnergyBalance {
    /// `input + spin work − (stored + dampers + friction + contact and residual-spring
    /// energy)` over the input
    /// (−).
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
        (self.external_work_j + self.spin_work_j + self.convective_work_j - out) / scale
    }
}

/// Everything one passage produces.
#[derive(Clone, Debug)]
pub struct PassageRecord {
    /// Speed (m/s).
    pub speed_m_per_s: f64,
    /// Time step (s).
    pub dt_s: f64,
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
    /// Energy balance (zeros unless [`PassageOptions::energy`]).
    pub energy: EnergyBalance,
    /// Static state: steady creepage ξ₀ (−) and approach δ₀ (m).
    pub static_creepage: f64,
    /// Static approach (m).
    pub static_approach_m: f64,
    /// Number of time steps.
    pub steps: usize,
    /// Wall time of the dynamic phase (s).
    pub seconds: f64,
}

/// The reduced-order engine of one model: modal systems, contact interpolation, loads.
pub struct PassageEngine {
    model: Model,
    frame: ContactFrame,
    track_sys: ModalSystem,
    wheel_sys: ModalSystem,
    rail_line: RailContactLine,
    wheel_contact: WheelContact,
    /// Generalised constant wheel loads: gravity, torque, train resistance.
    wheel_gravity: Vec<f64>,
    wheel_torque: Vec<f64>,
    wheel_drawbar: Vec<f64>,
    /// Columns of the wheel's rigid modes.
    rigid: Vec<usize>,
    wheel_radius_m: f64,
    wheel_load_n: f64,
    zone_m: [f64; 2],
    x_start_m: f64,
    hertz_b_m: f64,
    /// Rail-top node rows for the rail-point record: (plane, rows 3m in global x, y, z).
    track_modes_for_point: Option<(usize, [f64; 3], Vec<f64>)>,
    /// Static Hertz approach at the wheel load (m).
    hertz_approach_m: f64,
    /// Residual flexibility of the truncated track modes at the contact (static correction),
    /// `None` = modal flexibility only.
    residual: Option<ResidualFlexibility>,
    /// The constant series compliance applied, `[c_x, c_t, c_n]` (m/N), from `residual`.
    series_compliance: [f64; 3],
    /// The static start on the smooth rail (contact at steady rolling, its steady result),
    /// once computed: it does not depend on the speed ([`Self::started_contact`]).
    smooth_start: std::sync::Mutex<Option<(TransientRolling, crate::contact::StepResult)>>,
}

fn global_frame() -> ContactFrame {
    ContactFrame {
        x: [1.0, 0.0, 0.0],
        t: [0.0, 1.0, 0.0],
        n: [0.0, 0.0, 1.0],
    }
}

impl PassageEngine {
    /// Builds the engine from a model, its structures and their modal bases (mass-normalised
    /// modes over the free DOFs, frequencies in Hz), the assembled damping matrices, and the
    /// options (the rail-point offset fixes which node is recorded).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        model: &Model,
        track: &TrackStructure,
        track_freqs_hz: &[f64],
        track_modes: &Mat<f64>,
        track_c: faer::sparse::SparseColMatRef<'_, usize, f64>,
        wheel: &WheelStructure,
        wheel_freqs_hz: &[f64],
        wheel_modes: &Mat<f64>,
        wheel_mats: &crate::fe::assembly::FeMatrices,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let frame = ContactFrame::for_inclination(model.rail.inclination);
        let track_sys = ModalSystem::new(track_freqs_hz, track_modes, track_c, RIGID_HZ)?;
        if let Some(i) = track_sys.omega2.iter().position(|&w| w == 0.0) {
            return Err(DynamicsError::TrackNotSupported {
                mode: i,
                omega2_rad2_s2: 0.0,
            });
        }
        let mut wheel_sys =
            ModalSystem::new(wheel_freqs_hz, wheel_modes, wheel_mats.c.as_ref(), RIGID_HZ)?;
        wheel_sys.add_modal_damping(model.wheel.damping_ratio);
        let rigid: Vec<usize> = (0..wheel_sys.len())
            .filter(|&i| wheel_sys.omega2[i] == 0.0)
            .collect();
        let hertz = crate::contact::HertzContact::solve(&crate::contact::HertzInput {
            radius_x_m: model.wheel.radius,
            radius_y_m: model.contact.rail_crown_radius,
            youngs_pa: model.rail.youngs_modulus,
            poisson: model.rail.poisson_ratio,
            load_n: model.vehicle.wheel_load,
        })
        .map_err(DynamicsError::StaticHertz)?;
        let rail_line = RailContactLine::new(track, track_modes, &frame, hertz.b_m)?;
        let wheel_contact = WheelContact::new(wheel, wheel_modes, &frame, hertz.b_m)?;

        // Constant wheel loads as free-DOF vectors, projected on the modes.
        let mw = wheel_modes.ncols();
        let project = |free: &[f64]| -> Vec<f64> {
            let mut g = vec![0.0; mw];
            for (r, &f) in free.iter().enumerate() {
                if f == 0.0 {
                    continue;
                }
                let row = wheel_modes.row(r);
                for i in 0..mw {
                    g[i] += f * row[i];
                }
            }
            g
        };
        let loads = WheelLoads::new(model, wheel, wheel_mats)?;
        let radius = loads.contact_radius_m;
        let wheel_gravity = project(&loads.gravity);
        let wheel_torque = project(&loads.torque);
        let wheel_drawbar = project(&loads.drawbar);
        let w_load = model.vehicle.wheel_load;

        let layout = &track.layout;
        let track_modes_for_point = match opts.rail_point_offset_m {
            None => None,
            Some(off) => {
                let x = layout.solution_zone[0] + off;
                let p = (0..rail_line.planes_x_m.len())
                    .min_by(|&a, &b| {
                        (rail_line.planes_x_m[a] - x)
                            .abs()
                            .total_cmp(&(rail_line.planes_x_m[b] - x).abs())
                    })
                    .unwrap_or(0);
                // The node of the contact line with the largest weight.
                let (node, _) = rail_line.nodes[p]
                    .iter()
                    .copied()
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .ok_or(DynamicsError::MissingNodes {
                        what: "nodes on the contact line",
                    })?;
                let mut rows = vec![0.0; 3 * track_modes.ncols()];
                super::reduced::modal_rows(
                    &[(node, 1.0)],
                    &track.dofmap,
                    track_modes,
                    &global_frame(),
                    &mut rows,
                );
                Some((node, track.mesh.nodes[node], rows))
            }
        };
        Ok(PassageEngine {
            model: model.clone(),
            frame,
            track_sys,
            wheel_sys,
            rail_line,
            wheel_contact,
            wheel_gravity,
            wheel_torque,
            wheel_drawbar,
            rigid,
            wheel_radius_m: radius,
            wheel_load_n: w_load,
            zone_m: layout.solution_zone,
            x_start_m: layout.wheel_start,
            hertz_b_m: hertz.b_m,
            hertz_approach_m: hertz.approach_m,
            track_modes_for_point,
            residual: None,
            series_compliance: [0.0; 3],
            smooth_start: std::sync::Mutex::new(None),
        })
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Number of track and wheel modes.
    pub fn mode_counts(&self) -> (usize, usize) {
        (self.track_sys.len(), self.wheel_sys.len())
    }

    /// The track's modal system.
    pub fn track_system(&self) -> &ModalSystem {
        &self.track_sys
    }

    /// Records the rail-top point at `x_m` (m along the rail) in the following passages
    /// (replacing the one chosen at construction): the running-surface contact line at the
    /// nearest node plane, with the contact's lateral weights across the head, its
    /// displacements turned from the contact frame into global x, y, z.
    pub fn set_rail_point_at(&mut self, x_m: f64) -> Result<(), DynamicsError> {
        let px = &self.rail_line.planes_x_m;
        let p = (0..px.len())
            .min_by(|&a, &b| (px[a] - x_m).abs().total_cmp(&(px[b] - x_m).abs()))
            .ok_or(DynamicsError::MissingNodes {
                what: "rail contact line",
            })?;
        let mt = self.track_sys.len();
        let mut fr = vec![0.0; 3 * mt];
        self.rail_line.rows_at(px[p], &mut fr)?;
        let (t, n) = (self.frame.t, self.frame.n);
        let mut rows = vec![0.0; 3 * mt];
        for i in 0..mt {
            rows[i] = fr[i];
            rows[mt + i] = t[1] * fr[mt + i] + n[1] * fr[2 * mt + i];
            rows[2 * mt + i] = t[2] * fr[mt + i] + n[2] * fr[2 * mt + i];
        }
        let node = self.rail_line.nodes[p]
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |&(k, _)| k);
        let [yc, zc] = self.rail_line.contact_point_yz_m;
        self.track_modes_for_point = Some((node, [px[p], yc, zc], rows));
        Ok(())
    }

    /// The solution zone `[start, end]` (m).
    pub fn zone_m(&self) -> [f64; 2] {
        self.zone_m
    }

    /// The wheel's modal system.
    pub fn wheel_system(&self) -> &ModalSystem {
        &self.wheel_sys
    }

    /// The wheel's contact rows, `3·m_w` values (x, t, n blocks).
    pub fn wheel_contact_rows(&self) -> &[f64] {
        &self.wheel_contact.rows
    }

    /// Distance of the wheel's tread contact node from the axle (m).
    pub fn wheel_radius_m(&self) -> f64 {
        self.wheel_radius_m
    }

    /// The rail's contact line (modal rows of the contact nodes).
    pub fn rail_line(&self) -> &RailContactLine {
        &self.rail_line
    }

    /// The contact frame.
    pub fn frame(&self) -> &ContactFrame {
        &self.frame
    }

    /// The part of the rail the contact travels over in a passage, `[x_start, x_end]` (m),
    /// with room for the contact grid.
    pub fn travel_m(&self) -> [f64; 2] {
        let px = &self.rail_line.planes_x_m;
        let end = (self.zone_m[1] + 0.1).min(px[px.len() - 1]);
        [self.x_start_m.max(px[0]), end]
    }

    /// Sets (or clears) the residual flexibility of the truncated track modes: when set, the
    /// length-weighted mean of its structural part along the travel
    /// ([`ResidualFlexibility::mean_structural_weighted`], x, t, n) is the contact's series
    /// compliance. It must cover [`Self::travel_m`] and belong to this engine's track modes.
    pub fn set_residual_flexibility(
        &mut self,
        r: Option<ResidualFlexibility>,
    ) -> Result<(), DynamicsError> {
        if let Some(r) = &r {
            let [a, b] = self.travel_m();
            if r.modes != self.track_sys.len() || !r.covers(a, b) {
                return Err(DynamicsError::ResidualMismatch {
                    modes: r.modes,
                    start_m: r.planes_x_m[0],
                    end_m: r.planes_x_m[r.planes_x_m.len() - 1],
                    engine_modes: self.track_sys.len(),
                    travel_start_m: a,
                    travel_end_m: b,
                });
            }
        }
        self.series_compliance = r
            .as_ref()
            .map_or([0.0; 3], |r| r.mean_structural_weighted());
        self.residual = r;
        // the static start depends on the series compliance
        *self
            .smooth_start
            .get_mut()
            .unwrap_or_else(|e| e.into_inner()) = None;
        Ok(())
    }

    /// The residual flexibility in use, if any.
    pub fn residual_flexibility(&self) -> Option<&ResidualFlexibility> {
        self.residual.as_ref()
    }

    /// Series compliance of the contact `[c_x, c_y, c_z]` (m/N) in the contact solver's axes
    /// (rolling, lateral tangent t, normal n), zero without a residual: the length-weighted
    /// mean of the structural residual along the travel, the same at every position
    /// ([`ResidualFlexibility::mean_structural_weighted`] says why).
    pub fn series_compliance(&self) -> [f64; 3] {
        self.series_compliance
    }

    /// Receptances of the reduced model at the contact (see [`super::receptance`]): the rail
    /// at `positions_m` (m along the rail; the contact line's rows, the constant residual
    /// compliance of the truncated modes added), the wheel at its contact point, and the
    /// linearised Hertz compliance, at `frequencies_hz` (Hz).
    pub fn contact_receptance(
        &self,
        positions_m: &[f64],
        frequencies_hz: &[f64],
    ) -> Result<super::receptance::ContactReceptance, DynamicsError> {
        use super::receptance::modal_receptance;
        use faer::c64;
        let to3 = |h: &faer::Mat<c64>, add: [f64; 3]| {
            let mut o = [[c64::new(0.0, 0.0); 3]; 3];
            for a in 0..3 {
                for b in 0..3 {
                    o[a][b] = h[(a, b)];
                }
                o[a][a] += c64::new(add[a], 0.0);
            }
            o
        };
        // All positions' rows in one solve: one factorisation per frequency.
        let m = self.track_sys.len();
        let np = positions_m.len();
        let mut rows = vec![0.0; 3 * m * np];
        for (p, &x) in positions_m.iter().enumerate() {
            self.rail_line
                .rows_at(x, &mut rows[3 * m * p..3 * m * (p + 1)])?;
        }
        let r: Vec<&[f64]> = rows.chunks_exact(m).collect();
        let h = modal_receptance(&self.track_sys, &r, frequencies_hz)?;
        let rail = (0..np)
            .map(|p| {
                h.iter()
                    .map(|h| {
                        let block = h.submatrix(3 * p, 3 * p, 3, 3).to_owned();
                        to3(&block, self.series_compliance)
                    })
                    .collect()
            })
            .collect();
        let mw = self.wheel_sys.len();
        let wr: Vec<&[f64]> = self.wheel_contact.rows.chunks_exact(mw).collect();
        let wheel = modal_receptance(&self.wheel_sys, &wr, frequencies_hz)?
            .iter()
            .map(|h| to3(h, [0.0; 3]))
            .collect();
        Ok(super::receptance::ContactReceptance {
            frequencies_hz: frequencies_hz.to_vec(),
            positions_m: positions_m.to_vec(),
            rail,
            wheel,
            // δ = c N^{2/3} ⇒ dδ/dN = 2δ / (3N).
            hertz_compliance_m_per_n: 2.0 * self.hertz_approach_m / (3.0 * self.wheel_load_n),
        })
    }

    /// The elastic wheel modes as the contact sees them: for every wheel mode with ω > 0,
    /// `(index, [r_x², r_n²])`, the squared mass-normalised modal displacements at the wheel's
    /// contact point in the rolling (x) and normal (n) directions (1/kg): the residue of
    /// the mode's pole in the wheel's point receptance `H = Σ r² / (ω_i² − ω² + …)`.
    pub fn wheel_contact_participation(&self) -> Vec<(usize, [f64; 2])> {
        let m = self.wheel_sys.len();
        let r = &self.wheel_contact.rows;
        (0..m)
            .filter(|&i| self.wheel_sys.omega2[i] > 0.0)
            .map(|i| (i, [r[i] * r[i], r[2 * m + i] * r[2 * m + i]]))
            .collect()
    }

    /// The mid-span and the sleeper position nearest the centre of the solution zone (m): the
    /// two positions where the rail's support differs most.
    pub fn midspan_and_sleeper_m(&self) -> [f64; 2] {
        let layout = crate::structure::layout::Layout::new(&self.model);
        let c = 0.5 * (self.zone_m[0] + self.zone_m[1]);
        let nearest = |xs: &mut dyn Iterator<Item = f64>| {
            xs.min_by(|a, b| (a - c).abs().total_cmp(&(b - c).abs()))
                .unwrap_or(c)
        };
        let sl = &layout.sleepers;
        let sleeper = nearest(&mut sl.iter().copied());
        let mid = nearest(&mut sl.windows(2).map(|w| 0.5 * (w[0] + w[1])));
        [mid, sleeper]
    }

    /// Hertz semi-axis across the rail at the static load (m).
    pub fn hertz_b_m(&self) -> f64 {
        self.hertz_b_m
    }

    /// The contact configuration of a passage at `speed_m_per_s`: the model's grid around the
    /// static Hertz patch, and the tangential tolerance [`PASSAGE_TANGENTIAL_TOL`].
    pub fn contact_config(&self, speed_m_per_s: f64) -> Result<TransientConfig, DynamicsError> {
        contact_config_for(&self.model, speed_m_per_s)
    }

    /// The static loads of the contact: normal force `W / cos α` (N), longitudinal force
    /// `μ_t W` (N), and the spin of the coned wheel on the inclined rail `−sin α / R` (1/m).
    fn static_loads(&self) -> (f64, f64, f64) {
        let w = self.wheel_load_n;
        (
            w / self.frame.n[2],
            self.model.contact.traction_coefficient * w,
            self.frame.n[1] / self.wheel_radius_m,
        )
    }

    /// The contact of a passage at `v` (m/s) over `profile`, brought to steady rolling at the
    /// static load ([`steady_contact`], with the engine's series compliance), and its steady
    /// result. On the smooth rail the steady state does not depend on the speed (the contact
    /// state moves by one element per step whatever the speed: [`TransientRolling::set_speed`]),
    /// so it is computed once per engine and cloned: a sweep pays for one static start, and
    /// every passage gets the state bit for bit as if it had computed it itself.
    fn started_contact(
        &self,
        v: f64,
        profile: Option<&RailProfile>,
    ) -> Result<(TransientRolling, crate::contact::StepResult), DynamicsError> {
        let x0 = self.x_start_m;
        let contact_err = |source| DynamicsError::Contact {
            t_s: 0.0,
            x_m: x0,
            source,
        };
        let start = || -> Result<_, DynamicsError> {
            let mut contact =
                passage_contact(&self.model, v, profile.map(|p| (p, self.hertz_approach_m)))?;
            contact
                .set_series_compliance(self.series_compliance)
                .map_err(contact_err)?;
            let heights: Option<Vec<f64>> = profile.map(|p| {
                contact
                    .x_m()
                    .iter()
                    .map(|&xi| p.height_at(x0 + xi))
                    .collect()
            });
            let (f_n0, f_l0, spin) = self.static_loads();
            let st = steady_contact(&mut contact, f_n0, f_l0, spin, heights.as_deref(), x0)?;
            Ok((contact, st))
        };
        if profile.is_some() {
            return start();
        }
        check_speed(v)?;
        let mut cached = self.smooth_start.lock().unwrap_or_else(|e| e.into_inner());
        let (mut contact, st) = match cached.as_ref() {
            Some(c) => c.clone(),
            None => {
                let c = start()?;
                *cached = Some(c.clone());
                c
            }
        };
        drop(cached);
        contact.set_speed(v).map_err(contact_err)?;
        Ok((contact, st))
    }

    /// Runs one passage at `speed_m_per_s` (m/s) over the rail profile (`None` = smooth).
    pub fn passage(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
        opts: &PassageOptions,
        progress: Option<&indicatif::ProgressBar>,
    ) -> Result<PassageRecord, DynamicsError> {
        let v = speed_m_per_s;
        let (mut contact, st) = self.started_contact(v, profile)?;
        let dt = contact.time_step_s();
        let dx = v * dt;
        let mut tr = ModalVerlet::new(&self.track_sys, dt)?;
        let mut wh = ModalVerlet::new(&self.wheel_sys, dt)?;
        let (mt, mw) = (tr.len(), wh.len());
        let (f_n0, f_l0, spin) = self.static_loads();
        let x0 = self.x_start_m;
        let [z0, z1] = self.zone_m;
        let half_grid = contact.config().grid.half_length_x_m;
        let x_end = z1 + half_grid + 2.0 * dx;
        let n_steps = ((x_end - x0) / dx).ceil() as usize;
        let nx = contact.config().grid.nx;
        let xs: Vec<f64> = contact.x_m().to_vec();
        let mut heights = vec![0.0; nx];
        let fill_heights = |xc: f64, h: &mut [f64]| {
            if let Some(p) = profile {
                for (hi, &xi) in h.iter_mut().zip(&xs) {
                    *hi = p.height_at(xc + xi);
                }
            }
        };

        let series_c = self.series_compliance;
        // --- Static start (steady rolling at the static load): `st`, above.
        let (xi0, delta0) = (st.creepage, st.approach_m);

        let mut rr = vec![0.0; 3 * mt];
        let mut slopes = vec![0.0; 3 * mt];
        self.rail_line.rows_at(x0, &mut rr)?;
        let wr = &self.wheel_contact.rows;
        // Force on the wheel in frame components (x, t, n).
        let f0 = [f_l0, 0.0, f_n0];
        let mut ft = vec![0.0; mt];
        let mut fw = vec![0.0; mw];
        let mut fw_const = vec![0.0; mw];
        for i in 0..mw {
            fw_const[i] = self.wheel_gravity[i] + self.wheel_torque[i] + self.wheel_drawbar[i];
        }
        let gen_forces = |f: &[f64; 3], rr: &[f64], ft: &mut [f64], fw: &mut [f64]| {
            for i in 0..mt {
                ft[i] = -(f[0] * rr[i] + f[1] * rr[mt + i] + f[2] * rr[2 * mt + i]);
            }
            for i in 0..mw {
                fw[i] = fw_const[i] + f[0] * wr[i] + f[1] * wr[mw + i] + f[2] * wr[2 * mw + i];
            }
        };
        gen_forces(&f0, &rr, &mut ft, &mut fw);
        let qt0: Vec<f64> = (0..mt).map(|i| ft[i] / self.track_sys.omega2[i]).collect();
        let mut qw0 = vec![0.0; mw];
        for i in 0..mw {
            if self.wheel_sys.omega2[i] > 0.0 {
                qw0[i] = fw[i] / self.wheel_sys.omega2[i];
            }
        }
        // Rigid placement: observations (contact x, contact n, axle x) of the rigid modes.
        let nr = self.rigid.len();
        let obs = |i: usize| -> [f64; 3] { [wr[i], wr[2 * mw + i], self.wheel_contact.axle_x[i]] };
        let u_rail_n = dot(&rr[2 * mt..], &qt0);
        let u_wheel_n_el = dot(&wr[2 * mw..], &qw0);
        let target_n = u_rail_n - delta0 - u_wheel_n_el;
        let mut vw0 = vec![0.0; mw];
        if nr > 0 {
            let o: Vec<[f64; 3]> = self.rigid.iter().map(|&i| obs(i)).collect();
            let c = rigid_least_norm(&o, [0.0, target_n, 0.0]);
            for (k, &i) in self.rigid.iter().enumerate() {
                qw0[i] = c[k];
            }
            let c = rigid_least_norm(&o, [xi0 * v, 0.0, 0.0]);
            for (k, &i) in self.rigid.iter().enumerate() {
                vw0[i] = c[k];
            }
        }
        tr.set_state(&qt0, &vec![0.0; mt], &ft);
        wh.set_state(&qw0, &vw0, &fw);

        // --- Records.
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
            &mut h.slip_fraction,
            &mut h.frictional_power_w,
        ] {
            vct.reserve(n_steps);
        }
        let mut rail_point =
            self.track_modes_for_point
                .as_ref()
                .map(|(_, pos, _)| RailPointRecord {
                    position_m: *pos,
                    displacement_m: Vec::with_capacity(n_steps),
                });
        let nbins = ((z1 - z0) / dx).round().max(1.0) as usize;
        let mut wear = WearAccumulator::new(&contact, z0, nbins);
        let mut eb = EnergyBalance::default();
        let e_start =
            tr.kinetic_energy() + tr.strain_energy() + wh.kinetic_energy() + wh.strain_energy();
        // Elastic energy of the half-space (Hertz estimate) on the approach without the
        // residual spring's share c_z F_N.
        let hertz_energy = |f: f64, d: f64, cz: f64| 0.4 * f * (d - cz * f).max(0.0);
        let e_contact_start = hertz_energy(st.normal_force_n, st.approach_m, series_c[2]);
        let f_start = [st.fx_n, st.fy_n, st.normal_force_n];
        let mut f_end = f_start;
        let mut p_damp_prev = if opts.energy {
            tr.damping_power() + wh.damping_power()
        } else {
            0.0
        };
        let mut p_contact_prev = {
            // Contact power at the start: F · (v_w − v_r).
            let vw_x = dot(&wr[..mw], &wh.v);
            f_l0 * vw_x
        };
        let mut qw_prev = wh.q.clone();
        let mut last_delta = st.approach_m;
        let t_wall = Instant::now();
        if let Some(pb) = progress {
            pb.set_length(n_steps as u64);
            pb.set_position(0);
        }
        for n in 1..=n_steps {
            let t = n as f64 * dt;
            let xc = x0 + v * t;
            tr.advance_displacement();
            wh.advance_displacement();
            self.rail_line.rows_at(xc, &mut rr)?;
            let mut u_r = [0.0; 3];
            let mut v_r = [0.0; 3];
            let mut u_w = [0.0; 3];
            let mut v_w = [0.0; 3];
            for d in 0..3 {
                let r = &rr[d * mt..(d + 1) * mt];
                let mut su = 0.0;
                let mut sv = 0.0;
                for i in 0..mt {
                    su += r[i] * tr.q[i];
                    sv += r[i] * tr.predicted_velocity(i);
                }
                u_r[d] = su;
                v_r[d] = sv;
                let r = &wr[d * mw..(d + 1) * mw];
                let mut su = 0.0;
                let mut sv = 0.0;
                for i in 0..mw {
                    su += r[i] * wh.q[i];
                    sv += r[i] * wh.predicted_velocity(i);
                }
                u_w[d] = su;
                v_w[d] = sv;
            }
            if let (Some(r), ResidualVariation::Consistent) =
                (&self.residual, self.model.run.residual_variation)
            {
                contact
                    .set_series_compliance(r.consistent_at(xc)?)
                    .map_err(|source| DynamicsError::Contact {
                        t_s: t,
                        x_m: xc,
                        source,
                    })?;
            }
            let delta = u_r[2] - u_w[2];
            let xi = (v_w[0] - v_r[0]) / v;
            let eta = (v_w[1] - v_r[1]) / v;
            fill_heights(xc, &mut heights);
            let r = contact
                .step(&StepInputs {
                    normal: NormalInput::Approach(delta),
                    longitudinal: Longitudinal::Creepage(xi),
                    lateral_creepage: eta,
                    spin_per_m: spin,
                    rail_height_m: profile.map(|_| &heights[..]),
                })
                .map_err(|source| DynamicsError::Contact {
                    t_s: t,
                    x_m: xc,
                    source,
                })?;
            if xc - half_grid < z1 && xc + half_grid > z0 {
                wear.add_step(&contact, xc);
            }
            let f = [r.fx_n, r.fy_n, r.normal_force_n];
            f_end = f;
            gen_forces(&f, &rr, &mut ft, &mut fw);
            tr.complete(&ft);
            wh.complete(&fw);
            if !(tr.q.iter().all(|x| x.is_finite()) && wh.q.iter().all(|x| x.is_finite())) {
                return Err(DynamicsError::Diverged {
                    t_s: t,
                    x_m: xc,
                    what: "modal coordinates".into(),
                });
            }
            if opts.energy {
                // Constant wheel loads: exact work g · Δq.
                for i in 0..mw {
                    let dq = wh.q[i] - qw_prev[i];
                    eb.gravity_work_j += self.wheel_gravity[i] * dq;
                    eb.torque_work_j += self.wheel_torque[i] * dq;
                    eb.external_work_j += fw_const[i] * dq;
                }
                qw_prev.copy_from_slice(&wh.q);
                let p_damp = tr.damping_power() + wh.damping_power();
                eb.damper_dissipation_j += 0.5 * dt * (p_damp + p_damp_prev);
                p_damp_prev = p_damp;
                // Contact power with the corrected velocities.
                let mut p_c = 0.0;
                for d in 0..3 {
                    let vr = dot(&rr[d * mt..(d + 1) * mt], &tr.v);
                    let vw = dot(&wr[d * mw..(d + 1) * mw], &wh.v);
                    p_c += f[d] * (vw - vr);
                }
                eb.contact_work_j += 0.5 * dt * (p_c + p_contact_prev);
                p_contact_prev = p_c;
                eb.frictional_work_j += r.frictional_power_w * dt;
                eb.spin_work_j -= v * spin * r.mz_nm * dt;
                self.rail_line.row_slopes_at(xc, &mut slopes)?;
                let dun = dot(&slopes[2 * mt..], &tr.q);
                let dut = dot(&slopes[mt..2 * mt], &tr.q);
                eb.convective_work_j += v * (f[2] * dun + f[1] * dut) * dt;
            }
            last_delta = r.approach_m;
            h.push_step(&contact, &r, [t, xc, xi, delta], dx);
            if let (Some(rec), Some((_, _, rows))) =
                (rail_point.as_mut(), self.track_modes_for_point.as_ref())
            {
                rec.displacement_m.push([
                    dot(&rows[..mt], &tr.q),
                    dot(&rows[mt..2 * mt], &tr.q),
                    dot(&rows[2 * mt..], &tr.q),
                ]);
            }
            if let Some(pb) = progress {
                if n % 64 == 0 {
                    pb.set_position(n as u64);
                }
            }
        }
        if opts.energy {
            let e_end =
                tr.kinetic_energy() + tr.strain_energy() + wh.kinetic_energy() + wh.strain_energy();
            eb.stored_change_j = e_end - e_start;
            eb.contact_energy_change_j =
                hertz_energy(f_end[2], last_delta, series_c[2]) - e_contact_start;
            eb.residual_spring_energy_change_j = (0..3)
                .map(|d| 0.5 * series_c[d] * (f_end[d] * f_end[d] - f_start[d] * f_start[d]))
                .sum();
        }
        let mut w = vec![0.0; nbins];
        wear.work_x(&mut w);
        Ok(PassageRecord {
            speed_m_per_s: v,
            dt_s: dt,
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

/// The engine of a model with its classified bases, built once and reused for any number of
/// passages (speeds, rail profiles).
pub struct PreparedModel {
    /// The engine.
    pub engine: PassageEngine,
    /// Track modes: frequencies (Hz) and classification.
    pub track_frequencies_hz: Vec<f64>,
    /// Track mode classes.
    pub track_classes: Vec<crate::eigen::classify::TrackModeClass>,
    /// Wheel modes: frequencies (Hz).
    pub wheel_frequencies_hz: Vec<f64>,
    /// Seconds spent on the modal bases (0 when both came from the cache… plus loading).
    pub modal_seconds: f64,
    /// True when both bases came from the cache.
    pub cached: bool,
}

impl PreparedModel {
    /// Builds the track and wheel, loads or computes their modes below `model.run.fmax`
    /// (cached in `cache`), assembles the damping, and builds the engine.
    pub fn new(
        model: &Model,
        cache: &crate::eigen::cache::ModalCache,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let track = TrackStructure::build(model)?;
        let fmax = model.run.fmax;
        let tb = crate::eigen::basis::track_basis(model, &track, cache, fmax)?;
        let key = crate::eigen::basis::cache_key(model, fmax, "track")?;
        Self::with_track_basis(model, &track, tb, cache, Some(&key), opts)
    }

    /// As [`Self::new`] with the track's modal basis given (e.g. a substructured one,
    /// [`crate::eigen::substructure`]); the wheel's basis comes from `cache`. The residual
    /// flexibility (when the model asks for it) is cached with the track entry of
    /// `residual_key`, or computed without caching when `None`.
    pub fn with_track_basis(
        model: &Model,
        track: &TrackStructure,
        tb: crate::eigen::basis::ModalBasis<crate::eigen::classify::TrackModeClass>,
        cache: &crate::eigen::cache::ModalCache,
        residual_key: Option<&crate::eigen::cache::CacheKey>,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        use crate::eigen::basis::wheel_basis;

        let wheel = WheelStructure::build(model)?;
        let fmax = model.run.fmax;
        let wb = wheel_basis(model, &wheel, cache, fmax)?;
        let (tm, _) = track.assemble()?;
        let (wm, _) = wheel.assemble()?;
        // The wheel floats: its rigid modes' frequencies from the Rayleigh quotient, which is
        // 0 to round-off where the eigen-solver's eigenvalue may not be.
        let wheel_hz = super::reduced::rayleigh_frequencies_hz(wm.k.as_ref(), &wb.modes);
        let mut engine = PassageEngine::new(
            model,
            track,
            &tb.frequencies_hz,
            &tb.modes,
            tm.c.as_ref(),
            &wheel,
            &wheel_hz,
            &wb.modes,
            &wm,
            opts,
        )?;
        if model.run.residual_flexibility {
            let args = (
                &engine.rail_line,
                &engine.frame,
                &engine.track_sys.omega2,
                engine.hertz_b_m,
                engine.travel_m(),
            );
            let r = match residual_key {
                Some(key) => {
                    super::residual::cached_residual(
                        cache,
                        key,
                        track,
                        tm.k.as_ref(),
                        args.0,
                        args.1,
                        args.2,
                        args.3,
                        args.4,
                    )?
                    .0
                }
                None => super::residual::ResidualFlexibility::compute(
                    track,
                    &super::residual::StiffnessFactor::new(tm.k.as_ref())?,
                    args.0,
                    args.1,
                    args.2,
                    args.4[0],
                    args.4[1],
                )?,
            };
            engine.set_residual_flexibility(Some(r))?;
        }
        Ok(PreparedModel {
            engine,
            modal_seconds: tb.seconds + wb.seconds,
            cached: tb.cached && wb.cached,
            track_frequencies_hz: tb.frequencies_hz,
            track_classes: tb.classes,
            wheel_frequencies_hz: wheel_hz,
        })
    }

    /// Frequencies (Hz) of the track's longitudinal-compression modes.
    pub fn longitudinal_compression_hz(&self) -> Vec<f64> {
        use crate::eigen::classify::TrackFamily;
        self.track_frequencies_hz
            .iter()
            .zip(&self.track_classes)
            .filter(|(_, c)| c.family == TrackFamily::LongitudinalCompression)
            .map(|(&f, _)| f)
            .collect()
    }

    /// Frequencies (Hz) of the wheel modes the contact sees strongly: elastic wheel modes
    /// whose squared mass-normalised displacement at the wheel's contact point, in the rolling
    /// (x) or the normal (n) direction, is at least `share` (−, e.g. 0.1) of the largest one
    /// in that direction ([`PassageEngine::wheel_contact_participation`]). These are the poles
    /// of the wheel's contact receptance with the largest residues. Modes within 0.5 % of
    /// the previous one kept (the pairs of an axisymmetric wheel) give one frequency.
    pub fn wheel_contact_modes_hz(&self, share: f64) -> Vec<f64> {
        let p = self.engine.wheel_contact_participation();
        let max = |d: usize| p.iter().map(|(_, r)| r[d]).fold(0.0, f64::max);
        let (mx, mn) = (max(0), max(1));
        let mut out: Vec<f64> = Vec::new();
        for &(i, r) in &p {
            if (mx > 0.0 && r[0] >= share * mx) || (mn > 0.0 && r[1] >= share * mn) {
                let f = self.wheel_frequencies_hz[i];
                // A pair of modes (sine and cosine about the contact) is one line.
                if out.last().is_none_or(|&g| f > g * 1.005) {
                    out.push(f);
                }
            }
        }
        out
    }

    /// Frequencies (Hz) of the track's vertical-bending modes.
    pub fn vertical_bending_hz(&self) -> Vec<f64> {
        use crate::eigen::classify::TrackFamily;
        self.track_frequencies_hz
            .iter()
            .zip(&self.track_classes)
            .filter(|(_, c)| c.family == TrackFamily::VerticalBending)
            .map(|(&f, _)| f)
            .collect()
    }
}

impl super::PassageRunner for PreparedModel {
    fn prepared(&self) -> Option<&PreparedModel> {
        Some(self)
    }

    fn run(
        &self,
        speed_kmh: f64,
        profile: Option<&RailProfile>,
    ) -> Result<super::PassageSummary, DynamicsError> {
        let opts = PassageOptions {
            energy: false,
            rail_point_offset_m: None,
        };
        let rec = self
            .engine
            .passage(crate::units::kmh_to_ms(speed_kmh), profile, &opts, None)?;
        super::analysis::summarise(&rec)
    }
}

/// The contact grid for a passage over a rail profile of peak-to-trough `ptp_m` (m): the
/// model's grid (`contact.grid_margin` × the Hertz semi-axes) covers the static patch on a
/// smooth rail, but over a corrugation the crests ahead of and behind the patch can touch.
/// The undeformed gap `x²/(2R_x) − (rail height)` can close within the static approach
/// `δ_H` only where `x²/(2R_x) ≤ δ_H + ptp`, so the grid is lengthened along x to
/// `L_x ≥ √(2 R_x (δ_H + ptp))` with the **same element size** (hence the same time step
/// `Δt = Δx/V`, so passages over different trial amplitudes stay comparable). Never shrinks
/// the grid; the lateral extent is unchanged (the profile varies along x only).
pub fn grid_for_profile(grid: GridSpec, radius_x_m: f64, approach_m: f64, ptp_m: f64) -> GridSpec {
    let need = (2.0 * radius_x_m * (approach_m + ptp_m.max(0.0))).sqrt();
    if !(need.is_finite() && need > grid.half_length_x_m) {
        return grid;
    }
    let dx = grid.dx();
    let nx = ((2.0 * need / dx).ceil() as usize).max(grid.nx);
    GridSpec {
        nx,
        half_length_x_m: 0.5 * nx as f64 * dx,
        ..grid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference contact (R 0.46 m on the R300 crown, 100 kN: a = 7.162 mm, δ_H = 104.1
    /// µm) on the default grid (44 elements, margin 1.4): closed-form half-length
    /// √(2 R (δ_H + ptp)), element size kept.
    #[test]
    fn grid_grows_with_the_corrugation_depth_at_fixed_element_size() {
        let (r, a, delta) = (0.46, 7.162e-3, 104.1e-6);
        let g = GridSpec {
            nx: 44,
            ny: 32,
            half_length_x_m: 1.4 * a,
            half_length_y_m: 1.4 * 5.387e-3,
        };
        // smooth rail: √(2Rδ) = 9.79 mm < 10.03 mm → unchanged
        assert_eq!(grid_for_profile(g, r, delta, 0.0), g);
        for (ptp, nx) in [(10e-6, 45), (160e-6, 69)] {
            let w = grid_for_profile(g, r, delta, ptp);
            let need = (2.0 * r * (delta + ptp)).sqrt();
            assert_eq!(w.nx, nx, "ptp {ptp}");
            assert!(w.half_length_x_m >= need && w.half_length_x_m < need + w.dx());
            assert!((w.dx() - g.dx()).abs() < 1e-15);
            assert_eq!((w.ny, w.half_length_y_m), (g.ny, g.half_length_y_m));
        }
        // never shrinks, bad input leaves the grid alone
        assert_eq!(grid_for_profile(g, r, f64::NAN, 1e-4), g);
    }
}

/// The constant loads on the wheel substructure as free-DOF vectors (N): gravity on every
/// mass, the driving torque `T = μ_t W R` as a pure couple on the journal nodes, and the
/// train's resistance `−μ_t W` on the journal nodes (docs/theory.md §5.3). Shared by the
/// reduced and the explicit passage so that both apply the same loads.
#[derive(Clone, Debug)]
pub struct WheelLoads {
    /// Gravity `M (−g e_z)` (N).
    pub gravity: Vec<f64>,
    /// The driving torque's journal forces (N).
    pub torque: Vec<f64>,
    /// The train's resistance on the journals (N).
    pub drawbar: Vec<f64>,
    /// Distance of the tread contact node from the axle (m).
    pub contact_radius_m: f64,
}

impl WheelLoads {
    /// The loads of `model` on `wheel` with its assembled matrices.
    pub fn new(
        model: &Model,
        wheel: &WheelStructure,
        wheel_mats: &crate::fe::assembly::FeMatrices,
    ) -> Result<Self, DynamicsError> {
        let nf = wheel.dofmap.n_free();
        // Gravity: M · (−g e_z) over the free DOFs (mass matrix row sums in z).
        let g = model.vehicle.gravity;
        let mut gravity = vec![0.0; nf];
        {
            let m = wheel_mats.m.as_ref();
            let mut ez = vec![0.0; nf];
            for node in 0..wheel.dofmap.n_nodes() {
                if let Some(r) = wheel.dofmap.free_index(3 * node + 2) {
                    ez[r] = 1.0;
                }
            }
            let cols = m.symbolic().col_ptr();
            let rows = m.symbolic().row_idx();
            let vals = m.val();
            for j in 0..m.ncols() {
                for p in cols[j]..cols[j + 1] {
                    gravity[rows[p]] -= g * vals[p] * ez[j];
                }
            }
        }
        let f_l0 = model.contact.traction_coefficient * model.vehicle.wheel_load;
        let bearing = wheel.topology.bearing_nodes();
        // Contact radius: the tread contact node's distance from the axle.
        let cn = wheel.topology.contact_node();
        let radius = -wheel.mesh.nodes[cn][2];
        // Torque T = F_L0 · R about +y: forces c (ŷ × r_i) on the journal nodes minus their
        // resultant, spread with the balanced weights (which has no moment about the axle), so
        // the load is a pure couple whatever the grading of the node angles.
        let wj = crate::structure::wheel::balanced_journal_weights(&wheel.mesh, &bearing);
        let nw = wheel.dofmap.n_dofs();
        let mut torque_full = vec![0.0; nw];
        let r2: f64 = bearing
            .iter()
            .map(|&b| {
                let p = wheel.mesh.nodes[b];
                p[0] * p[0] + p[2] * p[2]
            })
            .sum();
        if r2 <= 0.0 {
            return Err(DynamicsError::JournalsOnAxis);
        }
        let t_y = f_l0 * radius;
        let (mut sx, mut sz) = (0.0, 0.0);
        for &b in &bearing {
            let p = wheel.mesh.nodes[b];
            torque_full[3 * b] += t_y / r2 * p[2];
            torque_full[3 * b + 2] += -t_y / r2 * p[0];
            sx += t_y / r2 * p[2];
            sz += -t_y / r2 * p[0];
        }
        let mut drawbar_full = vec![0.0; nw];
        for (&b, &w) in bearing.iter().zip(&wj) {
            torque_full[3 * b] -= w * sx;
            torque_full[3 * b + 2] -= w * sz;
            drawbar_full[3 * b] -= f_l0 * w;
        }
        let restrict = |full: &[f64]| -> Vec<f64> {
            let mut out = vec![0.0; nf];
            for (d, &f) in full.iter().enumerate() {
                if let Some(r) = wheel.dofmap.free_index(d) {
                    out[r] = f;
                }
            }
            out
        };
        Ok(WheelLoads {
            gravity,
            torque: restrict(&torque_full),
            drawbar: restrict(&drawbar_full),
            contact_radius_m: radius,
        })
    }

    /// Gravity + torque + resistance (N).
    pub fn total(&self) -> Vec<f64> {
        (0..self.gravity.len())
            .map(|i| self.gravity[i] + self.torque[i] + self.drawbar[i])
            .collect()
    }
}

/// The contact configuration of a passage of `model` at `speed_m_per_s` (m/s) under the wheel
/// load: the model's grid around the static Hertz patch, and the tangential tolerance
/// [`PASSAGE_TANGENTIAL_TOL`]. The reduced and the explicit passage use it alike.
pub fn contact_config_for(
    model: &Model,
    speed_m_per_s: f64,
) -> Result<TransientConfig, DynamicsError> {
    let m = model;
    let mut cfg = TransientConfig::around_hertz(
        m.wheel.radius,
        m.contact.rail_crown_radius,
        m.rail.youngs_modulus,
        m.rail.poisson_ratio,
        m.contact.friction,
        speed_m_per_s,
        m.vehicle.wheel_load,
        m.contact.grid_nx,
        m.contact.grid_ny,
        m.contact.grid_margin,
    )
    .map_err(DynamicsError::ContactGrid)?;
    cfg.tangential_tol = PASSAGE_TANGENTIAL_TOL;
    Ok(cfg)
}

/// The transient contact of a passage of `model` at `speed_m_per_s` (m/s, finite and > 0):
/// [`contact_config_for`], with the grid lengthened for a rail profile `(profile, static Hertz
/// approach (m))` by [`grid_for_profile`]. The reduced and the explicit passage use it alike.
pub fn passage_contact(
    model: &Model,
    speed_m_per_s: f64,
    profile: Option<(&RailProfile, f64)>,
) -> Result<TransientRolling, DynamicsError> {
    check_speed(speed_m_per_s)?;
    let mut cfg = contact_config_for(model, speed_m_per_s)?;
    if let Some((p, approach_m)) = profile {
        cfg.grid = grid_for_profile(cfg.grid, cfg.radius_x_m, approach_m, p.peak_to_trough_m());
    }
    TransientRolling::new(cfg).map_err(DynamicsError::ContactGrid)
}

/// A passage's speed must be finite and > 0 (m/s).
fn check_speed(speed_m_per_s: f64) -> Result<(), DynamicsError> {
    if speed_m_per_s > 0.0 && speed_m_per_s.is_finite() {
        Ok(())
    } else {
        Err(DynamicsError::OutOfRange {
            name: "speed (m/s)",
            value: speed_m_per_s,
            expected: "finite and > 0",
        })
    }
}

/// Brings the contact to steady rolling at the static load (normal force `f_n0`, longitudinal
/// force `f_l0`, N) by stepping with constant inputs until the creepage settles (relative
/// change ≤ 1e-6, at most 20 grid lengths): the static start of a passage.
pub fn steady_contact(
    contact: &mut TransientRolling,
    f_n0: f64,
    f_l0: f64,
    spin_per_m: f64,
    heights: Option<&[f64]>,
    x0: f64,
) -> Result<crate::contact::StepResult, DynamicsError> {
    let nx = contact.config().grid.nx;
    let mut res = None;
    let mut prev_xi = f64::NAN;
    for k in 0..(20 * nx) {
        let r = contact
            .step(&StepInputs {
                normal: NormalInput::Force(f_n0),
                longitudinal: Longitudinal::Force(f_l0),
                lateral_creepage: 0.0,
                spin_per_m,
                rail_height_m: heights,
            })
            .map_err(|source| DynamicsError::Contact {
                t_s: 0.0,
                x_m: x0,
                source,
            })?;
        let done = k > 2 * nx && (r.creepage - prev_xi).abs() <= 1e-6 * r.creepage.abs().max(1e-6);
        prev_xi = r.creepage;
        res = Some(r);
        if done {
            break;
        }
    }
    res.ok_or(DynamicsError::MissingNodes {
        what: "columns in the contact grid",
    })
}

/// The least-norm combination of the wheel's rigid modes that meets three observations:
/// `o[k]` holds what rigid mode `k` shows at (contact x, contact n, axle x); returns the
/// mode coefficients `c = Oᵀ (O Oᵀ)⁻¹ b` (a tiny Tikhonov term guards against rank loss).
pub fn rigid_least_norm(o: &[[f64; 3]], b: [f64; 3]) -> Vec<f64> {
    let mut g = [[0.0; 3]; 3];
    for oi in o {
        for a in 0..3 {
            for c in 0..3 {
                g[a][c] += oi[a] * oi[c];
            }
        }
    }
    let tr_g = g[0][0] + g[1][1] + g[2][2];
    for (a, row) in g.iter_mut().enumerate() {
        row[a] += 1e-12 * tr_g;
    }
    let m = nalgebra::Matrix3::from_fn(|r, c| g[r][c]);
    let y = m
        .lu()
        .solve(&nalgebra::Vector3::new(b[0], b[1], b[2]))
        .unwrap_or_else(nalgebra::Vector3::zeros);
    o.iter()
        .map(|ok| ok[0] * y[0] + ok[1] * y[1] + ok[2] * y[2])
        .collect()
}

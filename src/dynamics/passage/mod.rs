//! One passage of the wheel over the track (docs/theory.md §7).
//!
//! # The coupled problem
//! Track modes `q_t` and wheel modes `q_w` (see [`super::reduced`]) each obey
//! `q̈ + C_q q̇ + Ω² q = Φᵀ f`, integrated by [`super::integrator::ModalVerlet`] with the
//! time step of the contact grid, `Δt = Δx / V` (docs/theory.md §6.5: material moves one grid
//! element per step in Kalker's transient theory), in sub-steps when that step is too long
//! for the highest mode kept (the contact force of `t_n` held over them, §7.2). At each step:
//!
//! 1. both substructures advance their displacements to `t_{n+1}`;
//! 2. the contact point moves to `x_c = x_0 + V t_{n+1}` on the rail; the rail's
//!    displacement and (predicted) velocity there, and the wheel's at its tread contact
//!    point, are interpolated from the modes (frame x, t, n);
//! 3. the contact inputs: rigid approach `δ = (u_rail − u_wheel)·n` (the rail-top profile
//!    enters the contact solver's gap, column by column); creepages
//!    `ξ = (u̇_wheel,x − u̇_rail,x)/V`, `η = (u̇_wheel,t − u̇_rail,t)/V` — the rail's
//!    longitudinal vibration at the contact enters here — from the velocities at `t_{n+1}`,
//!    or with `run.creepage = "increment"` from the displacement increments over the step
//!    divided by `VΔt`; and the spin of the coned wheel on the inclined rail
//!    `φ = −sin α / R` (1/m);
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
//! # Start (`run.start`, docs/theory.md §7.5)
//! The contact is first brought to steady rolling at the static load (normal force
//! `W / cos α`, longitudinal force `μ_t W`), which gives the steady creepage ξ₀ and approach
//! δ₀; the track and the wheel's elastic modes take their static deflection under these
//! forces (exact modal static solution), the wheel's rigid modes are placed so that the
//! approach is δ₀ and turned so that the creepage is ξ₀. Results are read in the solution
//! zone, from `run.solution_zone_offset` after the start. The start from rest
//! (`run.start = "rest"`) does the same with no longitudinal force (free rolling under the
//! static vertical load, no driving torque, no train resistance); the torque and the
//! resistance come on as a step when the contact reaches `run.rest_start_distance` before
//! the zone.

use std::time::Instant;

use faer::Mat;

use super::integrator::ModalVerlet;
use super::record::{Histories, PassageRecord, WidenedGrid};
use super::reduced::{dot, ContactFrame, ModalSystem, RailContactLine, WheelContact};
use super::residual::ResidualFlexibility;
use super::setup::{
    check_profile_on_travel, check_speed, contact_config_for, passage_contact, passage_grid,
    rail_under_contact_m, rigid_least_norm, run_widening_grid, start_longitudinal_force_n,
    steady_contact, torque_onset_m, GridWidening, ProfileOnRail, WheelLoads,
};
use super::wheel_residual::WheelResidual;
use ledger::{Ledger, LedgerStep};
use overlap::DampingOverlap;

mod ledger;
mod overlap;
mod run;
mod spin;
mod step;
use super::{DynamicsError, RailProfile};
use crate::contact::WearAccumulator;
use crate::contact::{TransientConfig, TransientRolling};
use crate::model::{CreepageKind, Model, ResidualVariation, StartKind};
use crate::structure::{TrackStructure, WheelStructure};
use step::{check_finite, RoadAhead};

/// Frequencies below this are rigid-body modes (Hz).
pub const RIGID_HZ: f64 = 0.5;

pub use crate::passage::PassageOptions;

/// The reduced-order engine of one model: modal systems, contact interpolation, loads.
pub struct PassageEngine {
    model: Model,
    pub(super) frame: ContactFrame,
    pub(super) track_sys: ModalSystem,
    wheel_sys: ModalSystem,
    pub(super) rail_line: RailContactLine,
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
    pub(super) hertz_b_m: f64,
    /// Rail-top node rows for the rail-point record: (plane, rows 3m in global x, y, z).
    track_modes_for_point: Option<(usize, [f64; 3], Vec<f64>)>,
    /// Static Hertz approach at the wheel load (m).
    hertz_approach_m: f64,
    /// Residual flexibility of the truncated track modes at the contact (static correction),
    /// `None` = modal flexibility only.
    residual: Option<ResidualFlexibility>,
    /// The wheel's residual flexibility at the contact, `None` = modal flexibility only.
    wheel_residual: Option<WheelResidual>,
    /// The constant series compliance applied, `[c_x, c_t, c_n]` (m/N): the rail's from
    /// `residual` plus the wheel's structural residual from `wheel_residual`.
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

/// The track as [`PassageEngine::new`] takes it: the structure, its modal basis and its
/// assembled damping matrix.
#[derive(Clone, Copy)]
pub struct TrackInput<'a> {
    /// The track's FE structure.
    pub structure: &'a TrackStructure,
    /// Natural frequencies of the basis (Hz), ascending.
    pub frequencies_hz: &'a [f64],
    /// Mass-normalised modes over the free DOFs (n × m).
    pub modes: &'a Mat<f64>,
    /// The assembled damping matrix over the free DOFs (N·s/m).
    pub damping: faer::sparse::SparseColMatRef<'a, usize, f64>,
}

/// The wheel as [`PassageEngine::new`] takes it: the structure, its modal basis and its
/// assembled matrices (the damping, and the mass for the constant loads).
#[derive(Clone, Copy)]
pub struct WheelInput<'a> {
    /// The wheel's FE structure.
    pub structure: &'a WheelStructure,
    /// Natural frequencies of the basis (Hz), ascending; the rigid modes' 0 to round-off.
    pub frequencies_hz: &'a [f64],
    /// Mass-normalised modes over the free DOFs (n × m).
    pub modes: &'a Mat<f64>,
    /// The wheel's assembled K, M, C.
    pub matrices: &'a crate::fe::assembly::FeMatrices,
}

impl PassageEngine {
    /// Builds the engine from a model, its track and wheel with their modal bases and
    /// matrices, and the options (the rail-point offset fixes which node is recorded).
    pub fn new(
        model: &Model,
        track_in: TrackInput<'_>,
        wheel_in: WheelInput<'_>,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let TrackInput {
            structure: track,
            frequencies_hz: track_freqs_hz,
            modes: track_modes,
            damping: track_c,
        } = track_in;
        let WheelInput {
            structure: wheel,
            frequencies_hz: wheel_freqs_hz,
            modes: wheel_modes,
            matrices: wheel_mats,
        } = wheel_in;
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
        let hertz = super::setup::static_hertz(model, model.vehicle.wheel_load)?;
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
                    .ok_or(DynamicsError::Passage(
                        crate::passage::PassageError::MissingNodes {
                            what: "nodes on the contact line",
                        },
                    ))?;
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
            wheel_residual: None,
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
            .ok_or(DynamicsError::Passage(
                crate::passage::PassageError::MissingNodes {
                    what: "rail contact line",
                },
            ))?;
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
    pub(crate) fn set_residual_flexibility(
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
        self.residual = r;
        self.update_series_compliance();
        Ok(())
    }

    /// Sets (or clears) the wheel's residual flexibility at the contact: when set, its
    /// structural part ([`WheelResidual::structural_m_per_n`]) adds to the contact's series
    /// compliance. It must belong to this engine's wheel modes.
    pub(crate) fn set_wheel_residual(
        &mut self,
        r: Option<WheelResidual>,
    ) -> Result<(), DynamicsError> {
        if let Some(r) = &r {
            if r.modes != self.wheel_sys.len() {
                return Err(DynamicsError::SizeMismatch {
                    what: "wheel residual flexibility: modes it was computed for vs the engine's wheel modes (recompute it)",
                    found: r.modes,
                    expected: self.wheel_sys.len(),
                });
            }
        }
        self.wheel_residual = r;
        self.update_series_compliance();
        Ok(())
    }

    /// The wheel's residual flexibility in use, if any.
    pub fn wheel_residual(&self) -> Option<&WheelResidual> {
        self.wheel_residual.as_ref()
    }

    /// The rail's part of the series compliance `[c_x, c_t, c_n]` (m/N).
    fn rail_compliance(&self) -> [f64; 3] {
        self.residual
            .as_ref()
            .map_or([0.0; 3], |r| r.mean_structural_weighted())
    }

    /// The wheel's part of the series compliance `[c_x, c_t, c_n]` (m/N).
    fn wheel_compliance(&self) -> [f64; 3] {
        self.wheel_residual
            .as_ref()
            .map_or([0.0; 3], |w| w.structural_m_per_n)
    }

    fn update_series_compliance(&mut self) {
        let (r, w) = (self.rail_compliance(), self.wheel_compliance());
        self.series_compliance = [0, 1, 2].map(|d| r[d] + w[d]);
        // the static start depends on the series compliance
        *self
            .smooth_start
            .get_mut()
            .unwrap_or_else(|e| e.into_inner()) = None;
    }

    /// The residual flexibility in use, if any.
    pub fn residual_flexibility(&self) -> Option<&ResidualFlexibility> {
        self.residual.as_ref()
    }

    /// Series compliance of the contact `[c_x, c_y, c_z]` (m/N) in the contact solver's axes
    /// (rolling, lateral tangent t, normal n), zero without residuals: the rail's
    /// length-weighted mean of the structural residual along the travel, the same at every
    /// position ([`ResidualFlexibility::mean_structural_weighted`] says why), plus the wheel's
    /// structural residual ([`WheelResidual`]).
    pub fn series_compliance(&self) -> [f64; 3] {
        self.series_compliance
    }

    /// Receptances of the reduced model at the contact (see [`super::receptance`]): the rail
    /// at `positions_m` (m along the rail; the contact line's rows, the constant residual
    /// compliance of the truncated modes added), the wheel at its contact point (its
    /// structural residual compliance added), and the linearised Hertz compliance, at
    /// `frequencies_hz` (Hz).
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
        let (rail_c, wheel_c) = (self.rail_compliance(), self.wheel_compliance());
        let rail = (0..np)
            .map(|p| {
                h.iter()
                    .map(|h| {
                        let block = h.submatrix(3 * p, 3 * p, 3, 3).to_owned();
                        to3(&block, rail_c)
                    })
                    .collect()
            })
            .collect();
        let mw = self.wheel_sys.len();
        let wr: Vec<&[f64]> = self.wheel_contact.rows.chunks_exact(mw).collect();
        let wheel = modal_receptance(&self.wheel_sys, &wr, frequencies_hz)?
            .iter()
            .map(|h| to3(h, wheel_c))
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
    /// static Hertz patch, and the tangential tolerance [`PASSAGE_TANGENTIAL_TOL`](super::setup::PASSAGE_TANGENTIAL_TOL).
    pub fn contact_config(&self, speed_m_per_s: f64) -> Result<TransientConfig, DynamicsError> {
        Ok(contact_config_for(&self.model, speed_m_per_s)?)
    }

    /// Runs one passage at `speed_m_per_s` (m/s) over the rail profile (`None` = smooth) on
    /// the model's contact grid (lengthened for the profile: [`passage_contact`]). When its
    /// contact patch reaches the grid's boundary (a dynamic load beyond the room
    /// `contact.grid_margin` leaves, e.g. over a deep trial corrugation) the passage is run
    /// again from the start on a grid widened along that edge at the same element size
    /// ([`run_widening_grid`]); the record's `contact_grid_widened` then names the grid it ran
    /// on, and `progress` is warned. A passage that stays inside the model's grid runs once,
    /// bit for bit as before.
    ///
    /// A profile entirely off the rail the contact passes over
    /// ([`Self::rail_under_contact_m`]) is refused; one that only partly overlaps it is
    /// warned about on `progress` ([`check_profile_on_travel`]).
    pub fn passage(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
        opts: &PassageOptions,
        progress: Option<&dyn crate::progress::Progress>,
    ) -> Result<PassageRecord, DynamicsError> {
        if let Some(p) = profile {
            let travel = self.rail_under_contact_m(speed_m_per_s)?;
            if let (Some(w), Some(pr)) = (check_profile_on_travel(p, travel)?, progress) {
                pr.warn(&w);
            }
        }
        let (mut rec, w) = run_widening_grid(
            self.wheel_load_n,
            |w| self.passage_on_grid(speed_m_per_s, profile, opts, progress, w),
            |e: &DynamicsError| match e {
                DynamicsError::Passage(p) => Some(p),
                _ => None,
            },
            DynamicsError::Passage,
            |edge, w| {
                if let Some(p) = progress {
                    let grid = self.widened_grid(speed_m_per_s, profile, w);
                    p.warn(&format!(
                        "the contact patch reached the contact grid's boundary ({edge}); rerunning the passage on {}",
                        grid.map_or_else(|e| e.to_string(), |g| g.to_string())
                    ));
                }
            },
        )?;
        if w.any() {
            rec.contact_grid_widened = Some(self.widened_grid(speed_m_per_s, profile, w)?);
        }
        Ok(rec)
    }

    /// The contact grid of a passage at `v` (m/s) over `profile` widened by `w`.
    fn widened_grid(
        &self,
        v: f64,
        profile: Option<&RailProfile>,
        w: GridWidening,
    ) -> Result<WidenedGrid, DynamicsError> {
        let cfg = self.contact_config(v)?;
        let grid = passage_grid(
            &cfg,
            ProfileOnRail::of(profile, self.hertz_approach_m, || {
                self.rail_under_contact_m(v)
            })?,
            w,
        )?;
        Ok(WidenedGrid::new(&grid, w))
    }

    /// The rail the contact grid passes over in a passage at `v` (m/s):
    /// [`rail_under_contact_m`] of the model's grid.
    pub fn rail_under_contact_m(&self, v: f64) -> Result<[f64; 2], DynamicsError> {
        let cfg = self.contact_config(v)?;
        Ok(rail_under_contact_m(
            self.x_start_m,
            self.zone_m[1],
            &cfg.grid,
        ))
    }

    /// The static loads of the contact at the start: normal force `W / cos α` (N),
    /// longitudinal force (N: [`start_longitudinal_force_n`]), and the spin of the coned wheel
    /// on the inclined rail `−sin α / R` (1/m).
    fn static_loads(&self) -> (f64, f64, f64) {
        (
            self.wheel_load_n / self.frame.n[2],
            start_longitudinal_force_n(&self.model),
            self.frame.n[1] / self.wheel_radius_m,
        )
    }

    /// Position along the rail (m) from which the driving torque and the train's resistance
    /// act ([`torque_onset_m`]).
    pub fn torque_onset_m(&self) -> Result<f64, DynamicsError> {
        Ok(torque_onset_m(&self.model, self.x_start_m, self.zone_m[0])?)
    }

    /// The contact of a passage at `v` (m/s) over `profile` on the grid widened by `widening`
    /// ([`passage_contact`]), brought to steady rolling at the static load
    /// ([`steady_contact`], with the engine's series compliance), and its steady result. On
    /// the smooth rail's model grid the steady state does not depend on the speed (the
    /// contact state moves by one element per step whatever the speed:
    /// [`TransientRolling::set_speed`]), so it is computed once per engine and cloned: a sweep
    /// pays for one static start, and every passage gets the state bit for bit as if it had
    /// computed it itself.
    fn started_contact(
        &self,
        v: f64,
        profile: Option<&RailProfile>,
        widening: GridWidening,
    ) -> Result<(TransientRolling, crate::contact::StepResult), DynamicsError> {
        let x0 = self.x_start_m;
        let contact_err = |source| {
            DynamicsError::Passage(crate::passage::PassageError::Contact {
                t_s: 0.0,
                x_m: x0,
                source,
            })
        };
        let start = || -> Result<_, DynamicsError> {
            let mut contact = passage_contact(
                &self.model,
                v,
                ProfileOnRail::of(profile, self.hertz_approach_m, || {
                    self.rail_under_contact_m(v)
                })?,
                widening,
            )?;
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
        if profile.is_some() || widening.any() {
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

    /// The wheel's constant generalised loads (N per modal coordinate): gravity, and the
    /// driving torque and the train's resistance with the weight `drive` (0 to 1).
    fn wheel_constant_loads(&self, drive: f64, out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.wheel_gravity[i] + drive * (self.wheel_torque[i] + self.wheel_drawbar[i]);
        }
    }

    /// Generalised forces of the contact force `f` on the wheel (frame x, t, n; N), the rail
    /// taking `−f`: `ft` on the track modes through the rail's contact rows `rr`, `fw` on the
    /// wheel modes through its contact rows plus the constant loads `fw_const`.
    fn generalised_forces(
        &self,
        f: &[f64; 3],
        fw_const: &[f64],
        rr: &[f64],
        (ft, fw): (&mut [f64], &mut [f64]),
    ) {
        let (mt, mw) = (ft.len(), fw.len());
        let wr = &self.wheel_contact.rows;
        for i in 0..mt {
            ft[i] = -(f[0] * rr[i] + f[1] * rr[mt + i] + f[2] * rr[2 * mt + i]);
        }
        for i in 0..mw {
            fw[i] = fw_const[i] + f[0] * wr[i] + f[1] * wr[mw + i] + f[2] * wr[2 * mw + i];
        }
    }

    /// With `run.residual_variation = "consistent"`, sets the contact's series compliance to
    /// the position-dependent residual flexibility at `xc` (m) plus the wheel's; otherwise
    /// nothing. `t` (s) names the step in an error.
    fn follow_consistent_compliance(
        &self,
        contact: &mut TransientRolling,
        t: f64,
        xc: f64,
    ) -> Result<(), DynamicsError> {
        if let (Some(r), ResidualVariation::Consistent) =
            (&self.residual, self.model.run.residual_variation)
        {
            let (c, w) = (r.consistent_at(xc)?, self.wheel_compliance());
            contact
                .set_series_compliance([0, 1, 2].map(|d| c[d] + w[d]))
                .map_err(|source| {
                    DynamicsError::Passage(crate::passage::PassageError::Contact {
                        t_s: t,
                        x_m: xc,
                        source,
                    })
                })?;
        }
        Ok(())
    }

    /// Places both modal systems at the static start: the static deflections under the
    /// generalised static loads `(ft, fw)`, the wheel's rigid modes moved so that the
    /// contact approach is the steady state's `delta0` (m) and the wheel's contact point
    /// slides at the steady creepage `xi0` (−) times the speed `v` (m/s); `rr` the rail's
    /// contact rows at the start.
    fn place_at_static_start(
        &self,
        v: f64,
        (xi0, delta0): (f64, f64),
        rr: &[f64],
        (ft, fw): (&[f64], &[f64]),
        (tr, wh): (&mut ModalVerlet, &mut ModalVerlet),
    ) {
        let (mt, mw) = (tr.len(), wh.len());
        let wr = &self.wheel_contact.rows;
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
        tr.set_state(&qt0, &vec![0.0; mt], ft);
        wh.set_state(&qw0, &vw0, fw);
    }
}

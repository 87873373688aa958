//! The set-up shared by the reduced and the explicit passage (docs/theory.md §6, §7.4, §7.5):
//! the contact configuration and grid of a passage, the steady rolling state at the static
//! load, the constant wheel loads (gravity, driving torque, train resistance) and the
//! least-norm placement of the wheel's rigid modes.

use super::passage::PASSAGE_TANGENTIAL_TOL;
use super::{DynamicsError, RailProfile};
use crate::contact::{
    GridSpec, HertzGridParams, Longitudinal, NormalInput, StepInputs, TransientConfig,
    TransientRolling,
};
use crate::model::Model;
use crate::structure::WheelStructure;

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
/// train's resistance `−μ_t W` on the journal nodes (docs/theory.md §7.4). Shared by the
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

/// The elastic constants `(E (Pa), ν (−))` of the contact's half-spaces for `model`: the
/// rail's and the wheel's steel combined as quasi-identical bodies
/// ([`crate::contact::quasi_identical_pair`]); the rail's own when the two are the same.
pub fn contact_steel(model: &Model) -> (f64, f64) {
    crate::contact::quasi_identical_pair(
        (model.rail.youngs_modulus, model.rail.poisson_ratio),
        (model.wheel.youngs_modulus, model.wheel.poisson_ratio),
    )
}

/// The contact configuration of a passage of `model` at `speed_m_per_s` (m/s) under the wheel
/// load: the model's grid around the static Hertz patch, and the tangential tolerance
/// [`PASSAGE_TANGENTIAL_TOL`]. The reduced and the explicit passage use it alike.
pub fn contact_config_for(
    model: &Model,
    speed_m_per_s: f64,
) -> Result<TransientConfig, DynamicsError> {
    let m = model;
    let (youngs_pa, poisson) = contact_steel(m);
    let mut cfg = TransientConfig::around_hertz(&HertzGridParams {
        radius_x_m: m.wheel.radius,
        radius_y_m: m.contact.rail_crown_radius,
        youngs_pa,
        poisson,
        friction: m.contact.friction,
        speed_m_per_s,
        load_n: m.vehicle.wheel_load,
        nx: m.contact.grid_nx,
        ny: m.contact.grid_ny,
        margin: m.contact.grid_margin,
    })
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

/// The static Hertz patch of the model's wheel on its rail crown under a vertical load
/// `load_n` (N): the patch every passage, the explicit path and the compliance check build
/// their contact line from.
pub fn static_hertz(
    model: &Model,
    load_n: f64,
) -> Result<crate::contact::HertzContact, DynamicsError> {
    let (youngs_pa, poisson) = contact_steel(model);
    crate::contact::HertzContact::solve(&crate::contact::HertzInput {
        radius_x_m: model.wheel.radius,
        radius_y_m: model.contact.rail_crown_radius,
        youngs_pa,
        poisson,
        load_n,
    })
    .map_err(DynamicsError::StaticHertz)
}

/// Refuses a model whose `run.start` an engine does not implement: `engine` (e.g. the
/// explicit FE path) starts from the static solve only.
pub fn require_static_start(model: &Model, engine: &'static str) -> Result<(), DynamicsError> {
    if model.run.start == crate::model::StartKind::Static {
        return Ok(());
    }
    Err(DynamicsError::Engine {
        engine,
        source: "run.start = \"rest\" is implemented by the reduced passage only; use run.start = \"static\" with this engine".into(),
    })
}

/// A passage's speed must be finite and > 0 (m/s).
pub(super) fn check_speed(speed_m_per_s: f64) -> Result<(), DynamicsError> {
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

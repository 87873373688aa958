//! The explicit path's model: its options, and the track and wheel substructures prepared
//! for central-difference steps (operators, stable steps, the rail's contact line and load
//! patch, the local-compliance correction, the static factor), built once and run for any
//! number of passages ([`super::passage`], docs/theory.md §8).

use std::time::Instant;

use faer::Mat;

use super::coupling::Coupling;
use super::local::LocalCompliance;
use super::operator::ExplicitOperator;
use super::rotating::{tread_planes, WheelLocalCompliance};
use super::stable::{StableStep, DEFAULT_SAFETY};
use super::start::{
    add_line_force, solve_one, static_contact_force, wheel_rigid_modes, ElasticWheel,
};
use super::ExplicitError;
use crate::model::{ExplicitLocalCompliance, ExplicitWheel, LoadSpread, Model, StartKind};
use crate::passage::contact_line::{add_nodes_load, ContactFrame, RailContactLine, WheelContact};
use crate::passage::planes::{plane_weights, PlaneWeights};
use crate::passage::setup::WheelLoads;
use crate::passage::statics::{nodes_dot, StiffnessFactor};
use crate::structure::{TrackStructure, WheelStructure};

/// Options of the explicit path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExplicitOptions {
    /// Safety factor on the computed critical step (−), in (0, 1] here (a model file's
    /// `explicit.safety` is limited to 0.1–1); default `DEFAULT_SAFETY` = 0.9.
    pub safety: f64,
    /// A time step for both substructures (s), refused above `safety ×` either one's
    /// computed critical step (the estimate of `ω_max` approaches it from below, so the
    /// safety factor is the margin); `None` (default) = each substructure at `safety ×` its
    /// own critical step.
    pub time_step_s: Option<f64>,
    /// The coupling scheme (default predictor–corrector).
    pub coupling: Coupling,
    /// How the contact force is spread over the rail's node planes (default: over the
    /// static Hertz patch).
    pub load_spread: LoadSpread,
    /// Whether the element-scale variation of the mesh's local compliance is removed from
    /// the contact (default) or kept: on the rail its variation inside each element
    /// (docs/theory.md §8.6), on the rotating wheel its variation with the contact's
    /// material angle around the faceted tread, against its value at θ = 0 (§8.7).
    pub local_compliance: ExplicitLocalCompliance,
    /// The wheel treatment (default fixed, `explicit.wheel`; docs/theory.md §8.7).
    pub wheel: ExplicitWheel,
    /// The rotating wheel's spin rate (rad/s); `None` (default) = `V/R` at the contact
    /// radius, rolling without slip. Another value only isolates the effect of the rotation.
    pub spin_rate_rad_s: Option<f64>,
    /// Whether a passage also keeps the energy audit (a replay of every contact step with
    /// the forces the structures carried; twice the structural cost; default off,
    /// docs/theory.md §8.8).
    pub audit: bool,
}

impl Default for ExplicitOptions {
    fn default() -> Self {
        Self {
            safety: DEFAULT_SAFETY,
            time_step_s: None,
            coupling: Coupling::PredictorCorrector,
            load_spread: LoadSpread::Patch,
            local_compliance: ExplicitLocalCompliance::Constant,
            wheel: ExplicitWheel::Fixed,
            spin_rate_rad_s: None,
            audit: false,
        }
    }
}

impl ExplicitOptions {
    /// The options of a model's `[explicit]` section.
    pub fn from_model(model: &Model) -> Self {
        Self {
            safety: model.explicit.safety,
            time_step_s: model.explicit.time_step,
            coupling: Coupling::PredictorCorrector,
            load_spread: model.explicit.load_spread,
            local_compliance: model.explicit.local_compliance,
            wheel: model.explicit.wheel,
            spin_rate_rad_s: None,
            audit: false,
        }
    }
}

/// One substructure ready for explicit steps.
pub(super) struct Part {
    pub(super) op: ExplicitOperator,
    pub(super) step: StableStep,
    pub(super) dt_max_s: f64,
}

impl Part {
    pub(super) fn new(
        mats: &crate::fe::assembly::FeMatrices,
        opts: &ExplicitOptions,
        name: &'static str,
    ) -> Result<Self, ExplicitError> {
        let op = ExplicitOperator::new(mats.k.as_ref(), mats.m.as_ref(), mats.c.as_ref())?;
        let step = StableStep::estimate(&op)?;
        let limit = step.with_safety(opts.safety);
        let dt_max_s = match opts.time_step_s {
            Some(dt) if dt > limit => {
                return Err(ExplicitError::TimeStepTooLarge {
                    given_s: dt,
                    limit_s: limit,
                    safety: opts.safety,
                    critical_s: step.critical_s,
                    part: name,
                    omega_max: step.omega_max_estimate,
                })
            }
            Some(dt) => dt,
            None => limit,
        };
        Ok(Part { op, step, dt_max_s })
    }

    /// Sub-steps and step length inside a contact step of `dt_c` (s).
    pub(super) fn substeps(&self, dt_c: f64) -> (usize, f64) {
        let n = (dt_c / self.dt_max_s).ceil().max(1.0) as usize;
        (n, dt_c / n as f64)
    }
}

/// The model of the explicit path: the full track and wheel, their operators and stable
/// steps, and the static start (speed-independent), built once for any number of passages.
pub struct ExplicitModel {
    pub(super) model: Model,
    pub(super) frame: ContactFrame,
    pub(super) track_structure: TrackStructure,
    pub(super) wheel_structure: WheelStructure,
    pub(super) track: Part,
    pub(super) wheel: Part,
    pub(super) line: RailContactLine,
    pub(super) wheel_nodes: Vec<(usize, f64)>,
    /// Rigid modes of the wheel (M-orthonormal, free DOFs), 3 columns.
    pub(super) rigid: Vec<Vec<f64>>,
    /// (contact x, contact n, axle x) of each rigid mode.
    pub(super) rigid_obs: Vec<[f64; 3]>,
    pub(super) loads: WheelLoads,
    /// The wheel's constant loads with the driving torque and the resistance (N).
    pub(super) wheel_const: Vec<f64>,
    /// The same without them: gravity only (N), before the torque's onset of a start from
    /// rest.
    pub(super) wheel_free: Vec<f64>,
    /// Static deflection of the track and elastic deflection of the wheel.
    pub(super) track_static: Vec<f64>,
    pub(super) wheel_static: Vec<f64>,
    pub(super) x_start_m: f64,
    pub(super) zone_m: [f64; 2],
    pub(super) wheel_radius_m: f64,
    pub(super) hertz_b_m: f64,
    /// Half-length of the patch the rail load is spread over (m): the static Hertz `a`,
    /// or 0 for the node-plane load.
    pub(super) patch_a_m: f64,
    /// The mesh's local compliance under the patch, when its variation is removed.
    pub(super) local: Option<LocalCompliance>,
    /// The rotating wheel's tread compliance, when its variation is removed.
    pub(super) wheel_local: Option<WheelLocalCompliance>,
    /// Wall time of computing `wheel_local` (s).
    pub(super) wheel_local_seconds: f64,
    /// Static Hertz approach at the wheel load (m).
    pub(super) hertz_approach_m: f64,
    pub(super) opts: ExplicitOptions,
    pub(super) setup_seconds: f64,
}

impl ExplicitModel {
    /// The wheel's constant loads (N): with the driving torque and the train's resistance
    /// when `drive`, gravity only otherwise (a start from rest before the torque's onset).
    pub(super) fn wheel_loads(&self, drive: bool) -> &[f64] {
        if drive {
            &self.wheel_const
        } else {
            &self.wheel_free
        }
    }

    /// Builds the explicit model of `model`: structures, matrices, operators, stable steps
    /// and the static deflections.
    pub fn new(model: &Model, opts: ExplicitOptions) -> Result<Self, ExplicitError> {
        let t0 = Instant::now();
        let track_structure = TrackStructure::build(model)?;
        let wheel_structure = WheelStructure::build(model)?;
        let mut em = Self::from_structures(model, track_structure, wheel_structure, opts)?;
        em.setup_seconds = t0.elapsed().as_secs_f64();
        Ok(em)
    }

    /// As [`Self::new`] on given track and wheel structures instead of the model's (the
    /// model gives the rail inclination, the contact and the loads; the wheel's start and the
    /// solution zone are the track structure's layout): the explicit path of the same
    /// structures another engine runs on, e.g. meshes the model's keys do not reach ([`crate::structure::test_problems::all_modes_structures`]).
    pub fn from_structures(
        model: &Model,
        track_structure: TrackStructure,
        wheel_structure: WheelStructure,
        opts: ExplicitOptions,
    ) -> Result<Self, ExplicitError> {
        let t0 = Instant::now();
        if model.contact.influence == crate::model::ContactInfluence::FePatch {
            return Err(ExplicitError::FePatch);
        }
        if !(opts.safety > 0.0 && opts.safety <= 1.0) {
            return Err(ExplicitError::Safety {
                safety: opts.safety,
            });
        }
        let frame = ContactFrame::for_inclination(model.rail.inclination);
        let (tm, _) = track_structure.assemble()?;
        let (wm, _) = wheel_structure.assemble()?;
        let track = Part::new(&tm, &opts, "track")?;
        let wheel = Part::new(&wm, &opts, "wheel")?;
        let hertz = crate::passage::setup::static_hertz(model, model.vehicle.wheel_load)?;
        let n_t = track_structure.dofmap.n_free();
        let line = RailContactLine::new(&track_structure, &Mat::zeros(n_t, 0), &frame, hertz.b_m)?;
        let rigid = wheel_rigid_modes(&wheel_structure, &wheel.op)?;
        let n_w = wheel_structure.dofmap.n_free();
        let rigid_mat = Mat::from_fn(n_w, rigid.len(), |i, k| rigid[k][i]);
        let wc = WheelContact::new(&wheel_structure, &rigid_mat, &frame, hertz.b_m)?;
        let nr = rigid.len();
        let rigid_obs: Vec<[f64; 3]> = (0..nr)
            .map(|k| [wc.rows[k], wc.rows[2 * nr + k], wc.axle_x[k]])
            .collect();
        let loads = WheelLoads::new(model, &wheel_structure, &wm)?;
        let wheel_const = loads.total();
        let x_start_m = track_structure.layout.wheel_start;
        let zone_m = track_structure.layout.solution_zone;
        let patch_a_m = match opts.load_spread {
            LoadSpread::Patch => hertz.a_m,
            LoadSpread::Node => 0.0,
        };

        // Static deflections under the static contact force (x, t, n) = (μ_t W, 0, W/cos α).
        let f0 = static_contact_force(model, &frame);
        let mut ft = vec![0.0; n_t];
        add_line_force(
            &line,
            &track_structure,
            &frame,
            &plane_weights(&line.planes_x_m, x_start_m, patch_a_m)?,
            [-f0[0], -f0[1], -f0[2]],
            &mut ft,
        );
        let fac = StiffnessFactor::new(tm.k.as_ref())?;
        let track_static = solve_one(&fac, &ft);
        let local = match opts.local_compliance {
            ExplicitLocalCompliance::Mesh => None,
            ExplicitLocalCompliance::Constant => {
                let px = &line.planes_x_m;
                let x_hi = (zone_m[1] + 0.05).min(px[px.len() - 1] - 2.0 * patch_a_m - 1e-9);
                Some(LocalCompliance::compute(
                    &track_structure,
                    &fac,
                    &line,
                    &frame,
                    patch_a_m,
                    [x_start_m, x_hi],
                )?)
            }
        };
        drop(fac);
        let wheel_free = loads.gravity.clone();
        let mut fw = if model.run.start == StartKind::Static {
            wheel_const.clone()
        } else {
            wheel_free.clone()
        };
        add_nodes_load(&wc.nodes, &wheel_structure.dofmap, &frame, 1.0, f0, &mut fw);
        let elastic = ElasticWheel::new(&wheel_structure, &wm, &wheel.op, &rigid, &wc.nodes)?;
        let wheel_static = elastic.solve(&fw);
        let t_local = Instant::now();
        let wheel_local = match (opts.wheel, opts.local_compliance) {
            (ExplicitWheel::Rotating, ExplicitLocalCompliance::Constant) => {
                // The contact can turn the wheel at most by the rail's length from the start
                // over the contact radius.
                let px = &line.planes_x_m;
                let phi_max = (px[px.len() - 1] - x_start_m) / loads.contact_radius_m;
                let topo = &wheel_structure.topology;
                let dm = &wheel_structure.dofmap;
                let sprung: Vec<usize> = (0..3)
                    .filter_map(|c| dm.free_index(3 * wheel_structure.sprung_node + c))
                    .collect();
                Some(WheelLocalCompliance::compute(
                    &elastic.body_only(&sprung)?,
                    &tread_planes(&wheel_structure, &wc.nodes)?,
                    (&topo.thetas, topo.contact_angle_index()),
                    [frame.x, frame.t, frame.n],
                    phi_max,
                    n_w,
                )?)
            }
            _ => None,
        };
        let wheel_local_seconds = t_local.elapsed().as_secs_f64();
        Ok(ExplicitModel {
            model: model.clone(),
            frame,
            track_structure,
            wheel_structure,
            track,
            wheel,
            line,
            wheel_nodes: wc.nodes,
            rigid,
            rigid_obs,
            wheel_radius_m: loads.contact_radius_m,
            hertz_b_m: hertz.b_m,
            patch_a_m,
            local,
            wheel_local,
            wheel_local_seconds,
            hertz_approach_m: hertz.approach_m,
            loads,
            wheel_const,
            wheel_free,
            track_static,
            wheel_static,
            x_start_m,
            zone_m,
            opts,
            setup_seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Stable steps of the track and the wheel.
    pub fn stable_steps(&self) -> [StableStep; 2] {
        [self.track.step, self.wheel.step]
    }

    /// Track and wheel DOFs.
    pub fn dofs(&self) -> [usize; 2] {
        [self.track.op.n(), self.wheel.op.n()]
    }

    /// The track structure.
    pub fn track_structure(&self) -> &TrackStructure {
        &self.track_structure
    }

    /// The rail's contact line (node sets and weights per node plane).
    pub fn rail_line(&self) -> &RailContactLine {
        &self.line
    }

    /// Rail displacement at `x` (m) on the contact line, contact-frame components (m).
    pub(super) fn rail_at(&self, u: &[f64], x: f64) -> Result<[f64; 3], ExplicitError> {
        Ok(self.rail_under(u, &self.weights(x)?))
    }

    /// Rail displacement under the patch of plane weights `w`, contact-frame components (m).
    pub(super) fn rail_under(&self, u: &[f64], w: &PlaneWeights) -> [f64; 3] {
        let axes = [self.frame.x, self.frame.t, self.frame.n];
        let dm = &self.track_structure.dofmap;
        axes.map(|a| {
            w.iter()
                .map(|(j, wj)| wj * nodes_dot(&self.line.nodes[j], dm, a, |i| u[i]))
                .sum()
        })
    }

    pub(super) fn wheel_at(&self, u: &[f64]) -> [f64; 3] {
        let axes = [self.frame.x, self.frame.t, self.frame.n];
        let dm = &self.wheel_structure.dofmap;
        axes.map(|a| nodes_dot(&self.wheel_nodes, dm, a, |i| u[i]))
    }

    /// The element-scale variation `Δg` (m/N per contact-frame direction) of the mesh's local
    /// compliance under the patch of weights `w` at `x` (m) that the contact is relieved of;
    /// zero when it is kept (`explicit.local_compliance = "mesh"`).
    pub(super) fn local_variation(&self, x: f64, w: &PlaneWeights) -> [f64; 3] {
        self.local
            .as_ref()
            .map_or([0.0; 3], |lc| lc.variation(x, w))
    }

    /// The node planes' weights of the rail load with the contact at `x` (m).
    pub(super) fn weights(&self, x: f64) -> Result<PlaneWeights, ExplicitError> {
        Ok(plane_weights(&self.line.planes_x_m, x, self.patch_a_m)?)
    }
}

#[cfg(test)]
mod tests {
    use super::{ExplicitModel, ExplicitOptions};
    use crate::model::test_problems::all_modes_model;
    use crate::structure::test_problems::all_modes_structures;

    /// The railpad's longitudinal dampers reach the explicit path's damper forces: with the
    /// rail moving at 1 m/s along x and everything else at rest, the forces `C v` of the
    /// track operator on the rail sum to n·c for n fastenings of damping c (the model's only
    /// dampers). The reduced path reads the same `C` (structure::node_line_tests).
    #[test]
    fn railpad_x_dampers_reach_the_explicit_damper_forces() {
        let c_p = 7e3;
        let damping = format!("fastening.longitudinal_damping={c_p:e}");
        let model = all_modes_model(&[
            "fastening.model=custom",
            "fastening.custom.x={ rigid = \"none\" }",
            "fastening.custom.y={ rigid = \"rows\", indices = [0, 1, 2, 3] }",
            "fastening.custom.z={ rigid = \"none\" }",
            "fastening.longitudinal_stiffness=1e6",
            &damping,
        ])
        .unwrap();
        let (track, wheel) = all_modes_structures(&model).unwrap();
        let em = ExplicitModel::from_structures(
            &model,
            track,
            wheel,
            ExplicitOptions::from_model(&model),
        )
        .unwrap();
        let t = &em.track_structure;
        let mut v = vec![0.0; 3 * t.mesh.nodes.len()];
        for i in 0..t.rail.n_planes() {
            for j in 0..t.rail.n_section_nodes() {
                v[3 * t.rail.node(i, j)] = 1.0;
            }
        }
        let v = t.dofmap.restrict(&v).unwrap();
        let mut cv = vec![0.0; v.len()];
        em.track.op.apply_c(&v, &mut cv);
        let on_rail: f64 = (0..v.len()).filter(|&i| v[i] == 1.0).map(|i| cv[i]).sum();
        let want = model.track.bays as f64 * c_p;
        println!("explicit C: Σ (C v) on the rail {on_rail:.6e} N s/m, n c = {want:e}");
        assert!((on_rail - want).abs() <= 1e-9 * want, "{on_rail} vs {want}");
    }
}

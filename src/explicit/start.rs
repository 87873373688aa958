//! The static start of the explicit passage (docs/theory.md §8.5): the static deflections by
//! direct solves of the full `K` (no dynamic relaxation), and the wheel's rigid-body modes,
//! which the wheel's elastic static solution removes and the start places.

use faer::Mat;

use super::operator::ExplicitOperator;
use super::ExplicitError;
use crate::model::Model;
use crate::passage::contact_line::{add_nodes_load, ContactFrame, RailContactLine};
use crate::passage::planes::PlaneWeights;
use crate::passage::setup::start_longitudinal_force_n;
use crate::passage::statics::StiffnessFactor;
use crate::structure::{TrackStructure, WheelStructure};

/// Adds the load of a contact-frame force (N, on the rail) spread over the planes of `w`
/// into `f`.
pub(super) fn add_line_force(
    line: &RailContactLine,
    track: &TrackStructure,
    frame: &ContactFrame,
    w: &PlaneWeights,
    force: [f64; 3],
    f: &mut [f64],
) {
    for (j, wj) in w.iter() {
        add_nodes_load(&line.nodes[j], &track.dofmap, frame, wj, force, f);
    }
}

pub(super) fn solve_one(fac: &StiffnessFactor, rhs: &[f64]) -> Vec<f64> {
    let mut b = Mat::from_fn(rhs.len(), 1, |i, _| rhs[i]);
    let mut ws = fac.workspace(1);
    fac.solve_in_place(b.as_mut(), &mut ws);
    (0..rhs.len()).map(|i| b[(i, 0)]).collect()
}

/// The wheel's three rigid-body modes in the x–z plane (translation x, translation z with the
/// sprung mass, rotation about the axle), M-orthonormal over the free DOFs; checked to carry
/// no elastic force (`‖K r‖` against `‖K‖ ‖r‖`).
pub(super) fn wheel_rigid_modes(
    wheel: &WheelStructure,
    op: &ExplicitOperator,
) -> Result<Vec<Vec<f64>>, ExplicitError> {
    let n = wheel.dofmap.n_free();
    let dm = &wheel.dofmap;
    let mut modes: Vec<Vec<f64>> = Vec::new();
    for kind in 0..3 {
        let mut r = vec![0.0; n];
        for (node, p) in wheel.mesh.nodes.iter().enumerate() {
            let (ux, uz) = match kind {
                0 => (1.0, 0.0),
                1 => (0.0, 1.0),
                _ => (p[2], -p[0]),
            };
            if let Some(i) = dm.free_index(3 * node) {
                r[i] = ux;
            }
            if let Some(i) = dm.free_index(3 * node + 2) {
                r[i] = uz;
            }
        }
        modes.push(r);
    }
    let mass = op.mass();
    let mdot = |a: &[f64], b: &[f64]| -> f64 { (0..n).map(|i| a[i] * mass[i] * b[i]).sum() };
    for k in 0..modes.len() {
        for j in 0..k {
            let c = mdot(&modes[k], &modes[j]);
            let (head, tail) = modes.split_at_mut(k);
            tail[0]
                .iter_mut()
                .zip(&head[j])
                .for_each(|(x, y)| *x -= c * y);
        }
        let nn = mdot(&modes[k], &modes[k]).sqrt();
        if nn.is_nan() || nn <= 0.0 {
            return Err(ExplicitError::RigidModeMassless {
                part: "wheel",
                mode: k,
            });
        }
        modes[k].iter_mut().for_each(|x| *x /= nn);
    }
    // Check K r ≈ 0 relative to the stiffness scale.
    let mut kr = vec![0.0; n];
    let scale = op.gershgorin_omega2().sqrt();
    for (k, r) in modes.iter().enumerate() {
        op.apply_k(r, &mut kr);
        // ‖M^{-½} K r‖ / ‖M^{½} r‖ is an angular frequency squared: compare with ω_bound².
        let num: f64 = (0..n).map(|i| kr[i] * kr[i] / mass[i]).sum::<f64>().sqrt();
        if num > 1e-6 * scale * scale {
            return Err(ExplicitError::RigidModeNotFree {
                mode: k,
                relative_force: num / (scale * scale),
            });
        }
    }
    Ok(modes)
}

/// The elastic static solver of the free-floating wheel, by inertia relief: the rigid
/// components of a load are removed (`f − M R Rᵀ f`), three DOFs that fix the rigid motion in
/// a statically determinate way are held by a stiff spring (their reactions vanish for a
/// balanced load, so the spring's size does not matter), and the rigid part of the solution
/// is removed (`u − R Rᵀ M u`). The primary suspension stays in `K` (the sprung mass moves
/// with the rigid vertical mode). The held DOFs are the contact node's x and z and the x of
/// the node farthest from it in z.
pub(crate) struct ElasticWheel {
    fac: StiffnessFactor,
    rigid: Vec<Vec<f64>>,
    mass: Vec<f64>,
}

impl ElasticWheel {
    /// Factorises the held stiffness of `wheel` (matrices `mats`, operator `op`, rigid modes
    /// `rigid`, contact nodes `contact_nodes`).
    pub(super) fn new(
        wheel: &WheelStructure,
        mats: &crate::fe::assembly::FeMatrices,
        op: &ExplicitOperator,
        rigid: &[Vec<f64>],
        contact_nodes: &[(usize, f64)],
    ) -> Result<Self, ExplicitError> {
        // Supports: x and z of the contact node, x of the node farthest from it in z.
        let dm = &wheel.dofmap;
        let cn = contact_nodes
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|&(nd, _)| nd)
            .unwrap_or_else(|| wheel.topology.contact_node());
        let zc = wheel.mesh.nodes[cn][2];
        let far = (0..wheel.mesh.nodes.len())
            .filter(|&nd| nd != wheel.sprung_node && dm.free_index(3 * nd).is_some())
            .max_by(|&a, &b| {
                (wheel.mesh.nodes[a][2] - zc)
                    .abs()
                    .total_cmp(&(wheel.mesh.nodes[b][2] - zc).abs())
            })
            .unwrap_or(cn);
        let held: Vec<usize> = [3 * cn, 3 * cn + 2, 3 * far]
            .iter()
            .filter_map(|&d| dm.free_index(d))
            .collect();
        if held.len() != 3 {
            return Err(ExplicitError::ContactNodeHeld);
        }
        let mut k = mats.k.clone();
        {
            let (cp, ri) = (
                k.symbolic().col_ptr().to_vec(),
                k.symbolic().row_idx().to_vec(),
            );
            let vals = k.val_mut();
            for &d in &held {
                let p = (cp[d]..cp[d + 1])
                    .find(|&p| ri[p] == d)
                    .ok_or(ExplicitError::MissingDiagonal { dof: d })?;
                vals[p] *= 2.0;
            }
        }
        let fac = StiffnessFactor::new(k.as_ref()).map_err(ExplicitError::WheelStaticFactor)?;
        Ok(ElasticWheel {
            fac,
            rigid: rigid.to_vec(),
            mass: op.mass().to_vec(),
        })
    }

    /// The same solver with the inertia relief over the wheel body only: the `sprung` DOFs
    /// get no inertial share of a load (their mass is left out of the balancing and the rigid
    /// modes are M-orthonormalised again without it), so the primary suspension carries no
    /// force and the solution is the free wheel body's elastic deflection.
    pub(crate) fn body_only(mut self, sprung: &[usize]) -> Result<Self, ExplicitError> {
        for &d in sprung {
            self.mass[d] = 0.0;
        }
        let m = &self.mass;
        let mdot = |a: &[f64], b: &[f64]| -> f64 {
            a.iter().zip(b).zip(m).map(|((x, y), w)| x * w * y).sum()
        };
        for k in 0..self.rigid.len() {
            for j in 0..k {
                let c = mdot(&self.rigid[k], &self.rigid[j]);
                let (head, tail) = self.rigid.split_at_mut(k);
                tail[0]
                    .iter_mut()
                    .zip(&head[j])
                    .for_each(|(x, y)| *x -= c * y);
            }
            let nn = mdot(&self.rigid[k], &self.rigid[k]).sqrt();
            if nn.is_nan() || nn <= 0.0 {
                return Err(ExplicitError::RigidModeMassless {
                    part: "wheel body",
                    mode: k,
                });
            }
            self.rigid[k].iter_mut().for_each(|x| *x /= nn);
        }
        Ok(self)
    }

    /// The load `f` (N) without its rigid components, `f − M R Rᵀ f`, in place.
    fn balance(&self, f: &mut [f64]) {
        for r in &self.rigid {
            let c: f64 = r.iter().zip(f.iter()).map(|(a, b)| a * b).sum();
            f.iter_mut()
                .zip(r)
                .zip(&self.mass)
                .for_each(|((x, ri), mi)| *x -= c * mi * ri);
        }
    }

    /// The solution `u` without its rigid part, `u − R Rᵀ M u`, in place.
    fn elastic_part(&self, u: &mut [f64]) {
        let n = u.len();
        for r in &self.rigid {
            let c: f64 = (0..n).map(|i| r[i] * self.mass[i] * u[i]).sum();
            u.iter_mut().zip(r).for_each(|(x, y)| *x -= c * y);
        }
    }

    /// The elastic static deflection (m) under the load `f` (N).
    pub(crate) fn solve(&self, f: &[f64]) -> Vec<f64> {
        let mut fe = f.to_vec();
        self.balance(&mut fe);
        let mut u = solve_one(&self.fac, &fe);
        self.elastic_part(&mut u);
        u
    }

    /// [`Self::solve`] of several loads together (one block solve), each in place.
    pub(crate) fn solve_many(&self, loads: &mut [Vec<f64>]) {
        let Some(n) = loads.first().map(Vec::len) else {
            return;
        };
        loads.iter_mut().for_each(|f| self.balance(f));
        let mut b = Mat::from_fn(n, loads.len(), |i, j| loads[j][i]);
        let mut ws = self.fac.workspace(loads.len());
        self.fac.solve_in_place(b.as_mut(), &mut ws);
        for (j, u) in loads.iter_mut().enumerate() {
            u.iter_mut().enumerate().for_each(|(i, x)| *x = b[(i, j)]);
            self.elastic_part(u);
        }
    }
}

/// The static contact force (N, on the wheel, contact frame x, t, n): `(F_L, 0, W/cos α)`,
/// `F_L` the start's ([`start_longitudinal_force_n`]: `μ_t W` for the static start, 0 from
/// rest).
pub(super) fn static_contact_force(model: &Model, frame: &ContactFrame) -> [f64; 3] {
    let w = model.vehicle.wheel_load;
    [start_longitudinal_force_n(model), 0.0, w / frame.n[2]]
}

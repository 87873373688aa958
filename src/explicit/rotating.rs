//! The rotating wheel of the explicit path (E1r, docs/theory.md §8.7): the wheel's elastic
//! motion in a frame spinning with it at `Ω` about the axle (the wheel frame's y axis through
//! the origin), with the Coriolis (gyroscopic) and spin-softening terms
//!
//! ```text
//! M ü + (C + 2Ω G) u̇ + (K − Ω² S) u = f(t),   G = M J,  J u = ŷ × u,
//! S = M_⊥ − M â âᵀ M,  M_⊥ u = M (u_x, 0, u_z)
//! ```
//!
//! (`u` in the spinning frame's components; `G` is skew with a lumped mass, so the Coriolis
//! force does no work; `â` the M-normalised rigid rotation about the axle). The centrifugal
//! load of the undeformed wheel and the stress stiffening it causes are left out (relative
//! order `Ω²/ω²` of the lowest wheel mode, below 0.2 % at 140 km/h), except the stress
//! stiffening's action on the rigid rotation about the axle, `Ω² M â âᵀ M`, which cancels
//! the spin softening on it exactly: a body spinning freely is neutral to a turn about its
//! axis (without it the turn would be an unstable mode growing as `cosh Ωt`). The central
//! difference takes the Coriolis term at the mean of the two half-step velocities
//! (implicit midpoint in that term only: per node a 2×2 rotation of the half-step
//! velocity, a Cayley transform), which keeps the scheme's discrete energy
//! `½ v_{k+½}ᵀ M v_{k+½} + ½ u_kᵀ (K − Ω² S) u_{k+1}` exactly conserved without damping and
//! load, and leaves the stable step of the non-rotating wheel unchanged.
//!
//! In the spinning frame the ground-fixed loads rotate (gravity, the train's resistance on
//! the journals; the driving torque turns with the wheel), the primary suspension's vertical
//! direction rotates on the journal nodes, and the contact point moves around the tread at
//! `−Ω`: the contact force is applied to the tread nodes of the two angle planes around the
//! contact's material angle `Ωt`, interpolated linearly in angle, and the wheel's
//! displacement at the contact is read the same way. The coupling's unit responses are those
//! of the two angle planes around the contact (computed as the contact reaches a plane).

mod frame;
mod local;
use frame::{to_ground, to_spinning};
pub use frame::{SpinFrame, SpinScratch};

pub(crate) use local::WheelLocalCompliance;

use super::operator::{ExplicitOperator, StepScratch};
use super::response::{Hold, UnitResponse};
use super::ExplicitError;
use crate::fe::assembly::DofMap;
use crate::passage::contact_line::ContactFrame;
use crate::passage::setup::WheelLoads;
use crate::structure::WheelStructure;

/// Why a spinning frame cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum SpinError {
    /// The spin rate is NaN or infinite.
    #[error("spin rate {omega} rad/s is not finite")]
    NonFiniteRate {
        /// The spin rate (rad/s).
        omega: f64,
    },
    /// A spinning node has a held x or z DOF.
    #[error(
        "node {node} of the spinning wheel has a held x or z DOF: only the lateral DOF may be held"
    )]
    HeldInPlane {
        /// The node.
        node: usize,
    },
    /// A spinning node's lumped masses differ between x and z.
    #[error(
        "node {node} has lumped masses {mass_x_kg:e} (x) and {mass_z_kg:e} (z) kg: the Coriolis \
         term needs equal masses (no point mass on a spinning node)"
    )]
    UnequalMasses {
        /// The node.
        node: usize,
        /// Lumped mass of its x DOF (kg).
        mass_x_kg: f64,
        /// Lumped mass of its z DOF (kg).
        mass_z_kg: f64,
    },
    /// The wheel's first spring is not the primary suspension this frame expects.
    #[error(
        "the primary suspension is not a vertical spring from the sprung mass to the journal nodes"
    )]
    Suspension,
    /// The contact nodes do not lie on the wheel's contact angle plane.
    #[error("the wheel's contact nodes are not on the contact angle plane")]
    ContactOffPlane,
    /// The passage turns the wheel beyond the angles whose local compliance was computed.
    #[error(
        "the passage turns the wheel by {phi_rad:.3} rad, beyond the {phi_max_rad:.3} rad over \
         which the tread's local compliance was computed (a spin rate above V/R): set \
         explicit.local_compliance = \"mesh\" or leave the spin rate at V/R"
    )]
    Uncovered {
        /// The passage's rotation (rad).
        phi_rad: f64,
        /// The rotation covered (rad).
        phi_max_rad: f64,
    },
    /// One contact step turns the wheel backwards, or by a tread plane spacing or more, so
    /// the tread corrections' plane blocks (computed for planes at most two apart, forward
    /// from the contact plane) would not cover it.
    #[error(
        "one contact step turns the wheel by {turn_rad:.3e} rad; the tread's local-compliance \
         and convective corrections need a forward turn below the smallest angle-plane \
         spacing, {spacing_rad:.3e} rad: shorten the contact step (a finer contact.grid_nx) or \
         set explicit.local_compliance = \"mesh\""
    )]
    StepTurn {
        /// The wheel's turn over one contact step (rad; negative: backwards).
        turn_rad: f64,
        /// The smallest spacing of the tread's angle planes (rad).
        spacing_rad: f64,
    },
}

/// Checks that one contact step's turn `turn_rad` (rad) is forward and below the smallest
/// spacing of the angle planes at `thetas` (rad, increasing, one turn), so that the contact's
/// start and end planes of a step are at most two planes apart.
fn check_step_turn(thetas: &[f64], turn_rad: f64) -> Result<(), SpinError> {
    let tau = std::f64::consts::TAU;
    let n = thetas.len();
    let spacing_rad = (0..n)
        .map(|k| (thetas[(k + 1) % n] - thetas[k]).rem_euclid(tau))
        .map(|h| if h == 0.0 { tau } else { h })
        .fold(f64::INFINITY, f64::min);
    if turn_rad >= 0.0 && turn_rad < spacing_rad {
        Ok(())
    } else {
        Err(SpinError::StepTurn {
            turn_rad,
            spacing_rad,
        })
    }
}

/// The primary suspension of the spinning wheel: a vertical spring-damper from the
/// (non-spinning) sprung mass to the journal nodes, whose vertical direction in the spinning
/// frame is `d(t) = (−sin Ωt, 0, cos Ωt)`. The assembled operator holds it along the
/// spinning z; [`Suspension::correction`] is the difference to the true direction.
struct Suspension {
    sprung: usize,
    /// Journal nodes: free x and z indices and the balanced weight.
    journal: Vec<(usize, usize, f64)>,
    k: f64,
    c: f64,
}

impl Suspension {
    fn new(wheel: &WheelStructure) -> Result<Option<Self>, ExplicitError> {
        let Some(spring) = wheel.springs.first() else {
            return Ok(None);
        };
        let dm = &wheel.dofmap;
        let bad = || ExplicitError::from(SpinError::Suspension);
        let sprung = match spring.side_a.as_slice() {
            [(d, w)] if *w == 1.0 && d % 3 == 2 => dm.free_index(*d).ok_or_else(bad)?,
            _ => return Err(bad()),
        };
        let mut journal = Vec::with_capacity(spring.side_b.len());
        for &(d, w) in &spring.side_b {
            if d % 3 != 2 {
                return Err(bad());
            }
            let (ix, iz) = (dm.free_index(d - 2), dm.free_index(d));
            journal.push((ix.ok_or_else(bad)?, iz.ok_or_else(bad)?, w));
        }
        Ok(Some(Suspension {
            sprung,
            journal,
            k: spring.stiffness,
            c: spring.damping,
        }))
    }

    /// Adds to `f` the true spring-damper force minus the assembled one at the rotation
    /// `cs = (cos Ωt, sin Ωt)` (`omega` in rad/s), with the lagged velocity `v` (exactly zero
    /// at `Ωt = 0`, `Ω = 0`). Returns the two forces (N): the assembled one along the
    /// spinning z and the true one along the ground vertical.
    fn correction(
        &self,
        cs: [f64; 2],
        omega: f64,
        u: &[f64],
        v: &[f64],
        f: &mut [f64],
    ) -> [f64; 2] {
        let [c, s] = cs;
        let (mut r_a, mut rd_a) = (u[self.sprung], v[self.sprung]);
        let (mut r_t, mut rd_t) = (r_a, rd_a);
        for &(ix, iz, w) in &self.journal {
            r_a -= w * u[iz];
            rd_a -= w * v[iz];
            r_t -= w * (-s * u[ix] + c * u[iz]);
            // d/dt (d · u) = d · u̇ + ḋ · u with ḋ = Ω (−cos, 0, −sin).
            rd_t -= w * ((-s * v[ix] + c * v[iz]) + omega * (-c * u[ix] - s * u[iz]));
        }
        let fa = self.k * r_a + self.c * rd_a;
        let ft = self.k * r_t + self.c * rd_t;
        f[self.sprung] += fa - ft;
        for &(ix, iz, w) in &self.journal {
            f[ix] += ft * w * (-s);
            f[iz] += ft * w * c - fa * w;
        }
        [fa, ft]
    }

    /// Saves the velocities the correction acts on (sprung mass, then the journals' x and
    /// z) into `out` (length `1 + 2 × journals`).
    fn save_velocity(&self, v: &[f64], out: &mut [f64]) {
        out[0] = v[self.sprung];
        for (p, &(ix, iz, _)) in self.journal.iter().enumerate() {
            out[1 + 2 * p] = v[ix];
            out[2 + 2 * p] = v[iz];
        }
    }

    /// The work (J) of the correction `[fa, ft]` of [`Self::correction`] (at the rotation
    /// `cs`) over a central-difference step of `dt` (s), in the step's own sense
    /// `f · Δt (v_{k−½} + v_{k+½})/2`, with the saved velocities `old` ([`Self::save_velocity`])
    /// and the new ones `v`.
    fn correction_work(
        &self,
        [fa, ft]: [f64; 2],
        [c, s]: [f64; 2],
        dt: f64,
        old: &[f64],
        v: &[f64],
    ) -> f64 {
        let mean = |o: f64, n: f64| 0.5 * dt * (o + n);
        let mut w = (fa - ft) * mean(old[0], v[self.sprung]);
        for (p, &(ix, iz, wt)) in self.journal.iter().enumerate() {
            w += ft * wt * (-s) * mean(old[1 + 2 * p], v[ix]);
            w += (ft * wt * c - fa * wt) * mean(old[2 + 2 * p], v[iz]);
        }
        w
    }

    /// `½ k (r_t² − r_a²)` (J): the true spring's energy less the assembled one's at the
    /// rotation `cs`, `r` the spring's stretch along the ground vertical and the spinning z.
    fn energy_correction(&self, [c, s]: [f64; 2], u: &[f64]) -> f64 {
        let mut r_a = u[self.sprung];
        let mut r_t = r_a;
        for &(ix, iz, w) in &self.journal {
            r_a -= w * u[iz];
            r_t -= w * (-s * u[ix] + c * u[iz]);
        }
        0.5 * self.k * (r_t * r_t - r_a * r_a)
    }
}

/// The wheel's parts the rotating treatment needs (borrowed from the explicit model).
pub(super) struct WheelParts<'a> {
    /// The wheel substructure.
    pub(super) structure: &'a WheelStructure,
    /// Its operator (with the suspension along the spinning z).
    pub(super) op: &'a ExplicitOperator,
    /// The tread nodes and lateral weights of the contact at θ = 0.
    pub(super) contact_nodes: &'a [(usize, f64)],
    /// The contact frame.
    pub(super) frame: ContactFrame,
    /// The wheel loads.
    pub(super) loads: &'a WheelLoads,
    /// Their sum (N).
    pub(super) wheel_const: &'a [f64],
    /// The tread's local compliance whose variation with the angle is removed from the
    /// contact (`None`: kept).
    pub(super) local: Option<&'a WheelLocalCompliance>,
}

/// A node set of one angle plane: free indices (x, y, z; `usize::MAX` = held) and weight.
pub(super) type PlaneNodes = Vec<([usize; 3], f64)>;

/// The contact's tread nodes and lateral weights (`contact_nodes`, on the angle plane
/// θ = 0) repeated on every angle plane of `wheel`, in the order of its angles.
pub(super) fn tread_planes(
    wheel: &WheelStructure,
    contact_nodes: &[(usize, f64)],
) -> Result<Vec<PlaneNodes>, ExplicitError> {
    let topo = &wheel.topology;
    let nm = topo.meridian.len();
    let k0 = topo.contact_angle_index();
    let dm = &wheel.dofmap;
    let free = |node: usize| [0, 1, 2].map(|c| dm.free_index(3 * node + c).unwrap_or(usize::MAX));
    // The contact's meridian nodes and weights, repeated at every angle.
    let merid: Vec<(usize, f64)> = contact_nodes
        .iter()
        .map(|&(node, wt)| (node.wrapping_sub(topo.node(k0, 0)), wt))
        .collect();
    if merid.iter().any(|&(m, _)| m >= nm) {
        return Err(SpinError::ContactOffPlane.into());
    }
    Ok((0..topo.thetas.len())
        .map(|k| {
            merid
                .iter()
                .map(|&(m, wt)| (free(topo.node(k, m)), wt))
                .collect()
        })
        .collect())
}

/// The unit responses of one angle plane (rest to a unit load change over a contact step,
/// applied as the coupling's hold, in the spinning x, y, z) and the key of the plane (its index counted along the travel).
struct PlaneResponse {
    key: Option<i64>,
    r: UnitResponse,
}

/// The contact's place on a wheel with the angle planes at `thetas` (rad, increasing, in
/// (−π, π]) when the material angle under it is `phi` (rad).
fn locate_angle(th: &[f64], phi: f64) -> OnWheel {
    let nt = th.len();
    let tau = std::f64::consts::TAU;
    let turns = ((phi - th[0]) / tau).floor();
    let psi = phi - turns * tau;
    let k = th.partition_point(|&x| x <= psi).saturating_sub(1);
    let next = if k + 1 < nt { th[k + 1] } else { th[0] + tau };
    let s = ((psi - th[k]) / (next - th[k])).clamp(0.0, 1.0);
    OnWheel {
        j: k as i64 + nt as i64 * turns as i64,
        s,
        cs: [phi.cos(), phi.sin()],
    }
}

/// Where the contact is on the wheel: angle plane `j` (counted along the travel), weight `s`
/// of plane `j + 1`, and the rotation `(cos Ωt, sin Ωt)`.
#[derive(Clone, Copy, Debug)]
struct OnWheel {
    j: i64,
    s: f64,
    cs: [f64; 2],
}

/// The rotating wheel of a passage: spin, moving contact, rotated loads, suspension, and the
/// coupling's plane responses.
pub(super) struct RotatingWheel {
    spin: SpinFrame,
    sc: SpinScratch,
    axes: [[f64; 3]; 3],
    thetas: Vec<f64>,
    planes: Vec<PlaneNodes>,
    /// The constant loads (N) and their ground-fixed part on the spinning nodes (gravity and
    /// resistance), which rotates; with the driving torque and the resistance (`[1]`) and
    /// without (`[0]`: gravity only, a start from rest before the torque's onset).
    wheel_const: [Vec<f64>; 2],
    ground: [Vec<f64>; 2],
    /// Whether the driving torque and the resistance act (index into the loads).
    drive: bool,
    suspension: Option<Suspension>,
    /// Contact-step sub-steps and their length (s).
    steps: usize,
    dt: f64,
    /// How the corrector applies a force change over the sub-steps.
    hold: Hold,
    slots: [PlaneResponse; 2],
    f: Vec<f64>,
    fk: Vec<f64>,
    /// The contact's place during the current contact step (held at its end), and at the
    /// step's start.
    at: OnWheel,
    at_start: OnWheel,
    /// The tread's local compliance whose variation is removed (`None`: kept).
    local: Option<WheelLocalCompliance>,
    /// The suspension's velocities before a sub-step (m/s; sprung mass, journals' x and z).
    sus_v: Vec<f64>,
}

impl RotatingWheel {
    /// The rotating wheel at `omega` (rad/s) for contact steps of `steps` sub-steps of `dt`
    /// (s), the coupling's corrector applying force changes as `hold` says.
    pub(super) fn new(
        p: &WheelParts<'_>,
        omega: f64,
        (steps, dt, hold): (usize, f64, Hold),
    ) -> Result<Self, ExplicitError> {
        let w = p.structure;
        let topo = &w.topology;
        let nm = topo.meridian.len();
        let nt = topo.thetas.len();
        let ring = (0..nt).flat_map(|k| (0..nm).map(move |m| topo.node(k, m)));
        let spin = SpinFrame::new(p.op, &w.dofmap, &w.mesh.nodes, ring, omega)?;
        let planes = tread_planes(w, p.contact_nodes)?;
        let n = p.op.n();
        let mut ground = [vec![0.0; n], vec![0.0; n]];
        for &(ix, iz, _) in &spin.pairs {
            for i in [ix, iz] {
                ground[0][i] = p.loads.gravity[i];
                ground[1][i] = p.loads.gravity[i] + p.loads.drawbar[i];
            }
        }
        let slot = || PlaneResponse {
            key: None,
            r: UnitResponse::zeros(n),
        };
        let sc = spin.scratch(p.op);
        Ok(RotatingWheel {
            spin,
            sc,
            axes: [p.frame.x, p.frame.t, p.frame.n],
            thetas: topo.thetas.clone(),
            planes,
            wheel_const: [p.loads.gravity.clone(), p.wheel_const.to_vec()],
            ground,
            drive: true,
            suspension: Suspension::new(w)?,
            steps,
            dt,
            hold,
            slots: [slot(), slot()],
            f: vec![0.0; n],
            fk: vec![0.0; n],
            at: OnWheel {
                j: 0,
                s: 0.0,
                cs: [1.0, 0.0],
            },
            at_start: OnWheel {
                j: 0,
                s: 0.0,
                cs: [1.0, 0.0],
            },
            local: p.local.cloned(),
            sus_v: vec![0.0; 1 + 2 * w.springs.first().map_or(0, |s| s.side_b.len())],
        })
    }

    /// Switches the driving torque and the train's resistance on or off (off: gravity only,
    /// a start from rest before the torque's onset).
    pub(super) fn set_drive(&mut self, on: bool) {
        self.drive = on;
    }

    /// The spin rate (rad/s).
    pub(super) fn omega(&self) -> f64 {
        self.spin.omega
    }

    /// The contact's place on the wheel at time `t` (s): the material angle under the
    /// contact is `Ωt` (the tread runs backwards through the contact at `−Ω`).
    fn locate(&self, t: f64) -> OnWheel {
        locate_angle(&self.thetas, self.spin.omega * t)
    }

    /// `Δg_d = g_d(φ) − g_d(0)` (m/N per contact-frame direction), the variation of the
    /// tread's local compliance with the contact's material angle that the contact is
    /// relieved of at the current step's place (after [`Self::advance`]); zero when it is
    /// kept (`explicit.local_compliance = "mesh"`).
    pub(super) fn local_variation(&self) -> [f64; 3] {
        self.local
            .as_ref()
            .and_then(|l| l.variation(self.at))
            .unwrap_or([0.0; 3])
    }

    /// The convective part of the tread's static deflection over the current step (m,
    /// contact frame; after [`Self::advance`]) under the held force `f` (N, contact frame,
    /// on the wheel): the displacement increment of the material point under the contact
    /// as the force moves from the step's start angle to its end angle. Zero when the
    /// local compliance is kept (`explicit.local_compliance = "mesh"`).
    pub(super) fn convective(&self, f: [f64; 3]) -> [f64; 3] {
        self.local
            .as_ref()
            .and_then(|l| l.convective(self.at, self.at_start, f))
            .unwrap_or([0.0; 3])
    }

    /// Checks that the removal of the tread's local compliance variation covers a passage
    /// of `t_end` (s).
    pub(super) fn check_coverage(&self, t_end: f64) -> Result<(), ExplicitError> {
        let Some(l) = &self.local else {
            return Ok(());
        };
        check_step_turn(&self.thetas, self.spin.omega * self.steps as f64 * self.dt)?;
        let phi = self.spin.omega.abs() * t_end;
        if phi > l.phi_max() {
            return Err(SpinError::Uncovered {
                phi_rad: phi,
                phi_max_rad: l.phi_max(),
            }
            .into());
        }
        Ok(())
    }

    fn plane(&self, j: i64) -> &PlaneNodes {
        &self.planes[j.rem_euclid(self.planes.len() as i64) as usize]
    }

    /// Spinning-frame components of the weighted displacement at `at`.
    fn read(&self, at: OnWheel, u: &[f64]) -> [f64; 3] {
        let mut d = [0.0; 3];
        for (j, wj) in [(at.j, 1.0 - at.s), (at.j + 1, at.s)] {
            if wj == 0.0 {
                continue;
            }
            for &(idx, wt) in self.plane(j) {
                for c in 0..3 {
                    if idx[c] != usize::MAX {
                        d[c] += wj * wt * u[idx[c]];
                    }
                }
            }
        }
        d
    }

    /// Adds the spinning-frame force `fr` (N) at `at` into `f`.
    fn load(&self, at: OnWheel, fr: [f64; 3], f: &mut [f64]) {
        for (j, wj) in [(at.j, 1.0 - at.s), (at.j + 1, at.s)] {
            if wj == 0.0 {
                continue;
            }
            for &(idx, wt) in self.plane(j) {
                for c in 0..3 {
                    if fr[c] != 0.0 && idx[c] != usize::MAX {
                        f[idx[c]] += wj * wt * fr[c];
                    }
                }
            }
        }
    }

    /// Ground components of a contact-frame vector.
    fn ground_of(&self, fc: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|c| (0..3).map(|d| fc[d] * self.axes[d][c]).sum())
    }

    /// Contact-frame components (m) of the wheel's displacement at the material point under
    /// the contact at `t_place` (s), with the state `u` at time `t_state` (s).
    pub(super) fn wheel_at(&self, u: &[f64], t_state: f64, t_place: f64) -> [f64; 3] {
        let at = self.locate(t_place);
        let g = to_ground(self.locate(t_state).cs, self.read(at, u));
        self.axes.map(|a| a[0] * g[0] + a[1] * g[1] + a[2] * g[2])
    }

    /// Advances the wheel over the contact step ending at `t_end` (s) (`steps` sub-steps)
    /// under the contact force `f` (N, contact frame, on the wheel) held at the contact's
    /// end-of-step place and direction, the rotating ground loads, the torque and the
    /// suspension. The first sub-step carries `split` instead ([`Hold::boundary_split`]):
    /// `split[0]`, the previous step's share, where the previous step's force acted (the
    /// contact's place and direction at the step's start), and `split[1]` at the end-of-step
    /// place (docs/theory.md §8.8). Returns the work over the step (J) of the assembled
    /// dampers and of the suspension's turn to the ground vertical (its true force less
    /// the assembled one), each as the central difference's `f · (u_{k+1} − u_{k−1})/2`.
    pub(super) fn advance(
        &mut self,
        op: &ExplicitOperator,
        u: &mut [f64],
        v: &mut [f64],
        (split, f): ([[f64; 3]; 2], [f64; 3]),
        t_end: f64,
    ) -> [f64; 2] {
        let (mut damper_j, mut frame_j) = (0.0, 0.0);
        self.at = self.locate(t_end);
        self.at_start = self.locate(t_end - self.steps as f64 * self.dt);
        let prev = to_spinning(self.at_start.cs, self.ground_of(split[0]));
        let [first, held] = [split[1], f].map(|g| to_spinning(self.at.cs, self.ground_of(g)));
        let t0 = t_end - self.steps as f64 * self.dt;
        for k in 0..self.steps {
            let a = self.spin.omega * (t0 + k as f64 * self.dt);
            let (s, c) = a.sin_cos();
            // cos a − 1 without cancellation.
            let cm1 = -2.0 * (0.5 * a).sin().powi(2);
            let d = usize::from(self.drive);
            self.f.copy_from_slice(&self.wheel_const[d]);
            for &(ix, iz, _) in &self.spin.pairs {
                let (gx, gz) = (self.ground[d][ix], self.ground[d][iz]);
                self.f[ix] += cm1 * gx - s * gz;
                self.f[iz] += s * gx + cm1 * gz;
            }
            let mut f = std::mem::take(&mut self.f);
            if k == 0 {
                self.load(self.at_start, prev, &mut f);
                self.load(self.at, first, &mut f);
            } else {
                self.load(self.at, held, &mut f);
            }
            let forces = self.suspension.as_ref().map(|sus| {
                sus.save_velocity(v, &mut self.sus_v);
                sus.correction([c, s], self.spin.omega, u, v, &mut f)
            });
            damper_j += self.spin.step(op, self.dt, u, v, &f, &mut self.sc);
            if let (Some(sus), Some(fs)) = (&self.suspension, forces) {
                frame_j += sus.correction_work(fs, [c, s], self.dt, &self.sus_v, v);
            }
            self.f = f;
        }
        [damper_j, frame_j]
    }

    /// The stored energy of the wheel (J) in the spinning frame at time `t` (s) with the
    /// state `u`, `v`: `½ vᵀMv + ½ uᵀ(K − Ω² S)u` with the suspension's spring along the
    /// ground vertical (the assembled one lies along the spinning z); `ku` is scratch of
    /// length n.
    pub(super) fn stored(
        &self,
        op: &ExplicitOperator,
        u: &[f64],
        v: &[f64],
        t: f64,
        ku: &mut [f64],
    ) -> f64 {
        op.apply_k(u, ku);
        let strain = 0.5 * u.iter().zip(ku.iter()).map(|(a, b)| a * b).sum::<f64>();
        let sus = self
            .suspension
            .as_ref()
            .map_or(0.0, |sus| sus.energy_correction(self.locate(t).cs, u));
        op.kinetic_energy(v) + strain - self.spin.softening_energy(u) + sus
    }

    /// The work (J) of the ground-fixed load `g` (N, spinning-frame components at t = 0;
    /// its part on the spinning nodes turns in the spinning frame, the rest, on the sprung
    /// mass, does not) over the contact step from `t0` to `t1` (s), from the wheel's states
    /// `u0` and `u1` (m): `[spinning, ground]`, its work on the spinning frame's
    /// displacement increment (the trapezoidal rule of `Qᵀ(Ωt) g · Δu`, the work the
    /// scheme's energy sees) and on the ground frame's, `g · (Q₁u₁ − Q₀u₀)`.
    pub(super) fn load_work(
        &self,
        g: &[f64],
        [u0, u1]: [&[f64]; 2],
        [t0, t1]: [f64; 2],
    ) -> [f64; 2] {
        let mut spinning: f64 = g
            .iter()
            .zip(u1)
            .zip(u0)
            .map(|((g, a), b)| g * (a - b))
            .sum();
        let mut ground = spinning;
        let [cs0, cs1] = [t0, t1].map(|t| {
            let (s, c) = (self.spin.omega * t).sin_cos();
            [c, s]
        });
        // The in-plane (x, z) dot product of two 3-vectors.
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[2] * b[2];
        for &(ix, iz, _) in &self.spin.pairs {
            let gv = [g[ix], 0.0, g[iz]];
            let du = [u1[ix] - u0[ix], 0.0, u1[iz] - u0[iz]];
            // Less the non-turning g · Δu counted above.
            spinning -= dot(gv, du);
            ground -= dot(gv, du);
            for cs in [cs0, cs1] {
                spinning += 0.5 * dot(to_spinning(cs, gv), du);
            }
            let [a0, a1] = [(cs0, u0), (cs1, u1)].map(|(cs, u)| to_ground(cs, [u[ix], 0.0, u[iz]]));
            ground += gv[0] * (a1[0] - a0[0]) + gv[2] * (a1[2] - a0[2]);
        }
        [spinning, ground]
    }

    /// `½ k (r_t² − r_a²)` (J) of the suspension at time `t` (s) with the wheel's state `u`:
    /// the true spring's energy less the assembled one's ([`Self::stored`] holds the true
    /// one); zero without a suspension.
    pub(super) fn suspension_energy_correction(&self, u: &[f64], t: f64) -> f64 {
        self.suspension
            .as_ref()
            .map_or(0.0, |sus| sus.energy_correction(self.locate(t).cs, u))
    }

    /// Makes sure the plane responses of `j` and `j + 1` are in the slots (computing the
    /// missing ones in place of those not needed).
    fn ensure(&mut self, op: &ExplicitOperator, j: i64) {
        for key in [j, j + 1] {
            if self.slots.iter().any(|s| s.key == Some(key)) {
                continue;
            }
            let i = if self.slots[0].key.is_some_and(|k| k == j || k == j + 1) {
                1
            } else {
                0
            };
            self.compute_slot(op, i, key);
        }
    }

    /// The responses of plane `key` into slot `i`: from rest, a unit spinning-frame load
    /// change in x, y, z over a contact step (sub-step `k` applies `hold.share(k, steps)`).
    fn compute_slot(&mut self, op: &ExplicitOperator, i: usize, key: i64) {
        let mut unit = std::mem::take(&mut self.f);
        let mut fk = std::mem::take(&mut self.fk);
        let mut slot = std::mem::replace(
            &mut self.slots[i],
            PlaneResponse {
                key: None,
                r: UnitResponse::zeros(0),
            },
        );
        let at = OnWheel {
            j: key,
            s: 0.0,
            cs: [1.0, 0.0],
        };
        for c in 0..3 {
            unit.iter_mut().for_each(|x| *x = 0.0);
            let mut e = [0.0; 3];
            e[c] = 1.0;
            self.load(at, e, &mut unit);
            let (u, v) = (&mut slot.r.u[c], &mut slot.r.v[c]);
            u.iter_mut().for_each(|x| *x = 0.0);
            v.iter_mut().for_each(|x| *x = 0.0);
            for k in 0..self.steps {
                let a = self.hold.share(k, self.steps);
                fk.iter_mut().zip(&unit).for_each(|(x, y)| *x = a * y);
                self.spin.step(op, self.dt, u, v, &fk, &mut self.sc);
            }
        }
        slot.key = Some(key);
        self.slots[i] = slot;
        self.f = unit;
        self.fk = fk;
    }

    fn slot(&self, key: i64) -> &PlaneResponse {
        if self.slots[0].key == Some(key) {
            &self.slots[0]
        } else {
            &self.slots[1]
        }
    }

    /// The wheel's one-contact-step compliance (m/N) per contact-frame direction at the
    /// contact's place of the current step (after [`Self::advance`]).
    pub(super) fn compliance(&mut self, op: &ExplicitOperator) -> [f64; 3] {
        let at = self.at;
        self.ensure(op, at.j);
        let (ra, rb) = (self.slot(at.j), self.slot(at.j + 1));
        // g[c][c'] = displacement along c' at the contact under the interpolated unit load c.
        let mut g = [[0.0; 3]; 3];
        for c in 0..3 {
            let ua = self.read(at, &ra.r.u[c]);
            let ub = self.read(at, &rb.r.u[c]);
            for cp in 0..3 {
                g[c][cp] = (1.0 - at.s) * ua[cp] + at.s * ub[cp];
            }
        }
        self.axes.map(|a| {
            let ar = to_spinning(at.cs, a);
            let mut x = 0.0;
            for c in 0..3 {
                for cp in 0..3 {
                    x += ar[c] * g[c][cp] * ar[cp];
                }
            }
            x
        })
    }

    /// Adds the response to the contact-force change `df` (N, contact frame) applied over the
    /// current step as the hold says to the state (after [`Self::compliance`]).
    pub(super) fn correct(&self, df: [f64; 3], u: &mut [f64], v: &mut [f64]) {
        let at = self.at;
        let dr = to_spinning(at.cs, self.ground_of(df));
        for (key, wj) in [(at.j, 1.0 - at.s), (at.j + 1, at.s)] {
            self.slot(key).r.add_to(wj, dr, u, v);
        }
    }

    /// The ground-x material velocity (m/s) of the wheel at the contact at t = 0 beyond
    /// rigid rolling, `v + Ω ŷ × u` (x component: `v_x + Ω u_z`), from the state `u`, `v`.
    pub(super) fn contact_velocity_x(&self, u: &[f64], v: &[f64]) -> f64 {
        let at = self.locate(0.0);
        self.read(at, v)[0] + self.spin.omega * self.read(at, u)[2]
    }

    /// Adds to `v` (at t = 0, frames aligned) the spinning-frame velocity of the ground-fixed
    /// deflection `u` (steady rolling): `v = −Ω ∂w/∂θ` of the cylindrical components
    /// `w = (w_r, w_θ, w_y)` of `u` at each spinning node (central differences over the
    /// angle planes), so that the static deflection stays under the contact instead of
    /// turning away with the wheel.
    pub(super) fn add_rolling_velocity(&self, wheel: &WheelStructure, u: &[f64], v: &mut [f64]) {
        let topo = &wheel.topology;
        let (nt, nm) = (topo.thetas.len(), topo.meridian.len());
        let tau = std::f64::consts::TAU;
        let dm = &wheel.dofmap;
        let get = |node: usize, c: usize| dm.free_index(3 * node + c).map_or(0.0, |i| u[i]);
        // Cylindrical components at the node's own angle θ: e_r = (sin θ, 0, −cos θ),
        // e_θ = (cos θ, 0, sin θ).
        let cyl = |k: usize, m: usize, th: f64| {
            let node = topo.node(k, m);
            let (s, c) = th.sin_cos();
            let (x, y, z) = (get(node, 0), get(node, 1), get(node, 2));
            [s * x - c * z, c * x + s * z, y]
        };
        for k in 0..nt {
            let th = topo.thetas[k];
            let (kp, km) = ((k + 1) % nt, (k + nt - 1) % nt);
            let h2 = (topo.thetas[kp] - th).rem_euclid(tau);
            let h1 = (th - topo.thetas[km]).rem_euclid(tau);
            let (s, c) = th.sin_cos();
            for m in 0..nm {
                let w0 = cyl(k, m, th);
                let wp = cyl(kp, m, topo.thetas[kp]);
                let wm = cyl(km, m, topo.thetas[km]);
                let d = [0, 1, 2].map(|q| {
                    (h1 * h1 * (wp[q] - w0[q]) + h2 * h2 * (w0[q] - wm[q])) / (h1 * h2 * (h1 + h2))
                });
                let om = self.spin.omega;
                let (dr, dt, dy) = (-om * d[0], -om * d[1], -om * d[2]);
                let node = topo.node(k, m);
                let cart = [s * dr + c * dt, dy, -c * dr + s * dt];
                for q in 0..3 {
                    if let Some(i) = dm.free_index(3 * node + q) {
                        v[i] += cart[q];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{check_step_turn, to_ground, to_spinning, SpinError};
    /// The step-turn check against hand-computed plane spacings: planes at −0.1, 0 and
    /// 0.2 rad are 0.1, 0.2 and (wrapping round) 2π − 0.3 rad apart, so the smallest spacing
    /// is 0.1 rad: 0.099 rad passes, and 0.1 rad and any backward turn fail.
    #[test]
    fn a_contact_step_must_turn_forward_by_less_than_a_plane_spacing() {
        let th = [-0.1, 0.0, 0.2];
        assert!(check_step_turn(&th, 0.0).is_ok());
        assert!(check_step_turn(&th, 0.099).is_ok());
        match check_step_turn(&th, 0.1) {
            Err(SpinError::StepTurn { spacing_rad, .. }) => {
                assert!((spacing_rad - 0.1).abs() < 1e-15)
            }
            other => panic!("expected StepTurn, got {other:?}"),
        }
        assert!(check_step_turn(&th, -1e-6).is_err());
        // Two planes: the wrap-around gap is the smaller one.
        assert!(check_step_turn(&[0.0, 4.0], 2.0).is_ok());
        assert!(check_step_turn(&[0.0, 4.0], 2.3).is_err());
    }

    /// Ground and spinning components are inverse rotations, and the ground vertical seen
    /// from the spinning frame is `(−sin α, 0, cos α)`.
    #[test]
    fn rotations_are_inverse() {
        let a: f64 = 0.7;
        let cs = [a.cos(), a.sin()];
        let x = [0.3, -1.2, 2.5];
        let y = to_ground(cs, to_spinning(cs, x));
        for c in 0..3 {
            assert!((x[c] - y[c]).abs() < 1e-15);
        }
        let d = to_spinning(cs, [0.0, 0.0, 1.0]);
        assert!((d[0] + a.sin()).abs() < 1e-15 && (d[2] - a.cos()).abs() < 1e-15);
    }
}

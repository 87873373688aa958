//! The penalty contact law on the explicit path's central-difference step (P4b in
//! validation/contact_patch.md): two elastic steel blocks, the upper one's bottom-face nodes
//! the slaves, the lower one's top face the master. Checked against a conservation law (the
//! step's energy ledger plus the penalty's stored energy and the friction's dissipation stays
//! the initial kinetic energy) and against Coulomb's closed form (a pressed block sliding on
//! the other decelerates by `µ F / m`).

use super::operator::ExplicitOperator;
use super::stable::StableStep;
use crate::contact::penalty::{bilinear_weights, segment_stiffness, PenaltyLaw, TangentialState};
use crate::fe::assembly::{assemble, AssemblyOptions, DofMap};
use crate::fe::block::{block_node, graded_block_mesh};
use crate::fe::material::IsotropicElastic;
use crate::mesh::Part;

/// Element edge of both blocks (m).
const H: f64 = 1e-3;

/// One block: its operator, the DOF map and its surface's nodes on the tensor grid.
struct Block {
    op: ExplicitOperator,
    dofmap: DofMap,
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// Surface node of grid point `(i, j)` at `i · ys.len() + j`.
    surface: Vec<usize>,
    /// Vertical position of the surface (m).
    z_m: f64,
}

fn axis(n: usize, start: f64) -> Vec<f64> {
    (0..=n).map(|i| start + i as f64 * H).collect()
}

/// A steel block of `n` elements of edge `H` starting at `origin`; its surface the top
/// (`top = true`, base held) or the bottom face (free).
fn block(n: [usize; 3], origin: [f64; 3], top: bool) -> Block {
    let (xs, ys, zs) = (
        axis(n[0], origin[0]),
        axis(n[1], origin[1]),
        axis(n[2], origin[2]),
    );
    let mesh = graded_block_mesh([&xs, &ys, &zs], 0, Part::Rail);
    let k_face = if top { n[2] } else { 0 };
    let mut fixed = Vec::new();
    if top {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let node = block_node(n[0], n[1], i, j, 0);
                fixed.extend([3 * node, 3 * node + 1, 3 * node + 2]);
            }
        }
    }
    let dofmap = DofMap::with_constraints(mesh.nodes.len(), &fixed).unwrap();
    let fm = assemble(
        &mesh,
        &[IsotropicElastic::STEEL],
        &[],
        &[],
        &dofmap,
        AssemblyOptions::default(),
    )
    .unwrap();
    let op = ExplicitOperator::new(fm.k.as_ref(), fm.m.as_ref(), fm.c.as_ref()).unwrap();
    let surface = (0..=n[0])
        .flat_map(|i| (0..=n[1]).map(move |j| block_node(n[0], n[1], i, j, k_face)))
        .collect();
    Block {
        op,
        dofmap,
        z_m: zs[k_face],
        xs,
        ys,
        surface,
    }
}

impl Block {
    fn free(&self, node: usize, dir: usize) -> Option<usize> {
        self.dofmap.free_index(3 * node + dir)
    }

    fn value(&self, u: &[f64], node: usize, dir: usize) -> f64 {
        self.free(node, dir).map_or(0.0, |f| u[f])
    }

    fn mass_of(&self, node: usize) -> f64 {
        self.free(node, 2)
            .map_or(f64::INFINITY, |f| self.op.mass()[f])
    }
}

/// The contact of the upper block's bottom nodes (slaves) on the lower block's top face.
struct Contact {
    law: PenaltyLaw,
    /// Initial gap of each slave (m): the blocks' separation plus a Hertzian `r² / 2R`.
    gap0: Vec<f64>,
    states: Vec<TangentialState>,
    /// Each slave's relative displacement (slave less master point, x and y) at the last
    /// step (m).
    rel: Vec<[f64; 2]>,
    /// Each slave's penetration at the last evaluation (m).
    penetration: Vec<f64>,
    dissipated_j: f64,
    /// The springs' energy in the central difference's cross form between the last two
    /// evaluations, `Σ k_n ⟨p_k⟩⟨p_{k+1}⟩ / 2 + f_k · f_{k+1} / 2 k_t` (J): the penalty's
    /// counterpart of the step's `u_kᵀ K u_{k+1} / 2`.
    cross_j: f64,
}

impl Contact {
    /// The contact forces at the state `(u_up, u_low)` into `f_up`, `f_low` (N); updates
    /// the springs, the dissipation and the stored energy.
    fn forces(
        &mut self,
        (up, u_up, f_up): (&Block, &[f64], &mut [f64]),
        (low, u_low, f_low): (&Block, &[f64], &mut [f64]),
    ) {
        f_up.fill(0.0);
        f_low.fill(0.0);
        self.cross_j = 0.0;
        let ny = up.ys.len();
        for (s, &node) in up.surface.iter().enumerate() {
            let (i, j) = (s / ny, s % ny);
            let us = [0, 1, 2].map(|d| up.value(u_up, node, d));
            let at = [up.xs[i] + us[0], up.ys[j] + us[1]];
            let w = bilinear_weights(&low.xs, &low.ys, at);
            let lny = low.ys.len();
            let um = [0, 1, 2].map(|d| {
                w.iter()
                    .map(|&(a, b, wk)| wk * low.value(u_low, low.surface[a * lny + b], d))
                    .sum::<f64>()
            });
            let penetration = -(self.gap0[s] + us[2] - um[2]);
            let rel = [us[0] - um[0], us[1] - um[1]];
            let inc = [rel[0] - self.rel[s][0], rel[1] - self.rel[s][1]];
            self.rel[s] = rel;
            let old = self.states[s].force_n;
            let f = self.law.update(penetration, inc, &mut self.states[s]);
            self.dissipated_j += f.dissipated_j;
            let new = self.states[s].force_n;
            self.cross_j +=
                0.5 * self.law.normal_n_per_m * self.penetration[s].max(0.0) * penetration.max(0.0)
                    + (old[0] * new[0] + old[1] * new[1]) / (2.0 * self.law.tangential_n_per_m);
            self.penetration[s] = penetration;
            let force = [f.tangential_n[0], f.tangential_n[1], f.normal_n];
            for d in 0..3 {
                if let Some(k) = up.free(node, d) {
                    f_up[k] += force[d];
                }
                for &(a, b, wk) in &w {
                    if let Some(k) = low.free(low.surface[a * lny + b], d) {
                        f_low[k] -= wk * force[d];
                    }
                }
            }
        }
    }
}

/// The two blocks and their contact: a 12 × 12 × 4 base held at its bottom, a 4 × 4 × 3
/// block above its centre with the separation `gap_m` (m) at its centre node and a Hertzian
/// `r² / 2R` (`radius_m`, ∞ for flat) beyond it; penalty scale `scale`, friction `µ`.
fn two_blocks(gap_m: f64, radius_m: f64, scale: f64, mu: f64) -> (Block, Block, Contact) {
    let low = block([12, 12, 4], [-6.0 * H, -6.0 * H, -4.0 * H], true);
    let up = block([4, 4, 3], [-2.0 * H, -2.0 * H, 0.0], false);
    let steel = IsotropicElastic::STEEL;
    let k = segment_stiffness(
        steel.youngs_modulus,
        steel.poisson_ratio,
        H * H,
        H * H * H,
        scale,
    )
    .unwrap();
    let law = PenaltyLaw {
        normal_n_per_m: k,
        tangential_n_per_m: k,
        friction: mu,
    };
    let ny = up.ys.len();
    let gap0 = (0..up.surface.len())
        .map(|s| {
            let (x, y) = (up.xs[s / ny], up.ys[s % ny]);
            gap_m + up.z_m - low.z_m + (x * x + y * y) / (2.0 * radius_m)
        })
        .collect();
    let n = up.surface.len();
    let contact = Contact {
        law,
        gap0,
        states: vec![TangentialState::default(); n],
        rel: vec![[0.0; 2]; n],
        penetration: vec![f64::NEG_INFINITY; n],
        dissipated_j: 0.0,
        cross_j: 0.0,
    };
    (up, low, contact)
}

/// A stable step (s): 0.9 of the critical step of the stiffer block with the penalty springs
/// added to its lightest surface node (`ω² ≤ ω_max² + k (1/m_s + 1/m_m)`).
fn stable_step(up: &Block, low: &Block, k: f64) -> f64 {
    let w = |b: &Block| StableStep::estimate(&b.op).unwrap().omega_max_bound;
    let m_min = |b: &Block| {
        b.surface
            .iter()
            .map(|&n| b.mass_of(n))
            .fold(f64::INFINITY, f64::min)
    };
    let omega2 = w(up).max(w(low)).powi(2) + k * (1.0 / m_min(up) + 1.0 / m_min(low));
    0.9 * 2.0 / omega2.sqrt()
}

#[test]
fn penalty_impact_with_friction_closes_the_energy_ledger() {
    let (up, low, mut contact) = two_blocks(1e-6, 0.1, 1.0, 0.3);
    let dt = stable_step(&up, &low, contact.law.normal_n_per_m);
    let (nu, nl) = (up.op.n(), low.op.n());
    let (mut u_up, mut u_low) = (vec![0.0; nu], vec![0.0; nl]);
    let mut v_up = vec![0.0; nu];
    for n in 0..up.dofmap.n_nodes() {
        for (d, v0) in [(0, 0.5), (2, -1.0)] {
            if let Some(k) = up.free(n, d) {
                v_up[k] = v0;
            }
        }
    }
    let mut v_low = vec![0.0; nl];
    let e0 = up.op.kinetic_energy(&v_up);
    let (mut f_up, mut f_low) = (vec![0.0; nu], vec![0.0; nl]);
    let (mut s_up, mut s_low) = (up.op.scratch(), low.op.scratch());
    let mut worst: f64 = 0.0;
    // the step's conserved energy at k − ½ (kinetic and the strain's cross form), at first
    // the initial kinetic energy
    let mut before = e0;
    let mut touched = false;
    let mut steps = 0;
    let mut separated_for = 0;
    // until the block has left the base for 200 steps (or 40,000 steps)
    while separated_for < 200 && steps < 40_000 {
        // the dissipation through step k − 1, before the springs update at u_k
        let dissipated = contact.dissipated_j;
        contact.forces((&up, &u_up, &mut f_up), (&low, &u_low, &mut f_low));
        // the energy at the half step k − ½: the step's sums and the springs' cross form
        let closure = before + contact.cross_j + dissipated - e0;
        worst = worst.max(closure.abs() / e0);
        let in_contact = f_up.iter().any(|f| *f != 0.0);
        touched |= in_contact;
        separated_for = if touched && !in_contact {
            separated_for + 1
        } else {
            0
        };
        let a = up.op.step(dt, &mut u_up, &mut v_up, &f_up, &mut s_up);
        let b = low.op.step(dt, &mut u_low, &mut v_low, &f_low, &mut s_low);
        before = a.kinetic_j + a.strain_cross_j + b.kinetic_j + b.strain_cross_j;
        steps += 1;
    }
    let ke = up.op.kinetic_energy(&v_up);
    println!(
        "dt {dt:.3e} s, {steps} steps; initial {e0:.4e} J; dissipated {:.4e} J ({:.2} %), left as the block's kinetic energy {ke:.4e} J; worst ledger closure {:.3} %",
        contact.dissipated_j,
        100.0 * contact.dissipated_j / e0,
        100.0 * worst
    );
    assert!(touched && separated_for == 200, "the block bounced off");
    assert!(contact.dissipated_j > 0.0, "friction dissipated");
    assert!(worst < 0.01, "the ledger closes within 1 %: {worst}");
}

#[test]
fn a_pressed_block_sliding_decelerates_by_mu_f_over_m() {
    // flat on flat, pressed by a body force F, sliding at 0.5 m/s: Coulomb's friction force
    // µ F (once the normal force's ringing averages to F) takes its momentum at the rate µ F
    let (mu, force) = (0.3, 2.5);
    let (up, low, mut contact) = two_blocks(0.0, f64::INFINITY, 1.0, mu);
    let dt = stable_step(&up, &low, contact.law.normal_n_per_m);
    let (nu, nl) = (up.op.n(), low.op.n());
    let mass: f64 = (0..up.dofmap.n_nodes())
        .filter_map(|n| up.free(n, 2))
        .map(|k| up.op.mass()[k])
        .sum();
    let mut body = vec![0.0; nu];
    let mut v_up = vec![0.0; nu];
    let x_dofs: Vec<usize> = (0..up.dofmap.n_nodes())
        .filter_map(|n| up.free(n, 0))
        .collect();
    for n in 0..up.dofmap.n_nodes() {
        if let Some(k) = up.free(n, 2) {
            body[k] = -force * up.op.mass()[k] / mass;
        }
        if let Some(k) = up.free(n, 0) {
            v_up[k] = 0.5;
        }
    }
    let momentum = |v: &[f64]| -> f64 { x_dofs.iter().map(|&k| up.op.mass()[k] * v[k]).sum() };
    let p0 = momentum(&v_up);
    let (mut u_up, mut u_low, mut v_low) = (vec![0.0; nu], vec![0.0; nl], vec![0.0; nl]);
    let (mut f_up, mut f_low) = (vec![0.0; nu], vec![0.0; nl]);
    let (mut s_up, mut s_low) = (up.op.scratch(), low.op.scratch());
    let mut history: Vec<(f64, f64)> = Vec::new();
    let mut t = 0.0;
    // until the momentum has fallen to a fifth (the slide stops at about 2.5e-4 s)
    while momentum(&v_up) > 0.2 * p0 && history.len() < 100_000 {
        contact.forces((&up, &u_up, &mut f_up), (&low, &u_low, &mut f_low));
        for (f, b) in f_up.iter_mut().zip(&body) {
            *f += b;
        }
        up.op.step(dt, &mut u_up, &mut v_up, &f_up, &mut s_up);
        low.op.step(dt, &mut u_low, &mut v_low, &f_low, &mut s_low);
        t += dt;
        history.push((t, momentum(&v_up)));
    }
    // the least-squares slope of the momentum over the slide's last four fifths
    let tail = &history[history.len() / 5..];
    let n = tail.len() as f64;
    let (mt, mp) = (
        tail.iter().map(|h| h.0).sum::<f64>() / n,
        tail.iter().map(|h| h.1).sum::<f64>() / n,
    );
    let slope = tail.iter().map(|h| (h.0 - mt) * (h.1 - mp)).sum::<f64>()
        / tail.iter().map(|h| (h.0 - mt).powi(2)).sum::<f64>();
    let closed = -mu * force;
    println!(
        "dt {dt:.3e} s, {} steps to a fifth of the momentum; dp/dt {slope:.5} N against −µF = {closed:.5} N ({:+.3} %); deceleration {:.1} m/s²",
        history.len(),
        100.0 * (slope / closed - 1.0),
        -slope / mass
    );
    assert!((slope / closed - 1.0).abs() < 0.02);
}

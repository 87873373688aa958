//! Penalty contact with Coulomb friction between FE surfaces: the contact law of the
//! commercial explicit codes, which the reference study's passages used (theory §6.10).
//!
//! What it models: node-to-surface contact. Each slave node (here the tread's FE surface
//! nodes) meets a master point on the other body's surface (the rail head's), the master's
//! displacement and the slave's force shared by the bilinear shape functions of the master
//! face below it. The normal force is a spring on the penetration, `F_n = k_n ⟨−g⟩` (N; `g`
//! the gap, m; `⟨·⟩` the positive part), zero in separation. Friction is Coulomb's through an
//! elastic tangential spring: the trial force `f* = f_old − k_t Δs` (Δs the slave's tangential
//! displacement increment relative to the master point, m) is returned radially onto the
//! circle `|f| ≤ µ F_n`; the step's frictional dissipation (J) is what the spring loses
//! beyond the work of the actual forces on the relative motion (trapezoidal, as the central
//! difference measures it): `|f_old|²/2k_t − |f|²/2k_t − (f_old + f)·Δs/2`. In steady sliding
//! that is Coulomb's `µ F_n |Δs|`, in stick zero, and when the normal force falls it includes
//! the energy the lowered limit releases; the energy the return removes, `(|f*|² − |f|²) /
//! 2 k_t`, would exceed Coulomb's by `k_t λ² / 2` per step (`λ` the slip the return takes up),
//! an error of first order in the step. A contact that opens releases its spring's energy as
//! dissipation.
//!
//! The penalty per node is the segment stiffness of the codes, [`segment_stiffness`]:
//! `k = s K A² / V` (`K` the bulk modulus, `A` the node's face area, `V` its element's
//! volume, `s` the scale, 0.1 by the codes' default). The static normal problem of two
//! elastic bodies with a penalty ([`solve_static_normal`]) is solved on their condensed
//! point compliances: `F_i = k ⟨δ − g₀_i − (C F)_i⟩`, `Σ F_i = P`, by an active-set
//! iteration; `k = ∞` is the rigid (Lagrange) limit.
//!
//! Assumptions: small displacements and a fixed contact normal (the contact frame's); the
//! tangential spring is the regularisation of stick (the codes' "elastic slip"); friction is
//! isotropic with one coefficient (no static/dynamic distinction, as the reference's µ).
//!
//! References: J. O. Hallquist, *LS-DYNA Theory Manual* (2006), the chapter on sliding
//! interfaces (the penalty segment stiffness, friction); P. Wriggers, *Computational Contact
//! Mechanics*, 2nd ed. (2006), the penalty method and the return mapping of Coulomb friction;
//! T. Belytschko, W. K. Liu, B. Moran, *Nonlinear Finite Elements for Continua and
//! Structures* (2000), ch. 10 (contact-impact).

use nalgebra::{DMatrix, DVector};

use super::{check_positive, ContactError};

/// The codes' default scale of the segment stiffness (−).
pub const DEFAULT_SCALE: f64 = 0.1;

/// The segment stiffness of the codes (N/m): `scale · K · A² / V`, `K = E / (3 (1 − 2ν))`
/// the bulk modulus (Pa), `area_m2` the node's (or segment's) face area (m²), `volume_m3`
/// the element behind it (m³), `scale` (−, above 0; 0.1 by default, [`DEFAULT_SCALE`]).
pub fn segment_stiffness(
    youngs_pa: f64,
    poisson: f64,
    area_m2: f64,
    volume_m3: f64,
    scale: f64,
) -> Result<f64, ContactError> {
    check_positive("youngs_pa", youngs_pa)?;
    check_positive("area_m2", area_m2)?;
    check_positive("volume_m3", volume_m3)?;
    check_positive("scale", scale)?;
    if !(poisson > -1.0 && poisson < 0.5) {
        return Err(ContactError::InvalidParameter {
            name: "poisson",
            value: poisson,
            reason: "between -1 and 0.5",
        });
    }
    let bulk = youngs_pa / (3.0 * (1.0 - 2.0 * poisson));
    Ok(scale * bulk * area_m2 * area_m2 / volume_m3)
}

/// The penalty law of one slave node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenaltyLaw {
    /// Normal penalty `k_n` (N/m, above 0).
    pub normal_n_per_m: f64,
    /// Tangential (stick) penalty `k_t` (N/m, above 0).
    pub tangential_n_per_m: f64,
    /// Coulomb friction coefficient µ (−, 0–2).
    pub friction: f64,
}

/// The tangential spring's state of one slave node: its force on the slave (N, contact
/// frame x and y), zero out of contact.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TangentialState {
    /// The spring's force on the slave (N).
    pub force_n: [f64; 2],
}

/// One slave node's contact force over a step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PointForce {
    /// Normal force on the slave, pushing it out of the master (N, ≥ 0).
    pub normal_n: f64,
    /// Tangential force on the slave (N).
    pub tangential_n: [f64; 2],
    /// Whether the node slid this step (the return was active).
    pub slipping: bool,
    /// Energy the friction dissipated this step (J, ≥ 0).
    pub dissipated_j: f64,
}

impl PenaltyLaw {
    /// Checks the parameters (names the one out of range).
    pub fn check(&self) -> Result<(), ContactError> {
        check_positive("normal_n_per_m", self.normal_n_per_m)?;
        check_positive("tangential_n_per_m", self.tangential_n_per_m)?;
        if !(0.0..=2.0).contains(&self.friction) {
            return Err(ContactError::InvalidParameter {
                name: "friction",
                value: self.friction,
                reason: "between 0 and 2",
            });
        }
        Ok(())
    }

    /// The force on a slave node at penetration `penetration_m` (m; negative is a gap)
    /// after its tangential increment `slip_increment_m` relative to the master point (m),
    /// updating the spring's `state`. Out of contact the spring unloads (its stored energy is
    /// dissipated) and the increment does not load it.
    pub fn update(
        &self,
        penetration_m: f64,
        slip_increment_m: [f64; 2],
        state: &mut TangentialState,
    ) -> PointForce {
        let kt = self.tangential_n_per_m;
        if penetration_m <= 0.0 {
            // separated: the spring is not loaded by the motion; what it stored is released
            let f = state.force_n;
            *state = TangentialState::default();
            return PointForce {
                dissipated_j: (f[0] * f[0] + f[1] * f[1]) / (2.0 * kt),
                ..PointForce::default()
            };
        }
        let normal = self.normal_n_per_m * penetration_m;
        let trial = [
            state.force_n[0] - kt * slip_increment_m[0],
            state.force_n[1] - kt * slip_increment_m[1],
        ];
        let t2 = trial[0] * trial[0] + trial[1] * trial[1];
        let limit = self.friction * normal;
        if t2 <= limit * limit {
            state.force_n = trial;
            return PointForce {
                normal_n: normal,
                tangential_n: trial,
                slipping: false,
                dissipated_j: 0.0,
            };
        }
        let old = state.force_n;
        let scale = limit / t2.sqrt();
        let new = [trial[0] * scale, trial[1] * scale];
        state.force_n = new;
        // what the spring lost beyond the work done on it (trapezoidal, the actual forces)
        let stored = |f: [f64; 2]| (f[0] * f[0] + f[1] * f[1]) / (2.0 * kt);
        let work = -0.5
            * ((old[0] + new[0]) * slip_increment_m[0] + (old[1] + new[1]) * slip_increment_m[1]);
        PointForce {
            normal_n: normal,
            tangential_n: new,
            slipping: true,
            dissipated_j: stored(old) + work - stored(new),
        }
    }

    /// The energy stored in the node's springs (J): `k_n ⟨p⟩² / 2 + |f_t|² / 2 k_t`.
    pub fn stored_energy(&self, penetration_m: f64, state: &TangentialState) -> f64 {
        let p = penetration_m.max(0.0);
        let f = state.force_n;
        0.5 * self.normal_n_per_m * p * p
            + (f[0] * f[0] + f[1] * f[1]) / (2.0 * self.tangential_n_per_m)
    }
}

/// The bilinear shape-function weights of the point `p` (m) on the tensor grid `xs × ys`
/// (each strictly increasing, at least two values): `[(i, j, weight); 4]` of the face that
/// contains it (the nearest face outside the grid, extrapolated).
pub fn bilinear_weights(xs: &[f64], ys: &[f64], p: [f64; 2]) -> [(usize, usize, f64); 4] {
    let cell = |q: &[f64], v: f64| -> (usize, f64) {
        let i = q.partition_point(|&w| w <= v).clamp(1, q.len() - 1) - 1;
        (i, (v - q[i]) / (q[i + 1] - q[i]))
    };
    let (i, s) = cell(xs, p[0]);
    let (j, t) = cell(ys, p[1]);
    [
        (i, j, (1.0 - s) * (1.0 - t)),
        (i + 1, j, s * (1.0 - t)),
        (i + 1, j + 1, s * t),
        (i, j + 1, (1.0 - s) * t),
    ]
}

/// The static normal solution of [`solve_static_normal`].
#[derive(Debug, Clone, PartialEq)]
pub struct StaticNormal {
    /// Normal force per point (N, ≥ 0).
    pub forces_n: Vec<f64>,
    /// Penetration per point, `δ − g₀ − (C F)` (m; positive in contact).
    pub penetration_m: Vec<f64>,
    /// Rigid approach of the two bodies δ (m).
    pub approach_m: f64,
    /// Active-set iterations.
    pub iterations: usize,
}

/// Active-set iterations allowed (each drops every point of negative force or admits every
/// penetrating one; a Hertzian patch settles in a few dozen).
const MAX_ACTIVE_SET_ITERATIONS: usize = 200;

/// The static normal contact of two elastic bodies pressed together by `load_n` (N, above
/// 0) with a penalty `stiffness_n_per_m` per point (N/m, above 0; `f64::INFINITY` for the
/// rigid limit): `compliance` (m/N, `n × n`, symmetric positive semi-definite) the
/// displacement of the gap at point `i` per unit force pair at point `j` (both bodies' sum),
/// `gap_m` the initial gap at each point (m). Solves `F_i = k ⟨δ − g₀_i − (C F)_i⟩` with
/// `Σ F = P` by an active-set iteration (points with negative force leave, points that
/// penetrate join; each iteration a dense Cholesky solve of the active block).
pub fn solve_static_normal(
    compliance: &DMatrix<f64>,
    gap_m: &[f64],
    stiffness_n_per_m: f64,
    load_n: f64,
) -> Result<StaticNormal, ContactError> {
    let n = gap_m.len();
    if compliance.nrows() != n || compliance.ncols() != n {
        return Err(ContactError::WrongLength {
            name: "compliance",
            got: compliance.nrows() * compliance.ncols(),
            expected: n * n,
            per: "point pair",
        });
    }
    check_positive("load_n", load_n)?;
    if stiffness_n_per_m.is_nan() || stiffness_n_per_m <= 0.0 {
        return Err(ContactError::InvalidParameter {
            name: "stiffness_n_per_m",
            value: stiffness_n_per_m,
            reason: "above 0 (infinity for the rigid limit)",
        });
    }
    if n == 0 || gap_m.iter().any(|g| !g.is_finite()) {
        return Err(ContactError::InvalidParameter {
            name: "gap_m",
            value: n as f64,
            reason: "at least one point, all finite",
        });
    }
    let soft = 1.0 / stiffness_n_per_m;
    // start from the points of the smallest gap
    let g_min = gap_m.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut active: Vec<usize> = (0..n).filter(|&i| gap_m[i] <= g_min).collect();
    let mut violations = 0;
    for it in 1..=MAX_ACTIVE_SET_ITERATIONS {
        let m = active.len();
        let mut a = DMatrix::<f64>::from_fn(m, m, |r, c| compliance[(active[r], active[c])]);
        for r in 0..m {
            a[(r, r)] += soft;
        }
        let chol = a.cholesky().ok_or(ContactError::InvalidParameter {
            name: "compliance",
            value: m as f64,
            reason: "symmetric positive definite on the contact points (with the penalty)",
        })?;
        let ones = DVector::<f64>::from_element(m, 1.0);
        let g = DVector::<f64>::from_fn(m, |r, _| gap_m[active[r]]);
        let x = chol.solve(&ones);
        let y = chol.solve(&g);
        let delta = (load_n + y.sum()) / x.sum();
        let mut forces = vec![0.0; n];
        for (r, &i) in active.iter().enumerate() {
            forces[i] = delta * x[r] - y[r];
        }
        let cf = compliance * DVector::from_column_slice(&forces);
        let penetration: Vec<f64> = (0..n).map(|i| delta - gap_m[i] - cf[i]).collect();
        let negative: Vec<usize> = active
            .iter()
            .copied()
            .filter(|&i| forces[i] < 0.0)
            .collect();
        let tol = 1e-12 * delta.abs().max(g_min.abs());
        // the tolerance guards the joining side only: a point just touching stays out
        let mut is_active = vec![false; n];
        for &i in &active {
            is_active[i] = true;
        }
        let joining: Vec<usize> = (0..n)
            .filter(|&i| !is_active[i] && penetration[i] > tol)
            .collect();
        violations = negative.len() + joining.len();
        if negative.is_empty() && joining.is_empty() {
            return Ok(StaticNormal {
                forces_n: forces,
                penetration_m: penetration,
                approach_m: delta,
                iterations: it,
            });
        }
        // drop every point of negative force first, then admit every penetrating one
        if negative.is_empty() {
            active.extend(joining);
            active.sort_unstable();
        } else {
            active.retain(|i| forces[*i] >= 0.0);
            if active.is_empty() {
                active.push(negative[0]);
            }
        }
    }
    Err(ContactError::NotConverged {
        solver: "static penalty contact (active set; residual: points still violating)",
        iterations: MAX_ACTIVE_SET_ITERATIONS,
        residual: violations as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::{
        bilinear_weights, segment_stiffness, solve_static_normal, PenaltyLaw, TangentialState,
    };
    use approx::assert_relative_eq;
    use nalgebra::DMatrix;

    const LAW: PenaltyLaw = PenaltyLaw {
        normal_n_per_m: 1e7,
        tangential_n_per_m: 5e6,
        friction: 0.3,
    };

    #[test]
    fn segment_stiffness_of_a_cube_is_scale_times_bulk_times_edge() {
        // K = E / (3 (1 − 2ν)) = 175 GPa for steel; A² / V of a cube of edge h is h
        let h = 0.8e-3;
        let k = segment_stiffness(210e9, 0.3, h * h, h * h * h, 0.1).unwrap();
        assert_relative_eq!(k, 0.1 * 175e9 * h, max_relative = 1e-12);
        assert!(segment_stiffness(210e9, 0.5, h * h, h * h * h, 0.1).is_err());
        assert!(segment_stiffness(210e9, 0.3, h * h, 0.0, 0.1).is_err());
    }

    #[test]
    fn normal_force_is_the_spring_on_the_penetration() {
        let mut s = TangentialState::default();
        let f = LAW.update(2e-6, [0.0; 2], &mut s);
        assert_eq!(f.normal_n, 20.0);
        assert_eq!(LAW.update(-1e-6, [0.0; 2], &mut s).normal_n, 0.0);
        assert_relative_eq!(
            LAW.stored_energy(2e-6, &s),
            0.5 * 1e7 * 4e-12,
            max_relative = 1e-12
        );
    }

    #[test]
    fn friction_sticks_below_the_limit_and_slides_at_mu_n() {
        // penetration 1e-5 m: N = 100 N, limit 30 N; stick spring 5e6 N/m reaches it at 6 µm
        let mut s = TangentialState::default();
        let mut slid = 0.0;
        let mut dissipated = 0.0;
        let mut work = 0.0;
        let step = 1e-6;
        for k in 0..20 {
            let old = s.force_n[0];
            let f = LAW.update(1e-5, [step, 0.0], &mut s);
            // the work of the actual forces on the relative motion (trapezoidal)
            work += -(old + s.force_n[0]) / 2.0 * step;
            dissipated += f.dissipated_j;
            if k < 6 {
                assert!(!f.slipping, "step {k}");
                assert_relative_eq!(f.tangential_n[0], -5.0 * (k + 1) as f64, epsilon = 1e-9);
            } else {
                assert!(f.slipping, "step {k}");
                assert_relative_eq!(f.tangential_n[0], -30.0, epsilon = 1e-9);
                slid += step;
            }
        }
        // stored + dissipated = the work of the forces on the relative motion, exactly
        let stored = LAW.stored_energy(0.0, &s);
        assert_relative_eq!(stored + dissipated, work, max_relative = 1e-12);
        // Coulomb: µ N times the slid distance (14 µm)
        assert_relative_eq!(dissipated, 30.0 * slid, max_relative = 1e-12);
    }

    #[test]
    fn opening_with_a_loaded_spring_dissipates_its_energy() {
        let mut s = TangentialState::default();
        LAW.update(1e-5, [2e-6, 0.0], &mut s);
        let stored = LAW.stored_energy(1e-5, &s) - 0.5 * 1e7 * 1e-10;
        let f = LAW.update(-1e-6, [0.0; 2], &mut s);
        assert_eq!(s.force_n, [0.0, 0.0]);
        assert_relative_eq!(f.dissipated_j, stored, max_relative = 1e-12);
    }

    #[test]
    fn a_falling_normal_force_releases_the_springs_excess_as_dissipation() {
        // 10 N in stick at N = 100 N; N falls to 20 N (limit 6 N) without motion: the spring
        // drops to 6 N and the energy between, (10² − 6²)/2k_t, is dissipated
        let mut s = TangentialState::default();
        LAW.update(1e-5, [2e-6, 0.0], &mut s);
        let f = LAW.update(2e-6, [0.0; 2], &mut s);
        assert_relative_eq!(f.tangential_n[0], -6.0, epsilon = 1e-12);
        assert_relative_eq!(f.dissipated_j, (100.0 - 36.0) / 1e7, max_relative = 1e-12);
    }

    #[test]
    fn separated_motion_neither_loads_nor_dissipates() {
        let mut s = TangentialState::default();
        let f = LAW.update(-1e-6, [1e-3, 0.0], &mut s);
        assert_eq!(f, super::PointForce::default());
        assert_eq!(s, TangentialState::default());
    }

    #[test]
    fn slip_direction_follows_the_increment() {
        let mut s = TangentialState::default();
        let f = LAW.update(1e-5, [3e-5, 4e-5], &mut s);
        // the force opposes the increment, on the circle of radius µN = 30 N
        assert_relative_eq!(f.tangential_n[0], -18.0, epsilon = 1e-9);
        assert_relative_eq!(f.tangential_n[1], -24.0, epsilon = 1e-9);
    }

    #[test]
    fn bilinear_weights_reproduce_a_bilinear_field() {
        let xs = [0.0, 1.0, 3.0];
        let ys = [0.0, 2.0];
        let field = |x: f64, y: f64| 1.0 + 2.0 * x - 0.5 * y + 0.25 * x * y;
        for p in [[0.5, 1.0], [2.0, 0.3], [3.0, 2.0], [0.0, 0.0]] {
            let w = bilinear_weights(&xs, &ys, p);
            let v: f64 = w.iter().map(|&(i, j, w)| w * field(xs[i], ys[j])).sum();
            assert_relative_eq!(v, field(p[0], p[1]), epsilon = 1e-12);
            assert_relative_eq!(w.iter().map(|t| t.2).sum::<f64>(), 1.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn rigid_bodies_share_the_load_among_the_closest_points() {
        // C = 0: with equal gaps every point carries P / n, the approach is P / (n k)
        let c = DMatrix::<f64>::zeros(4, 4);
        let s = solve_static_normal(&c, &[0.0; 4], 1e6, 400.0).unwrap();
        for f in &s.forces_n {
            assert_relative_eq!(*f, 100.0, max_relative = 1e-12);
        }
        assert_relative_eq!(s.approach_m, 1e-4, max_relative = 1e-12);
        // gaps 0 and 1e-4: the second point joins only above P = k g = 100 N
        let c2 = DMatrix::<f64>::zeros(2, 2);
        let s = solve_static_normal(&c2, &[0.0, 1e-4], 1e6, 80.0).unwrap();
        assert_eq!(s.forces_n, vec![80.0, 0.0]);
        let s = solve_static_normal(&c2, &[0.0, 1e-4], 1e6, 300.0).unwrap();
        // δ = (P/k + g) / 2 = 2e-4: forces 200 and 100 N
        assert_relative_eq!(s.approach_m, 2e-4, max_relative = 1e-12);
        assert_relative_eq!(s.forces_n[0], 200.0, max_relative = 1e-12);
        assert_relative_eq!(s.forces_n[1], 100.0, max_relative = 1e-12);
    }

    #[test]
    fn winkler_foundation_under_a_cylinder_is_the_closed_form() {
        // A Winkler bed (diagonal compliance c per point) under a parabolic gap x²/2R: in
        // contact F_i = (δ − x_i²/2R)/(c + 1/k); the contact half-width b = √(2Rδ) with
        // P = Σ F. The points are dense, so the sum is the integral: P = (4/3) b δ/((c+1/k) h).
        let (h, r, c, k) = (1e-5, 0.05, 2e-8, 1e8);
        let n = 801;
        let x: Vec<f64> = (0..n).map(|i| (i as f64 - 400.0) * h).collect();
        let gap: Vec<f64> = x.iter().map(|x| x * x / (2.0 * r)).collect();
        let cm = DMatrix::<f64>::from_diagonal_element(n, n, c);
        let load = 2e3;
        let s = solve_static_normal(&cm, &gap, k, load).unwrap();
        let d = s.approach_m;
        for (i, xi) in x.iter().enumerate() {
            let expect = ((d - xi * xi / (2.0 * r)) / (c + 1.0 / k)).max(0.0);
            assert_relative_eq!(s.forces_n[i], expect, epsilon = 1e-9 * load);
        }
        let b = (2.0 * r * d).sqrt();
        let integral = 4.0 / 3.0 * b * d / ((c + 1.0 / k) * h);
        assert_relative_eq!(integral, load, max_relative = 5e-3);
        let total: f64 = s.forces_n.iter().sum();
        assert_relative_eq!(total, load, max_relative = 1e-12);
    }

    #[test]
    fn the_static_solver_refuses_bad_input() {
        let c = DMatrix::<f64>::zeros(2, 2);
        assert!(solve_static_normal(&c, &[0.0; 3], 1e6, 1.0).is_err());
        assert!(solve_static_normal(&c, &[0.0; 2], 0.0, 1.0).is_err());
        assert!(solve_static_normal(&c, &[0.0; 2], 1e6, -1.0).is_err());
        assert!(solve_static_normal(&c, &[0.0, f64::NAN], 1e6, 1.0).is_err());
        // rigid bodies and a rigid penalty: singular
        assert!(solve_static_normal(&c, &[0.0; 2], f64::INFINITY, 1.0).is_err());
    }
}

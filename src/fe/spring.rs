//! Linear multipoint spring-dampers and point masses.
//!
//! # Model
//! A [`Spring`] acts on a *relative displacement* that is a weighted combination of global
//! DOFs,
//!
//! `r = Σ_a w_a u(dof_a) − Σ_b w_b u(dof_b) = gᵀ u`   (m),
//!
//! with `g` the signed weight vector (side a positive, side b negative; side b empty means
//! ground). The force is `f = −(k r + c ṙ) g`, so its element matrices are `K_s = k g gᵀ`
//! (N/m) and `C_s = c g gᵀ` (N·s/m), and its strain energy is `½ k r²` (J). This one
//! element covers a point spring node–node or node–ground in one direction, a spring from a
//! node to an interpolated point of a hexahedron face (weights = shape functions, so the
//! spring acts on the interpolated displacement), and a pad spread over a patch of nodes
//! (weights = tributary fractions). It is linear-elastic, small-displacement, direction fixed
//! in space (a global axis or any combination of DOFs the caller supplies).
//!
//! A [`PointMass`] adds a mass (kg) to the three translational DOFs of one node.
//!
//! Global DOF of node `n`, direction `d`: `3 n + d` (see [`crate::fe`]). Constrained DOFs
//! in `g` are dropped at assembly (their displacement is zero).

use super::hex8;
use super::FeError;

/// A global translation direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// x, along the rail.
    X,
    /// y, lateral.
    Y,
    /// z, vertical.
    Z,
}

impl Direction {
    /// All three directions in DOF order.
    pub const ALL: [Direction; 3] = [Direction::X, Direction::Y, Direction::Z];

    /// DOF offset within a node (0, 1, 2).
    pub fn index(self) -> usize {
        match self {
            Direction::X => 0,
            Direction::Y => 1,
            Direction::Z => 2,
        }
    }

    /// Global DOF index `3 node + index` of this direction at a node.
    pub fn dof(self, node: usize) -> usize {
        3 * node + self.index()
    }
}

/// A linear spring-damper between two weighted DOF sets (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Spring {
    /// Side a: `(global DOF, weight)`, entering `r` with a plus sign.
    pub side_a: Vec<(usize, f64)>,
    /// Side b: `(global DOF, weight)`, entering `r` with a minus sign; empty = ground.
    pub side_b: Vec<(usize, f64)>,
    /// Stiffness k (N/m), ≥ 0.
    pub stiffness: f64,
    /// Viscous damping c (N·s/m), ≥ 0.
    pub damping: f64,
}

impl Spring {
    /// A general multipoint spring from DOF-level weights.
    pub fn new(
        side_a: Vec<(usize, f64)>,
        side_b: Vec<(usize, f64)>,
        stiffness_n_per_m: f64,
        damping_ns_per_m: f64,
    ) -> Self {
        Spring {
            side_a,
            side_b,
            stiffness: stiffness_n_per_m,
            damping: damping_ns_per_m,
        }
    }

    /// A spring from one node to the ground in direction `dir`.
    pub fn node_to_ground(
        node: usize,
        dir: Direction,
        stiffness_n_per_m: f64,
        damping_ns_per_m: f64,
    ) -> Self {
        Self::new(
            vec![(dir.dof(node), 1.0)],
            vec![],
            stiffness_n_per_m,
            damping_ns_per_m,
        )
    }

    /// A spring between two nodes in direction `dir` (`r = u_a − u_b`).
    pub fn node_to_node(
        node_a: usize,
        node_b: usize,
        dir: Direction,
        stiffness_n_per_m: f64,
        damping_ns_per_m: f64,
    ) -> Self {
        Self::new(
            vec![(dir.dof(node_a), 1.0)],
            vec![(dir.dof(node_b), 1.0)],
            stiffness_n_per_m,
            damping_ns_per_m,
        )
    }

    /// A spring from a node to the point of natural coordinates `xi` of a hexahedron with
    /// global nodes `hex_nodes` (e.g. a rail-foot node to the sleeper top face under it):
    /// `r = u_node − Σ N_a(ξ) u_{hex_a}` in direction `dir`. Shape functions that vanish
    /// (|N_a| < 1e-14, e.g. the far face) are dropped.
    pub fn node_to_point(
        node: usize,
        hex_nodes: &[usize; 8],
        xi: [f64; 3],
        dir: Direction,
        stiffness_n_per_m: f64,
        damping_ns_per_m: f64,
    ) -> Self {
        let n = hex8::shape_functions(xi);
        let side_b = hex_nodes
            .iter()
            .zip(n)
            .filter(|(_, w)| w.abs() >= 1e-14)
            .map(|(&h, w)| (dir.dof(h), w))
            .collect();
        Self::new(
            vec![(dir.dof(node), 1.0)],
            side_b,
            stiffness_n_per_m,
            damping_ns_per_m,
        )
    }

    /// A spring spread over patches of nodes in direction `dir`: `r = Σ w_a u_a − Σ w_b u_b`,
    /// node weights e.g. tributary-area fractions (summing to 1 on each side for a pad that
    /// acts on the mean displacement). `nodes_b` empty = ground.
    pub fn patch(
        nodes_a: &[(usize, f64)],
        nodes_b: &[(usize, f64)],
        dir: Direction,
        stiffness_n_per_m: f64,
        damping_ns_per_m: f64,
    ) -> Self {
        let map = |s: &[(usize, f64)]| s.iter().map(|&(n, w)| (dir.dof(n), w)).collect();
        Self::new(
            map(nodes_a),
            map(nodes_b),
            stiffness_n_per_m,
            damping_ns_per_m,
        )
    }

    /// The signed weight vector `g` as `(global DOF, weight)`, duplicates merged, sorted by
    /// DOF.
    pub fn weights(&self) -> Vec<(usize, f64)> {
        let mut g: Vec<(usize, f64)> = self
            .side_a
            .iter()
            .copied()
            .chain(self.side_b.iter().map(|&(d, w)| (d, -w)))
            .collect();
        g.sort_by_key(|e| e.0);
        let mut out: Vec<(usize, f64)> = Vec::with_capacity(g.len());
        for (d, w) in g {
            match out.last_mut() {
                Some(last) if last.0 == d => last.1 += w,
                _ => out.push((d, w)),
            }
        }
        out
    }

    /// Relative displacement `r = gᵀ u` (m) for a full (unreduced) displacement vector (m).
    /// DOFs beyond the vector's length count as zero (call [`Spring::validate`] first).
    pub fn relative_displacement(&self, u_full: &[f64]) -> f64 {
        let get = |d: usize| u_full.get(d).copied().unwrap_or(0.0);
        self.side_a.iter().map(|&(d, w)| w * get(d)).sum::<f64>()
            - self.side_b.iter().map(|&(d, w)| w * get(d)).sum::<f64>()
    }

    /// Strain energy `½ k r²` (J) for a full displacement vector (m).
    pub fn energy(&self, u_full: &[f64]) -> f64 {
        let r = self.relative_displacement(u_full);
        0.5 * self.stiffness * r * r
    }

    /// Checks DOF ranges, finite weights and non-negative finite k and c; `index` is the
    /// spring's position in its list (for the message).
    pub fn validate(&self, index: usize, n_dofs: usize) -> Result<(), FeError> {
        if !(self.stiffness.is_finite() && self.stiffness >= 0.0) {
            return Err(FeError::InvalidSpring {
                index,
                reason: format!("stiffness {} N/m must be finite and ≥ 0", self.stiffness),
            });
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(FeError::InvalidSpring {
                index,
                reason: format!("damping {} N·s/m must be finite and ≥ 0", self.damping),
            });
        }
        if self.side_a.is_empty() {
            return Err(FeError::InvalidSpring {
                index,
                reason: "side a is empty: give at least one DOF (side b may be empty = ground)"
                    .into(),
            });
        }
        for &(d, w) in self.side_a.iter().chain(&self.side_b) {
            if d >= n_dofs {
                return Err(FeError::IndexOutOfRange {
                    what: format!("spring {index} DOF"),
                    index: d,
                    len: n_dofs,
                });
            }
            if !w.is_finite() {
                return Err(FeError::InvalidSpring {
                    index,
                    reason: format!("weight {w} of DOF {d} is not finite"),
                });
            }
        }
        Ok(())
    }
}

/// A point mass (kg) on a node, acting in x, y and z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Global node index.
    pub node: usize,
    /// Mass (kg), ≥ 0.
    pub mass: f64,
}

#[cfg(test)]
mod tests {
    use super::{Direction, FeError, Spring};
    #[test]
    fn weights_merge_and_sign() {
        let s = Spring::new(
            vec![(3, 1.0), (5, 0.5)],
            vec![(5, 0.25), (0, 2.0)],
            1.0,
            0.0,
        );
        assert_eq!(s.weights(), vec![(0, -2.0), (3, 1.0), (5, 0.25)]);
    }

    #[test]
    fn spring_energy_is_half_k_r_squared() {
        // Node 1 z against the centre of the top face of a hex (ξ = 0, η = 0, ζ = 1): the
        // interpolated displacement is the mean of the four top nodes (closed form).
        let hex = [10, 11, 12, 13, 14, 15, 16, 17];
        let s = Spring::node_to_point(1, &hex, [0.0, 0.0, 1.0], Direction::Z, 2.0e8, 1.0e4);
        assert_eq!(s.side_b.len(), 4);
        let mut u = vec![0.0; 3 * 18];
        u[Direction::Z.dof(1)] = 1.0e-3;
        for (i, n) in (14..18).enumerate() {
            u[Direction::Z.dof(n)] = 1.0e-4 * (i as f64 + 1.0); // mean 2.5e-4
        }
        let r = 1.0e-3 - 2.5e-4;
        assert!((s.relative_displacement(&u) - r).abs() < 1e-18);
        assert!((s.energy(&u) - 0.5 * 2.0e8 * r * r).abs() < 1e-9);
        assert!(s.validate(0, u.len()).is_ok());
        assert!(s.validate(0, 10).is_err());
        let bad = Spring::node_to_ground(0, Direction::X, -1.0, 0.0);
        assert!(matches!(
            bad.validate(7, 3),
            Err(FeError::InvalidSpring { index: 7, .. })
        ));
    }
}

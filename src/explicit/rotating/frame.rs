//! The spinning frame of the rotating wheel (docs/theory.md §8.7): its x–z DOF pairs and
//! lumped masses, the gyroscopic central-difference step (a Cayley rotation of the half-step
//! velocity per node), the rigid turn about the axle, and the turn of vectors between the
//! ground and the spinning frame.

use super::{DofMap, ExplicitError, ExplicitOperator, SpinError, StepScratch};

/// A substructure spinning at `Ω` (rad/s) about the y axis through the origin: the
/// spinning nodes' x and z DOFs and their lumped masses, and the gyroscopic central
/// difference step.
#[derive(Clone, Debug)]
pub struct SpinFrame {
    pub(super) omega: f64,
    /// Free indices of the x and z DOF of each spinning node, and its lumped mass (kg).
    pub(super) pairs: Vec<(usize, usize, f64)>,
    /// The rigid rotation about the spin axis over the spinning nodes (x and z components
    /// per node, 1/√kg): `ŷ × X`, M-orthogonal to the x and z translations and
    /// M-normalised. The spin softening is not applied to it (see [`SpinFrame::step`]).
    axial: Vec<[f64; 2]>,
}

/// Scratch of [`SpinFrame::step`] (allocated once).
#[derive(Clone, Debug)]
pub struct SpinScratch {
    f: Vec<f64>,
    v_old: Vec<[f64; 2]>,
    op: StepScratch,
}

impl SpinFrame {
    /// The spin at `omega` (rad/s, positive about +y) of `nodes` of a substructure with the
    /// operator `op`, DOF map `dofmap` and node positions `positions` (m). Every spinning
    /// node needs free x and z DOFs with equal lumped masses (so that the Coriolis matrix is
    /// skew).
    pub fn new(
        op: &ExplicitOperator,
        dofmap: &DofMap,
        positions: &[[f64; 3]],
        nodes: impl IntoIterator<Item = usize>,
        omega: f64,
    ) -> Result<Self, ExplicitError> {
        if !omega.is_finite() {
            return Err(SpinError::NonFiniteRate { omega }.into());
        }
        let m = op.mass();
        let mut pairs = Vec::new();
        let mut axial = Vec::new();
        for node in nodes {
            let (Some(ix), Some(iz)) =
                (dofmap.free_index(3 * node), dofmap.free_index(3 * node + 2))
            else {
                return Err(SpinError::HeldInPlane { node }.into());
            };
            if (m[ix] - m[iz]).abs() > 1e-9 * m[ix] {
                return Err(SpinError::UnequalMasses {
                    node,
                    mass_x_kg: m[ix],
                    mass_z_kg: m[iz],
                }
                .into());
            }
            pairs.push((ix, iz, m[ix]));
            // ŷ × X = (z, 0, −x).
            let p = positions[node];
            axial.push([p[2], -p[0]]);
        }
        Ok(SpinFrame {
            omega,
            axial: axial_rotation(&pairs, axial),
            pairs,
        })
    }

    /// The M-weighted rigid rotation about the spin axis contained in `u` (m·√kg): the
    /// coefficient of [`SpinFrame::axial`].
    fn axial_part(&self, u: &[f64]) -> f64 {
        self.pairs
            .iter()
            .zip(&self.axial)
            .map(|(&(ix, iz, m), r)| m * (r[0] * u[ix] + r[1] * u[iz]))
            .sum()
    }

    /// The spin rate (rad/s).
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// `½ Ω² uᵀ S u` (J), the centrifugal potential's share of the stored energy with a minus
    /// sign (`S = M_⊥ − M a aᵀ M`, `a` the axial rotation).
    pub(crate) fn softening_energy(&self, u: &[f64]) -> f64 {
        let perp: f64 = self
            .pairs
            .iter()
            .map(|&(ix, iz, m)| m * (u[ix] * u[ix] + u[iz] * u[iz]))
            .sum();
        let a = self.axial_part(u);
        0.5 * self.omega * self.omega * (perp - a * a)
    }

    /// Scratch for [`Self::step`].
    pub fn scratch(&self, op: &ExplicitOperator) -> SpinScratch {
        SpinScratch {
            f: vec![0.0; op.n()],
            v_old: vec![[0.0; 2]; self.pairs.len()],
            op: op.scratch(),
        }
    }

    /// One central-difference step of length `dt` (s) in the spinning frame under the load
    /// `f` (N, spinning-frame components): `u` from `u_k` to `u_{k+1}`, `v` from `v_{k−½}` to
    /// `v_{k+½}`. With `Ω = 0` it is bitwise [`ExplicitOperator::step`]. No allocation.
    ///
    /// The operator's step runs with the spin-softening force and the Coriolis force of the
    /// lagged velocity added to `f`; each spinning node's velocity is then corrected to the
    /// midpoint rule of the Coriolis term, `(I + hJ) v⁺ = (I − hJ) v⁻ + Δt a` with
    /// `h = ΩΔt` (`J² = −I` in the x–z plane, so `(I + hJ)⁻¹ = (I − hJ)/(1 + h²)`), and the
    /// displacement with it. Returns the operator's damper work over the step (J, with the
    /// velocity before the Coriolis correction; it differs from the corrected one's by the
    /// relative order `ΩΔt`).
    pub fn step(
        &self,
        op: &ExplicitOperator,
        dt: f64,
        u: &mut [f64],
        v: &mut [f64],
        f: &[f64],
        sc: &mut SpinScratch,
    ) -> f64 {
        let w = self.omega;
        sc.f.copy_from_slice(f);
        let w2 = w * w;
        let c = self.axial_part(u);
        for (p, (&(ix, iz, m), r)) in self.pairs.iter().zip(&self.axial).enumerate() {
            let (vx, vz) = (v[ix], v[iz]);
            sc.v_old[p] = [vx, vz];
            // −Ω² M_⊥ (u − a aᵀM u) moved to the load side (a the axial rotation); −2Ω m ŷ × v
            // with ŷ × v = (v_z, 0, −v_x).
            sc.f[ix] += m * (w2 * (u[ix] - c * r[0]) - 2.0 * w * vz);
            sc.f[iz] += m * (w2 * (u[iz] - c * r[1]) + 2.0 * w * vx);
        }
        let damper_j = op.step(dt, u, v, &sc.f, &mut sc.op).damper_work_j;
        let h = w * dt;
        let inv = 1.0 / (1.0 + h * h);
        for (p, &(ix, iz, _)) in self.pairs.iter().enumerate() {
            let [ox, oz] = sc.v_old[p];
            let (tx, tz) = (v[ix], v[iz]);
            // b = v_tmp + hJ v⁻ = (I − hJ) v⁻ + Δt a; v⁺ = (I − hJ) b / (1 + h²).
            let (bx, bz) = (tx + h * oz, tz - h * ox);
            let (nx, nz) = ((bx - h * bz) * inv, (bz + h * bx) * inv);
            v[ix] = nx;
            v[iz] = nz;
            u[ix] += dt * (nx - tx);
            u[iz] += dt * (nz - tz);
        }
        damper_j
    }

    /// The scheme's conserved energy (J) between `u_k` (`u_prev`) and `u_{k+1}` (`u`) with
    /// the half-step velocity `v = v_{k+½}`: `½ vᵀMv + ½ u_kᵀ K u_{k+1} − ½ Ω² u_kᵀ S u_{k+1}`
    /// with `S = M_⊥ − M a aᵀ M` (kinetic energy relative to the spinning frame, strain
    /// energy, centrifugal potential; `a` the axial rotation); `ku` is scratch of length n.
    pub fn discrete_energy(
        &self,
        op: &ExplicitOperator,
        u_prev: &[f64],
        u: &[f64],
        v: &[f64],
        ku: &mut [f64],
    ) -> f64 {
        op.apply_k(u, ku);
        let strain: f64 = 0.5
            * u_prev
                .iter()
                .zip(ku.iter())
                .map(|(a, b)| a * b)
                .sum::<f64>();
        let centrifugal: f64 = self
            .pairs
            .iter()
            .map(|&(ix, iz, m)| m * (u_prev[ix] * u[ix] + u_prev[iz] * u[iz]))
            .sum::<f64>()
            - self.axial_part(u_prev) * self.axial_part(u);
        op.kinetic_energy(v) + strain - 0.5 * self.omega * self.omega * centrifugal
    }
}

/// The rigid rotation `ŷ × X` (`raw`, x and z per spinning node of `pairs`) made
/// M-orthogonal to the x and z translations of the spinning nodes and M-normalised; zero
/// when it has no mass (no nodes, or all on the axis).
fn axial_rotation(pairs: &[(usize, usize, f64)], mut raw: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    let mass: f64 = pairs.iter().map(|p| p.2).sum();
    for c in 0..2 {
        let mean = pairs.iter().zip(&raw).map(|(p, r)| p.2 * r[c]).sum::<f64>() / mass;
        raw.iter_mut().for_each(|r| r[c] -= mean);
    }
    let norm2: f64 = pairs
        .iter()
        .zip(&raw)
        .map(|(p, r)| p.2 * (r[0] * r[0] + r[1] * r[1]))
        .sum();
    if norm2.is_nan() || norm2 <= 0.0 {
        return vec![[0.0; 2]; pairs.len()];
    }
    let k = 1.0 / norm2.sqrt();
    raw.iter().map(|r| [k * r[0], k * r[1]]).collect()
}

/// `(cos α, sin α)` of a rotation about +y by `α` (rad): ground components of a spinning-frame
/// vector `(x, z)` are `(c x + s z, −s x + c z)`.
pub(super) fn to_ground([c, s]: [f64; 2], [x, y, z]: [f64; 3]) -> [f64; 3] {
    [c * x + s * z, y, -s * x + c * z]
}

/// Spinning-frame components of a ground vector (the inverse of [`to_ground`]).
pub(super) fn to_spinning([c, s]: [f64; 2], [x, y, z]: [f64; 3]) -> [f64; 3] {
    [c * x - s * z, y, s * x + c * z]
}

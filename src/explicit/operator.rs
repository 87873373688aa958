//! The central-difference operator of one substructure: the untruncated stiffness `K`
//! (N/m), the lumped mass `M` (kg, diagonal) and the discrete damping `C` (N·s/m) over the
//! free DOFs, and the explicit step (docs/theory.md §8.1)
//!
//! ```text
//! v_{k+½} = v_{k−½} + Δt M⁻¹ (f_k − K u_k − C v_{k−½})
//! u_{k+1} = u_k + Δt v_{k+½}
//! ```
//!
//! The damper force uses the lagged half-step velocity, so the step stays explicit; no
//! numerical damping is added. `K` is stored once as symmetric rows (CSR with 32-bit column
//! indices); `C` keeps only its non-zero entries (the discrete dampers touch few DOFs). A
//! row's update reads only the previous state, so any partition of the rows gives bitwise
//! the same result: the step is independent of the thread count.

use faer::sparse::SparseColMatRef;
use rayon::prelude::*;

use super::ExplicitError;

/// Rows per parallel chunk of the step (a fixed partition; the result does not depend on it).
const CHUNK: usize = 4096;

/// Below this many DOFs the step runs on one thread (the fork/join costs more than it saves).
const PARALLEL_MIN_DOFS: usize = 20_000;

/// Sums a step accumulates over its rows (in a fixed order).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepSums {
    /// Work of the external load over the step, `Δt f_k · (v_{k−½} + v_{k+½}) / 2` (J).
    pub external_work_j: f64,
    /// Work of the damper force over the step, `Δt (C v_{k−½}) · (v_{k−½} + v_{k+½}) / 2`
    /// (J, ≥ 0 for a dissipative C up to the lag).
    pub damper_work_j: f64,
    /// `½ u_kᵀ K u_{k+1}` (J): the strain part of the central difference's conserved energy.
    pub strain_cross_j: f64,
    /// `½ v_{k+½}ᵀ M v_{k+½}` (J).
    pub kinetic_j: f64,
}

impl StepSums {
    fn add(&mut self, o: &StepSums) {
        self.external_work_j += o.external_work_j;
        self.damper_work_j += o.damper_work_j;
        self.strain_cross_j += o.strain_cross_j;
        self.kinetic_j += o.kinetic_j;
    }
}

/// `K`, lumped `M` and `C` of one substructure, ready for explicit steps.
#[derive(Clone, Debug)]
pub struct ExplicitOperator {
    n: usize,
    row_ptr: Vec<usize>,
    col: Vec<u32>,
    k: Vec<f64>,
    c_rows: Vec<u32>,
    c_ptr: Vec<usize>,
    c_col: Vec<u32>,
    c_val: Vec<f64>,
    mass: Vec<f64>,
    inv_mass: Vec<f64>,
    lumped_from_consistent: bool,
}

/// Scratch of the step (allocated once, reused for every step).
#[derive(Clone, Debug)]
pub struct StepScratch {
    damper: Vec<f64>,
    u_next: Vec<f64>,
    partial: Vec<StepSums>,
}

impl ExplicitOperator {
    /// Builds the operator from assembled matrices (full symmetric storage, free DOFs).
    /// A consistent `M` is lumped by row sums (and [`Self::lumped_from_consistent`] says so);
    /// every DOF must carry mass.
    pub fn new(
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        c: SparseColMatRef<'_, usize, f64>,
    ) -> Result<Self, ExplicitError> {
        let n = k.nrows();
        for (name, a) in [("M", m), ("C", c)] {
            if a.nrows() != n || a.ncols() != n {
                return Err(ExplicitError::Shape {
                    what: name,
                    rows: a.nrows(),
                    cols: a.ncols(),
                    n,
                });
            }
        }
        if k.ncols() != n {
            return Err(ExplicitError::Shape {
                what: "K",
                rows: n,
                cols: k.ncols(),
                n,
            });
        }
        if n > u32::MAX as usize {
            return Err(ExplicitError::TooLarge { dofs: n });
        }
        // K is symmetric: its columns are its rows.
        let cp = k.symbolic().col_ptr();
        let ri = k.symbolic().row_idx();
        let kv = k.val();
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut col = Vec::with_capacity(kv.len());
        let mut kval = Vec::with_capacity(kv.len());
        row_ptr.push(0);
        for j in 0..n {
            for p in cp[j]..cp[j + 1] {
                if kv[p] != 0.0 {
                    col.push(ri[p] as u32);
                    kval.push(kv[p]);
                }
            }
            row_ptr.push(col.len());
        }
        // Lumped mass: row sums (exactly the diagonal when M is already lumped).
        let mut mass = vec![0.0; n];
        let mut lumped_from_consistent = false;
        let (mcp, mri, mv) = (m.symbolic().col_ptr(), m.symbolic().row_idx(), m.val());
        for j in 0..n {
            for p in mcp[j]..mcp[j + 1] {
                if mv[p] != 0.0 {
                    mass[mri[p]] += mv[p];
                    if mri[p] != j {
                        lumped_from_consistent = true;
                    }
                }
            }
        }
        if let Some(i) = mass.iter().position(|&x| !(x > 0.0 && x.is_finite())) {
            return Err(ExplicitError::Massless {
                dof: i,
                mass_kg: mass[i],
            });
        }
        let inv_mass = mass.iter().map(|&x| 1.0 / x).collect();
        // C: only rows with non-zero entries.
        let (ccp, cri, cv) = (c.symbolic().col_ptr(), c.symbolic().row_idx(), c.val());
        let (mut c_rows, mut c_ptr, mut c_col, mut c_val) = (vec![], vec![0], vec![], vec![]);
        for j in 0..n {
            let start = c_col.len();
            for p in ccp[j]..ccp[j + 1] {
                if cv[p] != 0.0 {
                    c_col.push(cri[p] as u32);
                    c_val.push(cv[p]);
                }
            }
            if c_col.len() > start {
                c_rows.push(j as u32);
                c_ptr.push(c_col.len());
            }
        }
        Ok(ExplicitOperator {
            n,
            row_ptr,
            col,
            k: kval,
            c_rows,
            c_ptr,
            c_col,
            c_val,
            mass,
            inv_mass,
            lumped_from_consistent,
        })
    }

    /// Number of DOFs.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Stored non-zeros of `K`.
    pub fn nnz(&self) -> usize {
        self.k.len()
    }

    /// The lumped mass per DOF (kg).
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// True when the assembled `M` was consistent and was lumped here by row sums.
    pub fn lumped_from_consistent(&self) -> bool {
        self.lumped_from_consistent
    }

    /// Memory held by the operator (bytes).
    pub fn bytes(&self) -> usize {
        self.row_ptr.len() * 8
            + self.col.len() * 4
            + self.k.len() * 8
            + self.c_col.len() * 12
            + self.c_rows.len() * 12
            + self.n * 16
    }

    /// Scratch for [`Self::step`].
    pub fn scratch(&self) -> StepScratch {
        StepScratch {
            damper: vec![0.0; self.n],
            u_next: vec![0.0; self.n],
            partial: vec![StepSums::default(); self.n.div_ceil(CHUNK).max(1)],
        }
    }

    /// `out = K u` (N).
    pub fn apply_k(&self, u: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.row_dot(i, u);
        }
    }

    /// `out = C v` (N).
    pub(crate) fn apply_c(&self, v: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|x| *x = 0.0);
        for (r, &row) in self.c_rows.iter().enumerate() {
            let mut s = 0.0;
            for p in self.c_ptr[r]..self.c_ptr[r + 1] {
                s += self.c_val[p] * v[self.c_col[p] as usize];
            }
            out[row as usize] = s;
        }
    }

    /// `½ uᵀ K u` (J).
    pub fn strain_energy(&self, u: &[f64]) -> f64 {
        0.5 * (0..self.n).map(|i| u[i] * self.row_dot(i, u)).sum::<f64>()
    }

    /// `½ vᵀ M v` (J).
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        0.5 * v
            .iter()
            .zip(&self.mass)
            .map(|(&x, &m)| m * x * x)
            .sum::<f64>()
    }

    /// `vᵀ C v` (W): the power of the dampers at velocity `v`.
    pub fn damper_power(&self, v: &[f64], scratch: &mut StepScratch) -> f64 {
        self.apply_c(v, &mut scratch.damper);
        scratch.damper.iter().zip(v).map(|(a, b)| a * b).sum()
    }

    #[inline]
    fn row_dot(&self, i: usize, u: &[f64]) -> f64 {
        let mut s = 0.0;
        for p in self.row_ptr[i]..self.row_ptr[i + 1] {
            s += self.k[p] * u[self.col[p] as usize];
        }
        s
    }

    /// One central-difference step of length `dt` (s) under the load `f` (N, held over the
    /// step): `u` (m) goes from `u_k` to `u_{k+1}`, `v` (m/s) from `v_{k−½}` to `v_{k+½}`.
    /// Returns the step's energy sums. No allocation.
    pub fn step(
        &self,
        dt: f64,
        u: &mut [f64],
        v: &mut [f64],
        f: &[f64],
        scratch: &mut StepScratch,
    ) -> StepSums {
        debug_assert!(u.len() == self.n && v.len() == self.n && f.len() == self.n);
        self.apply_c(v, &mut scratch.damper);
        let fd = &scratch.damper;
        let uk: &[f64] = u;
        let run = |r0: usize, un: &mut [f64], vv: &mut [f64]| -> StepSums {
            let mut s = StepSums::default();
            for (l, (un_i, v_i)) in un.iter_mut().zip(vv.iter_mut()).enumerate() {
                let i = r0 + l;
                let ku = self.row_dot(i, uk);
                let v_old = *v_i;
                let v_new = v_old + dt * self.inv_mass[i] * (f[i] - ku - fd[i]);
                let u_new = uk[i] + dt * v_new;
                let v_mid = 0.5 * (v_old + v_new);
                s.external_work_j += dt * f[i] * v_mid;
                s.damper_work_j += dt * fd[i] * v_mid;
                s.strain_cross_j += 0.5 * ku * u_new;
                s.kinetic_j += 0.5 * self.mass[i] * v_new * v_new;
                *v_i = v_new;
                *un_i = u_new;
            }
            s
        };
        let un = &mut scratch.u_next;
        if self.n >= PARALLEL_MIN_DOFS {
            un.par_chunks_mut(CHUNK)
                .zip(v.par_chunks_mut(CHUNK))
                .zip(scratch.partial.par_iter_mut())
                .enumerate()
                .for_each(|(c, ((un, vv), part))| *part = run(c * CHUNK, un, vv));
        } else {
            for (c, ((un, vv), part)) in un
                .chunks_mut(CHUNK)
                .zip(v.chunks_mut(CHUNK))
                .zip(scratch.partial.iter_mut())
                .enumerate()
            {
                *part = run(c * CHUNK, un, vv);
            }
        }
        u.copy_from_slice(&scratch.u_next);
        let mut total = StepSums::default();
        for p in &scratch.partial {
            total.add(p);
        }
        total
    }

    /// `steps` central-difference steps of length `dt` under the held load `f`; returns the
    /// summed external and damper work and the last step's energies.
    pub fn advance(
        &self,
        dt: f64,
        steps: usize,
        u: &mut [f64],
        v: &mut [f64],
        f: &[f64],
        scratch: &mut StepScratch,
    ) -> StepSums {
        let mut acc = StepSums::default();
        for _ in 0..steps {
            let s = self.step(dt, u, v, f, scratch);
            acc.external_work_j += s.external_work_j;
            acc.damper_work_j += s.damper_work_j;
            acc.strain_cross_j = s.strain_cross_j;
            acc.kinetic_j = s.kinetic_j;
        }
        acc
    }

    /// Iterates `y = M^{-½} K M^{-½} x` (1/s²): the operator whose largest eigenvalue is
    /// ω_max² of the undamped system.
    pub fn apply_scaled(&self, x: &[f64], y: &mut [f64]) {
        let apply = |i: usize| {
            let mut s = 0.0;
            for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                let j = self.col[p] as usize;
                s += self.k[p] * x[j] * self.inv_mass[j].sqrt();
            }
            s * self.inv_mass[i].sqrt()
        };
        if self.n >= PARALLEL_MIN_DOFS {
            y.par_iter_mut()
                .enumerate()
                .for_each(|(i, yi)| *yi = apply(i));
        } else {
            y.iter_mut().enumerate().for_each(|(i, yi)| *yi = apply(i));
        }
    }

    /// Gershgorin's bound on the largest eigenvalue of `M^{-½} K M^{-½}` (1/s²): the largest
    /// row sum `Σ_j |K_ij| / √(m_i m_j)`. An upper bound: a step `2/√bound` is always stable
    /// without damping.
    pub(crate) fn gershgorin_omega2(&self) -> f64 {
        (0..self.n)
            .map(|i| {
                let mut s = 0.0;
                for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                    let j = self.col[p] as usize;
                    s += self.k[p].abs() * (self.inv_mass[i] * self.inv_mass[j]).sqrt();
                }
                s
            })
            .fold(0.0, f64::max)
    }

    /// The Rayleigh quotient of the damping in the scaled vector `z` (of `M^{-½}KM^{-½}`):
    /// `zᵀ M^{-½} C M^{-½} z / zᵀz` (1/s), i.e. `2 ξ ω` of that vector.
    pub(crate) fn scaled_damping_quotient(&self, z: &[f64]) -> f64 {
        let zz: f64 = z.iter().map(|x| x * x).sum();
        if zz == 0.0 {
            return 0.0;
        }
        let mut s = 0.0;
        for (r, &row) in self.c_rows.iter().enumerate() {
            let i = row as usize;
            let mut a = 0.0;
            for p in self.c_ptr[r]..self.c_ptr[r + 1] {
                let j = self.c_col[p] as usize;
                a += self.c_val[p] * z[j] * self.inv_mass[j].sqrt();
            }
            s += z[i] * self.inv_mass[i].sqrt() * a;
        }
        s / zz
    }
}

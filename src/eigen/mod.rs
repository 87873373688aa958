//! Eigenmodes of the wheel–track substructures: the generalised symmetric eigenproblem
//!
//! ```text
//! K φ = λ M φ,   λ = ω² (rad²/s²),   f = ω / 2π (Hz),
//! ```
//!
//! with `K` (N/m, N·m/rad, …) symmetric positive *semi*-definite (rigid-body modes allowed) and
//! `M` (kg, …) symmetric positive definite, both sparse (faer `SparseColMat<usize, f64>`, full
//! symmetric storage, indexed by free DOFs).
//!
//! **Method** (Ericsson & Ruhe, Math. Comp. 35 (1980) 1251–1268; Grimes, Lewis & Simon, SIAM
//! J. Matrix Anal. Appl. 15 (1994) 228–272; Wu & Simon, SIAM J. Matrix Anal. Appl. 22 (2000)
//! 602–616 for thick restart):
//!
//! * **Spectrum slicing.** The band `[λ_min, λ_max)` with `λ = (2π f)²` is cut at shifts
//!   `σ_0 < σ_1 < … < σ_s = λ_max`. At every shift the sparse LDLᵀ of `K − σ M` is computed
//!   once ([`factor`]); its inertia gives the Sturm count `ν(σ)` = number of eigenvalues below
//!   σ (Sylvester's law of inertia). The slice `[σ_i, σ_{i+1})` therefore holds exactly
//!   `ν(σ_{i+1}) − ν(σ_i)` eigenvalues, and the solver does not stop a slice before it has
//!   found that many. For `f_min = 0` the first shift is negative, `σ_0 = −(2π f_rb)²`
//!   (`K − σ_0 M` is then positive definite, `ν(σ_0)` must be 0), so rigid-body modes
//!   (λ = 0) are ordinary, well separated eigenvalues of the transformed problem.
//! * **Shift-invert block Lanczos** in each slice (`lanczos`): the operator
//!   `Op = (K − σM)⁻¹ M` is self-adjoint in the M-inner product, with eigenvalues
//!   `θ = 1/(λ − σ)`; the eigenvalues of the slice are the *largest* θ. A block Krylov basis
//!   (block size b, every block one multi-right-hand-side solve) is kept M-orthonormal by full
//!   re-orthogonalisation (two passes of block classical Gram–Schmidt in the M-inner
//!   product, with the coefficients `(MV)ᵀz` taken from `M V` stored beside `V` — for a
//!   diagonal (lumped) M from `Vᵀ(d∘z)` instead, with no `M V` stored and the first pass's
//!   update fused with the second pass's coefficients in one sweep over V — then a
//!   symmetric (Löwdin) orthonormalisation of the block with one sparse product `M z`, which
//!   is carried into `M V`; another round when a column still shrank by half in the second
//!   pass or the block's Gram matrix is ill-conditioned). For a lumped M the second pass's
//!   update is skipped when its coefficients, which the fused sweep yields anyway, are below
//!   1e-12 of the column.
//!   The Rayleigh quotient `H = Vᵀ M Op V` is formed column block by column block; thick
//!   restart keeps the best Ritz vectors (and converged ones at the far negative end of θ).
//!   All modes found in earlier slices are deflated (the new basis is kept M-orthogonal to
//!   them; being eigenvectors of `Op`, they need one projection per block, not one per pass,
//!   made after the first basis pass so that the round-off of the large unreduced block does
//!   not stay in the small result), and so are the converged pairs that the previous slice found above its upper boundary
//!   (they are carried into this slice instead of being found again).
//!   Every accepted Ritz vector gets one free inverse-iteration step `x' = x + Q(Es)/θ`, which
//!   removes the amplification of the Lanczos residual by `K − σM` in the true residual.
//!   Convergence is checked when the subspace is full and, from half of it on, every 4
//!   blocks, so a slice stops as soon as its wanted pairs have converged instead of
//!   finishing the cycle.
//! * **Adaptive boundaries.** A slice is not cut in advance: Lanczos runs at the lower shift
//!   until 1.25 × `modes_per_slice` Ritz values nearest above it have converged (the
//!   boundary then keeps about `modes_per_slice` of them), the next boundary τ
//!   is put in the widest relative gap of the last third of them, and the Sturm count at τ
//!   must equal the number found below τ (otherwise the slice is iterated again with the
//!   count known, and [`EigenError::MissedModes`] names the interval if that fails). The last
//!   slice (once at most 1.5 × `modes_per_slice` modes remain) ends at `λ_max` with its count
//!   known and is two-sided (shift at its midpoint, see below) with everything below it
//!   deflated, so that its top modes are no farther from the shift than its bottom ones.
//!   For a grounded structure (no eigenvalue below 4/0.9 · |σ₀|, shown by a Sturm count
//!   factorised beside the band's ends) a short probe finds λ₁ and the first slice starts at
//!   0.9 λ₁ (Sturm count 0 there is verified); otherwise the probe could not move the shift
//!   and is skipped. For `f_min > 0` the first slice is two-sided (see below), so that
//!   the eigenvalues just below λ_min, which are not deflated, cannot swamp the iteration.
//! * **Concurrent bands** ([`EigenOptions::concurrent_bands`]). With several threads and a
//!   model of at least 20,000 DOFs the band is cut into two sub-bands (a fixed number, not one
//!   per thread: the modes must not depend on the machine), each sliced as above on one
//!   thread. The sub-band bounds are factorisations shared by the two
//!   neighbouring bands, so their Sturm counts make every band find exactly its own
//!   eigenvalues. Why it pays: the block solves and the re-orthogonalisation are
//!   memory-bound; a parallel column-group solve reads the whole factor once per group, a
//!   band on its own thread once per block, and each band deflates only its own modes.
//!   The bounds follow a work model (count law `ν ∝ x^α` fitted to one probe factorisation,
//!   cost per mode `1 + 2x²`, see `choose_splits`); the probe sits where the bound of the
//!   prior α = 1 would be, is factorised alongside the band's end factorisations and, if the
//!   fit confirms it, is the bound. While several bands run, each is sequential; the last
//!   one running switches to all threads (`Ctx::par`), so the threads whose bands are done
//!   help it finish. Its results do not depend on when that happens: the row ranges of the
//!   dense products are fixed, the factorisations and the one-group solves give bitwise the
//!   same numbers for every parallelism (tested). A band above 0 Hz cannot deflate the
//!   modes below its bound lo, so its first slice is *two-sided*: the Lanczos shift sits at
//!   the midpoint of `[lo, hi)`, the wanted pairs are all eigenvalues in `[lo, hi)` (Sturm
//!   count known) ordered by |θ|, and the undeflated ones below lo are farther from the
//!   shift than every wanted one. It is cut for about `modes_per_slice` modes and re-cut
//!   once if its Sturm count says more than 1.2 times that: it deflates nothing and needs
//!   the most solves per mode. The band's later one-sided slices
//!   are capped at 0.7 times their distance from lo; its two-sided last slice, with the same
//!   margin from its midpoint shift, may be up to 4.7 times that distance wide. The modes within 20 % in λ of a bound (at most 96 on each side) get one joint
//!   Rayleigh–Ritz step, since across a bound they were not deflated against each other.
//!   Times, memory and the orthonormality across a bound: docs/performance.md §2–§3.
//! * **Verification.** Every returned pair gets its true relative residual
//!   `‖Kφ − λMφ‖₂ / (‖Kφ‖₂ + max(|λ|, λ_floor)‖Mφ‖₂)` with `λ_floor = (2π·1 Hz)²` (the floor
//!   avoids 0/0 for rigid-body modes, but for them this measure is dominated by the round-off
//!   of `Kφ` and the normwise backward error `‖Kφ − λMφ‖₂ / ((‖K‖_∞ + |λ|‖M‖_∞)‖φ‖₂)` is the
//!   meaningful one; both are reported), and the M-orthonormality error `max |ΦᵀMΦ − I|`.
//!
//! The modal cache lives in [`cache`].
//!
//! Units: shifts and eigenvalues in rad²/s², frequencies in Hz, times in s.

pub mod basis;
pub mod cache;
pub mod classify;
pub mod factor;
pub(crate) mod lanczos;
pub mod spmm;
pub mod substructure;

#[cfg(test)]
mod tests;

pub use lanczos::solve;

/// The frequency (Hz) whose eigenvalue `(2π f)²` is the floor λ_floor of the relative
/// residual's denominator (module doc). Below it a mode is a rigid-body mode whose computed
/// eigenvalue is round-off, and its relative residual (up to about 1) says nothing about its
/// accuracy.
pub const RESIDUAL_FLOOR_HZ: f64 = 1.0;

use faer::Mat;

/// Fill-reducing ordering for the sparse LDLᵀ.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum FillOrdering {
    /// Run the METIS, identity (given numbering) and AMD symbolic analyses and keep the one
    /// with the smallest factor (default; on the default track METIS, docs/performance.md
    /// §3.1).
    #[default]
    Auto,
    /// faer's approximate minimum degree (robust for any numbering).
    Amd,
    /// Keep the DOF numbering (good when nodes are numbered along a slender rail).
    Identity,
    /// METIS multilevel nested dissection ([`crate::fe::ordering`]).
    Metis,
}

/// Options of the eigensolver. `EigenOptions::new(f_max_hz)` gives the defaults.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EigenOptions {
    /// Upper end of the band (Hz); all modes with f < f_max are computed.
    pub f_max_hz: f64,
    /// Lower end of the band (Hz); 0 includes rigid-body modes.
    pub f_min_hz: f64,
    /// Convergence tolerance on the Ritz residual of the transformed problem,
    /// `‖Op x − θ x‖_M ≤ tol · max(θ, θ_max/100)` (dimensionless). Default 1e-8. Much smaller
    /// values may be unattainable: the residuals stagnate at ≈ u·κ(K − σM)·θ_max
    /// (docs/performance.md §3.3). Eigenvalues are far more accurate than
    /// tol (error ∝ tol²).
    pub tolerance: f64,
    /// Block size b of the block Lanczos method (right-hand sides per solve). Default 8; why
    /// 8 (solved vectors and times for 4–32, and an accuracy case against 12):
    /// docs/performance.md §3.3.
    pub block_size: usize,
    /// Maximum thick restarts per slice before giving up. Default 30.
    pub max_restarts: usize,
    /// Fraction of the unwanted part of the Krylov subspace kept (as Ritz vectors) at a thick
    /// restart, in [0, 0.9]. Default 0.3. Larger keeps more approximate information, smaller
    /// leaves room for a longer Krylov sequence per cycle.
    pub restart_keep: f64,
    /// Target number of modes per slice; the slice boundaries are placed (with Sturm counts)
    /// so that each slice holds about this many. Default 125. The solved-vector count
    /// depends erratically on where the boundaries land (measured: docs/performance.md §3.3).
    pub modes_per_slice: usize,
    /// Largest Krylov subspace of a slice, as a multiple of the modes wanted in it (at least
    /// wanted + 4 blocks), in [1.5, 10]. Default 2.5 (why: docs/performance.md §3.3).
    pub subspace_ratio: f64,
    /// Magnitude (Hz) of the negative shift used for the lowest slice when `f_min_hz == 0`:
    /// σ₀ = −(2π f)². `None` → max(1 Hz, f_max / 100).
    pub rigid_shift_hz: Option<f64>,
    /// Fill-reducing ordering of the LDLᵀ.
    pub ordering: FillOrdering,
    /// Use all rayon threads inside faer (factorisation, solves, dense products).
    pub parallel: bool,
    /// One step of iterative refinement on every block solve (doubles the solve cost). The
    /// LDLᵀ of the indefinite `K − σM` is computed without pivoting, so its solves can lose a
    /// few digits; refinement restores them. Default false (the accuracy is limited by the
    /// re-orthogonalisation noise, not the solves, on the matrices tried).
    pub refine_solves: bool,
    /// Seed of the deterministic random start block.
    pub seed: u64,
    /// Number of frequency bands solved concurrently, one thread each (`None`: two, but no
    /// more than `count / modes_per_slice`, and one when `parallel` is false or the model
    /// has fewer than 20,000 free DOFs, whatever the number of threads, so that the modes do
    /// not depend on the machine; `Some(b)` forces
    /// b, run one after the other when `parallel` is false). The band bounds are Sturm-counted factorisations, so every band finds exactly
    /// its eigenvalues; a band above the lowest cannot deflate the modes below it and starts
    /// its first slice below its bound (as for `f_min > 0`).
    #[serde(default)]
    pub concurrent_bands: Option<usize>,
    /// Compute the full M-orthonormality error ΦᵀMΦ − I even when it is expensive
    /// (n·m² > 2·10¹⁰); otherwise only within slices and between neighbouring slices.
    pub full_orthogonality_check: bool,
}

impl EigenOptions {
    /// Defaults for the band [0, f_max_hz).
    pub fn new(f_max_hz: f64) -> Self {
        Self {
            f_max_hz,
            f_min_hz: 0.0,
            tolerance: 1e-8,
            block_size: 8,
            max_restarts: 30,
            restart_keep: 0.3,
            modes_per_slice: 125,
            subspace_ratio: 2.5,
            rigid_shift_hz: None,
            ordering: FillOrdering::Auto,
            parallel: true,
            refine_solves: false,
            seed: 0x5eed_c0de_1234_5678,
            full_orthogonality_check: false,
            concurrent_bands: None,
        }
    }
}

/// Diagnostics of one spectrum slice `[shift_lo, shift_hi)`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SliceReport {
    /// Lower bound σ_i (rad²/s²); also the Lanczos shift of the slice, except for the
    /// two-sided first slice of a band above 0 Hz, whose shift is the midpoint of the slice.
    pub shift_lo_rad2_s2: f64,
    /// Upper boundary σ_{i+1} (rad²/s²).
    pub shift_hi_rad2_s2: f64,
    /// Sturm count ν(σ_i): eigenvalues below σ_i.
    pub sturm_lo: usize,
    /// Sturm count ν(σ_{i+1}).
    pub sturm_hi: usize,
    /// Modes found in the slice (equals `sturm_hi − sturm_lo` on success).
    pub modes_found: usize,
    /// Modes of this slice that the previous one had already converged above its boundary
    /// (carried in and deflated, not found again).
    #[serde(default)]
    pub carried: usize,
    /// Thick restarts used.
    pub restarts: usize,
    /// Right-hand sides solved with the factorisation of this slice.
    pub solved_vectors: usize,
    /// Wall time of the Lanczos iteration of this slice (s).
    pub lanczos_s: f64,
}

/// Wall-clock timing (s) and work counters of a solve.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct EigenTiming {
    /// Total time (s).
    pub total_s: f64,
    /// Pattern union + symbolic analysis (s).
    pub symbolic_s: f64,
    /// All numeric factorisations (s).
    pub factorize_s: f64,
    /// Number of numeric factorisations.
    pub factorizations: usize,
    /// Time inside triangular solves (s).
    pub solve_s: f64,
    /// Number of right-hand sides solved.
    pub solved_vectors: usize,
    /// Time for the true residuals and the orthonormality check (s).
    pub check_s: f64,
    /// Time in the block M-orthonormalisation (projections, Gram matrices) (s).
    pub orthogonalize_s: f64,
    /// Part of `orthogonalize_s` spent in the sparse products `M z` (one per block and
    /// orthogonalisation round, plus `M·locked` once per slice) (s).
    #[serde(default)]
    pub orthogonalize_spmm_s: f64,
    /// Time in the Rayleigh–Ritz steps (dense eigen of the projected matrix) (s).
    pub rayleigh_ritz_s: f64,
    /// Time forming the restart bases and the returned Ritz vectors (s).
    pub restart_s: f64,
    /// Blocks M-orthonormalised (one per block solve, plus start blocks).
    pub orthogonalized_blocks: usize,
    /// Classical Gram–Schmidt passes applied over all those blocks: 2 per block for a
    /// consistent M; for a lumped M the second pass's update is skipped when it is
    /// negligible (its coefficients below 1e-12 of the column, measured in the first pass's
    /// sweep), so 1 per block is then possible.
    pub orthogonalization_passes: usize,
    /// Stored entries of the LDLᵀ factor.
    pub factor_entries: usize,
    /// Bands solved concurrently (see [`EigenOptions::concurrent_bands`]); with more than
    /// one, the per-phase times above are summed over the bands (thread-seconds while several
    /// run; the last band running uses all threads) and only `total_s` is wall-clock time.
    #[serde(default)]
    pub bands: usize,
}

impl EigenTiming {
    /// Adds the work counters and phase times of a band solved with its own context.
    fn absorb(&mut self, o: &EigenTiming) {
        self.factorize_s += o.factorize_s;
        self.factorizations += o.factorizations;
        self.solve_s += o.solve_s;
        self.solved_vectors += o.solved_vectors;
        self.check_s += o.check_s;
        self.orthogonalize_s += o.orthogonalize_s;
        self.orthogonalize_spmm_s += o.orthogonalize_spmm_s;
        self.rayleigh_ritz_s += o.rayleigh_ritz_s;
        self.restart_s += o.restart_s;
        self.orthogonalized_blocks += o.orthogonalized_blocks;
        self.orthogonalization_passes += o.orthogonalization_passes;
    }
}

/// Result of [`solve`]: all modes with f_min ≤ f < f_max.
#[derive(Clone, Debug)]
pub struct EigenSolution {
    /// Natural frequencies (Hz), ascending. Rigid-body modes (λ ≤ 0 to round-off) give 0.
    pub frequencies_hz: Vec<f64>,
    /// Eigenvalues λ = ω² (rad²/s²), ascending, raw (may be −ε for rigid-body modes).
    pub eigenvalues_rad2_s2: Vec<f64>,
    /// Mode shapes, n × m, M-orthonormal (ΦᵀMΦ = I; units: DOF unit / √kg).
    pub modes: Mat<f64>,
    /// Per-mode true relative residual (see module doc).
    pub relative_residuals: Vec<f64>,
    /// Per-mode normwise backward error `‖Kφ − λMφ‖₂ / ((‖K‖_∞ + |λ| ‖M‖_∞) ‖φ‖₂)`
    /// (Higham & Higham, BIT 38 (1998) 9–31): meaningful for rigid-body modes as well.
    pub backward_errors: Vec<f64>,
    /// max |ΦᵀMΦ − I| (within and between neighbouring slices unless the full check was asked).
    pub m_orthonormality_error: f64,
    /// Sturm count at f_max: number of eigenvalues below (2π f_max)².
    pub sturm_count: usize,
    /// Sturm count at f_min (0 when f_min = 0).
    pub sturm_count_below_min: usize,
    /// The slices.
    pub slices: Vec<SliceReport>,
    /// Timing.
    pub timing: EigenTiming,
}

/// Errors of the eigensolver.
#[derive(Debug, thiserror::Error)]
pub enum EigenError {
    /// K and M do not have the same square shape.
    #[error("K is {k_rows}×{k_cols} and M is {m_rows}×{m_cols}: both must be the same square size (free DOFs)")]
    DimensionMismatch {
        /// rows of K
        k_rows: usize,
        /// columns of K
        k_cols: usize,
        /// rows of M
        m_rows: usize,
        /// columns of M
        m_cols: usize,
    },
    /// An option is out of range.
    #[error("invalid option {name} = {value}: {reason}")]
    InvalidOption {
        /// option name
        name: &'static str,
        /// given value
        value: String,
        /// what is allowed
        reason: &'static str,
    },
    /// The nested-dissection fill-reducing ordering failed.
    #[error("nested-dissection ordering failed: {0}")]
    Ordering(#[from] crate::fe::ordering::OrderingError),
    /// The sparse factorisation failed.
    #[error("factorisation of K − σM failed at σ = {shift_rad2_s2:e} rad²/s²: {reason}")]
    Factorization {
        /// shift (rad²/s²)
        shift_rad2_s2: f64,
        /// cause
        reason: String,
    },
    /// The sparse LDLᵀ factorisation's workspace could not be allocated.
    #[error("out of memory for the LDLᵀ workspace of K − σM at σ = {shift_rad2_s2:e} rad²/s² ({bytes} bytes): the model is too large for this machine's memory; coarsen the mesh (`mesh.element_length`, `mesh.section_size`) or shorten the track (`track.bays`)")]
    FactorWorkspace {
        /// shift (rad²/s²)
        shift_rad2_s2: f64,
        /// the workspace asked for (bytes)
        bytes: usize,
        /// the allocator's error
        #[source]
        source: faer::dyn_stack::mem::AllocError,
    },
    /// A dense symmetric eigensolver failed (faer's `EvdError` is not a `std::error::Error`,
    /// so it is a field, not a source).
    #[error("dense symmetric eigensolver of the {what}: {error:?}")]
    DenseEigen {
        /// Which matrix.
        what: &'static str,
        /// faer's error.
        error: faer::linalg::evd::EvdError,
    },
    /// A dense Cholesky factorisation failed: the matrix is not positive definite.
    #[error("dense Cholesky factorisation of the {what} failed (shift {shift_rad2_s2:e} rad²/s²): it is not positive definite; check the masses and supports")]
    DenseCholesky {
        /// Which matrix.
        what: &'static str,
        /// The shift added to it (rad²/s²; 0 if none).
        shift_rad2_s2: f64,
        /// faer's error.
        #[source]
        source: faer::linalg::cholesky::llt::factor::LltError,
    },
    /// The symbolic analysis of the sparse factorisation failed (index overflow or out of
    /// memory: the model is too large for this machine; coarsen the mesh).
    #[error("symbolic analysis of the sparse LDLᵀ failed: the model is too large for this machine; coarsen the mesh")]
    Symbolic(#[source] faer::sparse::FaerError),
    /// K − σ₀M with σ₀ < 0 is not positive definite: K is not PSD or M not PD.
    #[error("K − σM at σ = {shift_rad2_s2:e} rad²/s² (< 0) has {negative_pivots} negative pivots: K must be positive semi-definite and M positive definite (check constraints, element orientation / negative Jacobians, negative springs or masses)")]
    NotSemiDefinite {
        /// negative shift (rad²/s²)
        shift_rad2_s2: f64,
        /// number of negative pivots (should be 0)
        negative_pivots: usize,
    },
    /// The Lanczos iteration did not find every eigenvalue the Sturm counts promise.
    #[error("missed modes in [{lo_hz:.3}, {hi_hz:.3}) Hz: Sturm count says {expected}, found {found} after {restarts} restarts; increase max_restarts or block_size, or lower modes_per_slice")]
    MissedModes {
        /// lower end of the slice (Hz; 0 for the rigid-body slice)
        lo_hz: f64,
        /// upper end (Hz)
        hi_hz: f64,
        /// Sturm count in the slice
        expected: usize,
        /// converged modes found
        found: usize,
        /// restarts used
        restarts: usize,
    },
}

/// λ (rad²/s²) → f (Hz); negative λ (round-off of rigid-body modes) gives 0.
pub fn lambda_to_hz(lambda: f64) -> f64 {
    lambda.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
}

/// f (Hz) → λ = (2π f)² (rad²/s²).
pub fn hz_to_lambda(f_hz: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f_hz;
    w * w
}

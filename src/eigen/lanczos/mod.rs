//! Shift-invert block Lanczos with thick restart and spectrum slicing (see the [`super`]
//! module doc for the method and references).
//!
//! Notation: `V` (n × j) is an M-orthonormal basis, `Q` (n × b) the pending block, and
//! `H` ((j + b) × j) satisfies `Op V = [V Q] H` with `Op = (K − σM)⁻¹M`. The leading j × j part
//! of `H` is the Rayleigh quotient `VᵀM Op V` (symmetric: `Op` is M-self-adjoint), the last
//! b rows `E` couple to `Q`, so a Ritz pair `(θ, V s)` has residual
//! `‖Op V s − θ V s‖_M = ‖E s‖₂` (Wu & Simon 2000, eq. 2.3, block form).
//!
//! Because `H` is formed from the *full* projection of every new block (not just the
//! tridiagonal recurrence coefficients) and `V` is re-orthogonalised twice, the method is a
//! block Krylov–Rayleigh–Ritz iteration that tolerates the arrow-shaped `H` after a thick
//! restart without special cases.

use crate::progress::{Counter, Progress};
use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};
use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

use super::factor::{ShiftFactor, ShiftedSystem, SolveWorkspace};
use super::spmm::{
    sym_spmm, tall_mul_add, tall_right_mul_in_place, tall_t_mul, tall_update_then_t_mul,
};
use super::{
    hz_to_lambda, lambda_to_hz, EigenError, EigenOptions, EigenSolution, EigenTiming, SliceReport,
};

mod band;
mod check;
mod ctx;
mod slice;
#[cfg(test)]
mod tests;

pub(crate) use check::drop_stored_zeros;

use band::{choose_splits, lambda_at, run_band, split_probe_x, BandOut, BandParams, GROUNDED_TEST};
use check::{rayleigh_ritz_window, validate, verify, BOUND_WINDOW, BOUND_WINDOW_MAX};
use ctx::{diagonal_of, factorize, Ctx, Rng};

/// Smallest model (free DOFs) that is split into concurrent bands by default: below it the
/// solves are cheap and not memory-bound, and one band is as fast.
const AUTO_BANDS_MIN_DOFS: usize = 20_000;

/// Concurrent bands of a model of at least [`AUTO_BANDS_MIN_DOFS`] free DOFs by default. A
/// constant, not the thread count: the band bounds decide which slice finds which mode, so
/// they must not depend on the machine for the modes to be bitwise reproducible everywhere.
const AUTO_BANDS: usize = 2;

/// The matrices of one solve and the parallelism of its operations: what every [`Ctx`] of
/// the solve shares.
#[derive(Clone, Copy)]
struct Problem<'a> {
    k: SparseColMatRef<'a, usize, f64>,
    /// M without its stored zeros.
    m: SparseColMatRef<'a, usize, f64>,
    sys: &'a ShiftedSystem,
    m_diag: Option<&'a [f64]>,
    par: Par,
}

impl<'a> Problem<'a> {
    /// A work context with no timing yet.
    fn ctx(&self, running: Option<&'a AtomicUsize>, rng: Rng) -> Ctx<'a> {
        Ctx {
            k: self.k,
            m: self.m,
            sys: self.sys,
            m_diag: self.m_diag,
            par: self.par,
            running,
            timing: EigenTiming::default(),
            rng,
        }
    }
}

/// The factorisations at the ends of the whole band (and the probes beside them).
struct Ends {
    /// At the lower bound: σ₀ < 0 from 0 Hz, else λ_min.
    first: ShiftFactor,
    /// At λ_max.
    top: ShiftFactor,
    /// Sturm count 0 at `GROUNDED_TEST · |σ₀|` (from 0 Hz only).
    grounded: bool,
    /// The count probe of `choose_splits` at its x, when two or more bands are likely.
    probe: Option<(f64, ShiftFactor)>,
}

/// One band of the solve: the factorisation at its lower bound, whether it starts at 0 Hz,
/// and its upper bound `(shift, Sturm count)`.
type BandJob = (ShiftFactor, bool, (f64, usize));

/// Computes all eigenpairs of `K φ = λ M φ` with `f_min ≤ f < f_max` (see module doc).
///
/// `k`, `m`: n × n, full symmetric storage (both triangles), K PSD, M PD.
/// `progress`: optional sink for the caller's current stage; its total is set to the Sturm
/// count and its count to the modes found so far.
///
/// Phases: the factorisations at the ends of the band (`factorize_ends`), the Sturm counts
/// and the cut into concurrent bands (`plan_bands`), the spectrum slicing of every band
/// (`run_bands`), the Rayleigh–Ritz repair across the band bounds
/// (`repair_band_bounds`) and the verification of the residuals and the M-orthonormality
/// (`verify`).
pub fn solve(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &EigenOptions,
    progress: Option<&dyn Progress>,
) -> Result<EigenSolution, EigenError> {
    let t_total = Instant::now();
    check_problem(k, m, opts)?;
    let n = k.nrows();
    let par = if opts.parallel {
        Par::rayon(0)
    } else {
        Par::Seq
    };
    let t = Instant::now();
    let sys = ShiftedSystem::new(k, m, opts.ordering, par)?;
    // Every product with M below uses a copy without the stored zeros: the assembled matrices
    // share one pattern of 3 × 3 DOF blocks, a consistent mass `m_ab I` fills only the
    // diagonal of each block (two thirds of M's stored entries are zeros) and a lumped mass
    // (the default model's) only the diagonal of M (figures in docs/performance.md).
    let m_compact = drop_stored_zeros(m);
    let m = m_compact.as_ref();
    let m_diag_vec = diagonal_of(m);
    let problem = Problem {
        k,
        m,
        sys: &sys,
        m_diag: m_diag_vec.as_deref(),
        par,
    };
    let mut ctx = problem.ctx(None, Rng(opts.seed | 1));
    ctx.timing.symbolic_s = t.elapsed().as_secs_f64();
    ctx.timing.factor_entries = sys.factor_len();
    let lam_max = hz_to_lambda(opts.f_max_hz);
    let ends = factorize_ends(&problem, &mut ctx.timing, opts, lam_max)?;
    let nu_max = ends.top.negative_count;
    if opts.f_min_hz == 0.0 && ends.first.negative_count != 0 {
        return Err(EigenError::NotSemiDefinite {
            shift_rad2_s2: ends.first.shift,
            negative_pivots: ends.first.negative_count,
        });
    }
    let nu0 = ends.first.negative_count;
    let first_shift = ends.first.shift;
    let total = nu_max.saturating_sub(nu0);
    if let Some(p) = progress {
        p.total(total as u64);
        p.done(0);
    }
    let counter = progress.map(Counter::within);
    let grounded = ends.grounded;
    let (jobs, band_bounds) = plan_bands(&mut ctx, ends, opts, n, lam_max)?;
    let mut timing = std::mem::take(&mut ctx.timing);
    timing.bands = jobs.len();
    let (mut phi, mut lambdas, slices) = run_bands(
        &problem,
        jobs,
        grounded,
        lam_max,
        opts,
        counter.as_ref(),
        &mut timing,
    )?;
    if lambdas.len() != total {
        return Err(EigenError::MissedModes {
            lo_hz: lambda_to_hz(first_shift.max(0.0)),
            hi_hz: opts.f_max_hz,
            expected: total,
            found: lambdas.len(),
            restarts: 0,
        });
    }
    sort_ascending(&mut phi, &mut lambdas);
    let t_rr = Instant::now();
    repair_band_bounds(k, m, &mut phi, &mut lambdas, &band_bounds, par)?;
    timing.restart_s += t_rr.elapsed().as_secs_f64();
    let t = Instant::now();
    let check = verify(&problem, &phi, &lambdas, opts);
    timing.check_s = t.elapsed().as_secs_f64();
    timing.total_s = t_total.elapsed().as_secs_f64();
    Ok(EigenSolution {
        frequencies_hz: lambdas.iter().map(|&l| lambda_to_hz(l)).collect(),
        eigenvalues_rad2_s2: lambdas,
        modes: phi,
        relative_residuals: check.residuals,
        backward_errors: check.backward,
        m_orthonormality_error: check.orthonormality,
        sturm_count: nu_max,
        sturm_count_below_min: nu0,
        slices,
        timing,
    })
}

/// Checks the shapes of K and M and the options.
fn check_problem(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &EigenOptions,
) -> Result<(), EigenError> {
    if k.nrows() != k.ncols() || m.nrows() != m.ncols() || k.nrows() != m.nrows() {
        return Err(EigenError::DimensionMismatch {
            k_rows: k.nrows(),
            k_cols: k.ncols(),
            m_rows: m.nrows(),
            m_cols: m.ncols(),
        });
    }
    validate(opts)?;
    if k.nrows() == 0 {
        return Err(EigenError::InvalidOption {
            name: "K, M",
            value: "0 × 0".into(),
            reason: "the model has no free DOFs",
        });
    }
    Ok(())
}

/// Bands the solve will most likely use (it decides once the Sturm counts are known, see
/// [`plan_bands`]).
fn likely_bands(opts: &EigenOptions, n: usize) -> usize {
    match opts.concurrent_bands {
        Some(b) => b,
        None if opts.parallel && n >= AUTO_BANDS_MIN_DOFS => AUTO_BANDS,
        None => 1,
    }
}

/// The factorisations at the band's ends, independent of each other (with `parallel` they
/// run side by side): at λ_max, at the lower bound (σ₀ < 0 from 0 Hz), the grounded test
/// from 0 Hz and, with two or more likely bands, the count probe of `choose_splits`. Their
/// timings are added to `timing`.
fn factorize_ends(
    problem: &Problem<'_>,
    timing: &mut EigenTiming,
    opts: &EigenOptions,
    lam_max: f64,
) -> Result<Ends, EigenError> {
    let s_first = if opts.f_min_hz == 0.0 {
        let rb = opts
            .rigid_shift_hz
            .unwrap_or((opts.f_max_hz / 100.0).max(1.0));
        -hz_to_lambda(rb)
    } else {
        hz_to_lambda(opts.f_min_hz)
    };
    let end_factor = |shift: f64, direction: f64| {
        let mut c = problem.ctx(None, Rng(1));
        factorize(&mut c, shift, direction, lam_max).map(|f| (f, c.timing))
    };
    // With two or more likely bands the count probe of `choose_splits` is factorised
    // alongside the ends.
    let likely = likely_bands(opts, problem.k.nrows());
    let probe_x = (likely >= 2).then(|| split_probe_x(likely));
    let probe_factor = || {
        probe_x
            .map(|x| end_factor(lambda_at(s_first, lam_max, x), 1.0))
            .transpose()
    };
    // From 0 Hz: the Sturm count at GROUNDED_TEST · |σ₀| says whether the structure is
    // grounded far enough above σ₀ for the probe of `run_band` to pay (default track: its
    // lowest mode, 74.7 Hz, is below that point, 105 Hz, and this factorisation, beside the
    // others, replaces a probe of 176 solved vectors that could not move the shift).
    let ground_factor = || {
        (opts.f_min_hz == 0.0)
            .then(|| end_factor(GROUNDED_TEST * s_first.abs(), 1.0))
            .transpose()
    };
    let ((top, ground), (first, probe)) = if opts.parallel {
        rayon::join(
            || rayon::join(|| end_factor(lam_max, 1.0), ground_factor),
            || rayon::join(|| end_factor(s_first, -1.0), probe_factor),
        )
    } else {
        (
            (end_factor(lam_max, 1.0), ground_factor()),
            (end_factor(s_first, -1.0), probe_factor()),
        )
    };
    let ((top, t_top), (first, t_first)) = (top?, first?);
    timing.absorb(&t_top);
    timing.absorb(&t_first);
    let grounded = match ground? {
        Some((f, t)) => {
            timing.absorb(&t);
            f.negative_count == 0
        }
        None => false,
    };
    let probe = match (probe?, probe_x) {
        (Some((f, t)), Some(x)) => {
            timing.absorb(&t);
            Some((x, f))
        }
        _ => None,
    };
    Ok(Ends {
        first,
        top,
        grounded,
        probe,
    })
}

/// Cuts the band into the concurrent bands (their bounds are Sturm-counted factorisations,
/// see `choose_splits`): the jobs in ascending order and the shifts of the inner bounds.
fn plan_bands(
    ctx: &mut Ctx<'_>,
    ends: Ends,
    opts: &EigenOptions,
    n: usize,
    lam_max: f64,
) -> Result<(Vec<BandJob>, Vec<f64>), EigenError> {
    let Ends {
        first, top, probe, ..
    } = ends;
    let from_zero = opts.f_min_hz == 0.0;
    let total = top.negative_count.saturating_sub(first.negative_count);
    let top_bound = (top.shift, top.negative_count);
    drop(top);
    let wanted_bands = match opts.concurrent_bands {
        Some(b) => b,
        // Small models: one band (faster, and exactly M-orthogonal across all slices).
        None if opts.parallel && n >= AUTO_BANDS_MIN_DOFS => {
            AUTO_BANDS.min(total / opts.modes_per_slice)
        }
        None => 1,
    };
    let mut jobs: Vec<BandJob> = Vec::new();
    let mut band_bounds: Vec<f64> = Vec::new();
    if wanted_bands >= 2 && total >= 2 {
        let splits = choose_splits(ctx, &first, top_bound, wanted_bands, lam_max, probe)?;
        let mut lower = first;
        let mut lower_from_zero = from_zero;
        for s in splits {
            let bound = (s.shift, s.negative_count);
            band_bounds.push(s.shift);
            jobs.push((lower, lower_from_zero, bound));
            lower = s;
            lower_from_zero = false;
        }
        jobs.push((lower, lower_from_zero, top_bound));
    } else {
        jobs.push((first, from_zero, top_bound));
    }
    Ok((jobs, band_bounds))
}

/// The modes of all bands (n × total), their eigenvalues (rad²/s², band by band) and the
/// slices' reports.
type BandsOut = (Mat<f64>, Vec<f64>, Vec<SliceReport>);

/// Runs the bands (concurrently with `parallel` and more than one), each writing its modes
/// into its own columns of one n × total matrix (no copies). Returns the modes, their
/// eigenvalues (band by band, each ascending) and the slices; the bands' timings are added
/// to `timing`.
fn run_bands(
    problem: &Problem<'_>,
    jobs: Vec<BandJob>,
    grounded: bool,
    lam_max: f64,
    opts: &EigenOptions,
    progress: Option<&Counter<'_>>,
    timing: &mut EigenTiming,
) -> Result<BandsOut, EigenError> {
    let n = problem.k.nrows();
    let bands = jobs.len();
    let total: usize = jobs
        .iter()
        .map(|(first, _, top)| top.1 - first.negative_count)
        .sum();
    // One thread per band while several run: the bands' solves then each read their own
    // factor once per block instead of once per column group (see module doc). The last band
    // running goes parallel again (`Ctx::par`).
    let running = AtomicUsize::new(bands);
    let mut phi = Mat::<f64>::zeros(n, total);
    let mut views: Vec<MatMut<'_, f64>> = Vec::with_capacity(bands);
    let mut rest = phi.as_mut();
    for (first, _, top) in &jobs {
        let (head, tail) = rest.split_at_col_mut(top.1 - first.negative_count);
        views.push(head);
        rest = tail;
    }
    let run = |i: usize, ((first, from_zero, top), view): (BandJob, MatMut<'_, f64>)| {
        // Band 0 keeps the seed of the single-band solver (reproducible results).
        let rng = Rng((opts.seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)) | 1);
        let mut ctx = problem.ctx((bands > 1).then_some(&running), rng);
        let band = BandParams {
            first,
            from_zero,
            grounded,
            top,
            lam_max,
        };
        let out = run_band(&mut ctx, view, band, opts, progress);
        running.fetch_sub(1, AtomicOrdering::Relaxed);
        out.map(|out| (out, ctx.timing))
    };
    let outs: Vec<Result<(BandOut, EigenTiming), EigenError>> = if bands > 1 && opts.parallel {
        use rayon::prelude::*;
        jobs.into_par_iter()
            .zip(views)
            .enumerate()
            .map(|(i, job)| run(i, job))
            .collect()
    } else {
        jobs.into_iter()
            .zip(views)
            .enumerate()
            .map(|(i, job)| run(i, job))
            .collect()
    };
    let mut lambdas: Vec<f64> = Vec::with_capacity(total);
    let mut slices: Vec<SliceReport> = Vec::new();
    for out in outs {
        let (band, t) = out?;
        timing.absorb(&t);
        lambdas.extend_from_slice(&band.lambdas);
        slices.extend(band.slices);
    }
    Ok((phi, lambdas, slices))
}

/// Sorts the eigenpairs ascending (slices and bands are ascending already; keeps it robust).
fn sort_ascending(phi: &mut Mat<f64>, lambdas: &mut Vec<f64>) {
    let mut idx: Vec<usize> = (0..lambdas.len()).collect();
    idx.sort_by(|&a, &b| lambdas[a].total_cmp(&lambdas[b]));
    if idx.iter().enumerate().any(|(i, &j)| i != j) {
        let sorted = Mat::<f64>::from_fn(phi.nrows(), idx.len(), |r, c| phi[(r, idx[c])]);
        *phi = sorted;
        *lambdas = idx.iter().map(|&i| lambdas[i]).collect();
    }
}

/// Across a band bound the modes were found without deflating each other: their mutual
/// M-orthogonality is only ≈ residual / gap. A Rayleigh–Ritz step on the modes near each
/// bound restores it (and cannot make them worse: the Ritz vectors of a subspace are its
/// best approximations).
fn repair_band_bounds(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    phi: &mut Mat<f64>,
    lambdas: &mut [f64],
    band_bounds: &[f64],
    par: Par,
) -> Result<(), EigenError> {
    for &b in band_bounds {
        let mid = lambdas.partition_point(|&l| l < b);
        let lo = lambdas
            .partition_point(|&l| l < b - BOUND_WINDOW * b.abs())
            .max(mid.saturating_sub(BOUND_WINDOW_MAX));
        let hi = lambdas
            .partition_point(|&l| l < b + BOUND_WINDOW * b.abs())
            .min(mid + BOUND_WINDOW_MAX);
        if hi > lo + 1 {
            rayleigh_ritz_window(
                k,
                m,
                phi.as_mut().subcols_mut(lo, hi - lo),
                &mut lambdas[lo..hi],
                par,
            )?;
        }
    }
    Ok(())
}

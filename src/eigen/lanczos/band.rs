//! Spectrum slicing over one band, and the cut of the whole band into concurrent bands by
//! a work model fitted to a Sturm count probe.

use super::slice::{lanczos_slice, SliceOut, SliceParams};
use super::{
    factorize, lambda_to_hz, Counter, Ctx, EigenError, EigenOptions, Instant, MatMut, MatRef,
    ShiftFactor, SliceReport,
};

/// What one band `[lower bound of first, top)` found besides its eigenvectors (written into
/// the band's columns of the solution).
pub(super) struct BandOut {
    /// Eigenvalues (rad²/s²) in the order of the band's columns.
    pub(super) lambdas: Vec<f64>,
    /// The band's slices, ascending.
    pub(super) slices: Vec<SliceReport>,
}

/// One band of the spectrum slicing: where it starts and ends.
pub(super) struct BandParams {
    /// The factorisation at the band's lower bound: the negative rigid-body shift σ₀
    /// (rad²/s²) of a band from 0 Hz, else a bound λ_lo > 0 (where the band starts with a
    /// two-sided slice).
    pub(super) first: ShiftFactor,
    /// The band starts at 0 Hz (`first` is at σ₀ < 0).
    pub(super) from_zero: bool,
    /// A band from 0 Hz of a grounded structure: no eigenvalue below `GROUNDED_TEST · |σ₀|`
    /// (Sturm count), so the grounded-structure probe may move the first shift up.
    pub(super) grounded: bool,
    /// The band's upper bound: `(shift (rad²/s²), Sturm count there)`.
    pub(super) top: (f64, usize),
    /// λ_max (rad²/s²) of the whole solve: scales the small moves of a shift that hits a
    /// zero pivot.
    pub(super) lam_max: f64,
}

/// The running state of a band: what its committed slices found and what they carry on.
struct BandState {
    /// Eigenvalues found so far (rad²/s²), in the order of the band's columns.
    lambdas: Vec<f64>,
    /// Converged pairs above the last boundary (λ ≥ τ, from the converged prefix of the
    /// previous slice), rad²/s²: their vectors sit in phi right after the committed columns.
    /// They are eigenpairs of the next slice already, so it deflates them (with all modes
    /// found so far) and needs that many fewer new ones; discarding them would make the
    /// next slice converge them again. Measured on the default track to 5 kHz with all
    /// earlier slices deflated: 3064 solved vectors with carrying, 3120 without (−2 %,
    /// within the run-to-run spread of the wall time).
    carried: Vec<f64>,
    /// The band's slices, ascending.
    slices: Vec<SliceReport>,
    /// Eigenvalues per rad²/s² in the previous slice.
    last_density: Option<f64>,
}

/// Where a slice starts, what kind of slice it is, and the band it lies in (the
/// factorisation at its lower bound is handed to [`solve_slice`] by value).
struct SliceStart {
    /// Lower bound lo (rad²/s²): the shift of the factorisation there.
    lo: f64,
    /// Sturm count at lo.
    nu_cur: usize,
    /// The band's last slice (the remainder is at most 1.5 targets).
    last: bool,
    /// The first slice of a band above 0 Hz: two-sided from the start.
    two_sided: bool,
    /// Lower bound (rad²/s²) of a band above 0 Hz, whose modes below it are never
    /// deflated; `None` for a band from 0 Hz.
    band_lo: Option<f64>,
    /// The band's upper bound: `(shift (rad²/s²), Sturm count there)`.
    top: (f64, usize),
    /// λ_max (rad²/s²), see [`BandParams::lam_max`].
    lam_max: f64,
}

/// A solved slice: the Lanczos result, its upper bound `hi` (rad²/s²) and the Sturm count
/// there, the factorisation at `hi` when a slice follows, and the factorisation the slice
/// was solved with (the one at its lower bound, or at its midpoint for a two-sided solve,
/// which replaces the lower one: that is dropped before the midpoint is factorised, so a
/// band holds at most two factors while Lanczos runs; [`recut`] factorises a candidate bound
/// beside the slice's and the old bound's factors, three for that moment).
struct SolvedSlice {
    out: SliceOut,
    hi: f64,
    nu_hi: usize,
    next: Option<ShiftFactor>,
    solver: ShiftFactor,
    /// Solved two-sided (`solver` at the midpoint).
    sided: bool,
}

/// Spectrum slicing over one band (see [`BandParams`]): from the factorisation at its lower
/// bound up to its top, slice by slice ([`solve_slice`], [`complete_slice`],
/// [`BandState::commit`]). The eigenvectors go into `phi` (n × the band's Sturm count) in
/// the order of the returned eigenvalues.
pub(super) fn run_band(
    ctx: &mut Ctx<'_>,
    mut phi: MatMut<'_, f64>,
    band: BandParams,
    opts: &EigenOptions,
    progress: Option<&Counter<'_>>,
) -> Result<BandOut, EigenError> {
    let n = ctx.sys.n();
    let BandParams {
        first,
        from_zero,
        grounded,
        top,
        lam_max,
    } = band;
    let (top_shift, nu_max) = top;
    let total = nu_max.saturating_sub(first.negative_count);
    let mut reported = 0usize;
    debug_assert_eq!((phi.nrows(), phi.ncols()), (n, total));
    let mut st = BandState {
        lambdas: Vec::with_capacity(total),
        carried: Vec::new(),
        slices: Vec::new(),
        last_density: None,
    };
    let mut cur = if from_zero && grounded && total > 0 {
        grounded_first_shift(ctx, phi.as_ref(), first, lam_max, opts)?
    } else {
        first
    };
    // Lower bound of a band above 0 Hz: the modes below it are never deflated here.
    let band_lo = (!from_zero).then_some(cur.shift);
    loop {
        let nu_cur = cur.negative_count;
        if nu_cur >= nu_max {
            break;
        }
        let target = opts.modes_per_slice;
        let t_slice = Instant::now();
        let start = SliceStart {
            lo: cur.shift,
            nu_cur,
            // A remainder of up to 1.5 targets is one last slice (default track to 5 kHz: a
            // 170-mode last slice instead of a 152-mode one and an 18-mode tail costing a
            // factorisation and ~4 s).
            last: nu_max - nu_cur <= target + target / 2,
            // The first slice of a band above 0 Hz cannot deflate the modes below its bound
            // lo (another band's, or below f_min): with the shift at lo they would converge
            // at the negative end of θ as unwanted pairs, about as many as the slice wants
            // and denser in λ (default track to 2 kHz in two bands: 872 solved vectors for
            // the upper band's first 93 modes, against ~3 per mode otherwise). So that slice
            // is two-sided: it wants every eigenvalue in [lo, hi) (Sturm count known) with
            // the Lanczos shift at the midpoint, where the undeflated ones below lo are
            // farther from the shift than every wanted one.
            two_sided: band_lo.is_some() && st.slices.is_empty(),
            band_lo,
            top,
            lam_max,
        };
        let mut solved = solve_slice(ctx, phi.as_ref(), &st, &start, cur, opts)?;
        let keep = complete_slice(ctx, phi.as_ref(), &st, &start, &mut solved, opts)?;
        let SolvedSlice {
            out,
            hi,
            nu_hi,
            next,
            solver,
            ..
        } = solved;
        drop(solver);
        let lo = start.lo;
        let carried_in = st.carried.iter().filter(|&&x| x < hi).count();
        // Layout from the committed columns: the slice's modes (carried ones below hi, then
        // the new ones), then the pairs carried on (carried ones at or above hi, then new
        // converged ones between hi and λ_max, as many as fit).
        st.commit(
            phi.as_mut(),
            (&out, &keep),
            hi,
            (top_shift, next.is_some()),
            total,
        );
        st.last_density = Some((nu_hi - nu_cur) as f64 / (hi - lo).max(f64::MIN_POSITIVE));
        st.slices.push(SliceReport {
            shift_lo_rad2_s2: lo,
            shift_hi_rad2_s2: hi,
            sturm_lo: nu_cur,
            sturm_hi: nu_hi,
            modes_found: nu_hi - nu_cur,
            carried: carried_in,
            restarts: out.restarts,
            solved_vectors: out.solved,
            lanczos_s: t_slice.elapsed().as_secs_f64(),
        });
        if let Some(c) = progress {
            c.add((st.lambdas.len() - reported) as u64);
            reported = st.lambdas.len();
        }
        match next {
            Some(f) => cur = f,
            None => break,
        }
    }
    Ok(BandOut {
        lambdas: st.lambdas,
        slices: st.slices,
    })
}

/// Solves the slice from `start`, deflating every mode found so far and
/// the carried pairs (the first columns of `phi`). The modes of earlier slices lie below σ
/// at θ = 1/(λ − σ) < 0; left in, the ones of the slices before the last compete with the
/// far end of the wanted θ and converge as unwanted Ritz values (default track to 5 kHz,
/// subspace ratio 3: deflating only the previous slice solved 3592 vectors, deflating all
/// 2880, and the M-orthonormality error of the whole basis fell from 1.3e-8 to 2.5e-14).
///
/// The slice ends at a bound whose Sturm count is known (the cap of [`cap_factor`], or the
/// band top for its last slice, solved two-sided), at the upper bound of a two-sided first
/// slice ([`two_sided_upper`]), or, open-ended, in a wide gap of its converged eigenvalues
/// ([`gap_boundary`]).
fn solve_slice(
    ctx: &mut Ctx<'_>,
    phi: MatRef<'_, f64>,
    st: &BandState,
    start: &SliceStart,
    cur: ShiftFactor,
    opts: &EigenOptions,
) -> Result<SolvedSlice, EigenError> {
    let (top_shift, nu_max) = start.top;
    let lam_max = start.lam_max;
    let (lo, nu_cur, last, two_sided) = (start.lo, start.nu_cur, start.last, start.two_sided);
    let target = opts.modes_per_slice;
    let nc = st.carried.len();
    let locked = phi.subcols(0, st.lambdas.len() + nc);
    // In a band above 0 Hz a slice whose width exceeds CAP_RATIO × its distance from the
    // band's lower bound would meet the undeflated modes below that bound at the far end
    // of θ. Such a slice ends at the cap instead, with the Sturm count known there
    // (default track to 5 kHz in two bands: the upper band's second slice, as wide as
    // that distance, needed 4 restarts and 5.8 solved vectors per mode). The band's last
    // slice is two-sided (shift at its midpoint m, half-width h): the same margin,
    // h ≤ CAP_RATIO · (m − bound), allows it a width of up to
    // 2·CAP_RATIO/(1 − CAP_RATIO) = 4.7 times that distance (default track to 5 kHz:
    // a 183-mode last slice of 536 vectors instead of a capped 97-mode one of 464 and
    // an 86-mode last one of 264).
    let capped = match (start.band_lo, st.last_density) {
        (Some(b), Some(rho))
            if !(two_sided || (last && top_shift - lo <= TWO_SIDED_CAP_RATIO * (lo - b))) =>
        {
            cap_factor(
                ctx,
                (lo, b),
                rho,
                (nu_cur, nu_max),
                top_shift,
                target,
                lam_max,
            )?
        }
        _ => None,
    };
    // A cap placed by the previous slice's density can enclose a cluster that slice did not
    // see (the 34-bay strip-held track to 5 kHz: 312 modes under a cap after a 51-mode
    // slice). Such a cap does not end the slice: the slice runs open-ended below it and its
    // bound goes into a gap of its converged values ([`recut`]).
    let (capped, over_cap) = match capped {
        Some(f) if oversized(f.negative_count.saturating_sub(nu_cur), target) => (None, Some(f)),
        c => (c, None),
    };
    // A slice to a bound whose Sturm count is known: the cap, or the band top.
    let known_end = match capped {
        Some(f) => Some((f.shift, f.negative_count, Some(f))),
        None if last && !two_sided => Some((top_shift, nu_max, None)),
        None => None,
    };
    if let Some((hi, nu_hi, next)) = known_end {
        let carried_below = st.carried.iter().filter(|&&x| x < hi).count();
        let need_new = (nu_hi - nu_cur).saturating_sub(carried_below);
        let want = need_new + opts.block_size.max((nu_hi - nu_cur) / 5);
        // The band's last slice is two-sided (deflating everything below lo): with the
        // shift midway, its modes near the band top lie half as far from the shift as
        // with the shift at lo, so they converge sooner and more accurately (default
        // track to 5 kHz: 416 instead of 536 solved vectors in the upper band's last
        // slice, and the M-orthogonality across the band bound 5e-8 instead of 2e-7).
        let (out, solver, sided) = if next.is_none() {
            drop(cur);
            let m = factorize(ctx, 0.5 * (lo + hi), 1.0, lam_max)?;
            let slice = SliceParams {
                fac: &m,
                locked,
                want,
                known: Some((hi, need_new)),
                two_sided: Some(lo),
            };
            let o = lanczos_slice(ctx, &slice, opts)?;
            (o, m, true)
        } else {
            let slice = SliceParams {
                fac: &cur,
                locked,
                want,
                known: Some((hi, need_new)),
                two_sided: None,
            };
            (lanczos_slice(ctx, &slice, opts)?, cur, two_sided)
        };
        Ok(SolvedSlice {
            out,
            hi,
            nu_hi,
            next,
            solver,
            sided,
        })
    } else if two_sided {
        drop(cur);
        // Width of about `target` modes, corrected once by the Sturm count.
        let (hi, nu_hi, next) =
            two_sided_upper(ctx, lo, (nu_cur, nu_max), top_shift, target, last, lam_max)?;
        let need = nu_hi - nu_cur;
        let m = factorize(ctx, 0.5 * (lo + hi), 1.0, lam_max)?;
        let want = need + opts.block_size.max(need / 5);
        let slice = SliceParams {
            fac: &m,
            locked: phi.subcols(0, 0),
            want,
            known: Some((hi, need)),
            two_sided: Some(lo),
        };
        let out = lanczos_slice(ctx, &slice, opts)?;
        Ok(SolvedSlice {
            out,
            hi,
            nu_hi,
            next,
            solver: m,
            sided: true,
        })
    } else {
        // The slice stops once `want` pairs converged (early convergence checks) and
        // the boundary below keeps 2/3 or more of them: 1.25 targets keep about one.
        let want = (target + target / 4).saturating_sub(nc).max(target / 2);
        let slice = SliceParams {
            fac: &cur,
            locked,
            want,
            known: None,
            two_sided: None,
        };
        let out = lanczos_slice(ctx, &slice, opts)?;
        // Boundary in the widest relative gap of the last third of the converged λ
        // (carried and new; everything below it has converged; a wide gap keeps K − τM
        // well conditioned).
        let converged = converged_above(&out.lambdas, lo, &st.carried);
        let tau = gap_boundary(&converged, top_shift);
        let bound = match over_cap {
            Some(f) if tau >= f.shift => (f.shift, f.negative_count, Some(f)),
            _ if tau >= top_shift => (top_shift, nu_max, None),
            _ => {
                let f = factorize(ctx, tau, 1.0, lam_max)?;
                (f.shift, f.negative_count, Some(f))
            }
        };
        let (hi, nu_hi, next) = recut(ctx, &converged, (lo, nu_cur), bound, target, lam_max)?;
        Ok(SolvedSlice {
            out,
            hi,
            nu_hi,
            next,
            solver: cur,
            sided: two_sided,
        })
    }
}

/// The indices of the new pairs of `solved` in `[lo, hi)`, after a second Lanczos run with
/// the count known if the Sturm count says the converged prefix skipped an eigenvalue (e.g.
/// a multiplicity larger than the block). An error if they are still too few.
fn complete_slice(
    ctx: &mut Ctx<'_>,
    phi: MatRef<'_, f64>,
    st: &BandState,
    start: &SliceStart,
    solved: &mut SolvedSlice,
    opts: &EigenOptions,
) -> Result<Vec<usize>, EigenError> {
    let (lo, hi) = (start.lo, solved.hi);
    let need = solved.nu_hi - start.nu_cur;
    let carried_in = st.carried.iter().filter(|&&x| x < hi).count();
    let select = |o: &SliceOut| -> Vec<usize> {
        (0..o.lambdas.len())
            .filter(|&i| o.lambdas[i] >= lo && o.lambdas[i] < hi)
            .collect()
    };
    let mut keep = select(&solved.out);
    if keep.len() + carried_in != need {
        let locked = phi.subcols(0, st.lambdas.len() + st.carried.len());
        let nl = need.saturating_sub(carried_in);
        let wide = if solved.sided { 2 * nl } else { nl };
        let slice = SliceParams {
            fac: &solved.solver,
            locked,
            want: wide + opts.block_size,
            known: Some((hi, nl)),
            two_sided: solved.sided.then_some(lo),
        };
        solved.out = lanczos_slice(ctx, &slice, opts)?;
        keep = select(&solved.out);
        if keep.len() + carried_in != need {
            return Err(EigenError::MissedModes {
                lo_hz: lambda_to_hz(lo),
                hi_hz: lambda_to_hz(hi),
                expected: need,
                found: keep.len() + carried_in,
                restarts: solved.out.restarts,
            });
        }
    }
    Ok(keep)
}

/// The grounded-structure probe at the start of a band from 0 Hz: a short, loose Lanczos run
/// at the negative shift σ₀ of `first` finds an upper bound l₁ of the lowest eigenvalue λ₁
/// (rad²/s²); if `GROUNDED_SHIFT · l₁` exceeds `GROUNDED_MOVE · |σ₀|` and the Sturm count
/// there is 0, the band's first shift moves up to it (else `first` is returned).
///
/// If the structure is grounded, λ₁ can lie far above σ₀; Lanczos at σ₀ would then see a
/// tightly clustered θ = 1/(λ − σ₀) and converge slowly. The caller's Sturm count at
/// `GROUNDED_TEST · |σ₀|` has shown that λ₁ lies that high; otherwise the probe could not
/// move the shift and is not run.
fn grounded_first_shift(
    ctx: &mut Ctx<'_>,
    phi: MatRef<'_, f64>,
    first: ShiftFactor,
    lam_max: f64,
    opts: &EigenOptions,
) -> Result<ShiftFactor, EigenError> {
    let probe = {
        let empty = phi.subcols(0, 0);
        // Loose tolerance and one wanted value: any Ritz value bounds λ₁ from above
        // (θ_Ritz ≤ θ₁), and the Sturm count at 0.9·l1 decides whether the shift moves.
        let mut popts = opts.clone();
        popts.tolerance = 1e-4;
        let slice = SliceParams {
            fac: &first,
            locked: empty,
            want: 1,
            known: None,
            two_sided: None,
        };
        lanczos_slice(ctx, &slice, &popts)?
    };
    let l1 = probe.lambdas.first().copied().unwrap_or(0.0);
    let moved = GROUNDED_SHIFT * l1;
    // (True whenever the probe returned a value: l1 ≥ λ₁ > GROUNDED_TEST · |σ₀|.)
    if moved > GROUNDED_MOVE * first.shift.abs() {
        let f = factorize(ctx, moved, -1.0, lam_max)?;
        if f.negative_count == 0 {
            return Ok(f);
        }
    }
    Ok(first)
}

/// The cap of a slice in a band above 0 Hz: the factorisation at
/// `lo + CAP_RATIO · (lo − b)` (rad²/s²; `(lo, b)` = the slice's lower shift and the band's
/// lower bound), if it lies below `top_shift`, the previous slice's density `rho`
/// (eigenvalues per rad²/s²) puts at most 1.25 `target` modes below it, and its Sturm count
/// lies strictly between the Sturm counts `nu_cur` at `lo` and `nu_max` at the band top. `None`: the slice is not capped.
fn cap_factor(
    ctx: &mut Ctx<'_>,
    (lo, b): (f64, f64),
    rho: f64,
    (nu_cur, nu_max): (usize, usize),
    top_shift: f64,
    target: usize,
    lam_max: f64,
) -> Result<Option<ShiftFactor>, EigenError> {
    let cap = lo + CAP_RATIO * (lo - b);
    if cap < top_shift && rho * (cap - lo) <= (target + target / 4) as f64 {
        let f = factorize(ctx, cap, 1.0, lam_max)?;
        Ok(
            (f.negative_count > nu_cur && f.negative_count < nu_max && f.shift < top_shift)
                .then_some(f),
        )
    } else {
        Ok(None)
    }
}

/// Upper bound `(hi, Sturm count at hi, its factorisation)` of the two-sided first slice of
/// a band above 0 Hz starting at `lo` (rad²/s²): a width of about `target` modes by the
/// count model ν ∝ λ^{3/2} up to `top_shift`, corrected once if the Sturm count says it
/// holds more than 1.2 targets; the band top `(top_shift, nu_max, None)` if the bound
/// reaches it (`last`: the slice is the band's last). `nu_cur`, `nu_max`: the Sturm counts
/// at `lo` and at the band top.
///
/// This slice deflates nothing and needs more solves per mode than any other (default
/// track to 5 kHz: 185 modes, 616 vectors; corrected to 100 modes, 320 vectors, and the
/// band's two-sided last slice, which deflates them, 183 modes in 536 vectors).
fn two_sided_upper(
    ctx: &mut Ctx<'_>,
    lo: f64,
    (nu_cur, nu_max): (usize, usize),
    top_shift: f64,
    target: usize,
    last: bool,
    lam_max: f64,
) -> Result<(f64, usize, Option<ShiftFactor>), EigenError> {
    let mut w = if last {
        top_shift - lo
    } else {
        (top_shift * ((nu_cur + target) as f64 / nu_max as f64).powf(2.0 / 3.0) - lo)
            .max(1e-3 * top_shift)
    };
    let mut bound = None;
    for _ in 0..2 {
        if lo + w >= top_shift {
            bound = None;
            break;
        }
        let f = factorize(ctx, lo + w, 1.0, lam_max)?;
        let count = f.negative_count - nu_cur;
        let too_many = count > target + target / 5;
        bound = Some(f);
        if !too_many {
            break;
        }
        w *= target as f64 / count as f64;
    }
    Ok(match bound {
        Some(f) if f.negative_count < nu_max && f.shift < top_shift => {
            (f.shift, f.negative_count, Some(f))
        }
        _ => (top_shift, nu_max, None),
    })
}

/// Moves an open-ended slice's upper bound `(hi, Sturm count there, its factorisation)` down
/// while its Sturm count says the slice holds more than [`RECUT_RATIO`] `target` modes
/// (at most [`RECUT_TRIES`] factorisations): the slice's Lanczos run converged the
/// eigenvalues below `hi` only in part (the members of a cluster more multiple than the
/// block, e.g. the sleepers' modes of a long track on identical supports), so a gap of its
/// converged values `converged` (rad²/s², ascending, [`converged_above`]) can enclose many
/// unseen ones, and the slice's
/// second run, with the count known, would need a subspace that many times larger (the
/// 34-bay strip-held track to 5 kHz: 312 modes in one slice, a 3.4 GB basis, 1432 solved
/// vectors). The new bound is the middle of the widest relative gap of the converged values
/// between the λ the count predicts for `target` modes (linear in λ between `lo` and `hi`)
/// and halfway down to `lo`, or of the highest gap below that λ if none lies there: a bound
/// only ever sits between converged values, as
/// [`gap_boundary`]'s, since one on an eigenvalue of a multiple cluster can split the
/// cluster's Sturm count arbitrarily (an equal-chains test: 1 of 24 below it, and the next
/// slice's 23 at its own shift). Without such a gap, or when the bound's count is not above
/// `nu_cur` (the Sturm count at `lo`), the bound stays.
fn recut(
    ctx: &mut Ctx<'_>,
    converged: &[f64],
    (lo, nu_cur): (f64, usize),
    mut bound: (f64, usize, Option<ShiftFactor>),
    target: usize,
    lam_max: f64,
) -> Result<(f64, usize, Option<ShiftFactor>), EigenError> {
    for _ in 0..RECUT_TRIES {
        let (hi, nu_hi, _) = bound;
        let count = nu_hi.saturating_sub(nu_cur);
        if !oversized(count, target) {
            break;
        }
        let predicted = lo + (hi - lo) * target as f64 / count as f64;
        let floor = 0.5 * (lo + predicted);
        let mid = |w: &[f64]| 0.5 * (w[0] + w[1]);
        let below: Vec<&[f64]> = converged
            .windows(2)
            .filter(|w| w[1] > w[0] && mid(w) <= predicted)
            .collect();
        let widest = below
            .iter()
            .filter(|w| mid(w) >= floor)
            .max_by(|a, b| relative_gap(a[0], a[1]).total_cmp(&relative_gap(b[0], b[1])));
        let Some(w) = widest.or(below.last()) else {
            break;
        };
        let f = factorize(ctx, mid(w), 1.0, lam_max)?;
        if f.negative_count <= nu_cur || f.negative_count >= nu_hi {
            break;
        }
        bound = (f.shift, f.negative_count, Some(f));
    }
    Ok(bound)
}

/// A slice of `count` modes holds more than [`RECUT_RATIO`] `target` modes.
fn oversized(count: usize, target: usize) -> bool {
    count as f64 > RECUT_RATIO * target as f64
}

/// The converged eigenvalues of an open-ended slice at shift `lo` (rad²/s²), ascending: the
/// slice's own at or above `lo` (`lambdas`) and the `carried` ones (found by the slice
/// below, all above `lo`).
fn converged_above(lambdas: &[f64], lo: f64, carried: &[f64]) -> Vec<f64> {
    let mut l: Vec<f64> = lambdas.iter().copied().filter(|&x| x >= lo).collect();
    l.extend_from_slice(carried);
    l.sort_by(f64::total_cmp);
    l
}

/// The relative gap `(b − a)/|b|` between consecutive eigenvalues `a ≤ b` (rad²/s²; −).
fn relative_gap(a: f64, b: f64) -> f64 {
    (b - a) / b.abs().max(1e-300)
}

/// Boundary τ (rad²/s²) of an open-ended slice: the middle of the widest relative gap in
/// the last third of its converged eigenvalues `l` (ascending, [`converged_above`];
/// everything below τ has converged, and a wide gap keeps K − τM well conditioned).
/// `top_shift` if fewer than two are known.
fn gap_boundary(l: &[f64], top_shift: f64) -> f64 {
    if l.len() >= 2 {
        let k0 = (2 * l.len() / 3).min(l.len() - 2);
        let kbest = (k0..l.len() - 1)
            .max_by(|&a, &b| relative_gap(l[a], l[a + 1]).total_cmp(&relative_gap(l[b], l[b + 1])))
            .unwrap_or(k0);
        0.5 * (l[kbest] + l[kbest + 1])
    } else {
        top_shift
    }
}

impl BandState {
    /// Writes a finished slice into `phi` from the first column after the committed ones:
    /// first the slice's modes (the `carried` pairs below `hi`, then the new ones
    /// `out.vecs[keep]`, their eigenvalues appended to `lambdas`), then the pairs carried
    /// on to the next slice (carried ones at or above `hi`, then, if there is a next slice
    /// (`more`), the strictly converged new ones between `hi` and `top_shift` up to the
    /// first that is not), as many as fit in `total` columns. `carried` is replaced by the
    /// eigenvalues carried on (rad²/s²).
    fn commit(
        &mut self,
        mut phi: MatMut<'_, f64>,
        (out, keep): (&SliceOut, &[usize]),
        hi: f64,
        (top_shift, more): (f64, bool),
        total: usize,
    ) {
        let (carried, lambdas) = (&mut self.carried, &mut self.lambdas);
        let col0 = lambdas.len();
        let nc = carried.len();
        let old_carried = phi.as_ref().subcols(col0, nc).to_owned();
        let mut next_carried: Vec<(f64, usize, bool)> = Vec::new(); // (λ, index, from old)
        let mut c = col0;
        for (i, &x) in carried.iter().enumerate() {
            if x < hi {
                phi.as_mut().col_mut(c).copy_from(old_carried.col(i));
                lambdas.push(x);
                c += 1;
            } else {
                next_carried.push((x, i, true));
            }
        }
        for &i in keep {
            phi.as_mut().col_mut(c).copy_from(out.vecs.col(i));
            lambdas.push(out.lambdas[i]);
            c += 1;
        }
        if more {
            // Carried: the strictly converged pairs above hi, up to the first that is not
            // (the next slice must find every eigenvalue above the carried ones itself).
            for (i, &x) in out.lambdas.iter().enumerate() {
                if x >= hi && x < top_shift {
                    if !out.strict[i] {
                        break;
                    }
                    next_carried.push((x, i, false));
                }
            }
        }
        next_carried.sort_by(|a, b| a.0.total_cmp(&b.0));
        next_carried.truncate(total.saturating_sub(c));
        carried.clear();
        for &(x, i, from_old) in &next_carried {
            let src = if from_old {
                old_carried.col(i)
            } else {
                out.vecs.col(i)
            };
            phi.as_mut().col_mut(c).copy_from(src);
            carried.push(x);
            c += 1;
        }
    }
}

/// Fraction of the probed λ₁ (an upper bound of it) where the grounded-structure probe of
/// `run_band` puts the first shift (kept only if the Sturm count there is 0).
pub(super) const GROUNDED_SHIFT: f64 = 0.9;

/// The probe moves the first shift from σ₀ < 0 up to `GROUNDED_SHIFT` · λ₁ only if that
/// exceeds `GROUNDED_MOVE` · |σ₀|.
pub(super) const GROUNDED_MOVE: f64 = 4.0;

/// Where the caller counts eigenvalues before that probe, as a multiple of |σ₀|: no
/// eigenvalue below it ⇔ λ₁ > GROUNDED_MOVE / GROUNDED_SHIFT · |σ₀|, the condition under
/// which the probe can move the shift.
pub(super) const GROUNDED_TEST: f64 = GROUNDED_MOVE / GROUNDED_SHIFT;

/// λ (rad²/s²) at the fraction `x` of the way from `lo` to `hi` in √λ (i.e. in frequency),
/// `x = (√λ − √λ_lo)/(√λ_hi − √λ_lo)` with a negative `lo` (rigid-body shift) taken as 0.
pub(super) fn lambda_at(lo: f64, hi: f64, x: f64) -> f64 {
    let (a, b) = (lo.max(0.0).sqrt(), hi.max(0.0).sqrt());
    (a + x * (b - a)).powi(2)
}

/// Work of the modes up to `x` (see [`choose_splits`]) for the count exponent `alpha`.
pub(super) fn band_work(x: f64, alpha: f64) -> f64 {
    x.powf(alpha) + 2.0 * alpha / (alpha + 2.0) * x.powf(alpha + 2.0)
}

/// `x` in [0, 1] where `band_work(x, alpha)` reaches `goal` (bisection; the work increases).
pub(super) fn work_point(goal: f64, alpha: f64) -> f64 {
    let (mut x0, mut x1) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let xm = 0.5 * (x0 + x1);
        if band_work(xm, alpha) < goal {
            x0 = xm;
        } else {
            x1 = xm;
        }
    }
    0.5 * (x0 + x1)
}

/// Where the count probe of [`choose_splits`] goes, for `bands` bands: the first split of
/// the prior α = 1 (the default track's exponent), so that on such a model the probe is the
/// bound itself and no further factorisation is needed. Known before any Sturm count, so the
/// probe is factorised alongside the band's ends.
pub(super) fn split_probe_x(bands: usize) -> f64 {
    work_point(band_work(1.0, 1.0) / bands.max(2) as f64, 1.0)
}

/// Tolerance in x within which the probe serves as a band bound.
pub(super) const PROBE_AS_BOUND: f64 = 0.03;

/// Band bounds for `bands` concurrent bands between the factorisations `first` (lower bound)
/// and `top = (shift, Sturm count)`: factorisations of `K − λ_i M`, ascending, chosen so that
/// every band has about the same *work*. With `x = (√λ − √λ_lo)/(√λ_top − √λ_lo)` the count
/// model is `ν(λ) − ν₀ ≈ N·x^α`, fitted to one probe `(x_p, factorisation at x_p)` (the
/// default track has α ≈ 1: its rail and sleepers are slender; without a probe one is
/// factorised at x = ½), and a mode at x costs `1 + 2x²` units (the slices near f_max take
/// longer per mode: denser spectrum in θ, more deflated modes; docs/performance.md §3.3).
/// Band i then ends where the work `W(x) = x^α + 2α/(α+2)·x^{α+2}` reaches
/// `i/bands · W(1)`; the probe is that bound if it lies within [`PROBE_AS_BOUND`] of it. A split whose count does not lie
/// strictly between its neighbours' is dropped (fewer, non-empty bands).
pub(super) fn choose_splits(
    ctx: &mut Ctx<'_>,
    first: &ShiftFactor,
    top: (f64, usize),
    bands: usize,
    lam_max: f64,
    probe: Option<(f64, ShiftFactor)>,
) -> Result<Vec<ShiftFactor>, EigenError> {
    let nu0 = first.negative_count;
    let total = top.1.saturating_sub(nu0).max(1) as f64;
    let lam_at = |x: f64| lambda_at(first.shift, top.0, x);
    let (xp, probe) = match probe {
        Some(p) => p,
        None => (0.5, factorize(ctx, lam_at(0.5), 1.0, lam_max)?),
    };
    let frac = probe.negative_count.saturating_sub(nu0) as f64 / total;
    let alpha = if frac <= 0.0 {
        4.0
    } else if frac >= 1.0 {
        0.25
    } else {
        (frac.ln() / xp.ln()).clamp(0.25, 4.0)
    };
    let mut probe = Some(probe);
    let mut out: Vec<ShiftFactor> = Vec::new();
    for i in 1..bands {
        let x = work_point(i as f64 / bands as f64 * band_work(1.0, alpha), alpha);
        let f = match probe.take() {
            Some(p) if (x - xp).abs() <= PROBE_AS_BOUND => p,
            other => {
                probe = other;
                factorize(ctx, lam_at(x), 1.0, lam_max)?
            }
        };
        let above_last = out.last().map_or(nu0, |l| l.negative_count);
        if f.negative_count > above_last && f.negative_count < top.1 && f.shift < top.0 {
            out.push(f);
        }
    }
    Ok(out)
}

/// Largest width of a slice in a band above 0 Hz, as a multiple of its distance from the
/// band's lower bound (see `run_band`).
pub(super) const CAP_RATIO: f64 = 0.7;

/// An open-ended slice whose Sturm count at its upper bound exceeds this many
/// `modes_per_slice` gets a lower bound ([`recut`]): the band's last slice may hold 1.5
/// targets, so a slice above that is one the Lanczos run saw only in part.
pub(super) const RECUT_RATIO: f64 = 1.5;

/// Factorisations [`recut`] may spend on one slice's bound (each takes one; the count
/// model is linear in λ and a cluster can defeat it).
pub(super) const RECUT_TRIES: usize = 3;

/// Widest two-sided last slice of a band above 0 Hz, as a multiple of its distance from the
/// band's lower bound: the margin of [`CAP_RATIO`] for a shift at the slice's midpoint.
pub(super) const TWO_SIDED_CAP_RATIO: f64 = 2.0 * CAP_RATIO / (1.0 - CAP_RATIO);

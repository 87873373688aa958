//! The track's implicit damping product beside the contact step, for a passage that runs
//! alone ([`super::PassageOptions::overlap`]).
//!
//! The velocity half-step of the track needs `E rhs` (`E = (I + ½Δt C_q)⁻¹ − I`, the packed
//! single-precision product of [`ModalVerlet`], about a tenth of a passage's time loop),
//! and `rhs` contains the contact force of the step. By linearity it splits: with the last
//! step's force `F'` on the new rows `r_d(x_c)` (`d` = x, t, n),
//!
//! ```text
//! f = −Σ_d F_d r_d = f_known + df,   f_known = −Σ_d F'_d r_d,   df = −Σ_d (F_d − F'_d) r_d,
//! E rhs = E b + ½Δt E df,            E df = −Σ_d (F_d − F'_d) [(1 − s) E r_d(p) + s E r_d(p+1)],
//! ```
//! where `b` is the right-hand side with `f_known` and the rows are the linear interpolation
//! between node planes `p`, `p + 1`. `E b` needs only the state after the displacement half
//! (it runs on a second core while the contact step runs), and `E r_d` of a plane is formed
//! once, when the contact reaches the plane. The single-precision rounding of `E df` is
//! scaled by the step's force change `F − F'`, a small fraction of the force. The arithmetic
//! does not depend on whether the second core is there (the passage hands `E b` to a spinning
//! worker, module `spin`, when the thread pool allows two threads, and otherwise runs it on
//! the calling thread after the contact step), so the results do not depend on the thread
//! count; they differ from [`ModalVerlet::complete`]'s by the rounding of the split products.

use super::super::integrator::ModalVerlet;
use super::super::reduced::RailContactLine;

/// Scratch of the split track step (allocated once per passage).
pub(super) struct DampingOverlap {
    /// First node plane held in `er`.
    p0: usize,
    /// Mode count.
    m: usize,
    /// `E r_d(p)` per plane `p0..`, `3m` values each (x, t, n blocks).
    er: Vec<f64>,
    /// Whether a plane's `E r_d` is formed.
    done: Vec<bool>,
    f_known: Vec<f64>,
    b: Vec<f64>,
    e_b: Vec<f64>,
    df: Vec<f64>,
    e_df: Vec<f64>,
    x32: Vec<f32>,
    y32: Vec<f32>,
}

impl DampingOverlap {
    /// Scratch for a passage whose contact runs over planes `p_first..=p_last + 1` of a
    /// track with `m` modes.
    pub(super) fn new(m: usize, p_first: usize, p_last: usize) -> Self {
        let planes = p_last.saturating_sub(p_first) + 2;
        Self {
            p0: p_first,
            m,
            er: vec![0.0; planes * 3 * m],
            done: vec![false; planes],
            f_known: vec![0.0; m],
            b: vec![0.0; m],
            e_b: vec![0.0; m],
            df: vec![0.0; m],
            e_df: vec![0.0; m],
            x32: vec![0.0; m],
            y32: vec![0.0; m],
        }
    }

    /// The part known before the contact force (beside the contact step): `f_known` from
    /// the last force `f_prev` (N, frame x, t, n) on the rows `rr` at the contact, `b` and
    /// `E b`, and `E r_d` of planes `p`, `p + 1` when not yet formed.
    pub(super) fn begin(
        &mut self,
        tr: &ModalVerlet,
        line: &RailContactLine,
        p: usize,
        f_prev: &[f64; 3],
        rr: &[f64],
    ) {
        let m = self.m;
        for i in 0..m {
            self.f_known[i] =
                -(f_prev[0] * rr[i] + f_prev[1] * rr[m + i] + f_prev[2] * rr[2 * m + i]);
        }
        tr.split_begin(
            &self.f_known,
            &mut self.b,
            (&mut self.x32, &mut self.y32),
            &mut self.e_b,
        );
        for q in [p, p + 1] {
            let k = q - self.p0;
            if self.done[k] {
                continue;
            }
            let rows = line.plane_rows(q);
            let er = &mut self.er[k * 3 * m..(k + 1) * 3 * m];
            for d in 0..3 {
                tr.damping_correction(
                    &rows[d * m..(d + 1) * m],
                    &mut self.x32,
                    &mut self.y32,
                    &mut er[d * m..(d + 1) * m],
                );
            }
            self.done[k] = true;
        }
    }

    /// Completes the track's step with the contact force `f` (N, frame x, t, n), the last
    /// force `f_prev`, the rows `rr` at the contact and its interval `(p, s)`
    /// ([`RailContactLine::locate`]).
    pub(super) fn finish(
        &mut self,
        tr: &mut ModalVerlet,
        f: &[f64; 3],
        f_prev: &[f64; 3],
        rr: &[f64],
        (p, s): (usize, f64),
    ) {
        let m = self.m;
        let dfc = [f[0] - f_prev[0], f[1] - f_prev[1], f[2] - f_prev[2]];
        let k = p - self.p0;
        let (ea, eb) = self.er[k * 3 * m..(k + 2) * 3 * m].split_at(3 * m);
        for i in 0..m {
            let mut d = 0.0;
            let mut e = 0.0;
            for c in 0..3 {
                d += dfc[c] * rr[c * m + i];
                e += dfc[c] * ((1.0 - s) * ea[c * m + i] + s * eb[c * m + i]);
            }
            self.df[i] = -d;
            self.e_df[i] = -e;
        }
        tr.complete_split(&self.b, &self.e_b, &self.df, &self.e_df);
    }
}

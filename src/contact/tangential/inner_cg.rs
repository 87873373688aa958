//! The tangential solver's inner conjugate gradients on the contact's box: the CG steps between
//! two exact whole-grid products, in a branching form (any algorithm and preconditioner) and a
//! branch-free one (the Jacobi-preconditioned Newton CG: adhesion and slip as masks, the
//! reductions in four interleaved partial sums), compiled for AVX2 when the CPU has it
//! (docs/theory.md §6.5; docs/log/performance.md §5.13).

use super::super::influence::TangentialInfluence;
use super::{project, Problem, TangentialAlgorithm, TangentialSolver, LANES};

/// `body` for `i` in `0..n` with its lane `l`, in blocks of four (`LANES`; the remainder on
/// lane 0). The slices named after `mut` and `ref` (each of length `n`) are re-sliced to the
/// block inside a block, so that its four bodies (written out: constant lane indices) index
/// arrays of known length: no bounds checks, and the lanes' partial sums stay in registers.
macro_rules! lanes {
    ($n:expr, $i:ident, $l:ident, mut [$($m:ident),*], ref [$($r:ident),*], $body:block) => {{
        let n: usize = $n;
        let mut c = 0;
        while c + 4 <= n {
            {
                $(let $m = &mut $m[c..c + 4];)*
                $(let $r = &$r[c..c + 4];)*
                {
                    let ($i, $l) = (0, 0);
                    $body
                }
                {
                    let ($i, $l) = (1, 1);
                    $body
                }
                {
                    let ($i, $l) = (2, 2);
                    $body
                }
                {
                    let ($i, $l) = (3, 3);
                    $body
                }
            }
            c += 4;
        }
        for $i in c..n {
            let $l = 0;
            $body
        }
    }};
}

/// The sum of the lanes' partial sums `k` (pairwise: `(l0 + l1) + (l2 + l3)`).
#[inline(always)]
fn lane_sum<const K: usize>(acc: &[[f64; K]; LANES], k: usize) -> f64 {
    (acc[0][k] + acc[1][k]) + (acc[2][k] + acc[3][k])
}

/// One CG step's data for [`TangentialSolver::cg_update`] and
/// [`TangentialSolver::cg_update_masked`]: the traction bound `g` (Pa), the traction
/// `(tx, ty)` (Pa, updated in place), the step length `alpha` (−, the CG's `r·z / dᵀ w`)
/// and the box's row segments `segs` (element ranges).
pub(super) struct CgStep<'a> {
    pub(super) g: &'a [f64],
    pub(super) tx: &'a mut [f64],
    pub(super) ty: &'a mut [f64],
    pub(super) alpha: f64,
    pub(super) segs: &'a [(usize, usize)],
}

impl TangentialSolver {
    /// The inner conjugate gradients from the search direction `(dx_, dy_)` with `r·z = rr`
    /// until the model residual is below `stop` (m), an adhesion element leaves its disc
    /// (it joins the slip set; an exact product follows) or the products run out.
    ///
    /// The loops run branch-free where they can (adhesion and slip as masks, with the Jacobi
    /// preconditioner) and reduce in four interleaved partial sums ([`lanes!`]); compiled for
    /// AVX2 when the CPU has it (checked at run time; no fused multiply-add, so both builds
    /// give the same bits).
    pub(super) fn inner_cg(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        pb: &Problem<'_>,
        tx: &mut [f64],
        ty: &mut [f64],
        rr: f64,
        stop: f64,
    ) {
        #[cfg(test)]
        let plain = tests::PLAIN_CG.with(|p| p.get());
        #[cfg(not(test))]
        let plain = false;
        #[cfg(target_arch = "x86_64")]
        if !plain && std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above), the only requirement of the
            // `target_feature` function.
            unsafe { self.inner_cg_avx2(conv, pb, tx, ty, rr, stop) };
            return;
        }
        self.inner_cg_body::<false>(conv, pb, tx, ty, rr, stop);
    }

    /// [`Self::inner_cg_body`] compiled with AVX2 enabled, its loops in AVX2 vectors (module
    /// `avx2`: the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn inner_cg_avx2(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        pb: &Problem<'_>,
        tx: &mut [f64],
        ty: &mut [f64],
        rr: f64,
        stop: f64,
    ) {
        self.inner_cg_body::<true>(conv, pb, tx, ty, rr, stop);
    }

    /// The inner CG of [`Self::inner_cg`]; with `SIMD` (only from [`Self::inner_cg_avx2`],
    /// i.e. on a CPU with AVX2) its loops run in the AVX2 kernels of module `avx2`, which
    /// give the bits of the [`lanes!`] loops.
    #[inline(always)]
    fn inner_cg_body<const SIMD: bool>(
        &mut self,
        conv: &mut (impl TangentialInfluence + ?Sized),
        pb: &Problem<'_>,
        tx: &mut [f64],
        ty: &mut [f64],
        mut rr: f64,
        stop: f64,
    ) {
        let norot = self.algorithm == TangentialAlgorithm::ElementTest;
        let masked = self.jacobi && !norot;
        // the search direction is zero outside the box's segments within `lo..hi` (see
        // `start`): its sums and the loops below run there
        let segs = std::mem::take(&mut self.segs);
        let (mut sdx, mut sdy) = (0.0, 0.0);
        if self.uniform_x_m_per_pa != 0.0 || self.uniform_y_m_per_pa != 0.0 {
            let mut acc = [[0.0; 2]; LANES];
            for &(a, b) in &segs {
                let (dx, dy) = (&self.dx_[a..b], &self.dy_[a..b]);
                lanes!(b - a, i, l, mut [], ref [dx, dy], {
                    acc[l][0] += dx[i];
                    acc[l][1] += dy[i];
                });
            }
            (sdx, sdy) = (lane_sum(&acc, 0), lane_sum(&acc, 1));
        }
        while self.products < self.cg_iterations {
            conv.tangential_box(
                &self.dx_,
                &self.dy_,
                &mut self.qx,
                &mut self.qy,
                self.rows,
                self.cols,
            );
            let (cux, cuy) = self.uniform_of_sums(sdx, sdy);
            self.products += 1;
            self.exact_now = false;
            // model product w = C d on adhesion, P C d + κ d on slip (d ∥ tangent there),
            // with the series compliance's uniform displacement added to C d (exactly 0
            // without it), and dᵀ w
            let mut acc = [[0.0; 1]; LANES];
            for &(a, b) in &segs {
                // the AVX2 kernel takes the whole blocks of four, `lanes!` the rest
                let mut a = a;
                #[cfg(target_arch = "x86_64")]
                if SIMD {
                    let (qx, qy) = (&mut self.qx[a..b], &mut self.qy[a..b]);
                    let (dx, dy, kap) = (&self.dx_[a..b], &self.dy_[a..b], &self.kap[a..b]);
                    // SAFETY: `SIMD` only on a CPU with AVX2 (see `inner_cg_avx2`)
                    a += unsafe {
                        crate::contact::avx2::cg::model_product(
                            qx,
                            qy,
                            [dx, dy, kap],
                            (cux, cuy),
                            &mut acc,
                        )
                    };
                }
                let (qx, qy) = (&mut self.qx[a..b], &mut self.qy[a..b]);
                let (dx, dy, kap) = (&self.dx_[a..b], &self.dy_[a..b], &self.kap[a..b]);
                lanes!(b - a, i, l, mut [qx, qy], ref [dx, dy, kap], {
                    let (q1, q2) = (qx[i] + cux, qy[i] + cuy);
                    qx[i] = q1;
                    qy[i] = q2;
                    acc[l][0] += q1 * dx[i] + q2 * dy[i] + kap[i] * (dx[i] * dx[i] + dy[i] * dy[i]);
                });
            }
            let den = lane_sum(&acc, 0);
            if den <= 0.0 || rr == 0.0 {
                break;
            }
            let alpha = rr / den;
            let step = CgStep {
                g: pb.g,
                tx: &mut *tx,
                ty: &mut *ty,
                alpha,
                segs: &segs,
            };
            let (violated, mut rr_new, mut rmax) = if masked {
                self.cg_update_masked_body::<SIMD>(step)
            } else {
                self.cg_update(step)
            };
            if violated {
                if !norot {
                    self.to_circles(pb.g, tx, ty);
                }
                self.exact(conv, pb.ex, pb.ey, tx, ty);
                break;
            }
            if norot {
                (rr_new, rmax) = self.residual(pb.g, false);
            }
            if rmax <= stop {
                break;
            }
            let beta = rr_new / rr;
            rr = rr_new;
            let mut acc = [[0.0; 2]; LANES];
            for &(a, b) in &segs {
                let mut a = a;
                #[cfg(target_arch = "x86_64")]
                if SIMD {
                    let (qx, qy) = (&self.qx[a..b], &self.qy[a..b]);
                    let (dx, dy) = (&mut self.dx_[a..b], &mut self.dy_[a..b]);
                    // SAFETY: `SIMD` only on a CPU with AVX2 (see `inner_cg_avx2`)
                    a += unsafe {
                        crate::contact::avx2::cg::direction(dx, dy, [qx, qy], beta, &mut acc)
                    };
                }
                let (qx, qy) = (&self.qx[a..b], &self.qy[a..b]);
                let (dx, dy) = (&mut self.dx_[a..b], &mut self.dy_[a..b]);
                lanes!(b - a, i, l, mut [dx, dy], ref [qx, qy], {
                    dx[i] = qx[i] + beta * dx[i];
                    dy[i] = qy[i] + beta * dy[i];
                    acc[l][0] += dx[i];
                    acc[l][1] += dy[i];
                });
            }
            (sdx, sdy) = (lane_sum(&acc, 0), lane_sum(&acc, 1));
        }
        self.segs = segs;
    }

    /// [`Self::cg_update`] with the Jacobi preconditioner and
    /// [`TangentialAlgorithm::Newton`], branch-free: the model product `w` from the masks
    /// `(wa, ws)` of [`Self::precondition`] (`w = wa q + ws (c t + κ d)`, the same values as the
    /// branches), the reductions in [`lanes!`]. An adhesion element that left its disc is
    /// projected in a second pass (the CG then stops: the step's residual is not used).
    /// (The inner CG calls its body directly; this entry is the tests'.)
    #[cfg(test)]
    pub(super) fn cg_update_masked(&mut self, step: CgStep<'_>) -> (bool, f64, f64) {
        self.cg_update_masked_body::<false>(step)
    }

    /// [`Self::cg_update_masked`] in the AVX2 kernel of module `avx2` (the same bits);
    /// `None` on a CPU without AVX2.
    #[cfg(all(test, target_arch = "x86_64"))]
    pub(super) fn cg_update_masked_avx2(&mut self, step: CgStep<'_>) -> Option<(bool, f64, f64)> {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return None;
        }
        Some(self.cg_update_masked_body::<true>(step))
    }

    /// [`Self::cg_update_masked`]; with `SIMD` (only on a CPU with AVX2) in the AVX2 kernel.
    #[inline(always)]
    fn cg_update_masked_body<const SIMD: bool>(&mut self, step: CgStep<'_>) -> (bool, f64, f64) {
        let (g, alpha, segs) = (step.g, step.alpha, step.segs);
        let (tx, ty) = (step.tx, step.ty);
        let mut acc = [[0.0; 2]; LANES];
        let mut violated = false;
        for &(a, b) in segs {
            // the AVX2 kernel takes the whole blocks of four, `lanes!` the rest
            let mut a = a;
            #[cfg(target_arch = "x86_64")]
            if SIMD {
                let out = crate::contact::avx2::cg::MaskedOut {
                    s: [&mut self.sx[a..b], &mut self.sy[a..b]],
                    q: [&mut self.qx[a..b], &mut self.qy[a..b]],
                    r: [&mut self.rx[a..b], &mut self.ry[a..b]],
                    t: [&mut tx[a..b], &mut ty[a..b]],
                };
                let inp = crate::contact::avx2::cg::MaskedIn {
                    d: [&self.dx_[a..b], &self.dy_[a..b]],
                    p: [&self.px[a..b], &self.py[a..b]],
                    mi: [&self.mix[a..b], &self.miy[a..b]],
                    w: [&self.wa[a..b], &self.ws[a..b]],
                    kap: &self.kap[a..b],
                    g: &g[a..b],
                };
                // SAFETY: `SIMD` only on a CPU with AVX2 (see `inner_cg_avx2`)
                let (done, v) =
                    unsafe { crate::contact::avx2::cg::masked_update(out, inp, alpha, &mut acc) };
                violated |= v;
                a += done;
            }
            let (sx, sy) = (&mut self.sx[a..b], &mut self.sy[a..b]);
            let (qx, qy) = (&mut self.qx[a..b], &mut self.qy[a..b]);
            let (rx, ry) = (&mut self.rx[a..b], &mut self.ry[a..b]);
            let (dx, dy, kap) = (&self.dx_[a..b], &self.dy_[a..b], &self.kap[a..b]);
            let (px, py) = (&self.px[a..b], &self.py[a..b]);
            let (mix, miy) = (&self.mix[a..b], &self.miy[a..b]);
            let (wa, ws) = (&self.wa[a..b], &self.ws[a..b]);
            let (txs, tys, gs) = (&mut tx[a..b], &mut ty[a..b], &g[a..b]);
            lanes!(b - a, i, l, mut [sx, sy, qx, qy, rx, ry, txs, tys],
                ref [dx, dy, kap, px, py, mix, miy, wa, ws, gs], {
                let (q1, q2) = (qx[i], qy[i]);
                sx[i] += alpha * q1;
                sy[i] += alpha * q2;
                let ax = txs[i] + alpha * dx[i];
                let ay = tys[i] + alpha * dy[i];
                violated |= (wa[i] > 0.0) & (ax * ax + ay * ay > gs[i] * gs[i]);
                txs[i] = ax;
                tys[i] = ay;
                let c = q1 * px[i] + q2 * py[i];
                let wx = q1 * wa[i] + (c * px[i] + kap[i] * dx[i]) * ws[i];
                let wy = q2 * wa[i] + (c * py[i] + kap[i] * dy[i]) * ws[i];
                let (r1, r2) = (rx[i] - alpha * wx, ry[i] - alpha * wy);
                rx[i] = r1;
                ry[i] = r2;
                let (z1, z2) = (r1 * mix[i], r2 * miy[i]);
                qx[i] = z1;
                qy[i] = z2;
                acc[l][0] += r1 * z1 + r2 * z2;
                acc[l][1] = acc[l][1].max(r1.abs()).max(r2.abs());
            });
        }
        if violated {
            for i in segs.iter().flat_map(|&(a, b)| a..b) {
                if self.wa[i] > 0.0 {
                    let (mut ax, mut ay) = (tx[i], ty[i]);
                    if ax * ax + ay * ay > g[i] * g[i] {
                        project(&mut ax, &mut ay, g[i]);
                        (tx[i], ty[i]) = (ax, ay);
                        self.slip[i] = true;
                    }
                }
            }
        }
        let rmax = acc.iter().fold(0.0_f64, |m, a| m.max(a[1]));
        (violated, lane_sum(&acc, 0), rmax)
    }

    /// One pass of a CG step of length `alpha`: the slip and traction update (an adhesion
    /// element leaving its disc is projected onto it and joins the slip set) and, with
    /// [`TangentialAlgorithm::Newton`], the model residual, its preconditioned copy (into
    /// `qx, qy`; the product is no longer needed) and the reductions of the next step, over
    /// the box's segments `segs` (every element with a positive bound; elsewhere the search
    /// direction and the residual are zero). Returns whether an element left its disc, `r·z`
    /// and `max |r|`.
    pub(super) fn cg_update(&mut self, step: CgStep<'_>) -> (bool, f64, f64) {
        let (g, alpha, segs) = (step.g, step.alpha, step.segs);
        let (tx, ty) = (step.tx, step.ty);
        let norot = self.algorithm == TangentialAlgorithm::ElementTest;
        let jacobi = self.jacobi && !norot;
        let mut violated = false;
        let (mut rr_new, mut rmax) = (0.0, 0.0_f64);
        for i in segs.iter().flat_map(|&(a, b)| a..b) {
            let (qx, qy) = (self.qx[i], self.qy[i]);
            self.sx[i] += alpha * qx;
            self.sy[i] += alpha * qy;
            let (wx, wy) = if g[i] <= 0.0 {
                (0.0, 0.0)
            } else {
                let mut ax = tx[i] + alpha * self.dx_[i];
                let mut ay = ty[i] + alpha * self.dy_[i];
                if self.slip[i] {
                    // rotation along the tangent; back onto the circle after the CG
                } else if ax * ax + ay * ay > g[i] * g[i] {
                    project(&mut ax, &mut ay, g[i]);
                    self.slip[i] = true;
                    violated = true;
                }
                tx[i] = ax;
                ty[i] = ay;
                if self.slip[i] {
                    let c = qx * self.px[i] + qy * self.py[i];
                    (
                        c * self.px[i] + self.kap[i] * self.dx_[i],
                        c * self.py[i] + self.kap[i] * self.dy_[i],
                    )
                } else {
                    (qx, qy)
                }
            };
            if norot {
                continue;
            }
            let (rx, ry) = (self.rx[i] - alpha * wx, self.ry[i] - alpha * wy);
            self.rx[i] = rx;
            self.ry[i] = ry;
            let (zx, zy) = if jacobi {
                (rx * self.mix[i], ry * self.miy[i])
            } else {
                (rx, ry)
            };
            self.qx[i] = zx;
            self.qy[i] = zy;
            rr_new += rx * zx + ry * zy;
            rmax = rmax.max(rx.abs()).max(ry.abs());
        }
        (violated, rr_new, rmax)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::cell::Cell;

    thread_local! {
        /// Run the inner CG's baseline loops even on a CPU with AVX2 (to compare the two).
        pub(in crate::contact) static PLAIN_CG: Cell<bool> = const { Cell::new(false) };
    }
}

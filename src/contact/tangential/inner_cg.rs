//! The tangential solver's inner conjugate gradients on the contact's box: the CG steps between
//! two exact whole-grid products, in a branching form (any algorithm and preconditioner) and a
//! branch-free one (the Jacobi-preconditioned Newton CG: adhesion and slip as masks, the
//! reductions in four interleaved partial sums), compiled for AVX2 when the CPU has it
//! (docs/theory.md §6.5; docs/log/performance.md §5.13).

use super::*;

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

/// Partial sums of the inner CG's reductions: element `i` of a segment goes to lane `i mod 4`
/// of its blocks of four (the segment's last `n mod 4` elements to lane 0), so that the
/// additions run in four independent chains (and vector lanes) instead of one.
const LANES: usize = 4;

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
        conv: &mut Convolver,
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
        conv: &mut Convolver,
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
        conv: &mut Convolver,
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
                    a +=
                        unsafe { avx2::model_product(qx, qy, [dx, dy, kap], (cux, cuy), &mut acc) };
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
                    a += unsafe { avx2::direction(dx, dy, [qx, qy], beta, &mut acc) };
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
                let out = avx2::MaskedOut {
                    s: [&mut self.sx[a..b], &mut self.sy[a..b]],
                    q: [&mut self.qx[a..b], &mut self.qy[a..b]],
                    r: [&mut self.rx[a..b], &mut self.ry[a..b]],
                    t: [&mut tx[a..b], &mut ty[a..b]],
                };
                let inp = avx2::MaskedIn {
                    d: [&self.dx_[a..b], &self.dy_[a..b]],
                    p: [&self.px[a..b], &self.py[a..b]],
                    mi: [&self.mix[a..b], &self.miy[a..b]],
                    w: [&self.wa[a..b], &self.ws[a..b]],
                    kap: &self.kap[a..b],
                    g: &g[a..b],
                };
                // SAFETY: `SIMD` only on a CPU with AVX2 (see `inner_cg_avx2`)
                let (done, v) = unsafe { avx2::masked_update(out, inp, alpha, &mut acc) };
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

/// The inner CG's loops over the whole blocks of four of one row segment in AVX2 vectors, with
/// the bits of the [`lanes!`] loops: element `c + l` of a block in vector lane `l` (the lane
/// of the partial sums in [`lanes!`]), the same multiplications and additions in the same
/// order (no fused multiply-add). Each kernel returns how many elements it took (`n − n mod
/// 4`); the caller runs [`lanes!`] on the rest (fewer than four: lane 0, as there). The one
/// difference: a NaN in a residual is not ignored by the `max |r|` reduction (`vmaxpd`
/// returns its second operand when either is NaN; `f64::max` returns the other one); a NaN
/// ends the passage anyway (its finiteness check).
///
/// Safety of every kernel: the CPU must support AVX2 (the callers run them only from
/// `inner_cg_avx2`, after the run-time check); the slices are re-sliced to the first one's
/// length at entry (a shorter one panics), so the vector loads and stores of the blocks stay
/// inside them.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::LANES;
    use std::arch::x86_64::*;

    /// The lanes `acc[·][k]` of the partial sums as a vector.
    #[inline(always)]
    unsafe fn lanes_in<const K: usize>(acc: &[[f64; K]; LANES], k: usize) -> __m256d {
        _mm256_set_pd(acc[3][k], acc[2][k], acc[1][k], acc[0][k])
    }

    /// The vector `v` back into the lanes `acc[·][k]`.
    #[inline(always)]
    unsafe fn lanes_out<const K: usize>(acc: &mut [[f64; K]; LANES], k: usize, v: __m256d) {
        let mut a = [0.0; LANES];
        _mm256_storeu_pd(a.as_mut_ptr(), v);
        for (l, x) in a.into_iter().enumerate() {
            acc[l][k] = x;
        }
    }

    /// Four elements of `x` from `c` (the caller keeps `c + 4 ≤ x.len()`).
    #[inline(always)]
    unsafe fn ld(x: &[f64], c: usize) -> __m256d {
        debug_assert!(c + 4 <= x.len());
        _mm256_loadu_pd(x.as_ptr().add(c))
    }

    /// `v` into four elements of `x` from `c` (the caller keeps `c + 4 ≤ x.len()`).
    #[inline(always)]
    unsafe fn st(x: &mut [f64], c: usize, v: __m256d) {
        debug_assert!(c + 4 <= x.len());
        _mm256_storeu_pd(x.as_mut_ptr().add(c), v);
    }

    /// `q += cu` and `acc[·][0] += q·d + κ (d·d)` (the CG's model product and `dᵀ w`).
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn model_product(
        qx: &mut [f64],
        qy: &mut [f64],
        [dx, dy, kap]: [&[f64]; 3],
        (cux, cuy): (f64, f64),
        acc: &mut [[f64; 1]; LANES],
    ) -> usize {
        let n = qx.len();
        let (qy, dx, dy, kap) = (&mut qy[..n], &dx[..n], &dy[..n], &kap[..n]);
        let (vx, vy) = (_mm256_set1_pd(cux), _mm256_set1_pd(cuy));
        let mut a = lanes_in(acc, 0);
        let mut c = 0;
        while c + 4 <= n {
            let q1 = _mm256_add_pd(ld(qx, c), vx);
            let q2 = _mm256_add_pd(ld(qy, c), vy);
            st(qx, c, q1);
            st(qy, c, q2);
            let (d1, d2) = (ld(dx, c), ld(dy, c));
            let qd = _mm256_add_pd(_mm256_mul_pd(q1, d1), _mm256_mul_pd(q2, d2));
            let dd = _mm256_add_pd(_mm256_mul_pd(d1, d1), _mm256_mul_pd(d2, d2));
            a = _mm256_add_pd(a, _mm256_add_pd(qd, _mm256_mul_pd(ld(kap, c), dd)));
            c += 4;
        }
        lanes_out(acc, 0, a);
        c
    }

    /// `d = q + β d` and `acc[·][0] += dx`, `acc[·][1] += dy` (the CG's new direction and its
    /// sums).
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn direction(
        dx: &mut [f64],
        dy: &mut [f64],
        [qx, qy]: [&[f64]; 2],
        beta: f64,
        acc: &mut [[f64; 2]; LANES],
    ) -> usize {
        let n = dx.len();
        let (dy, qx, qy) = (&mut dy[..n], &qx[..n], &qy[..n]);
        let b = _mm256_set1_pd(beta);
        let (mut a0, mut a1) = (lanes_in(acc, 0), lanes_in(acc, 1));
        let mut c = 0;
        while c + 4 <= n {
            let d1 = _mm256_add_pd(ld(qx, c), _mm256_mul_pd(b, ld(dx, c)));
            let d2 = _mm256_add_pd(ld(qy, c), _mm256_mul_pd(b, ld(dy, c)));
            st(dx, c, d1);
            st(dy, c, d2);
            a0 = _mm256_add_pd(a0, d1);
            a1 = _mm256_add_pd(a1, d2);
            c += 4;
        }
        lanes_out(acc, 0, a0);
        lanes_out(acc, 1, a1);
        c
    }

    /// The segment's arrays that [`masked_update`] writes: slip `s`, product in / scaled
    /// residual out `q`, residual `r`, traction `t` (x, y each).
    pub(super) struct MaskedOut<'a> {
        pub(super) s: [&'a mut [f64]; 2],
        pub(super) q: [&'a mut [f64]; 2],
        pub(super) r: [&'a mut [f64]; 2],
        pub(super) t: [&'a mut [f64]; 2],
    }

    /// The segment's arrays that [`masked_update`] reads: direction `d`, tangent `p`, Jacobi
    /// scale `mi` (x, y each), adhesion and slip masks `w`, curvature `kap`, bound `g`.
    pub(super) struct MaskedIn<'a> {
        pub(super) d: [&'a [f64]; 2],
        pub(super) p: [&'a [f64]; 2],
        pub(super) mi: [&'a [f64]; 2],
        pub(super) w: [&'a [f64]; 2],
        pub(super) kap: &'a [f64],
        pub(super) g: &'a [f64],
    }

    /// The masked CG step of `cg_update_masked_body` on the blocks of one segment; returns
    /// the elements taken and whether an adhesion element left its disc, and accumulates `r·z` into `acc[·][0]` and `max |r|`
    /// into `acc[·][1]`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn masked_update(
        out: MaskedOut<'_>,
        inp: MaskedIn<'_>,
        alpha: f64,
        acc: &mut [[f64; 2]; LANES],
    ) -> (usize, bool) {
        let MaskedOut {
            s: [sx, sy],
            q: [qx, qy],
            r: [rx, ry],
            t: [tx, ty],
        } = out;
        let n = sx.len();
        let (sy, qx, qy, rx, ry, tx, ty) = (
            &mut sy[..n],
            &mut qx[..n],
            &mut qy[..n],
            &mut rx[..n],
            &mut ry[..n],
            &mut tx[..n],
            &mut ty[..n],
        );
        let (dx, dy, px, py) = (
            &inp.d[0][..n],
            &inp.d[1][..n],
            &inp.p[0][..n],
            &inp.p[1][..n],
        );
        let (mix, miy, wa, ws) = (
            &inp.mi[0][..n],
            &inp.mi[1][..n],
            &inp.w[0][..n],
            &inp.w[1][..n],
        );
        let (kap, g) = (&inp.kap[..n], &inp.g[..n]);
        let al = _mm256_set1_pd(alpha);
        let zero = _mm256_setzero_pd();
        let sign = _mm256_set1_pd(-0.0);
        let (mut a0, mut a1) = (lanes_in(acc, 0), lanes_in(acc, 1));
        let mut viol = _mm256_setzero_pd();
        let mut c = 0;
        while c + 4 <= n {
            let (q1, q2) = (ld(qx, c), ld(qy, c));
            st(sx, c, _mm256_add_pd(ld(sx, c), _mm256_mul_pd(al, q1)));
            st(sy, c, _mm256_add_pd(ld(sy, c), _mm256_mul_pd(al, q2)));
            let (d1, d2) = (ld(dx, c), ld(dy, c));
            let ax = _mm256_add_pd(ld(tx, c), _mm256_mul_pd(al, d1));
            let ay = _mm256_add_pd(ld(ty, c), _mm256_mul_pd(al, d2));
            let (w_a, w_s, gg) = (ld(wa, c), ld(ws, c), ld(g, c));
            let out = _mm256_cmp_pd::<_CMP_GT_OQ>(
                _mm256_add_pd(_mm256_mul_pd(ax, ax), _mm256_mul_pd(ay, ay)),
                _mm256_mul_pd(gg, gg),
            );
            let adh = _mm256_cmp_pd::<_CMP_GT_OQ>(w_a, zero);
            viol = _mm256_or_pd(viol, _mm256_and_pd(adh, out));
            st(tx, c, ax);
            st(ty, c, ay);
            let (p1, p2, k) = (ld(px, c), ld(py, c), ld(kap, c));
            let cc = _mm256_add_pd(_mm256_mul_pd(q1, p1), _mm256_mul_pd(q2, p2));
            let sl1 = _mm256_add_pd(_mm256_mul_pd(cc, p1), _mm256_mul_pd(k, d1));
            let sl2 = _mm256_add_pd(_mm256_mul_pd(cc, p2), _mm256_mul_pd(k, d2));
            let wx = _mm256_add_pd(_mm256_mul_pd(q1, w_a), _mm256_mul_pd(sl1, w_s));
            let wy = _mm256_add_pd(_mm256_mul_pd(q2, w_a), _mm256_mul_pd(sl2, w_s));
            let r1 = _mm256_sub_pd(ld(rx, c), _mm256_mul_pd(al, wx));
            let r2 = _mm256_sub_pd(ld(ry, c), _mm256_mul_pd(al, wy));
            st(rx, c, r1);
            st(ry, c, r2);
            let z1 = _mm256_mul_pd(r1, ld(mix, c));
            let z2 = _mm256_mul_pd(r2, ld(miy, c));
            st(qx, c, z1);
            st(qy, c, z2);
            let rz = _mm256_add_pd(_mm256_mul_pd(r1, z1), _mm256_mul_pd(r2, z2));
            a0 = _mm256_add_pd(a0, rz);
            let m = _mm256_max_pd(a1, _mm256_andnot_pd(sign, r1));
            a1 = _mm256_max_pd(m, _mm256_andnot_pd(sign, r2));
            c += 4;
        }
        lanes_out(acc, 0, a0);
        lanes_out(acc, 1, a1);
        (c, _mm256_movemask_pd(viol) != 0)
    }
}

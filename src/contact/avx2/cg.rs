//! The inner CG's loops over the whole blocks of four of one row segment in AVX2 vectors, with
//! the bits of the [`lanes!`] loops: element `c + l` of a block in vector lane `l` (the lane
//! of the partial sums in [`lanes!`]), the same multiplications and additions in the same
//! order (no fused multiply-add). Each kernel returns how many elements it took (`n − n mod
//! 4`); the caller runs [`lanes!`] on the rest (fewer than four: lane 0, as there). The one
//! difference: a NaN in a residual is not ignored by the `max |r|` reduction (`vmaxpd`
//! returns its second operand when either is NaN; `f64::max` returns the other one); a NaN
//! ends the passage anyway (its finiteness check).
//!
//! Safety of every kernel: the CPU must support AVX2 (the callers run them only from
//! `inner_cg_avx2`, after the run-time check); the slices are re-sliced to the first one's
//! length at entry (a shorter one panics), so the vector loads and stores of the blocks stay
//! inside them.

use crate::contact::tangential::LANES;
use std::arch::x86_64::{
    __m256d, _mm256_add_pd, _mm256_and_pd, _mm256_andnot_pd, _mm256_cmp_pd, _mm256_loadu_pd,
    _mm256_max_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_or_pd, _mm256_set1_pd, _mm256_set_pd,
    _mm256_setzero_pd, _mm256_storeu_pd, _mm256_sub_pd, _CMP_GT_OQ,
};

/// The lanes `acc[·][k]` of the partial sums as a vector.
#[inline(always)]
unsafe fn lanes_in<const K: usize>(acc: &[[f64; K]; LANES], k: usize) -> __m256d {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe { _mm256_set_pd(acc[3][k], acc[2][k], acc[1][k], acc[0][k]) }
}

/// The vector `v` back into the lanes `acc[·][k]`.
#[inline(always)]
unsafe fn lanes_out<const K: usize>(acc: &mut [[f64; K]; LANES], k: usize, v: __m256d) {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe {
        let mut a = [0.0; LANES];
        _mm256_storeu_pd(a.as_mut_ptr(), v);
        for (l, x) in a.into_iter().enumerate() {
            acc[l][k] = x;
        }
    }
}

/// Four elements of `x` from `c` (the caller keeps `c + 4 ≤ x.len()`).
#[inline(always)]
unsafe fn ld(x: &[f64], c: usize) -> __m256d {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe {
        debug_assert!(c + 4 <= x.len());
        _mm256_loadu_pd(x.as_ptr().add(c))
    }
}

/// `v` into four elements of `x` from `c` (the caller keeps `c + 4 ≤ x.len()`).
#[inline(always)]
unsafe fn st(x: &mut [f64], c: usize, v: __m256d) {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe {
        debug_assert!(c + 4 <= x.len());
        _mm256_storeu_pd(x.as_mut_ptr().add(c), v);
    }
}

/// `q += cu` and `acc[·][0] += q·d + κ (d·d)` (the CG's model product and `dᵀ w`).
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn model_product(
    qx: &mut [f64],
    qy: &mut [f64],
    [dx, dy, kap]: [&[f64]; 3],
    (cux, cuy): (f64, f64),
    acc: &mut [[f64; 1]; LANES],
) -> usize {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe {
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
}

/// `d = q + β d` and `acc[·][0] += dx`, `acc[·][1] += dy` (the CG's new direction and its
/// sums).
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn direction(
    dx: &mut [f64],
    dy: &mut [f64],
    [qx, qy]: [&[f64]; 2],
    beta: f64,
    acc: &mut [[f64; 2]; LANES],
) -> usize {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe {
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
}

/// The segment's arrays that [`masked_update`] writes: slip `s`, product in / scaled
/// residual out `q`, residual `r`, traction `t` (x, y each).
pub(crate) struct MaskedOut<'a> {
    pub(crate) s: [&'a mut [f64]; 2],
    pub(crate) q: [&'a mut [f64]; 2],
    pub(crate) r: [&'a mut [f64]; 2],
    pub(crate) t: [&'a mut [f64]; 2],
}

/// The segment's arrays that [`masked_update`] reads: direction `d`, tangent `p`, Jacobi
/// scale `mi` (x, y each), adhesion and slip masks `w`, curvature `kap`, bound `g`.
pub(crate) struct MaskedIn<'a> {
    pub(crate) d: [&'a [f64]; 2],
    pub(crate) p: [&'a [f64]; 2],
    pub(crate) mi: [&'a [f64]; 2],
    pub(crate) w: [&'a [f64]; 2],
    pub(crate) kap: &'a [f64],
    pub(crate) g: &'a [f64],
}

/// The masked CG step of `cg_update_masked_body` on the blocks of one segment; returns
/// the elements taken and whether an adhesion element left its disc, and accumulates `r·z` into `acc[·][0]` and `max |r|`
/// into `acc[·][1]`.
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn masked_update(
    out: MaskedOut<'_>,
    inp: MaskedIn<'_>,
    alpha: f64,
    acc: &mut [[f64; 2]; LANES],
) -> (usize, bool) {
    // SAFETY: this function's contract (module docs): AVX2 is present and the blocks lie inside the slices.
    unsafe {
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

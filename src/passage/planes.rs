//! How the contact force is shared among the rail's node planes (docs/theory.md §8.6).
//!
//! The contact pressure acts over the patch, not on a line. Integrated across the patch,
//! Hertz's elliptical pressure `p₀√(1 − x²/a² − y²/b²)` is a parabolic line load along the
//! rail, `q(ξ) = 3/(4a) · (1 − ξ²/a²)` per newton, `|ξ| ≤ a` (Johnson 1985, §4.2). Its
//! consistent nodal loads on the node planes of a mesh with linear shape functions `N_j(x)`
//! are `w_j = ∫ N_j(x_c + ξ) q(ξ) dξ`; the same weights read the rail's displacement under
//! the patch (work-conjugate). With `a = 0` they reduce to the linear interpolation between
//! the two planes around the contact point.
//!
//! Spreading matters only for the untruncated FE: a load on one node line indents the mesh
//! locally by an amount that depends on where between two planes the load is, which the
//! half-space of the contact model already counts (local flexibility counted twice, and
//! modulated at the element-passing frequency). A load spread over the patch excites far
//! less of that mesh-dependent local deformation. Assumption: the patch length is the static
//! Hertz one (constant over a passage, so that unit responses can be reused).

/// Most node planes one patch may cover.
pub(crate) const MAX_PLANES: usize = 32;

/// The weights of the node planes under a patch centred at one contact position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneWeights {
    /// Index of the first plane with a weight.
    pub first: usize,
    /// Number of planes with a weight.
    pub len: usize,
    /// The weights (−), `len` of them, summing to 1.
    pub w: [f64; MAX_PLANES],
}

impl PlaneWeights {
    /// `(plane, weight)` pairs.
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.w[..self.len]
            .iter()
            .enumerate()
            .map(move |(k, &w)| (self.first + k, w))
    }

    /// The last plane with a weight.
    pub fn last(&self) -> usize {
        self.first + self.len - 1
    }
}

/// Why a patch's weights could not be formed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PatchError {
    /// The patch reaches beyond the first or last plane.
    #[error("the contact patch [{lo_m:.4}, {hi_m:.4}] m reaches off the rail [{first_m:.3}, {last_m:.3}] m: lengthen the track (track.bays)")]
    OffRail {
        /// Patch start (m).
        lo_m: f64,
        /// Patch end (m).
        hi_m: f64,
        /// First plane (m).
        first_m: f64,
        /// Last plane (m).
        last_m: f64,
    },
    /// The patch covers more planes than `MAX_PLANES`.
    #[error("the contact patch (2a = {length_m:.4} m) covers {planes} node planes, more than {max}: coarsen mesh.fine_element_length or set explicit.load_spread = \"node\"")]
    TooManyPlanes {
        /// Patch length 2a (m).
        length_m: f64,
        /// Planes covered.
        planes: usize,
        /// The limit.
        max: usize,
    },
}

/// Three-point Gauss–Legendre nodes and weights on [−1, 1] (exact to degree 5; the
/// integrand `N_j·q` is a cubic).
const GAUSS3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// The weights of the planes at `planes_x_m` (m, increasing) under a parabolic line load of
/// unit resultant over `[x_c − a, x_c + a]` (m); `a = 0` gives the linear interpolation
/// between the two planes around `x_c`. No allocation.
pub fn plane_weights(planes_x_m: &[f64], x_c: f64, a: f64) -> Result<PlaneWeights, PatchError> {
    let px = planes_x_m;
    let n = px.len();
    let (lo, hi) = (x_c - a, x_c + a);
    let off = || PatchError::OffRail {
        lo_m: lo,
        hi_m: hi,
        first_m: px[0],
        last_m: px[n - 1],
    };
    if n < 2 || !(lo >= px[0] && hi <= px[n - 1]) {
        return Err(off());
    }
    // Elements e = [px[e], px[e+1]] overlapping [lo, hi].
    let e0 = px.partition_point(|&v| v <= lo).clamp(1, n - 1) - 1;
    let e1 = (px.partition_point(|&v| v < hi).clamp(1, n - 1) - 1).max(e0);
    let planes = e1 - e0 + 2;
    if planes > MAX_PLANES {
        return Err(PatchError::TooManyPlanes {
            length_m: 2.0 * a,
            planes,
            max: MAX_PLANES,
        });
    }
    let mut out = PlaneWeights {
        first: e0,
        len: planes,
        w: [0.0; MAX_PLANES],
    };
    if a <= 0.0 {
        let s = (x_c - px[e0]) / (px[e0 + 1] - px[e0]);
        out.w[0] = 1.0 - s;
        out.w[1] = s;
        return Ok(out);
    }
    let q = |x: f64| {
        let r = (x - x_c) / a;
        0.75 / a * (1.0 - r * r).max(0.0)
    };
    for e in e0..=e1 {
        let (xa, xb) = (px[e], px[e + 1]);
        let (l, r) = (xa.max(lo), xb.min(hi));
        if r <= l {
            continue;
        }
        let (mid, half) = (0.5 * (l + r), 0.5 * (r - l));
        for (g, gw) in GAUSS3 {
            let x = mid + half * g;
            let f = gw * half * q(x);
            let s = (x - xa) / (xb - xa);
            out.w[e - e0] += f * (1.0 - s);
            out.w[e - e0 + 1] += f * s;
        }
    }
    Ok(out)
}

/// The most planes any patch of half-length `a` (m) covers on `planes_x_m`.
pub fn max_planes(planes_x_m: &[f64], a: f64) -> usize {
    let px = planes_x_m;
    let mut most = 2;
    for i in 0..px.len() {
        let j = px.partition_point(|&v| v < px[i] + 2.0 * a);
        most = most.max(j - i + 2);
    }
    most.min(MAX_PLANES)
}

#[cfg(test)]
mod tests {
    use super::{max_planes, plane_weights, PatchError};
    use approx::assert_relative_eq;

    fn planes() -> Vec<f64> {
        // A graded line: 40 mm elements, then 10 mm ones.
        let mut p: Vec<f64> = (0..10).map(|i| 0.04 * i as f64).collect();
        p.extend((1..40).map(|i| 0.36 + 0.01 * i as f64));
        p
    }

    #[test]
    fn weights_are_a_partition_of_unity_and_reproduce_the_load_centroid() {
        // Σ w_j = 1 (resultant) and Σ w_j x_j = x_c (moment: linear shape functions
        // reproduce x, and the parabola is symmetric about x_c).
        let px = planes();
        for &a in &[0.0, 0.003, 0.007, 0.015, 0.05] {
            for k in 0..200 {
                let xc = 0.1 + 0.003_7 * k as f64;
                if xc + a > 0.74 {
                    break;
                }
                let w = plane_weights(&px, xc, a).unwrap();
                let sum: f64 = w.iter().map(|(_, w)| w).sum();
                let mom: f64 = w.iter().map(|(j, w)| w * px[j]).sum();
                assert_relative_eq!(sum, 1.0, epsilon = 1e-13);
                assert_relative_eq!(mom, xc, epsilon = 1e-13);
                assert!(w.iter().all(|(_, w)| w >= -1e-15));
            }
        }
    }

    #[test]
    fn a_patch_inside_one_element_gives_the_closed_form_weights() {
        // Within one element [0, h] the weights are ∫ (1 − x/h) q and ∫ (x/h) q:
        // 1 − x_c/h and x_c/h, whatever a (the parabola's centroid is x_c).
        let px = [0.0, 0.01, 0.02];
        let w = plane_weights(&px, 0.004, 0.002).unwrap();
        assert_eq!(w.first, 0);
        assert_relative_eq!(w.w[0], 0.6, epsilon = 1e-14);
        assert_relative_eq!(w.w[1], 0.4, epsilon = 1e-14);
        // Centred on a plane with a = h: the middle plane gets
        // ∫_{-h}^{h} (1 − |ξ|/h)·3/(4h)(1 − ξ²/h²) dξ = (3/2)∫_0^1 (1 − t)(1 − t²) dt = 5/8.
        let w = plane_weights(&px, 0.01, 0.01).unwrap();
        let mid: f64 = w.iter().filter(|&(j, _)| j == 1).map(|(_, w)| w).sum();
        assert_relative_eq!(mid, 0.625, epsilon = 1e-13);
    }

    #[test]
    fn a_patch_off_the_rail_or_over_too_many_planes_is_an_error() {
        let px = planes();
        assert!(matches!(
            plane_weights(&px, 0.001, 0.005),
            Err(PatchError::OffRail { .. })
        ));
        assert!(matches!(
            plane_weights(&px, 0.5, 0.2),
            Err(PatchError::TooManyPlanes { .. })
        ));
        assert!(max_planes(&px, 0.007) >= plane_weights(&px, 0.5, 0.007).unwrap().len);
    }
}

//! Hertz closed form for two quasi-identical elastic bodies with elliptic contact.
//!
//! Undeformed gap `h(x, y) = A x² + B y²` with `A = 1/(2 Rx)`, `B = 1/(2 Ry)` the relative
//! curvatures (`Rx` along the rolling direction, `Ry` lateral; for the wheel on the rail crown
//! `1/Rx = 1/R_wheel`, `1/Ry = 1/R_crown + 1/R_wheel,lateral`). With the eccentricity
//! `e² = 1 − (b/a)²` of the ellipse, `a` the semi-axis along the *smaller* curvature, and the
//! complete elliptic integrals `K(e)`, `E(e)` (Johnson 1985, eqs. 4.39; 4.41):
//!
//! ```text
//! A_major = p0 b /(E* e² a²) [K − E],    A_minor = p0 b /(E* e² a²) [(a/b)² E − K],
//! δ = p0 b K / E*,    P = (2/3) π a b p0,    E* = E / (2(1 − ν²)).
//! ```
//! The ratio of the two curvature equations fixes `e`; `a³ = 3 P (K − E) / (2π E* A_major e²)`.
//! Normal contact stiffness `k_N = dP/dδ = 3P/(2δ)` (P ∝ δ^{3/2}).
//!
//! [`lateral_weights`] shares a contact force among FE nodes across the rail (or tread) in
//! proportion to the Hertz pressure integrated against their shape functions; both
//! engines' load rows and the contact patch's global twin use it (theory §7.1, §6.9).

use super::{check_poisson, check_positive, combined_modulus, ContactError};
use std::f64::consts::PI;

/// Input of the Hertz closed form (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzInput {
    /// Relative radius of curvature along the rolling direction `Rx` (m); `f64::INFINITY` = flat.
    pub radius_x_m: f64,
    /// Relative radius of curvature across (lateral) `Ry` (m); `f64::INFINITY` = flat.
    pub radius_y_m: f64,
    /// Young's modulus of both bodies (Pa).
    pub youngs_pa: f64,
    /// Poisson's ratio of both bodies (−).
    pub poisson: f64,
    /// Normal load (N).
    pub load_n: f64,
}

impl HertzInput {
    /// Wheel (rolling radius `r_wheel`, lateral radius `r_wheel_lat`, `INFINITY` = flat)
    /// on a rail crown of lateral radius `r_crown` (all m).
    pub(crate) fn wheel_on_rail(
        r_wheel: f64,
        r_wheel_lat: f64,
        r_crown: f64,
        youngs_pa: f64,
        poisson: f64,
        load_n: f64,
    ) -> Self {
        HertzInput {
            radius_x_m: r_wheel,
            radius_y_m: 1.0 / (1.0 / r_crown + 1.0 / r_wheel_lat),
            youngs_pa,
            poisson,
            load_n,
        }
    }
}

/// Hertz solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzContact {
    /// Semi-axis along x (rolling direction) (m).
    pub a_m: f64,
    /// Semi-axis along y (lateral) (m).
    pub b_m: f64,
    /// Maximum pressure (Pa).
    pub p0_pa: f64,
    /// Approach of distant points (m).
    pub approach_m: f64,
    /// Normal contact stiffness dP/dδ (N/m).
    pub stiffness_n_per_m: f64,
}

/// Complete elliptic integrals `(K(k), E(k))` of modulus `k` (parameter m = k²), by the
/// arithmetic–geometric mean (Abramowitz & Stegun 17.6). Valid for `0 ≤ k < 1`.
pub(crate) fn elliptic_ke(k: f64) -> (f64, f64) {
    let mut a = 1.0_f64;
    let mut b = (1.0 - k * k).sqrt();
    let mut c = k;
    let mut sum = 0.5 * c * c;
    let mut pow2 = 0.5;
    for _ in 0..60 {
        if c.abs() < 1e-16 {
            break;
        }
        let an = 0.5 * (a + b);
        let bn = (a * b).sqrt();
        c = 0.5 * (a - b);
        a = an;
        b = bn;
        pow2 *= 2.0;
        sum += pow2 * c * c;
    }
    let kk = PI / (2.0 * a);
    (kk, kk * (1.0 - sum))
}

impl HertzContact {
    /// Solve the Hertz problem. Zero load gives a zero-size contact (not NaN).
    pub fn solve(inp: &HertzInput) -> Result<HertzContact, ContactError> {
        check_positive("youngs_pa", inp.youngs_pa)?;
        check_poisson(inp.poisson)?;
        if !(inp.load_n >= 0.0 && inp.load_n.is_finite()) {
            return Err(ContactError::InvalidParameter {
                name: "load_n",
                value: inp.load_n,
                reason: "must be finite and ≥ 0",
            });
        }
        for (name, r) in [
            ("radius_x_m", inp.radius_x_m),
            ("radius_y_m", inp.radius_y_m),
        ] {
            if r.is_nan() || r <= 0.0 {
                return Err(ContactError::InvalidParameter {
                    name,
                    value: r,
                    reason: "must be > 0 (INFINITY for flat)",
                });
            }
        }
        let ax = 0.5 / inp.radius_x_m;
        let by = 0.5 / inp.radius_y_m;
        if ax <= 0.0 && by <= 0.0 {
            return Err(ContactError::InvalidParameter {
                name: "radius_x_m",
                value: inp.radius_x_m,
                reason: "both bodies flat: no Hertz contact",
            });
        }
        if ax <= 0.0 || by <= 0.0 {
            return Err(ContactError::InvalidParameter {
                name: "radius_x_m",
                value: inp.radius_x_m,
                reason: "one relative curvature is zero (line contact): use a 2D model",
            });
        }
        let es = combined_modulus(inp.youngs_pa, inp.poisson);
        let p = inp.load_n;
        if p == 0.0 {
            return Ok(HertzContact {
                a_m: 0.0,
                b_m: 0.0,
                p0_pa: 0.0,
                approach_m: 0.0,
                stiffness_n_per_m: 0.0,
            });
        }
        // major axis along the smaller curvature
        let (amaj, amin) = if ax <= by { (ax, by) } else { (by, ax) };
        let ratio = amin / amaj;
        let (major, minor, kk) = if ratio - 1.0 < 1e-10 {
            // circular
            let r = 0.5 / amaj;
            let a = (3.0 * p * r / (4.0 * es)).cbrt();
            (a, a, PI / 2.0)
        } else {
            // f(k) = [(1/k²)E − K]/[K − E] − ratio, k = b/a ∈ (0,1), decreasing in k.
            let f = |kr: f64| {
                let e = (1.0 - kr * kr).sqrt();
                let (kk, ee) = elliptic_ke(e);
                (ee / (kr * kr) - kk) / (kk - ee) - ratio
            };
            let (mut lo, mut hi) = (1e-6_f64, 1.0 - 1e-12);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if f(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let kr = 0.5 * (lo + hi);
            let e2 = 1.0 - kr * kr;
            let (kk, ee) = elliptic_ke(e2.sqrt());
            let a = (3.0 * p * (kk - ee) / (2.0 * PI * es * amaj * e2)).cbrt();
            (a, kr * a, kk)
        };
        let p0 = 3.0 * p / (2.0 * PI * major * minor);
        let delta = p0 * minor * kk / es;
        let (a_m, b_m) = if ax <= by {
            (major, minor)
        } else {
            (minor, major)
        };
        Ok(HertzContact {
            a_m,
            b_m,
            p0_pa: p0,
            approach_m: delta,
            stiffness_n_per_m: 1.5 * p / delta,
        })
    }
}

/// Weights of nodes at lateral positions `s` (m, ascending) that interpolate the Hertz
/// pressure `∝ √(1 − s²/b²)` centred at `s = 0` with linear hat functions. Falls back to
/// linear interpolation of the point `s = 0` when fewer than two nodes lie within `b`.
/// The weights sum to 1.
pub fn lateral_weights(s: &[f64], b: f64) -> Vec<f64> {
    let n = s.len();
    let mut w = vec![0.0; n];
    if n == 0 {
        return w;
    }
    if n == 1 {
        w[0] = 1.0;
        return w;
    }
    let hat = |j: usize, x: f64| -> f64 {
        if j > 0 && x >= s[j - 1] && x <= s[j] {
            (x - s[j - 1]) / (s[j] - s[j - 1])
        } else if j + 1 < n && x >= s[j] && x <= s[j + 1] {
            (s[j + 1] - x) / (s[j + 1] - s[j])
        } else if (j == 0 && x < s[0]) || (j == n - 1 && x > s[n - 1]) {
            1.0
        } else {
            0.0
        }
    };
    let inside = s.iter().filter(|&&v| v.abs() < b).count();
    if b > 0.0 && inside >= 2 {
        // Midpoint rule over the ellipse: 400 intervals is far below the mesh's error.
        let k = 400;
        let mut total = 0.0;
        for q in 0..k {
            let x = -b + (q as f64 + 0.5) * 2.0 * b / k as f64;
            let p = (1.0 - (x / b).powi(2)).max(0.0).sqrt();
            total += p;
            for (j, wj) in w.iter_mut().enumerate() {
                *wj += p * hat(j, x);
            }
        }
        for wj in &mut w {
            *wj /= total;
        }
    } else {
        for (j, wj) in w.iter_mut().enumerate() {
            *wj = hat(j, 0.0);
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::{combined_modulus, elliptic_ke, lateral_weights, HertzContact, HertzInput, PI};
    #[test]
    fn elliptic_integrals_match_tables() {
        // A&S Table 17.1: K(m=0.5) = 1.854074677, E(m=0.5) = 1.350643881.
        let (k, e) = elliptic_ke(0.5_f64.sqrt());
        assert!((k - 1.854_074_677).abs() < 1e-8, "K = {k}");
        assert!((e - 1.350_643_881).abs() < 1e-8, "E = {e}");
        let (k0, e0) = elliptic_ke(0.0);
        assert!((k0 - PI / 2.0).abs() < 1e-14 && (e0 - PI / 2.0).abs() < 1e-14);
    }

    #[test]
    fn reference_wheel_on_r300_crown() {
        // docs/theory.md §6.2: a = 7.162 mm, b = 5.387 mm, p0 = 1237.6 MPa, approach 104.1 µm.
        let h = HertzContact::solve(&HertzInput::wheel_on_rail(
            0.46,
            f64::INFINITY,
            0.3,
            210e9,
            0.3,
            100e3,
        ))
        .unwrap();
        assert!((h.a_m * 1e3 - 7.162).abs() < 0.002, "a = {}", h.a_m);
        assert!((h.b_m * 1e3 - 5.387).abs() < 0.002, "b = {}", h.b_m);
        assert!((h.p0_pa / 1e6 - 1237.6).abs() < 0.2, "p0 = {}", h.p0_pa);
        assert!(
            (h.approach_m * 1e6 - 104.1).abs() < 0.1,
            "δ = {}",
            h.approach_m
        );
        assert!((h.stiffness_n_per_m - 1.5 * 100e3 / h.approach_m).abs() < 1.0);
    }

    #[test]
    fn sphere_on_flat_textbook() {
        // Johnson eq. 4.22–4.23: a = (3PR/4E*)^(1/3), δ = a²/R, p0 = 3P/(2πa²).
        let (r, e, nu, p) = (0.01, 210e9, 0.3, 1000.0);
        let es = combined_modulus(e, nu);
        let a = (3.0 * p * r / (4.0 * es)).cbrt();
        let h = HertzContact::solve(&HertzInput {
            radius_x_m: r,
            radius_y_m: r,
            youngs_pa: e,
            poisson: nu,
            load_n: p,
        })
        .unwrap();
        assert!((h.a_m / a - 1.0).abs() < 1e-12);
        assert!((h.approach_m / (a * a / r) - 1.0).abs() < 1e-12);
        assert!((h.p0_pa / (1.5 * p / (PI * a * a)) - 1.0).abs() < 1e-12);
        // nearly circular via the elliptic branch agrees with the circular formula
        let h2 = HertzContact::solve(&HertzInput {
            radius_y_m: r * (1.0 + 1e-6),
            ..HertzInput {
                radius_x_m: r,
                radius_y_m: r,
                youngs_pa: e,
                poisson: nu,
                load_n: p,
            }
        })
        .unwrap();
        assert!((h2.approach_m / h.approach_m - 1.0).abs() < 1e-5);
        assert!((h2.a_m / h.a_m - 1.0).abs() < 1e-5);
    }

    #[test]
    fn crossed_cylinders_equal_radius_equal_sphere() {
        // Johnson §4.2: crossed cylinders of equal radius R ≡ sphere of radius R on a flat.
        let r = 0.02;
        let c = HertzContact::solve(&HertzInput::wheel_on_rail(
            r,
            f64::INFINITY,
            r,
            200e9,
            0.28,
            500.0,
        ))
        .unwrap();
        let es = combined_modulus(200e9, 0.28);
        let a = (3.0 * 500.0 * r / (4.0 * es)).cbrt();
        assert!((c.a_m / a - 1.0).abs() < 1e-12 && (c.b_m / a - 1.0).abs() < 1e-12);
    }

    #[test]
    fn zero_load_and_bad_input() {
        let z = HertzContact::solve(&HertzInput::wheel_on_rail(
            0.46,
            f64::INFINITY,
            0.3,
            210e9,
            0.3,
            0.0,
        ))
        .unwrap();
        assert_eq!(z.a_m, 0.0);
        assert!(HertzContact::solve(&HertzInput::wheel_on_rail(
            0.46,
            f64::INFINITY,
            0.3,
            210e9,
            0.6,
            1.0
        ))
        .is_err());
    }

    #[test]
    fn lateral_weights_sum_to_one_and_are_symmetric() {
        let s: Vec<f64> = (-8..=8).map(|i| i as f64 * 0.0025).collect();
        let w = lateral_weights(&s, 0.0054);
        let total: f64 = w.iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        for i in 0..s.len() {
            assert!((w[i] - w[s.len() - 1 - i]).abs() < 1e-12);
        }
        // First moment of the weights = first moment of the pressure (0 by symmetry), second
        // moment of the elliptic pressure is b²/4; the hat interpolation adds h²/6·(share of
        // nodes) at most.
        let m2: f64 = w.iter().zip(&s).map(|(w, s)| w * s * s).sum();
        let b: f64 = 0.0054;
        assert!(m2 > b * b / 4.0 && m2 < b * b / 4.0 + 0.0025f64.powi(2) / 6.0 + 1e-12);
    }

    #[test]
    fn lateral_weights_fall_back_to_point_interpolation() {
        let s = [-0.03, 0.01, 0.05];
        let w = lateral_weights(&s, 0.005);
        assert!((w[0] - 0.25).abs() < 1e-12 && (w[1] - 0.75).abs() < 1e-12 && w[2] == 0.0);
    }
}

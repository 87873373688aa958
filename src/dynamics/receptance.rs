//! Receptance (dynamic compliance, m/N) of the reduced track and wheel at the contact point:
//! which structural resonances the moving contact can see, and at which frequencies the
//! frequency selection of a sweep may lock on (docs/theory.md §2.3 and §7.6).
//!
//! For a reduced system `q̈ + C_q q̇ + Ω² q = Φᵀ f` (module [`super::reduced`]) and
//! observation/load rows `r_a = Φᵀ e_a` (the modal rows of a weighted node set in direction
//! a, as the passage uses them), the steady harmonic response to a unit force `e^{iωt}` is
//!
//! ```text
//! H_ab(ω) = r_aᵀ (Ω² − ω² I + iω C_q)⁻¹ r_b        (m/N, complex)
//! ```
//!
//! with the **full** projected damping matrix (the discrete dampers are not proportional;
//! docs/theory.md §7.1). It is computed exactly by one complex LU factorisation of the m × m
//! dynamic stiffness per frequency (frequencies in parallel with rayon); no modal-damping
//! approximation. The truncated modes above f_max add their static compliance (the passage's
//! constant residual compliance, [`super::residual`]) to the diagonal terms.
//!
//! What the curves mean for corrugation: the contact force per unit rail-top roughness in
//! the normal direction is `1 / (H_nn^rail + H_nn^wheel + c_H)` (N/m) with the linearised
//! Hertz compliance `c_H = dδ/dN = 2δ/(3N)`; its maxima are the coupled wheel–track
//! resonances that amplify a roughness of that frequency. The longitudinal receptance
//! `H_xx^rail` is what turns a fluctuating creep force into a fluctuating rail surface
//! velocity (the creepage feedback of docs/theory.md §7.3).
//!
//! References: Ewins, *Modal Testing*, ch. 2 (receptance of non-proportionally damped
//! systems); Grassie, Gregory, Harrison & Johnson, "The dynamic response of railway track to
//! high frequency vertical excitation", J. Mech. Eng. Sci. 24 (1982) (rail and contact
//! receptances in wheel–rail interaction).

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use rayon::prelude::*;

use super::reduced::ModalSystem;
use super::DynamicsError;

/// `H_ab(ω)` for every pair of `rows` at every frequency: `out[k][(a, b)]` (m/N) at
/// `frequencies_hz[k]` (Hz). Each row has the system's m entries (a modal row `Φᵀ e_a`).
///
/// Errors: rows of the wrong length, a negative or non-finite frequency, or a frequency that
/// coincides with an undamped mode (singular dynamic stiffness: shift the grid).
pub(crate) fn modal_receptance(
    sys: &ModalSystem,
    rows: &[&[f64]],
    frequencies_hz: &[f64],
) -> Result<Vec<Mat<c64>>, DynamicsError> {
    let m = sys.len();
    let k = rows.len();
    if let Some(r) = rows.iter().find(|r| r.len() != m) {
        return Err(DynamicsError::SizeMismatch {
            what: "receptance: entries of a modal row vs modes of the system",
            found: r.len(),
            expected: m,
        });
    }
    if let Some(f) = frequencies_hz
        .iter()
        .find(|f| !(f.is_finite() && **f >= 0.0))
    {
        return Err(DynamicsError::Passage(
            crate::passage::PassageError::OutOfRange {
                name: "receptance frequency (Hz)",
                value: *f,
                expected: "finite and ≥ 0",
            },
        ));
    }
    let rhs = Mat::<c64>::from_fn(m, k, |i, j| c64::new(rows[j][i], 0.0));
    frequencies_hz
        .par_iter()
        .map(|&f| {
            let w = 2.0 * std::f64::consts::PI * f;
            // A mode exactly at ω with no damping of its own makes the dynamic stiffness
            // singular (also ω = 0 with a rigid-body mode).
            let scale = sys.omega2.iter().copied().fold(w * w, f64::max);
            if (0..m).any(|i| {
                (sys.omega2[i] - w * w).abs() <= 1e-12 * scale
                    && w * sys.damping[(i, i)] <= 1e-12 * scale
            }) {
                return Err(DynamicsError::SingularReceptance { frequency_hz: f });
            }
            let d = Mat::<c64>::from_fn(m, m, |i, j| {
                let re = if i == j { sys.omega2[i] - w * w } else { 0.0 };
                c64::new(re, w * sys.damping[(i, j)])
            });
            let z = d.partial_piv_lu().solve(&rhs);
            let h = Mat::<c64>::from_fn(k, k, |a, b| {
                let mut s = c64::new(0.0, 0.0);
                for i in 0..m {
                    s += z[(i, b)] * rows[a][i];
                }
                s
            });
            let finite = (0..k)
                .all(|a| (0..k).all(|b| h[(a, b)].re.is_finite() && h[(a, b)].im.is_finite()));
            if finite {
                Ok(h)
            } else {
                Err(DynamicsError::SingularReceptance { frequency_hz: f })
            }
        })
        .collect()
}

/// The receptances of the reduced model at the contact (directions x, t, n of the contact
/// frame, see [`super::reduced::ContactFrame`]).
#[derive(Clone, Debug)]
pub struct ContactReceptance {
    /// Frequencies (Hz).
    pub frequencies_hz: Vec<f64>,
    /// Positions along the rail of the rail receptances (m).
    pub positions_m: Vec<f64>,
    /// Rail receptance per position and frequency: `rail[p][k]` is the 3 × 3 matrix (x, t, n)
    /// (m/N), the constant residual compliance of the truncated modes included on the
    /// diagonal.
    pub rail: Vec<Vec<[[c64; 3]; 3]>>,
    /// Wheel receptance at its contact point per frequency, 3 × 3 (x, t, n) (m/N).
    pub wheel: Vec<[[c64; 3]; 3]>,
    /// Linearised Hertz normal compliance `dδ/dN` at the static wheel load (m/N).
    pub hertz_compliance_m_per_n: f64,
}

impl ContactReceptance {
    /// `|H|` of one rail direction (0 = x, 1 = t, 2 = n) at position `p` (m/N).
    pub fn rail_abs(&self, p: usize, dir: usize) -> Vec<f64> {
        self.rail[p].iter().map(|h| h[dir][dir].norm()).collect()
    }

    /// `|H|` of one wheel direction (m/N).
    pub fn wheel_abs(&self, dir: usize) -> Vec<f64> {
        self.wheel.iter().map(|h| h[dir][dir].norm()).collect()
    }

    /// Normal contact force per unit rail-top roughness at position `p`:
    /// `|1 / (H_nn^rail + H_nn^wheel + c_H)|` (N/m).
    pub fn normal_force_per_roughness(&self, p: usize) -> Vec<f64> {
        self.rail[p]
            .iter()
            .zip(&self.wheel)
            .map(|(r, w)| {
                let s = r[2][2] + w[2][2] + c64::new(self.hertz_compliance_m_per_n, 0.0);
                1.0 / s.norm()
            })
            .collect()
    }
}

/// Local maxima of `y` over the grid `x`, refined by a parabola through the three points
/// around each, sorted by height (highest first), at most `max` of them: `(x, y)`.
pub fn peaks(x: &[f64], y: &[f64], max: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for i in 1..y.len().saturating_sub(1) {
        if y[i] > y[i - 1] && y[i] >= y[i + 1] {
            let (a, b, c) = (y[i - 1], y[i], y[i + 1]);
            let den = a - 2.0 * b + c;
            let d = if den < 0.0 {
                (0.5 * (a - c) / den).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            let h = x[i + 1] - x[i];
            out.push((x[i] + d * h, b - 0.25 * (a - c) * d));
        }
    }
    out.sort_by(|a, b| b.1.total_cmp(&a.1));
    out.truncate(max);
    out
}

#[cfg(test)]
mod tests {
    use super::{c64, modal_receptance, peaks, Mat, ModalSystem};
    use faer::linalg::solvers::Solve;
    use faer::sparse::{SparseColMat, Triplet};

    /// A single damped oscillator: `H = 1/(ω_n² − ω² + iωc)` per unit modal mass (closed form).
    #[test]
    fn single_mode_is_the_closed_form() {
        let wn = 2.0 * std::f64::consts::PI * 100.0;
        let c = 30.0;
        let sys = ModalSystem {
            omega2: vec![wn * wn],
            damping: Mat::from_fn(1, 1, |_, _| c),
        };
        let r = [0.7];
        let f = [0.0, 50.0, 100.0, 180.0];
        let h = modal_receptance(&sys, &[&r], &f).unwrap();
        for (k, &fk) in f.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * fk;
            let exact = c64::new(0.49, 0.0) / c64::new(wn * wn - w * w, w * c);
            let got = h[k][(0, 0)];
            assert!(
                (got - exact).norm() <= 1e-12 * exact.norm(),
                "{fk} Hz: {got} vs {exact}"
            );
        }
    }

    /// With *all* modes kept, the modal receptance with the full projected damping equals the
    /// direct solution of `(K − ω²M + iωC) u = e_b` on the physical matrices (an independent
    /// dense complex solve), to round-off, for a non-proportionally damped chain with a
    /// concentrated and a distributed damper; a modal-damping (diagonal) approximation does not.
    #[test]
    fn all_modes_equal_the_direct_frequency_domain_solve() {
        let n = 24;
        // Spring chain fixed at one end, masses varying, two dampers.
        let kv = |i: usize| 1.0e6 * (1.0 + 0.3 * (i as f64 * 0.7).sin());
        let mut k = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            k[(i, i)] += kv(i);
            if i + 1 < n {
                let s = kv(i + 1);
                k[(i, i)] += s;
                k[(i + 1, i + 1)] += s;
                k[(i, i + 1)] -= s;
                k[(i + 1, i)] -= s;
            }
        }
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * ((i * 3) % 5) as f64).collect();
        let mut trip = vec![Triplet::new(3usize, 3usize, 400.0)];
        for (a, b, c) in [(10usize, 11usize, 250.0), (17, 18, 90.0)] {
            trip.extend([
                Triplet::new(a, a, c),
                Triplet::new(b, b, c),
                Triplet::new(a, b, -c),
                Triplet::new(b, a, -c),
            ]);
        }
        let cs = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).unwrap();
        // Mass-normalised modes: eigen of M^{-1/2} K M^{-1/2}.
        let s = Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)] / (mass[i] * mass[j]).sqrt());
        let eig = s.self_adjoint_eigen(faer::Side::Lower).unwrap();
        let lam = eig.S().column_vector();
        let freqs: Vec<f64> = (0..n)
            .map(|i| lam[i].sqrt() / (2.0 * std::f64::consts::PI))
            .collect();
        let phi = Mat::<f64>::from_fn(n, n, |i, j| eig.U()[(i, j)] / mass[i].sqrt());
        let sys = ModalSystem::new(&freqs, &phi, cs.as_ref(), 0.0).unwrap();
        assert!(
            sys.damping_coupling() > 0.1,
            "the test needs non-proportional damping"
        );
        let dofs = [5usize, 17];
        let rows: Vec<Vec<f64>> = dofs
            .iter()
            .map(|&d| (0..n).map(|j| phi[(d, j)]).collect())
            .collect();
        let rr: Vec<&[f64]> = rows.iter().map(|r| r.as_slice()).collect();
        let fgrid = [3.0, 41.0, freqs[4], 0.5 * (freqs[9] + freqs[10]), 230.0];
        let h = modal_receptance(&sys, &rr, &fgrid).unwrap();
        let cd = cs.to_dense();
        let mut diag_err: f64 = 0.0;
        for (kf, &f) in fgrid.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let d = Mat::<c64>::from_fn(n, n, |i, j| {
                let m_ij = if i == j { mass[i] } else { 0.0 };
                c64::new(k[(i, j)] - w * w * m_ij, w * cd[(i, j)])
            });
            let e = Mat::<c64>::from_fn(n, 2, |i, b| {
                c64::new(if i == dofs[b] { 1.0 } else { 0.0 }, 0.0)
            });
            let u = d.partial_piv_lu().solve(&e);
            for a in 0..2 {
                for b in 0..2 {
                    let exact = u[(dofs[a], b)];
                    let got = h[kf][(a, b)];
                    assert!(
                        (got - exact).norm() <= 1e-9 * exact.norm(),
                        "{f} Hz ({a},{b}): {got} vs {exact}"
                    );
                }
            }
            // Modal (diagonal) damping instead of the full matrix.
            let mut s = c64::new(0.0, 0.0);
            for i in 0..n {
                s += c64::new(rows[0][i] * rows[0][i], 0.0)
                    / c64::new(sys.omega2[i] - w * w, w * sys.damping[(i, i)]);
            }
            diag_err = diag_err.max((s - u[(dofs[0], 0)]).norm() / u[(dofs[0], 0)].norm());
        }
        assert!(
            diag_err > 1e-3,
            "diagonal damping should differ here ({diag_err})"
        );
    }

    /// `add_modal_damping(ζ)` gives each elastic mode the resonance peak of a damped
    /// oscillator, `|H(ω_n)| = r² / (2 ζ ω_n²)` (closed form), and leaves rigid modes alone.
    #[test]
    fn modal_damping_ratio_gives_the_closed_form_peak() {
        let wn = 2.0 * std::f64::consts::PI * 1060.0;
        let mut sys = ModalSystem {
            omega2: vec![0.0, wn * wn],
            damping: Mat::zeros(2, 2),
        };
        sys.add_modal_damping(1e-3);
        assert_eq!(sys.damping[(0, 0)], 0.0);
        let r = [0.0, 0.025];
        let h = modal_receptance(&sys, &[&r], &[1060.0]).unwrap();
        let exact = 0.025f64.powi(2) / (2.0 * 1e-3 * wn * wn);
        let got = h[0][(0, 0)];
        assert!(
            (got.norm() - exact).abs() <= 1e-12 * exact,
            "{got} vs {exact}"
        );
        assert!(
            (got.arg() + std::f64::consts::FRAC_PI_2).abs() < 1e-12,
            "phase −90°"
        );
    }

    #[test]
    fn peaks_are_refined_to_the_parabola_vertex() {
        let x: Vec<f64> = (0..101).map(|i| i as f64 * 10.0).collect();
        // Two Lorentzian peaks at 333 Hz (higher) and 712 Hz.
        let y: Vec<f64> = x
            .iter()
            .map(|&f| {
                2.0 / (1.0 + ((f - 333.0) / 40.0).powi(2))
                    + 1.0 / (1.0 + ((f - 712.0) / 40.0).powi(2))
            })
            .collect();
        let p = peaks(&x, &y, 5);
        assert_eq!(p.len(), 2);
        assert!((p[0].0 - 333.0).abs() < 1.0, "{:?}", p);
        assert!((p[1].0 - 712.0).abs() < 1.5, "{:?}", p);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let sys = ModalSystem {
            omega2: vec![1.0, 4.0],
            damping: Mat::zeros(2, 2),
        };
        assert!(modal_receptance(&sys, &[&[1.0]], &[1.0]).is_err());
        assert!(modal_receptance(&sys, &[&[1.0, 0.0]], &[f64::NAN]).is_err());
        // Exactly at an undamped mode (ω = 1 rad/s).
        let f = 1.0 / (2.0 * std::f64::consts::PI);
        let r = modal_receptance(&sys, &[&[1.0, 0.0]], &[f]);
        assert!(r.is_err(), "{r:?}");
    }
}

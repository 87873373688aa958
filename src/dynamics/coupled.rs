//! Coupled wheel–track modes (docs/theory.md §7.10): the eigenmodes of the reduced track and
//! wheel joined at the contact by the contact linearised at the static state.
//!
//! # The linearised contact
//! At a frozen contact position `x` the rail's contact rows `r_d = Φ_tᵀ b_d(x)` and the
//! wheel's `w_d` (directions d = x, t, n of the contact frame, [`super::reduced`]) give the
//! relative motion `g_dᵀ q` with `g_d = [−r_d; w_d]` over `q = [q_track; q_wheel]`. The
//! contact force on the wheel, linearised about the static rolling state, is
//!
//! - normal: `F_n = k_n δ`, `δ = −g_nᵀ q` the approach, `k_n` the slope of the normal force
//!   against the approach (half-space contact with the series compliance of the residual
//!   flexibility, §7.7), which adds `k_n g_n g_nᵀ` to the stiffness;
//! - tangential (x and t): a creep force `F_d = −κ_d ξ_d`, `ξ_d = g_dᵀ q̇ / V` (κ_d the
//!   creep coefficient, N per unit creepage, at the static traction: partial slip included)
//!   that builds up over the relaxation length `L_d` of the transient rolling contact: a
//!   Maxwell element of damping `c_d = κ_d / V` (N·s/m) in series with the stiffness
//!   `k_d = κ_d / L_d` (N/m), `Ḟ_d = −k_d g_dᵀ q̇ − (V / L_d) F_d`. With `L_d = 0` it is the
//!   damper `c_d g_d g_dᵀ`.
//!
//! κ_d, L_d and k_n are measured on the passage's own contact solver (same grid, friction,
//! traction and series compliance) by small perturbations of the static state
//! (`PassageEngine::linearise_contact`); L_d is the mean delay of the force's step
//! response times V (the first moment, exact for a first-order lag).
//!
//! # The eigenproblem
//! With the state `z = [q; q̇; F_x; F_t]`
//!
//! ```text
//! q̇ = v
//! v̇ = −(Ω² + k_n g_n g_nᵀ) q − C_q v + g_x F_x + g_t F_t
//! Ḟ_d = −k_d g_dᵀ v − (V / L_d) F_d
//! ```
//!
//! (`C_q` block-diagonal: the track's full `Φᵀ C Φ`, the wheel's with its modal damping) is
//! solved as a dense real eigenproblem. Each complex pair `λ = −ζω₀ ± iω₀√(1−ζ²)` is one
//! coupled mode: frequency `Im λ / 2π`, damping ratio `ζ = −Re λ / |λ|`.
//!
//! # Energy shares
//! For the mode's eigenvector each modal coordinate holds `e_i = |v_i|² + ω_i² |q_i|²`
//! (twice its mean kinetic plus strain energy), the normal contact spring `k_n |δ|²`, the
//! tangential springs `|F_d|² / k_d`. A track coordinate's share is split into the rail
//! (its strain-energy share of rail elements, filed under the family of the rail's motion)
//! and the support (sleepers, fastenings, ballast); a wheel coordinate is rigid (ω = 0, incl.
//! the sprung mass) or elastic. The split neglects the cross terms of the non-diagonal
//! damping (energy is not exactly additive over coordinates of a non-proportionally damped
//! mode); the shares say where the mode lives, they are not a power balance.
//!
//! References: Knothe & Grassie, Vehicle Syst. Dyn. 22 (1993) 209–262 (coupled
//! wheel–track dynamics, linearised contact); Gross-Thebing (1989) and Knothe & Gross-Thebing,
//! Vehicle Syst. Dyn. 15 (1986) 133–153 (creep force lag over the contact length); Tisseur &
//! Meerbergen, SIAM Rev. 43 (2001) 235–286 (state-space form of damped eigenproblems).

use faer::{c64, Mat};
use serde::{Deserialize, Serialize};

use super::reduced::ModalSystem;
use super::DynamicsError;
use super::{passage::PassageEngine, prepared::PreparedModel, setup::steady_contact};
use crate::contact::{Longitudinal, NormalInput, StepInputs, TransientRolling};
use crate::eigen::classify::{TrackFamily, TrackModeClass};

/// The contact linearised at the static rolling state (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactLinearisation {
    /// Slope of the normal force against the approach, `k_n` (N/m, > 0).
    pub normal_stiffness_n_per_m: f64,
    /// Creep coefficients `κ = −dF/dξ` in x and t (N per unit creepage, ≥ 0).
    pub creep_coefficient_n: [f64; 2],
    /// Relaxation lengths of the creep force in x and t (m, ≥ 0; 0 = no lag).
    pub relaxation_length_m: [f64; 2],
    /// Rolling speed (m/s, > 0).
    pub speed_m_per_s: f64,
}

impl ContactLinearisation {
    /// No contact at all (every coupling zero): the substructures are uncoupled.
    pub fn uncoupled(speed_m_per_s: f64) -> Self {
        Self {
            normal_stiffness_n_per_m: 0.0,
            creep_coefficient_n: [0.0; 2],
            relaxation_length_m: [0.0; 2],
            speed_m_per_s,
        }
    }

    /// Creep damping `κ_d / V` (N·s/m) of direction `d` (0 = x, 1 = t).
    pub(crate) fn creep_damping_ns_per_m(&self, d: usize) -> f64 {
        self.creep_coefficient_n[d] / self.speed_m_per_s
    }

    /// Tangential stiffness `κ_d / L_d` (N/m) of direction `d`, `None` without lag.
    pub(crate) fn tangential_stiffness_n_per_m(&self, d: usize) -> Option<f64> {
        let l = self.relaxation_length_m[d];
        (l > 0.0 && self.creep_coefficient_n[d] > 0.0).then_some(self.creep_coefficient_n[d] / l)
    }

    fn check(&self) -> Result<(), DynamicsError> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !(ok(self.normal_stiffness_n_per_m)
            && self.creep_coefficient_n.iter().all(|&v| ok(v))
            && self.relaxation_length_m.iter().all(|&v| ok(v))
            && self.speed_m_per_s.is_finite()
            && self.speed_m_per_s > 0.0)
        {
            return Err(DynamicsError::ContactLinearisation {
                reason: "it needs finite stiffness, creep coefficients and relaxation lengths ≥ 0 and a speed > 0",
            });
        }
        Ok(())
    }
}

/// The two reduced substructures and their contact rows at one contact position.
#[derive(Clone, Copy, Debug)]
pub struct CoupledSystem<'a> {
    /// The track's modal system (m_t modes).
    pub track: &'a ModalSystem,
    /// The wheel's modal system (m_w modes, rigid modes with ω = 0).
    pub wheel: &'a ModalSystem,
    /// The rail's contact rows, `3·m_t` values (x, t, n blocks).
    pub rail_rows: &'a [f64],
    /// The wheel's contact rows, `3·m_w` values (x, t, n blocks).
    pub wheel_rows: &'a [f64],
}

/// One eigenpair of the state-space problem (oscillatory, `Im λ > 0`).
#[derive(Clone, Debug)]
pub(crate) struct StateMode {
    /// Eigenvalue λ (1/s).
    pub lambda: c64,
    /// Modal displacements `q = [q_track; q_wheel]` of the eigenvector.
    pub q: Vec<c64>,
    /// The tangential contact forces `[F_x, F_t]` of the eigenvector (zero without lag).
    pub forces: [c64; 2],
}

/// Energy shares of a coupled mode (−, summing to 1).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct ModeShares {
    /// The wheel's elastic modes.
    pub wheel_elastic: f64,
    /// The wheel's rigid-body motion and the sprung mass on the primary suspension.
    pub wheel_rigid: f64,
    /// The rail, by the family of the rail's motion in each track mode, in the order of
    /// [`TrackFamily::ALL`].
    pub rail: [f64; 8],
    /// Sleepers, fastenings and ballast.
    pub support: f64,
    /// The contact springs (normal Hertz, tangential).
    pub contact: f64,
}

impl ModeShares {
    /// The labels of [`Self::values`], e.g. `rail_longitudinal_compression`.
    pub fn labels() -> Vec<String> {
        let mut l = vec!["wheel_elastic".to_string(), "wheel_rigid".to_string()];
        l.extend(
            TrackFamily::ALL
                .iter()
                .map(|f| format!("rail_{}", f.name())),
        );
        l.extend(["support".to_string(), "contact".to_string()]);
        l
    }

    /// The shares in the order of [`Self::labels`].
    pub fn values(&self) -> Vec<f64> {
        let mut v = vec![self.wheel_elastic, self.wheel_rigid];
        v.extend(self.rail);
        v.extend([self.support, self.contact]);
        v
    }

    /// The rail's total share.
    pub fn rail_total(&self) -> f64 {
        self.rail.iter().sum()
    }

    /// The wheel's total share (elastic and rigid).
    pub fn wheel_total(&self) -> f64 {
        self.wheel_elastic + self.wheel_rigid
    }

    /// The attribution's name of a mode (docs/theory.md §7.10): the part of the system that
    /// holds the largest share of its energy, the wheel's elastic and rigid parts taken
    /// together — `wheel`, `rail LC`, `rail LS`, `rail VB`, `rail LB`, `rail torsion`,
    /// `rail sleeper`, `rail local`, `rail other`, `support` or `contact` — and that share.
    /// Every output that names a mode (tables, maps, texts, the verdict) uses this.
    pub fn dominant(&self) -> (String, f64) {
        let (i, v) = self.dominant_part();
        let name = match i {
            0 => "wheel".to_string(),
            10 => "support".to_string(),
            11 => "contact".to_string(),
            k => format!("rail {}", short_family(TrackFamily::ALL[k - 2])),
        };
        (name, v)
    }

    /// The part of [`Self::dominant`] as the index of its column in [`Self::labels`], 0
    /// (`wheel_elastic`) standing for the wheel's two parts together.
    pub fn dominant_index(&self) -> usize {
        self.dominant_part().0
    }

    /// `(column, share)` of the largest part, the wheel's two parts together in column 0;
    /// the first of equal shares.
    fn dominant_part(&self) -> (usize, f64) {
        let mut best = (0, self.wheel_total());
        for (k, &v) in self.rail.iter().enumerate() {
            if v > best.1 {
                best = (2 + k, v);
            }
        }
        for (i, v) in [(10, self.support), (11, self.contact)] {
            if v > best.1 {
                best = (i, v);
            }
        }
        best
    }
}

/// Short name of a track family on plots: `LC`, `LS`, `VB`, `LB`, or the family's name.
fn short_family(f: TrackFamily) -> &'static str {
    match f {
        TrackFamily::LongitudinalCompression => "LC",
        TrackFamily::LongitudinalShear => "LS",
        TrackFamily::VerticalBending => "VB",
        TrackFamily::LateralBending => "LB",
        other => other.name(),
    }
}

/// One coupled wheel–track mode as the outputs report it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoupledMode {
    /// Contact position along the rail the contact was frozen at (m).
    pub position_m: f64,
    /// Damped natural frequency `Im λ / 2π` (Hz).
    pub frequency_hz: f64,
    /// Damping ratio `−Re λ / |λ|` (−).
    pub damping_ratio: f64,
    /// Energy shares.
    pub shares: ModeShares,
    /// Its name by the attribution rule ([`ModeShares::dominant`]), e.g. `wheel`, `rail LC`.
    pub dominant: String,
    /// Amplitudes at the contact per square root of the mode's energy measure (m/√J, with
    /// `Σ e = 1 J`): rail x, rail n, wheel x, wheel n.
    pub contact_amplitudes_m_per_sqrt_j: [f64; 4],
    /// The rail's longitudinal motion at the contact relative to its normal motion,
    /// `|u_rail,x| / |u_rail,n|` (−).
    pub rail_x_to_n: f64,
}

impl CoupledMode {
    /// Largest contact amplitude per √energy (m/√J): rail or wheel, x or n.
    pub(crate) fn visibility(&self) -> f64 {
        self.contact_amplitudes_m_per_sqrt_j
            .iter()
            .fold(0.0f64, |a, &b| a.max(b))
    }

    /// The mode's weight in the receptance at the contact, `φ_c² = 2 ω² a²` (1/kg), with
    /// `a` the [`Self::visibility`] and `ω = 2πf`: a mode normalised to unit modal mass has
    /// the energy measure `|λ|² + ω² ≈ 2ω²` per unit coordinate, so its contact displacement
    /// per unit coordinate is `φ_c = √2 ω a`, and `φ_c²` is its residue in the receptance
    /// `Σ φ_c² / (ω_r² − ω²)` at the contact (the largest of rail and wheel, x and n).
    pub(crate) fn contact_residue_per_kg(&self) -> f64 {
        let w = 2.0 * std::f64::consts::PI * self.frequency_hz;
        2.0 * (w * self.visibility()).powi(2)
    }
}

/// Share of the largest contact residue ([`CoupledMode::contact_residue_per_kg`]) at or
/// above which the contact "sees" a coupled mode (−): such a mode adds at least 3 % of the
/// strongest mode's peak to the receptance at the contact for the same damping, and is drawn
/// on the sweep maps. The same share as the wheel lines' contact participation
/// (`studies::grow::WHEEL_LINE_SHARE`).
pub(crate) const SEEN_SHARE: f64 = 0.03;

/// Most lines of coupled modes drawn on one sweep map: the strongest by contact residue.
pub(crate) const MAX_SEEN_LINES: usize = 16;

/// The coupled modes the contact sees (contact residue at least `SEEN_SHARE` of the
/// largest among `modes`) with a frequency in `band_hz` (Hz), at most `MAX_SEEN_LINES`
/// (the strongest), ascending in frequency. Modes within 0.5 % of each other in frequency
/// (the same mode at two contact positions, or a sine–cosine pair of the wheel) are one:
/// the one with the larger residue.
pub fn seen_by_contact(modes: &[CoupledMode], band_hz: [f64; 2]) -> Vec<CoupledMode> {
    let top = modes
        .iter()
        .map(CoupledMode::contact_residue_per_kg)
        .fold(0.0, f64::max);
    let mut seen: Vec<&CoupledMode> = modes
        .iter()
        .filter(|m| {
            (band_hz[0]..=band_hz[1]).contains(&m.frequency_hz)
                && top > 0.0
                && m.contact_residue_per_kg() >= SEEN_SHARE * top
        })
        .collect();
    seen.sort_by(|a, b| {
        b.contact_residue_per_kg()
            .total_cmp(&a.contact_residue_per_kg())
    });
    let mut out: Vec<CoupledMode> = Vec::new();
    for m in seen {
        let dup = out
            .iter()
            .any(|o| (o.frequency_hz - m.frequency_hz).abs() <= 0.005 * m.frequency_hz);
        if !dup && out.len() < MAX_SEEN_LINES {
            out.push(m.clone());
        }
    }
    out.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    out
}

/// Labels of the substructures' coordinates: what each track mode's energy counts as.
#[derive(Clone, Debug)]
pub struct CoordinateLabels {
    /// Per track mode: the rail's strain-energy share (0–1) and the family of the rail's
    /// motion.
    pub track: Vec<(f64, TrackFamily)>,
}

impl CoordinateLabels {
    /// From the track modes' classes (the rail share of the strain energy; the family of the
    /// rail's own motion, which differs from the mode's family for sleeper modes).
    pub(crate) fn from_classes(classes: &[TrackModeClass]) -> Self {
        Self {
            track: classes
                .iter()
                .map(|c| (c.energy.rail, c.rail_family.unwrap_or(c.family)))
                .collect(),
        }
    }
}

/// The state matrix `A` of `ż = A z` (see the module doc).
fn state_matrix(sys: &CoupledSystem<'_>, lin: &ContactLinearisation) -> Mat<f64> {
    let (mt, mw) = (sys.track.len(), sys.wheel.len());
    let m = mt + mw;
    let lag: Vec<usize> = (0..2)
        .filter(|&d| lin.tangential_stiffness_n_per_m(d).is_some())
        .collect();
    let n = 2 * m + lag.len();
    let g = |d: usize| -> Vec<f64> {
        let mut v = vec![0.0; m];
        for i in 0..mt {
            v[i] = -sys.rail_rows[d * mt + i];
        }
        for i in 0..mw {
            v[mt + i] = sys.wheel_rows[d * mw + i];
        }
        v
    };
    let mut a = Mat::<f64>::zeros(n, n);
    for i in 0..m {
        a[(i, m + i)] = 1.0;
    }
    for i in 0..mt {
        a[(m + i, i)] = -sys.track.omega2[i];
        for j in 0..mt {
            a[(m + i, m + j)] = -sys.track.damping[(i, j)];
        }
    }
    for i in 0..mw {
        a[(m + mt + i, mt + i)] = -sys.wheel.omega2[i];
        for j in 0..mw {
            a[(m + mt + i, m + mt + j)] = -sys.wheel.damping[(i, j)];
        }
    }
    let gn = g(2);
    let kn = lin.normal_stiffness_n_per_m;
    for i in 0..m {
        for j in 0..m {
            a[(m + i, j)] -= kn * gn[i] * gn[j];
        }
    }
    for d in 0..2 {
        let gd = g(d);
        match lag.iter().position(|&l| l == d) {
            None => {
                let c = lin.creep_damping_ns_per_m(d);
                for i in 0..m {
                    for j in 0..m {
                        a[(m + i, m + j)] -= c * gd[i] * gd[j];
                    }
                }
            }
            Some(s) => {
                let k = lin.tangential_stiffness_n_per_m(d).unwrap_or(0.0);
                let row = 2 * m + s;
                for i in 0..m {
                    a[(m + i, row)] = gd[i];
                    a[(row, m + i)] = -k * gd[i];
                }
                a[(row, row)] = -lin.speed_m_per_s / lin.relaxation_length_m[d];
            }
        }
    }
    a
}

/// Parallelism of the dense eigen-solve of the state matrix: faer splits its work into this
/// many parts whatever the size of the rayon pool it runs on, so the eigenpairs are the same
/// bits on one thread as on two or more (faer's default, the pool's thread count, splits
/// the work by the thread count and so rounds differently).
const EIGEN_PARTS: usize = 2;

/// The eigenvalues and right eigenvectors (columns) of the real matrix `a`, complex pairs
/// as conjugate columns (as faer's `Mat::eigen`), computed with [`EIGEN_PARTS`] parts.
fn real_eigen(a: &Mat<f64>) -> Result<(Vec<c64>, Mat<c64>), DynamicsError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd;
    let n = a.nrows();
    let par = faer::Par::rayon(EIGEN_PARTS);
    let mut u_real = Mat::<f64>::zeros(n, n);
    let mut s_re = faer::diag::Diag::<f64>::zeros(n);
    let mut s_im = faer::diag::Diag::<f64>::zeros(n);
    let scratch = evd::evd_scratch::<f64>(
        n,
        evd::ComputeEigenvectors::No,
        evd::ComputeEigenvectors::Yes,
        par,
        Default::default(),
    );
    evd::evd_real(
        a.as_ref(),
        s_re.as_mut(),
        s_im.as_mut(),
        None,
        Some(u_real.as_mut()),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|error| DynamicsError::CoupledEigen { error })?;
    let mut s = vec![c64::new(0.0, 0.0); n];
    let mut u = Mat::<c64>::zeros(n, n);
    let mut j = 0;
    while j < n {
        let (re, im) = (s_re[j], s_im[j]);
        if im == 0.0 || j + 1 == n {
            s[j] = c64::new(re, 0.0);
            for i in 0..n {
                u[(i, j)] = c64::new(u_real[(i, j)], 0.0);
            }
            j += 1;
        } else {
            s[j] = c64::new(re, im);
            s[j + 1] = c64::new(re, -im);
            for i in 0..n {
                u[(i, j)] = c64::new(u_real[(i, j)], u_real[(i, j + 1)]);
                u[(i, j + 1)] = c64::new(u_real[(i, j)], -u_real[(i, j + 1)]);
            }
            j += 2;
        }
    }
    Ok((s, u))
}

/// The oscillatory eigenpairs of the coupled system with a damped frequency above
/// [`super::passage::RIGID_HZ`] (`Im λ > 0`; the wheel's rigid-body motion on the contact
/// gives eigenvalues at or near zero), ascending in frequency. Overdamped (real) eigenvalues
/// are dropped.
pub(crate) fn coupled_state_modes(
    sys: &CoupledSystem<'_>,
    lin: &ContactLinearisation,
) -> Result<Vec<StateMode>, DynamicsError> {
    lin.check()?;
    let (mt, mw) = (sys.track.len(), sys.wheel.len());
    if sys.rail_rows.len() != 3 * mt || sys.wheel_rows.len() != 3 * mw {
        return Err(DynamicsError::SizeMismatch {
            what: "coupled modes: contact rows of the track and the wheel (3 per mode)",
            found: sys.rail_rows.len() + sys.wheel_rows.len(),
            expected: 3 * (mt + mw),
        });
    }
    let m = mt + mw;
    let a = state_matrix(sys, lin);
    let (s, u) = real_eigen(&a)?;
    let lag: Vec<usize> = (0..2)
        .filter(|&d| lin.tangential_stiffness_n_per_m(d).is_some())
        .collect();
    let mut out: Vec<StateMode> = (0..a.nrows())
        .filter(|&k| s[k].im > 2.0 * std::f64::consts::PI * super::passage::RIGID_HZ)
        .map(|k| {
            let mut forces = [c64::new(0.0, 0.0); 2];
            for (p, &d) in lag.iter().enumerate() {
                forces[d] = u[(2 * m + p, k)];
            }
            StateMode {
                lambda: s[k],
                q: (0..m).map(|i| u[(i, k)]).collect(),
                forces,
            }
        })
        .collect();
    out.sort_by(|a, b| a.lambda.im.total_cmp(&b.lambda.im));
    Ok(out)
}

/// Describes a state mode: frequency, damping, energy shares, contact amplitudes.
pub(crate) fn describe_mode(
    sys: &CoupledSystem<'_>,
    lin: &ContactLinearisation,
    labels: &CoordinateLabels,
    mode: &StateMode,
    position_m: f64,
) -> CoupledMode {
    let (mt, mw) = (sys.track.len(), sys.wheel.len());
    let lam = mode.lambda;
    let w2 = lam.norm_sqr();
    let mut shares = ModeShares::default();
    for i in 0..mt {
        let q2 = mode.q[i].norm_sqr();
        let e = q2 * (w2 + sys.track.omega2[i]);
        let (rail, fam) = labels
            .track
            .get(i)
            .copied()
            .unwrap_or((1.0, TrackFamily::Other));
        shares.rail[fam.code()] += rail * e;
        shares.support += (1.0 - rail) * e;
    }
    for i in 0..mw {
        let q2 = mode.q[mt + i].norm_sqr();
        let w = sys.wheel.omega2[i];
        if w > 0.0 {
            shares.wheel_elastic += q2 * (w2 + w);
        } else {
            shares.wheel_rigid += q2 * w2;
        }
    }
    let at = |rows: &[f64], off: usize, len: usize, d: usize| -> c64 {
        (0..len)
            .map(|i| mode.q[off + i] * rows[d * len + i])
            .fold(c64::new(0.0, 0.0), |s, v| s + v)
    };
    let rail: [c64; 3] = std::array::from_fn(|d| at(sys.rail_rows, 0, mt, d));
    let wheel: [c64; 3] = std::array::from_fn(|d| at(sys.wheel_rows, mt, mw, d));
    let approach = rail[2] - wheel[2];
    shares.contact += lin.normal_stiffness_n_per_m * approach.norm_sqr();
    for d in 0..2 {
        if let Some(k) = lin.tangential_stiffness_n_per_m(d) {
            shares.contact += mode.forces[d].norm_sqr() / k;
        }
    }
    let total = shares.values().iter().sum::<f64>().max(f64::MIN_POSITIVE);
    shares.wheel_elastic /= total;
    shares.wheel_rigid /= total;
    shares.rail.iter_mut().for_each(|v| *v /= total);
    shares.support /= total;
    shares.contact /= total;
    let scale = 1.0 / total.sqrt();
    let amps = [
        rail[0].norm() * scale,
        rail[2].norm() * scale,
        wheel[0].norm() * scale,
        wheel[2].norm() * scale,
    ];
    let dominant = shares.dominant().0;
    CoupledMode {
        position_m,
        frequency_hz: lam.im / (2.0 * std::f64::consts::PI),
        damping_ratio: -lam.re / lam.norm(),
        shares,
        dominant,
        contact_amplitudes_m_per_sqrt_j: amps,
        rail_x_to_n: rail[0].norm() / rail[2].norm().max(f64::MIN_POSITIVE),
    }
}

/// All coupled modes of `sys` (ascending frequency), described.
pub fn coupled_modes(
    sys: &CoupledSystem<'_>,
    lin: &ContactLinearisation,
    labels: &CoordinateLabels,
    position_m: f64,
) -> Result<Vec<CoupledMode>, DynamicsError> {
    Ok(coupled_state_modes(sys, lin)?
        .iter()
        .map(|m| describe_mode(sys, lin, labels, m, position_m))
        .collect())
}

/// A selected frequency of a passage, sweep or growth run attributed to the nearest coupled
/// mode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModeAttribution {
    /// The selected frequency (Hz).
    pub frequency_hz: f64,
    /// The nearest coupled mode's frequency (Hz).
    pub mode_frequency_hz: f64,
    /// Its damping ratio (−).
    pub damping_ratio: f64,
    /// The contact position it was computed at (m).
    pub position_m: f64,
    /// Its name by the attribution rule ([`ModeShares::dominant`]).
    pub dominant: String,
    /// Its energy shares.
    pub shares: ModeShares,
    /// `|u_rail,x| / |u_rail,n|` at the contact (−).
    pub rail_x_to_n: f64,
}

impl ModeAttribution {
    /// The mode's offset from the selected frequency, `(f_mode − f)/f` (−).
    pub fn relative_offset(&self) -> f64 {
        (self.mode_frequency_hz - self.frequency_hz) / self.frequency_hz
    }

    /// Whether the mode lies outside [`ATTRIBUTION_WINDOW`] of the frequency: no visible
    /// coupled mode is that close, the nearest visible one was taken, and the frequency is
    /// not explained by a single coupled mode (a forced response between modes, or a mode of
    /// another contact position or speed).
    pub fn is_distant(&self) -> bool {
        self.relative_offset().abs() > ATTRIBUTION_WINDOW
    }
}

/// Attributes each frequency `f` of `frequencies_hz` to a coupled mode (over all positions
/// in `modes`): among the modes within `window` (relative, e.g. 0.03) of `f`, the one the
/// contact sees most (largest contact amplitude per √energy, rail or wheel, x or n); when
/// none is that close, the nearest in frequency among the modes whose contact amplitude is at
/// least `MIN_VISIBILITY` of the largest. A dense cluster of support modes a fraction of a
/// hertz from `f` that barely moves the contact does not take the attribution from the mode
/// that carries the contact's motion. Empty when there are no modes.
pub fn attribute(
    frequencies_hz: &[f64],
    modes: &[CoupledMode],
    window: f64,
) -> Vec<ModeAttribution> {
    let vis = CoupledMode::visibility;
    let top = modes.iter().map(vis).fold(0.0, f64::max);
    frequencies_hz
        .iter()
        .filter_map(|&f| {
            let close = modes
                .iter()
                .filter(|m| (m.frequency_hz - f).abs() <= window * f)
                .max_by(|a, b| vis(a).total_cmp(&vis(b)));
            let m = close.or_else(|| {
                modes
                    .iter()
                    .filter(|m| vis(m) >= MIN_VISIBILITY * top)
                    .min_by(|a, b| {
                        (a.frequency_hz - f)
                            .abs()
                            .total_cmp(&(b.frequency_hz - f).abs())
                    })
            })?;
            Some(ModeAttribution {
                frequency_hz: f,
                mode_frequency_hz: m.frequency_hz,
                damping_ratio: m.damping_ratio,
                position_m: m.position_m,
                dominant: m.dominant.clone(),
                shares: m.shares.clone(),
                rail_x_to_n: m.rail_x_to_n,
            })
        })
        .collect()
}

/// One line of text per attribution, e.g.
/// `1066 Hz → coupled mode 1061 Hz (ζ 0.8 %): wheel_elastic 62 %, rail_vertical_bending 20 %`.
pub fn attribution_text(a: &ModeAttribution) -> String {
    let mut parts: Vec<(String, f64)> = ModeShares::labels()
        .into_iter()
        .zip(a.shares.values())
        .filter(|(_, v)| *v >= 0.05)
        .collect();
    parts.sort_by(|x, y| y.1.total_cmp(&x.1));
    let shares: Vec<String> = parts
        .iter()
        .map(|(l, v)| format!("{l} {:.0} %", 100.0 * v))
        .collect();
    let distant = if a.is_distant() {
        format!(
            " [no coupled mode within {:.0} %: the nearest visible one is {:+.0} % away]",
            100.0 * ATTRIBUTION_WINDOW,
            100.0 * a.relative_offset()
        )
    } else {
        String::new()
    };
    format!(
        "{:.0} Hz → coupled mode {:.0} Hz (ζ {:.2} %, at x = {:.3} m): {}{distant}",
        a.frequency_hz,
        a.mode_frequency_hz,
        100.0 * a.damping_ratio,
        a.position_m,
        shares.join(", ")
    )
}

/// Relative size of the perturbations of the static state used to linearise the contact
/// (of the static creepage, approach): small enough to stay in the linear range of partial
/// slip, large enough for the solver's tolerance ([`super::setup::PASSAGE_TANGENTIAL_TOL`]).
pub(crate) const LINEARISATION_STEP: f64 = 0.02;

/// The contact of `engine` at `v` (m/s, smooth rail, the engine's series compliance) brought
/// to the static rolling state of a passage's start; the static inputs
/// `[F_n0 (N), F_l0 (N), spin (1/m)]` and the steady step result.
pub fn static_state(
    engine: &PassageEngine,
    v: f64,
) -> Result<(TransientRolling, [f64; 3], crate::contact::StepResult), DynamicsError> {
    let model = engine.model();
    let frame = engine.frame();
    let w = model.vehicle.wheel_load;
    let loads = [
        w / frame.n[2],
        model.contact.traction_coefficient * w,
        frame.n[1] / engine.wheel_radius_m(),
    ];
    let mut contact = super::setup::passage_contact(model, v, None, Default::default())?;
    contact
        .set_series_compliance(engine.series_compliance())
        .map_err(|source| {
            DynamicsError::Passage(crate::passage::PassageError::Contact {
                t_s: 0.0,
                x_m: 0.0,
                source,
            })
        })?;
    let st = steady_contact(&mut contact, loads[0], loads[1], loads[2], None, 0.0)?;
    Ok((contact, loads, st))
}

/// Steps `contact` `steps` times with constant inputs; the results.
fn hold_inputs(
    contact: &mut TransientRolling,
    inp: &StepInputs<'_>,
    steps: usize,
) -> Result<Vec<crate::contact::StepResult>, DynamicsError> {
    (0..steps)
        .map(|_| {
            contact.step(inp).map_err(|source| {
                DynamicsError::Passage(crate::passage::PassageError::Contact {
                    t_s: 0.0,
                    x_m: 0.0,
                    source,
                })
            })
        })
        .collect()
}

/// Slope and relaxation length of a force history pair `(f₊, f₋)` answering a step `±h` of
/// an input: `(Δf∞ / 2h, L)` with `L = dx (½ + Σ (1 − r_n))`, `r_n = Δf_n / Δf∞` (the mean
/// delay of the step response, trapezoidal with r(0) = 0).
fn slope_and_relaxation(plus: &[f64], minus: &[f64], h: f64, dx: f64) -> (f64, f64) {
    let d: Vec<f64> = plus.iter().zip(minus).map(|(a, b)| a - b).collect();
    let inf = d.last().copied().unwrap_or(0.0);
    if inf == 0.0 {
        return (0.0, 0.0);
    }
    let delay: f64 = d.iter().map(|x| 1.0 - x / inf).sum::<f64>() + 0.5;
    (inf / (2.0 * h), (delay * dx).max(0.0))
}

impl PassageEngine {
    /// The contact linearised at the static rolling state at `speed_m_per_s` (m/s), measured
    /// on the passage's contact solver (module doc).
    pub(crate) fn linearise_contact(
        &self,
        speed_m_per_s: f64,
    ) -> Result<ContactLinearisation, DynamicsError> {
        let v = speed_m_per_s;
        let (probe, _, st) = static_state(self, v)?;
        let nx = probe.config().grid.nx;
        let dx = probe.config().grid.dx();
        let steps = 10 * nx;
        let (xi0, delta0) = (st.creepage, st.approach_m);
        let spin = self.frame().n[1] / self.wheel_radius_m();
        let h_xi = (LINEARISATION_STEP * xi0.abs()).max(1e-6);
        let h_delta = LINEARISATION_STEP * delta0.abs();
        // (normal, longitudinal creepage, lateral creepage) of each probe.
        let run = |dn: f64, dxi: f64, deta: f64| -> Result<Vec<[f64; 3]>, DynamicsError> {
            let (mut c, _, _) = static_state(self, v)?;
            let inp = StepInputs {
                normal: if dn == 0.0 {
                    NormalInput::Force(st.normal_force_n)
                } else {
                    NormalInput::Approach(delta0 + dn)
                },
                longitudinal: Longitudinal::Creepage(xi0 + dxi),
                lateral_creepage: deta,
                spin_per_m: spin,
                rail_height_m: None,
            };
            Ok(hold_inputs(&mut c, &inp, steps)?
                .iter()
                .map(|r| [r.normal_force_n, r.fx_n, r.fy_n])
                .collect())
        };
        let col = |h: &[[f64; 3]], k: usize| h.iter().map(|r| r[k]).collect::<Vec<_>>();
        let (xp, xm) = (run(0.0, h_xi, 0.0)?, run(0.0, -h_xi, 0.0)?);
        let (sx, lx) = slope_and_relaxation(&col(&xp, 1), &col(&xm, 1), h_xi, dx);
        let (tp, tm) = (run(0.0, 0.0, h_xi)?, run(0.0, 0.0, -h_xi)?);
        let (st_, lt) = slope_and_relaxation(&col(&tp, 2), &col(&tm, 2), h_xi, dx);
        let (np_, nm) = (run(h_delta, 0.0, 0.0)?, run(-h_delta, 0.0, 0.0)?);
        let (kn, _) = slope_and_relaxation(&col(&np_, 0), &col(&nm, 0), h_delta, dx);
        let lin = ContactLinearisation {
            normal_stiffness_n_per_m: kn,
            creep_coefficient_n: [-sx, -st_],
            relaxation_length_m: [lx, lt],
            speed_m_per_s: v,
        };
        if !(kn > 0.0 && lin.creep_coefficient_n.iter().all(|&k| k > 0.0)) {
            return Err(DynamicsError::ContactLinearisation {
                reason: "the static state gave a non-positive stiffness or creep coefficient: it is in full slip (contact.traction_coefficient ≥ contact.friction?)",
            });
        }
        lin.check()?;
        Ok(lin)
    }

    /// The coupled modes with the contact frozen at `position_m` (m) and linearised as `lin`.
    pub(crate) fn coupled_modes_at(
        &self,
        labels: &CoordinateLabels,
        lin: &ContactLinearisation,
        position_m: f64,
    ) -> Result<Vec<CoupledMode>, DynamicsError> {
        let mut rr = vec![0.0; 3 * self.track_system().len()];
        self.rail_line().rows_at(position_m, &mut rr)?;
        let sys = CoupledSystem {
            track: self.track_system(),
            wheel: self.wheel_system(),
            rail_rows: &rr,
            wheel_rows: self.wheel_contact_rows(),
        };
        coupled_modes(&sys, lin, labels, position_m)
    }
}

/// The coupled modes of a prepared model at one speed, at one or more contact positions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoupledModes {
    /// Speed (m/s).
    pub speed_m_per_s: f64,
    /// The contact linearisation used.
    pub linearisation: ContactLinearisation,
    /// The contact positions (m).
    pub positions_m: Vec<f64>,
    /// The modes, position by position, each ascending in frequency.
    pub modes: Vec<CoupledMode>,
}

impl CoupledModes {
    /// The modes below `fmax_hz` (Hz).
    pub fn below(&self, fmax_hz: f64) -> impl Iterator<Item = &CoupledMode> {
        self.modes.iter().filter(move |m| m.frequency_hz <= fmax_hz)
    }

    /// Attributes `frequencies_hz` to the modes the contact sees (see [`attribute`], window
    /// [`ATTRIBUTION_WINDOW`]).
    pub fn attribute(&self, frequencies_hz: &[f64]) -> Vec<ModeAttribution> {
        attribute(frequencies_hz, &self.modes, ATTRIBUTION_WINDOW)
    }

    /// The modes [`attribute`] can choose: those whose contact amplitude is at least
    /// `MIN_VISIBILITY` of the largest. Attributing to these alone gives the same result
    /// as attributing to all modes, except where every mode within the window is below that
    /// visibility (then the nearest visible mode is taken instead of an invisible one).
    pub fn visible(&self) -> Vec<CoupledMode> {
        let top = self
            .modes
            .iter()
            .map(CoupledMode::visibility)
            .fold(0.0, f64::max);
        self.modes
            .iter()
            .filter(|m| m.visibility() >= MIN_VISIBILITY * top)
            .cloned()
            .collect()
    }
}

/// Contact amplitude (per √energy) below which a coupled mode is not a candidate for the
/// attribution of a selected frequency far from every mode, relative to the largest (−): a
/// mode the contact does not move cannot select a wavelength there.
pub(crate) const MIN_VISIBILITY: f64 = 0.01;

/// Relative frequency window of the attribution (−): the initiation criterion's wavelength
/// deviation, 3 % (docs/theory.md §11.4).
pub const ATTRIBUTION_WINDOW: f64 = 0.03;

impl PreparedModel {
    /// Coupled wheel–track modes at `speed_m_per_s` (m/s) with the contact frozen at each of
    /// `positions_m` (m; default the mid-span and the sleeper nearest the solution-zone
    /// centre when empty).
    pub fn coupled_modes(
        &self,
        speed_m_per_s: f64,
        positions_m: &[f64],
    ) -> Result<CoupledModes, DynamicsError> {
        let positions = if positions_m.is_empty() {
            self.engine.midspan_and_sleeper_m().to_vec()
        } else {
            positions_m.to_vec()
        };
        let lin = self.engine.linearise_contact(speed_m_per_s)?;
        let labels = CoordinateLabels::from_classes(&self.track_classes);
        let mut modes = Vec::new();
        for &x in &positions {
            modes.extend(self.engine.coupled_modes_at(&labels, &lin, x)?);
        }
        Ok(CoupledModes {
            speed_m_per_s,
            linearisation: lin,
            positions_m: positions,
            modes,
        })
    }
}

#[cfg(test)]
mod tests;

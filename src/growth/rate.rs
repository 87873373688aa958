//! The growth-rate spectrum (docs/theory.md §10.6): the linear wear response of a passage to
//! a small sinusoidal rail-top roughness, per unit roughness, as a function of wavelength.
//!
//! For a roughness `r(x) = Re(r̂ e^{ikx})` passed at speed V (frequency `ω = kV`) every
//! perturbation of the steady rolling state is `Re(· e^{ikx})` at the contact position x, and
//! the new wear (frictional work per metre, J/m, §6.6) is `Re(G(k) r̂ e^{ikx})`:
//!
//! 1. **The contact** (`ContactTransfer`, measured): the transient rolling contact of the
//!    passage (same grid, friction, traction, spin and series compliance), started in the
//!    static rolling state, is driven by one small sinusoidal input at a time — the roughness
//!    under the grid (at fixed approach and creepages), the approach δ, the longitudinal
//!    creepage ξ, the lateral creepage η — and the harmonic at k of its outputs (F_x, F_t, F_n
//!    on the wheel and the wear in rail-fixed bins) is fitted by least squares after the start
//!    transient. This one table holds the contact filter of the patch, the Hertz stiffness,
//!    the creep coefficients with their transient lag and the wear law, all as the passage's
//!    own solver has them. It is smooth in k and is interpolated from a coarse grid.
//! 2. **The structure**: `g = u_wheel − u_rail = H F` with `H = H_rail + H_wheel` (3 × 3 in
//!    x, t, n; [`crate::dynamics::receptance`], modal parts only: the residual flexibility is
//!    the contact's series compliance, as in a passage) at ω; the rail's receptance is the
//!    mean over positions across one sleeper bay at the centre of the solution zone.
//! 3. **The loop**: the contact inputs are `δ = −g_n`, `ξ = iω g_x / V`, `η = iω g_t / V`, so
//!    `F = T_F,r r̂ + B H F` with `B = [i ω/V T_F,ξ | i ω/V T_F,η | −T_F,δ]`, solved as
//!    `F = (I − B H)⁻¹ T_F,r r̂`; the wear is
//!    `G r̂ = T_W,r r̂ + T_W,δ δ + T_W,ξ ξ + T_W,η η` (four parts, reported separately).
//!
//! **Sign.** Wear removes material: over `N` passages the roughness changes by
//! `Δr = −N k_w W / (2b)` (§10.5), so the growth rate per passage is
//! `σ = −k_w Re(G) / (2b)` (1/passage): a wavelength grows when the new wear is in antiphase
//! with the roughness (`|arg G| > 90°`), decays when it is in phase. `Im G` only shifts the
//! corrugation along the rail.
//!
//! [`passage_gain`] measures `G` directly, from the wear difference of passages over a small
//! sinusoidal corrugation and over the smooth rail: the check of the linear theory.

use faer::c64;
use rayon::prelude::*;
use serde::Serialize;

use crate::contact::{Longitudinal, NormalInput, StepInputs, TransientRolling, WearAccumulator};
use crate::dynamics::passage::{PassageEngine, PassageOptions};
use crate::dynamics::{DynamicsError, RailProfile};
use crate::passage::record::PassageRecord;
use crate::units::Speed;

/// The contact inputs of a `ContactTransfer`, in column order.
pub const INPUTS: [&str; 4] = ["roughness", "approach", "creepage_x", "creepage_t"];
/// The contact outputs of a `ContactTransfer`, in row order.
pub const OUTPUTS: [&str; 4] = ["F_x", "F_t", "F_n", "W_f"];
/// The parts of the wear response, in the order of `RatePoint::wear_parts`.
pub const WEAR_PARTS: [&str; 4] = ["roughness", "approach", "creepage_x", "creepage_t"];

/// The linearised rolling contact at one wavenumber: `t[o][j]` is the complex amplitude of
/// output `o` ([`OUTPUTS`]: forces on the wheel F_x, F_t, F_n in N, wear in J/m) per unit
/// complex amplitude of input `j` ([`INPUTS`]: roughness and approach in m, creepages −),
/// phases referred to the rail coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ContactTransfer {
    /// Wavelength (m).
    pub wavelength_m: f64,
    /// The transfer table, outputs × inputs.
    pub t: [[c64; 4]; 4],
}

/// Settings of the growth-rate spectrum.
#[derive(Clone, Debug, PartialEq)]
pub struct RateOptions {
    /// Wavelength range (m), default 20–80 mm.
    pub band_m: [f64; 2],
    /// Wavelengths of the spectrum, evenly spaced in frequency (−, ≥ 2; default 241: about
    /// 6 Hz apart at 140 km/h).
    pub points: usize,
    /// Wavelengths at which the contact is measured, evenly spaced in wavenumber over the band
    /// (−, ≥ 4; default 12); interpolated in between.
    pub contact_points: usize,
    /// Rail positions across one sleeper bay over which the rail receptance is averaged
    /// (−, ≥ 1; default 8).
    pub positions: usize,
    /// Size of each contact probe relative to the static approach or creepage (−, default
    /// 0.01).
    pub probe: f64,
}

impl Default for RateOptions {
    fn default() -> Self {
        Self {
            band_m: [0.02, 0.08],
            points: 241,
            contact_points: 12,
            positions: 8,
            probe: 0.01,
        }
    }
}

impl RateOptions {
    fn check(&self) -> Result<(), DynamicsError> {
        let [a, b] = self.band_m;
        let bad = |name, value: f64, expected| {
            Err(DynamicsError::Passage(
                crate::passage::PassageError::OutOfRange {
                    name,
                    value,
                    expected,
                },
            ))
        };
        if !(a.is_finite() && a > 0.0 && b > a && b.is_finite()) {
            return bad("growth-rate band (m)", b, "finite, 0 < shortest < longest");
        }
        if self.points < 2 || self.contact_points < 4 || self.positions < 1 {
            return bad(
                "growth-rate points / contact points / positions",
                self.points.min(self.contact_points) as f64,
                "points ≥ 2, contact points ≥ 4, positions ≥ 1",
            );
        }
        if !(self.probe > 0.0 && self.probe <= 0.1) {
            return bad("growth-rate probe size (−)", self.probe, "in (0, 0.1]");
        }
        Ok(())
    }
}

/// The linear response at one wavelength, per unit roughness amplitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateResponse {
    /// Forces on the wheel `[F_x, F_t, F_n]` per unit roughness (N/m).
    pub forces: [c64; 3],
    /// The contact inputs `[δ (−), ξ (1/m), η (1/m)]` from the structure per unit roughness.
    pub inputs: [c64; 3],
    /// Wear per unit roughness `G` (J/m per m).
    pub wear: c64,
    /// The four parts of `G` ([`WEAR_PARTS`]): the roughness at fixed approach and
    /// creepages, and the approach, ξ and η the structure adds (J/m per m).
    pub wear_parts: [c64; 4],
}

/// Closes the loop of the module doc for one frequency: contact table `t`, structural
/// receptance `h` (3 × 3, m/N, `u_wheel − u_rail = h F` for the force `F` on the wheel),
/// angular frequency `omega` (rad/s) and speed `v` (m/s).
pub(crate) fn closed_loop(
    t: &[[c64; 4]; 4],
    h: &[[c64; 3]; 3],
    omega: f64,
    v: f64,
) -> RateResponse {
    let iw = c64::new(0.0, omega / v);
    // B: output o per unit relative displacement g_j (x, t, n).
    let b: [[c64; 3]; 3] = std::array::from_fn(|o| [iw * t[o][2], iw * t[o][3], -t[o][1]]);
    // A = I − B H.
    let a: [[c64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let bh = (0..3).fold(c64::new(0.0, 0.0), |s, k| s + b[i][k] * h[k][j]);
            let id = if i == j { 1.0 } else { 0.0 };
            c64::new(id, 0.0) - bh
        })
    });
    let forces = solve3(a, [t[0][0], t[1][0], t[2][0]]);
    let g: [c64; 3] =
        std::array::from_fn(|i| (0..3).fold(c64::new(0.0, 0.0), |s, k| s + h[i][k] * forces[k]));
    let inputs = [-g[2], iw * g[0], iw * g[1]];
    let wear_parts = [
        t[3][0],
        t[3][1] * inputs[0],
        t[3][2] * inputs[1],
        t[3][3] * inputs[2],
    ];
    RateResponse {
        forces,
        inputs,
        wear: wear_parts.iter().fold(c64::new(0.0, 0.0), |s, &p| s + p),
        wear_parts,
    }
}

/// Solves the 3 × 3 complex system `a x = rhs` by Gaussian elimination with partial pivoting.
fn solve3(mut a: [[c64; 3]; 3], mut rhs: [c64; 3]) -> [c64; 3] {
    for c in 0..3 {
        let p = (c..3)
            .max_by(|&i, &j| a[i][c].norm().total_cmp(&a[j][c].norm()))
            .unwrap_or(c);
        a.swap(c, p);
        rhs.swap(c, p);
        for r in c + 1..3 {
            let f = a[r][c] / a[c][c];
            let pivot = a[c];
            for (ark, &v) in a[r].iter_mut().zip(&pivot).skip(c) {
                *ark -= f * v;
            }
            let v = rhs[c];
            rhs[r] -= f * v;
        }
    }
    let mut x = [c64::new(0.0, 0.0); 3];
    for r in (0..3).rev() {
        let mut s = rhs[r];
        for k in r + 1..3 {
            s -= a[r][k] * x[k];
        }
        x[r] = s / a[r][r];
    }
    x
}

/// The least-squares fit `y ≈ c + a cos(kx) + b sin(kx)`: the complex amplitude `a − ib` of
/// the harmonic `Re((a − ib) e^{ikx})`.
pub(crate) fn fit_harmonic(x: &[f64], y: &[f64], k: f64) -> c64 {
    let mut m = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for (&xi, &yi) in x.iter().zip(y) {
        let f = [1.0, (k * xi).cos(), (k * xi).sin()];
        for a in 0..3 {
            for b in 0..3 {
                m[a][b] += f[a] * f[b];
            }
            r[a] += f[a] * yi;
        }
    }
    let s = solve3(
        std::array::from_fn(|a| std::array::from_fn(|b| c64::new(m[a][b], 0.0))),
        r.map(|v| c64::new(v, 0.0)),
    );
    c64::new(s[1].re, -s[2].re)
}

/// The passage's contact in its static rolling state, driven by sinusoidal probes.
pub(crate) struct ContactProbe {
    steady: TransientRolling,
    normal_approach_m: f64,
    creepage: f64,
    spin_per_m: f64,
    probe: f64,
}

impl ContactProbe {
    /// The contact of `engine` at `speed_m_per_s` (m/s) in the static rolling state; each
    /// probe is `probe` (−) times the static approach or creepage.
    pub fn new(
        engine: &PassageEngine,
        speed_m_per_s: f64,
        probe: f64,
    ) -> Result<Self, DynamicsError> {
        let (steady, loads, st) = crate::dynamics::coupled::static_state(engine, speed_m_per_s)?;
        Ok(Self {
            steady,
            normal_approach_m: st.approach_m,
            creepage: st.creepage,
            spin_per_m: loads[2],
            probe,
        })
    }

    /// The transfer table at `wavelength_m` (m): one run per input.
    pub fn transfer(&self, wavelength_m: f64) -> Result<ContactTransfer, DynamicsError> {
        let cols = (0..4)
            .map(|j| self.run(j, wavelength_m))
            .collect::<Result<Vec<_>, _>>()?;
        let t = std::array::from_fn(|o| std::array::from_fn(|j| cols[j][o]));
        Ok(ContactTransfer { wavelength_m, t })
    }

    /// One run with input `input` (see [`INPUTS`]) at `wavelength_m`: the outputs' complex
    /// amplitudes per unit input.
    fn run(&self, input: usize, wavelength_m: f64) -> Result<[c64; 4], DynamicsError> {
        let mut c = self.steady.clone();
        let grid = c.config().grid;
        let (nx, dx, half) = (grid.nx, grid.dx(), grid.half_length_x_m);
        let k = 2.0 * std::f64::consts::PI / wavelength_m;
        let eps = self.probe
            * if input < 2 {
                self.normal_approach_m.abs()
            } else {
                self.creepage.abs()
            };
        // Start transient: the contact forgets its history within one patch transit; four
        // grid lengths are kept out of the fits.
        let settle = 4 * nx;
        let n_meas = ((2.0 * wavelength_m / dx).ceil() as usize).max(4 * nx);
        let x_wear = settle as f64 * dx + half;
        let mut wear = WearAccumulator::new(&c, x_wear, n_meas);
        let n_steps = settle + n_meas + (2.0 * half / dx).ceil() as usize + 2;
        let xs: Vec<f64> = c.x_m().to_vec();
        let mut heights = vec![0.0; nx];
        let mut xc_rec = Vec::with_capacity(n_steps);
        let mut f_rec: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::with_capacity(n_steps));
        for n in 1..=n_steps {
            let xc = n as f64 * dx;
            let s = eps * (k * xc).cos();
            if input == 0 {
                for (h, &xi) in heights.iter_mut().zip(&xs) {
                    *h = eps * (k * (xc + xi)).cos();
                }
            }
            let r = c
                .step(&StepInputs {
                    normal: NormalInput::Approach(
                        self.normal_approach_m + if input == 1 { s } else { 0.0 },
                    ),
                    longitudinal: Longitudinal::Creepage(
                        self.creepage + if input == 2 { s } else { 0.0 },
                    ),
                    lateral_creepage: if input == 3 { s } else { 0.0 },
                    spin_per_m: self.spin_per_m,
                    rail_height_m: (input == 0).then_some(&heights[..]),
                })
                .map_err(|source| {
                    DynamicsError::Passage(crate::passage::PassageError::Contact {
                        t_s: 0.0,
                        x_m: xc,
                        source,
                    })
                })?;
            wear.add_step(&c, xc);
            if n >= settle {
                xc_rec.push(xc);
                f_rec[0].push(r.fx_n);
                f_rec[1].push(r.fy_n);
                f_rec[2].push(r.normal_force_n);
            }
        }
        let mut w = vec![0.0; n_meas];
        wear.work_x(&mut w);
        let xw = wear.x_m();
        Ok([
            fit_harmonic(&xc_rec, &f_rec[0], k) / eps,
            fit_harmonic(&xc_rec, &f_rec[1], k) / eps,
            fit_harmonic(&xc_rec, &f_rec[2], k) / eps,
            fit_harmonic(&xw, &w, k) / eps,
        ])
    }
}

/// Interpolates the contact tables (ascending in wavenumber) at wavenumber `k` (1/m): cubic
/// Hermite with Catmull–Rom slopes, entry by entry; clamped to the end tables outside.
pub(crate) fn interpolate_transfer(tables: &[ContactTransfer], k: f64) -> [[c64; 4]; 4] {
    let ks: Vec<f64> = tables
        .iter()
        .map(|t| 2.0 * std::f64::consts::PI / t.wavelength_m)
        .collect();
    let n = ks.len();
    if n == 1 || k <= ks[0] {
        return tables[0].t;
    }
    if k >= ks[n - 1] {
        return tables[n - 1].t;
    }
    let i = ks.partition_point(|&x| x <= k).clamp(1, n - 1) - 1;
    let h = ks[i + 1] - ks[i];
    let s = (k - ks[i]) / h;
    let slope = |j: usize, o: usize, c: usize| -> c64 {
        let (a, b) = (j.saturating_sub(1), (j + 1).min(n - 1));
        (tables[b].t[o][c] - tables[a].t[o][c]) / (ks[b] - ks[a]) * h
    };
    let (h00, h10) = (
        2.0 * s.powi(3) - 3.0 * s * s + 1.0,
        s.powi(3) - 2.0 * s * s + s,
    );
    let (h01, h11) = (-2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
    std::array::from_fn(|o| {
        std::array::from_fn(|c| {
            tables[i].t[o][c] * h00
                + slope(i, o, c) * h10
                + tables[i + 1].t[o][c] * h01
                + slope(i + 1, o, c) * h11
        })
    })
}

/// One wavelength of the growth-rate spectrum.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RatePoint {
    /// Wavelength (m).
    pub wavelength_m: f64,
    /// Frequency at the speed, `V/λ` (Hz).
    pub frequency_hz: f64,
    /// `|G|`, wear per unit roughness amplitude (J/m per m).
    pub gain_j_per_m2: f64,
    /// `arg G` (degrees, −180 … 180): 0 = wear in phase with the roughness (decays),
    /// ±180 = in antiphase (grows).
    pub phase_deg: f64,
    /// Growth rate `σ = −k_w Re(G)/(2b)` (1/passage): relative change of the roughness
    /// amplitude per passage; > 0 grows.
    pub growth_rate_per_passage: f64,
    /// `Re` of each part of `G` ([`WEAR_PARTS`]) (J/m per m).
    pub wear_parts_re: [f64; 4],
    /// `Im` of each part of `G` (J/m per m).
    pub wear_parts_im: [f64; 4],
    /// `|F_n|` per unit roughness (N/m).
    pub normal_force_n_per_m: f64,
    /// `|F_x|` per unit roughness (N/m).
    pub longitudinal_force_n_per_m: f64,
}

impl RatePoint {
    fn new(wavelength_m: f64, v: f64, r: &RateResponse, sigma_per_g: f64) -> Self {
        Self {
            wavelength_m,
            frequency_hz: v / wavelength_m,
            gain_j_per_m2: r.wear.norm(),
            phase_deg: r.wear.arg().to_degrees(),
            growth_rate_per_passage: -sigma_per_g * r.wear.re,
            wear_parts_re: r.wear_parts.map(|p| p.re),
            wear_parts_im: r.wear_parts.map(|p| p.im),
            normal_force_n_per_m: r.forces[2].norm(),
            longitudinal_force_n_per_m: r.forces[0].norm(),
        }
    }

    /// Whether this wavelength grows (`σ > 0`).
    pub fn grows(&self) -> bool {
        self.growth_rate_per_passage > 0.0
    }
}

/// The growth-rate spectrum of a model at one speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GrowthRateSpectrum {
    /// The speed as requested (km/h and m/s; see [`Speed`]).
    pub speed: Speed,
    /// Wear coefficient `k_w` (m³/J).
    pub wear_coefficient_m3_per_j: f64,
    /// Worn width `2b` (m), the static contact width.
    pub width_m: f64,
    /// The spectrum, ascending in wavelength.
    pub points: Vec<RatePoint>,
    /// The same on a rigid structure (`H = 0`): the contact filter and the wear law alone.
    pub rigid: Vec<RatePoint>,
    /// The same with the structure's normal receptance only (`H_nn`; x, t rows and columns
    /// zero): the normal dynamics without the creepage feedback.
    pub normal_only: Vec<RatePoint>,
}

impl GrowthRateSpectrum {
    /// The wavelength ranges (m) where the roughness grows, `[from, to]` ascending.
    pub fn growing_ranges_m(&self) -> Vec<[f64; 2]> {
        let mut out: Vec<[f64; 2]> = Vec::new();
        let mut open = false;
        for p in &self.points {
            if p.grows() {
                match (open, out.last_mut()) {
                    (true, Some(r)) => r[1] = p.wavelength_m,
                    _ => out.push([p.wavelength_m, p.wavelength_m]),
                }
                open = true;
            } else {
                open = false;
            }
        }
        out
    }

    /// The fastest-growing (or slowest-decaying) wavelength.
    pub fn fastest(&self) -> Option<&RatePoint> {
        self.points.iter().max_by(|a, b| {
            a.growth_rate_per_passage
                .total_cmp(&b.growth_rate_per_passage)
        })
    }

    /// One sentence on which wavelengths grow at the spectrum's speed.
    pub fn sentence(&self) -> String {
        let speed_kmh = self.speed.kmh();
        let mm = |m: f64| format!("{:.1}", crate::units::m_to_mm(m));
        let band = match (self.points.first(), self.points.last()) {
            (Some(a), Some(b)) => format!("{}–{} mm", mm(a.wavelength_m), mm(b.wavelength_m)),
            _ => return "The growth-rate spectrum is empty.".into(),
        };
        let ranges = self.growing_ranges_m();
        let fastest = self.fastest().map(|p| {
            format!(
                "{} mm / {:.0} Hz (σ = {:.3e} per passage, wear phase {:.0}°)",
                mm(p.wavelength_m),
                p.frequency_hz,
                p.growth_rate_per_passage,
                p.phase_deg
            )
        });
        let fastest = fastest.unwrap_or_default();
        if ranges.is_empty() {
            format!(
                "Growth-rate spectrum at {speed_kmh:.0} km/h: no wavelength in {band} grows (the linear wear response is in phase with a small roughness everywhere); the slowest decay is at {fastest}."
            )
        } else {
            let r: Vec<String> = ranges
                .iter()
                .map(|r| {
                    if r[0] == r[1] {
                        format!("{} mm", mm(r[0]))
                    } else {
                        format!("{}–{} mm", mm(r[0]), mm(r[1]))
                    }
                })
                .collect();
            format!(
                "Growth-rate spectrum at {speed_kmh:.0} km/h: a small roughness grows at {} (of {band}); the fastest growth is at {fastest}.",
                r.join(", ")
            )
        }
    }
}

/// The rail receptance averaged over `n` positions across the sleeper bay at the centre of
/// the solution zone and the wheel's, modal parts only (m/N), at `frequencies_hz`.
fn structure_receptance(
    engine: &PassageEngine,
    frequencies_hz: &[f64],
    n: usize,
) -> Result<Vec<[[c64; 3]; 3]>, DynamicsError> {
    let [mid, sleeper] = engine.midspan_and_sleeper_m();
    let bay = 2.0 * (mid - sleeper).abs();
    let positions: Vec<f64> = (0..n)
        .map(|p| sleeper - 0.5 * bay + (p as f64 + 0.5) * bay / n as f64)
        .collect();
    let r = engine.contact_receptance(&positions, frequencies_hz)?;
    let series = engine.series_compliance();
    Ok((0..frequencies_hz.len())
        .map(|k| {
            std::array::from_fn(|a| {
                std::array::from_fn(|b| {
                    let mean = r
                        .rail
                        .iter()
                        .fold(c64::new(0.0, 0.0), |s, p| s + p[k][a][b])
                        / n as f64;
                    let res = if a == b { series[a] } else { 0.0 };
                    mean - c64::new(res, 0.0) + r.wheel[k][a][b]
                })
            })
        })
        .collect())
}

/// The wavelengths of the spectrum (m, ascending): `points` evenly spaced in frequency over
/// the band.
pub(crate) fn spectrum_wavelengths(o: &RateOptions) -> Vec<f64> {
    let [a, b] = o.band_m;
    let (k0, k1) = (1.0 / b, 1.0 / a);
    let mut l: Vec<f64> = (0..o.points)
        .map(|i| 1.0 / (k0 + (k1 - k0) * i as f64 / (o.points - 1) as f64))
        .collect();
    l.reverse();
    l
}

/// The contact tables at `n` wavelengths evenly spaced in wavenumber over `band_m`,
/// ascending in wavenumber (the runs in parallel).
pub(crate) fn contact_tables(
    probe: &ContactProbe,
    band_m: [f64; 2],
    n: usize,
) -> Result<Vec<ContactTransfer>, DynamicsError> {
    let (k0, k1) = (1.0 / band_m[1], 1.0 / band_m[0]);
    (0..n)
        .into_par_iter()
        .map(|i| probe.transfer(1.0 / (k0 + (k1 - k0) * i as f64 / (n - 1) as f64)))
        .collect()
}

/// The linear responses of `engine` at `speed_m_per_s` (m/s) at `wavelengths_m` (m, inside
/// the band of `o`, where the contact is measured): per wavelength `[full, rigid structure,
/// normal receptance only]` (see [`GrowthRateSpectrum`]).
pub fn linear_responses(
    engine: &PassageEngine,
    speed_m_per_s: f64,
    wavelengths_m: &[f64],
    o: &RateOptions,
) -> Result<Vec<[RateResponse; 3]>, DynamicsError> {
    o.check()?;
    let v = speed_m_per_s;
    let probe = ContactProbe::new(engine, v, o.probe)?;
    let tables = contact_tables(&probe, o.band_m, o.contact_points)?;
    let freqs: Vec<f64> = wavelengths_m.iter().map(|l| v / l).collect();
    let h = structure_receptance(engine, &freqs, o.positions)?;
    let zero = [[c64::new(0.0, 0.0); 3]; 3];
    Ok(wavelengths_m
        .iter()
        .zip(&h)
        .map(|(&l, h)| {
            let k = 2.0 * std::f64::consts::PI / l;
            let t = interpolate_transfer(&tables, k);
            let w = k * v;
            let mut hn = zero;
            hn[2][2] = h[2][2];
            [
                closed_loop(&t, h, w, v),
                closed_loop(&t, &zero, w, v),
                closed_loop(&t, &hn, w, v),
            ]
        })
        .collect())
}

/// The growth-rate spectrum of `engine` at `speed` with the wear coefficient
/// `wear_coefficient` (m³/J; the growth rate scales with it).
pub fn growth_rate_spectrum(
    engine: &PassageEngine,
    speed: Speed,
    wear_coefficient: f64,
    o: &RateOptions,
) -> Result<GrowthRateSpectrum, DynamicsError> {
    o.check()?;
    let v = speed.m_per_s();
    let lambdas = spectrum_wavelengths(o);
    let r = linear_responses(engine, v, &lambdas, o)?;
    let width = 2.0 * engine.hertz_b_m();
    let sigma_per_g = wear_coefficient / width;
    let pick = |which: usize| -> Vec<RatePoint> {
        lambdas
            .iter()
            .zip(&r)
            .map(|(&l, r)| RatePoint::new(l, v, &r[which], sigma_per_g))
            .collect()
    };
    Ok(GrowthRateSpectrum {
        speed,
        wear_coefficient_m3_per_j: wear_coefficient,
        width_m: width,
        points: pick(0),
        rigid: pick(1),
        normal_only: pick(2),
    })
}

/// The sinusoidal rail-top profile `a cos(2πx/λ)` (m) over the passage's travel, faded in
/// over the run-in before the solution zone by a raised cosine (so that its onset does not
/// ring the lightly damped modes through the zone).
pub(crate) fn sinusoidal_profile(
    engine: &PassageEngine,
    wavelength_m: f64,
    amplitude_m: f64,
) -> Result<RailProfile, DynamicsError> {
    let [t0, t1] = engine.travel_m();
    let z0 = engine.zone_m()[0];
    let margin = 0.05;
    let (x0, x1) = (t0 - margin, t1 + margin);
    let dx = wavelength_m / 32.0;
    let n = ((x1 - x0) / dx).ceil() as usize + 1;
    let k = 2.0 * std::f64::consts::PI / wavelength_m;
    let x: Vec<f64> = (0..n).map(|i| x0 + i as f64 * dx).collect();
    let h = x
        .iter()
        .map(|&xi| {
            let s = ((xi - t0) / (z0 - t0).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            let fade = 0.5 - 0.5 * (std::f64::consts::PI * s).cos();
            amplitude_m * fade * (k * xi).cos()
        })
        .collect();
    Ok(RailProfile::new(x, h)?)
}

/// `G` measured by passages: the harmonic at `2π/λ` of the wear difference (J/m) between a
/// passage over `sinusoidal_profile` of amplitude `amplitude_m` and the smooth passage
/// `smooth` (same engine and speed), over the solution zone, per unit amplitude.
pub fn passage_gain(
    engine: &PassageEngine,
    smooth: &PassageRecord,
    wavelength_m: f64,
    amplitude_m: f64,
) -> Result<c64, DynamicsError> {
    let v = smooth.speed_m_per_s;
    let profile = sinusoidal_profile(engine, wavelength_m, amplitude_m)?;
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let rec = engine.passage(v, Some(&profile), &opts, None)?;
    if rec.wear_j_per_m.len() != smooth.wear_j_per_m.len() {
        return Err(DynamicsError::SizeMismatch {
            what: "growth-rate check: wear bins of the corrugated vs the smooth passage",
            found: rec.wear_j_per_m.len(),
            expected: smooth.wear_j_per_m.len(),
        });
    }
    let d: Vec<f64> = rec
        .wear_j_per_m
        .iter()
        .zip(&smooth.wear_j_per_m)
        .map(|(a, b)| a - b)
        .collect();
    let k = 2.0 * std::f64::consts::PI / wavelength_m;
    Ok(fit_harmonic(&rec.wear_x_m, &d, k) / amplitude_m)
}

#[cfg(test)]
mod tests {
    use super::{
        c64, closed_loop, fit_harmonic, interpolate_transfer, ContactTransfer, GrowthRateSpectrum,
        RatePoint, Speed,
    };
    fn c(re: f64, im: f64) -> c64 {
        c64::new(re, im)
    }

    /// The harmonic fit recovers `a cos + b sin + c` exactly over a non-integer number of
    /// periods.
    #[test]
    fn harmonic_fit_is_exact_for_a_sinusoid() {
        let k = 2.0 * std::f64::consts::PI / 0.037;
        let x: Vec<f64> = (0..300).map(|i| 0.3 + i as f64 * 6.3e-4).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|&x| 5.0 + 1.5 * (k * x).cos() - 0.7 * (k * x).sin())
            .collect();
        let z = fit_harmonic(&x, &y, k);
        assert!((z - c(1.5, 0.7)).norm() < 1e-10, "{z}");
    }

    /// On a rigid structure the wear response is the contact's own roughness term.
    #[test]
    fn rigid_structure_leaves_the_contact_term() {
        let mut t = [[c(0.0, 0.0); 4]; 4];
        for (o, row) in t.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = c(1.0 + o as f64, 0.5 * j as f64 - 0.3);
            }
        }
        let r = closed_loop(&t, &[[c(0.0, 0.0); 3]; 3], 6000.0, 38.9);
        assert!((r.wear - t[3][0]).norm() < 1e-15);
        assert!((r.forces[2] - t[2][0]).norm() < 1e-15);
    }

    /// Normal dynamics alone, a Hertz spring `k_n` with the contact filter `s` on a normal
    /// receptance `h`: `F_n = k_n s r/(1 + k_n h)` (closed form), and the wear through the
    /// approach term `T_W,δ δ` with `δ = −h F_n`.
    #[test]
    fn normal_loop_is_the_closed_form() {
        let (kn, s) = (1.4e9, c(0.8, -0.1));
        let h = c(-2.0e-9, -4.0e-10);
        let (wr, wd) = (c(3.0e4, 1.0e3), c(3.5e4, -2.0e3));
        let mut t = [[c(0.0, 0.0); 4]; 4];
        t[2][0] = kn * s;
        t[2][1] = c(kn, 0.0);
        t[3][0] = wr;
        t[3][1] = wd;
        let mut hm = [[c(0.0, 0.0); 3]; 3];
        hm[2][2] = h;
        let r = closed_loop(&t, &hm, 6000.0, 38.9);
        let f = kn * s / (c(1.0, 0.0) + kn * h);
        assert!(
            (r.forces[2] - f).norm() < 1e-9 * f.norm(),
            "{} vs {f}",
            r.forces[2]
        );
        let w = wr + wd * (-h * f);
        assert!((r.wear - w).norm() < 1e-9 * w.norm());
    }

    /// The creepage loop of one direction: a creep force `F_x = −κ ξ` on a receptance `h_xx`
    /// with `ξ = iω h F_x / V` and a roughness force `F_r`: `F_x = F_r/(1 + iωκh/V)`.
    #[test]
    fn creepage_loop_is_the_closed_form() {
        let (kappa, fr, h) = (1.1e7, c(2.0e5, 3.0e4), c(1.0e-9, -3.0e-9));
        let (w, v) = (7000.0, 38.9);
        let mut t = [[c(0.0, 0.0); 4]; 4];
        t[0][0] = fr;
        t[0][2] = c(-kappa, 0.0);
        let mut hm = [[c(0.0, 0.0); 3]; 3];
        hm[0][0] = h;
        let r = closed_loop(&t, &hm, w, v);
        let f = fr / (c(1.0, 0.0) + c(0.0, w / v) * kappa * h);
        assert!((r.forces[0] - f).norm() < 1e-9 * f.norm());
    }

    /// The interpolation reproduces its nodes and a cubic in k between them.
    #[test]
    fn interpolation_hits_nodes_and_cubics() {
        let tab: Vec<ContactTransfer> = (0..6)
            .map(|i| {
                let k = 80.0 + 40.0 * i as f64;
                let mut t = [[c(0.0, 0.0); 4]; 4];
                t[3][0] = c(2.0 * k, -0.5 * k);
                ContactTransfer {
                    wavelength_m: 2.0 * std::f64::consts::PI / k,
                    t,
                }
            })
            .collect();
        for k in [80.0, 100.0, 173.0, 280.0] {
            let t = interpolate_transfer(&tab, k);
            assert!((t[3][0] - c(2.0 * k, -0.5 * k)).norm() < 1e-9, "{k}");
        }
    }

    #[test]
    fn growing_ranges_and_sentence() {
        let p = |l: f64, s: f64| RatePoint {
            wavelength_m: l,
            frequency_hz: 38.9 / l,
            gain_j_per_m2: 1.0,
            phase_deg: if s > 0.0 { 170.0 } else { 10.0 },
            growth_rate_per_passage: s,
            wear_parts_re: [0.0; 4],
            wear_parts_im: [0.0; 4],
            normal_force_n_per_m: 0.0,
            longitudinal_force_n_per_m: 0.0,
        };
        let mut g = GrowthRateSpectrum {
            speed: Speed::from_kmh(60.0),
            wear_coefficient_m3_per_j: 1e-13,
            width_m: 0.01,
            points: vec![
                p(0.02, -1.0),
                p(0.03, 1.0),
                p(0.04, 2.0),
                p(0.05, -1.0),
                p(0.06, 0.5),
            ],
            rigid: vec![],
            normal_only: vec![],
        };
        assert_eq!(g.growing_ranges_m(), vec![[0.03, 0.04], [0.06, 0.06]]);
        assert!(g.sentence().contains("grows at 30.0–40.0 mm, 60.0 mm"));
        assert!(g.sentence().starts_with("Growth-rate spectrum at 60 km/h"));
        g.points.retain(|p| !p.grows());
        assert!(g.sentence().contains("no wavelength in 20.0–50.0 mm grows"));
    }
}

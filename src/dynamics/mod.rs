//! The reduced-order wheel passage (docs/theory.md §7): modal synthesis of the track and the
//! wheel, the moving frictional rolling contact, time integration, and the frictional work
//! (wear) along the rail.
//!
//! - [`summary`]: what a passage reports to the growth loop, sweeps and studies.
//! - [`RailProfile`]: a rail-top height profile along the rail (the corrugation).
//! - [`PassageRunner`]: anything that runs passages at a given speed over a profile — the
//!   reduced-order engine, or a cheap stand-in in the tests of the later stages.

// Numerical kernels index several parallel arrays with one loop index.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod compliance;
pub mod coupled;
pub mod integrator;
pub mod moving_load;
pub mod passage;
pub mod patch;
pub mod receptance;
pub mod reduced;
pub mod residual;
pub mod summary;

pub use summary::{PassageSummary, WavelengthComponent, WavelengthSpectrum};

use std::path::Path;

/// Errors of the passage. Each variant says what to change.
#[derive(Debug, thiserror::Error)]
pub enum DynamicsError {
    /// A rail profile file could not be read or is malformed.
    #[error("rail profile {path}: {reason}")]
    Profile {
        /// The file.
        path: String,
        /// What is wrong and what to change.
        reason: String,
    },
    /// The time step is too large for the highest mode kept.
    #[error("time step {dt_s:.3e} s is unstable for the highest mode ({f_max_hz:.0} Hz): the limit is {dt_limit_s:.3e} s; lower run.fmax or refine the contact grid (contact.grid_nx: the time step is grid dx / speed)")]
    UnstableTimeStep {
        /// The time step (s).
        dt_s: f64,
        /// The highest natural frequency (Hz).
        f_max_hz: f64,
        /// The stable limit (s).
        dt_limit_s: f64,
    },
    /// The contact solver failed at a step.
    #[error("contact solver at t = {t_s:.6} s (x = {x_m:.4} m): {source} (model keys: contact.grid_margin sizes the grid around the static patch, contact.grid_nx/grid_ny its resolution)")]
    Contact {
        /// Time (s).
        t_s: f64,
        /// Contact position along the rail (m).
        x_m: f64,
        /// The contact error (says what to change).
        source: crate::contact::ContactError,
    },
    /// The passage diverged (non-finite state).
    #[error("the passage diverged at t = {t_s:.6} s (x = {x_m:.4} m): {what}; lower contact.grid_nx's time step (raise grid_nx) or run.fmax")]
    Diverged {
        /// Time (s).
        t_s: f64,
        /// Contact position (m).
        x_m: f64,
        /// What became non-finite.
        what: String,
    },
    /// The wheel left the rail: the contact force was zero at some steps, so the forces and
    /// the wear of the passage are not those of a rolling wheel.
    #[error("the wheel lost contact with the rail at t = {t_s:.6} s (x = {x_m:.4} m), {lost} of {steps} steps without contact: the forces and wear would be zero there, not a result; check vehicle.primary_stiffness (a soft suspension lets the wheel bounce off), vehicle.wheel_load and the rail profile's amplitude")]
    ContactLost {
        /// First time without contact (s).
        t_s: f64,
        /// Contact position then (m).
        x_m: f64,
        /// Steps without contact.
        lost: usize,
        /// Steps of the passage.
        steps: usize,
    },
    /// Any other failure of the passage (message says what to change).
    #[error("{0}")]
    Other(String),
}

/// A rail-top height profile along the rail: `height_m[i]` at `x_m[i]`, ascending `x`
/// (global track coordinate, m). Heights are positive up (a crest reduces the gap to the
/// wheel). Between samples the height is interpolated linearly; outside it is zero.
#[derive(Clone, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct RailProfile {
    /// Positions along the rail (m), strictly ascending.
    pub x_m: Vec<f64>,
    /// Rail-top height (m), positive up.
    pub height_m: Vec<f64>,
}

impl RailProfile {
    /// Peak-to-trough height of the profile (m): max − min of the tabulated heights.
    pub fn peak_to_trough_m(&self) -> f64 {
        let (lo, hi) = self
            .height_m
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        if hi >= lo {
            hi - lo
        } else {
            0.0
        }
    }

    /// A profile from samples; checks lengths, finiteness and ascending `x`.
    pub fn new(x_m: Vec<f64>, height_m: Vec<f64>) -> Result<Self, DynamicsError> {
        let bad = |reason: String| DynamicsError::Profile {
            path: "<memory>".into(),
            reason,
        };
        if x_m.len() != height_m.len() {
            return Err(bad(format!(
                "{} positions but {} heights",
                x_m.len(),
                height_m.len()
            )));
        }
        if x_m.len() < 2 {
            return Err(bad("need at least two samples".into()));
        }
        if let Some(i) = (0..x_m.len()).find(|&i| !x_m[i].is_finite() || !height_m[i].is_finite()) {
            return Err(bad(format!("sample {i} is not a finite number")));
        }
        if let Some(i) = (1..x_m.len()).find(|&i| x_m[i] <= x_m[i - 1]) {
            return Err(bad(format!(
                "x must be strictly ascending; sample {i} (x = {} m) is not",
                x_m[i]
            )));
        }
        Ok(Self { x_m, height_m })
    }

    /// Reads a CSV file with a header line and two columns: `x` in m and the rail-top
    /// height in µm (the unit users measure corrugation in), converted here to m. A numeric
    /// first line is an error (a file without a header would lose its first row).
    pub fn read_csv_um(path: &Path) -> Result<Self, DynamicsError> {
        let err = |reason: String| DynamicsError::Profile {
            path: path.display().to_string(),
            reason,
        };
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(path)
            .map_err(|e| err(e.to_string()))?;
        let header = rdr.headers().map_err(|e| err(e.to_string()))?;
        if header.len() >= 2 && header.iter().take(2).all(|f| f.parse::<f64>().is_ok()) {
            return Err(err(format!(
                "the first line `{}` is numbers, not a header: add a header line `x_m, height_um` (without one the first row would be lost)",
                header.iter().collect::<Vec<_>>().join(", ")
            )));
        }
        let (mut xs, mut hs) = (Vec::new(), Vec::new());
        for (line, rec) in rdr.records().enumerate() {
            let rec = rec.map_err(|e| err(e.to_string()))?;
            if rec.len() < 2 {
                return Err(err(format!(
                    "data row {} has {} column(s); expected `x_m, height_um`",
                    line + 1,
                    rec.len()
                )));
            }
            let parse = |s: &str, what: &str| {
                s.parse::<f64>().map_err(|_| {
                    err(format!(
                        "data row {}: {what} `{s}` is not a number",
                        line + 1
                    ))
                })
            };
            xs.push(parse(&rec[0], "x (m)")?);
            hs.push(crate::units::um_to_m(parse(&rec[1], "height (µm)")?));
        }
        Self::new(xs, hs).map_err(|e| match e {
            DynamicsError::Profile { reason, .. } => err(reason),
            other => other,
        })
    }

    /// Height (m) at `x` (m): linear interpolation, zero outside the sampled range.
    pub fn height_at(&self, x: f64) -> f64 {
        let n = self.x_m.len();
        if n < 2 || x < self.x_m[0] || x > self.x_m[n - 1] {
            return 0.0;
        }
        let i = self.x_m.partition_point(|&xi| xi <= x).clamp(1, n - 1);
        let (x0, x1) = (self.x_m[i - 1], self.x_m[i]);
        let t = (x - x0) / (x1 - x0);
        self.height_m[i - 1] * (1.0 - t) + self.height_m[i] * t
    }
}

/// Anything that produces full passage records (histories, wear) of one model: the
/// reduced-order engine and the explicit FE path. The growth procedure takes it, so that
/// trial corrugations run on either engine.
pub trait PassageRecorder: Sync {
    /// One passage at `speed_m_per_s` (m/s) over `profile` (`None` = smooth rail), without
    /// the energy ledger or the rail-point record.
    fn record(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
    ) -> Result<passage::PassageRecord, DynamicsError>;

    /// Hertz semi-axis across the rail at the static load (m): the width the wear is spread
    /// over in the iterative growth.
    fn hertz_b_m(&self) -> f64;
}

impl PassageRecorder for passage::PassageEngine {
    fn record(
        &self,
        speed_m_per_s: f64,
        profile: Option<&RailProfile>,
    ) -> Result<passage::PassageRecord, DynamicsError> {
        let quiet = passage::PassageOptions {
            energy: false,
            rail_point_offset_m: None,
        };
        self.passage(speed_m_per_s, profile, &quiet, None)
    }

    fn hertz_b_m(&self) -> f64 {
        passage::PassageEngine::hertz_b_m(self)
    }
}

/// Runs passages of one prepared model (modal basis built once) at any speed over any rail
/// profile. The reduced-order engine implements it; the sweeps and studies take it so that
/// their logic is tested with cheap stand-ins.
pub trait PassageRunner: Sync {
    /// One passage at `speed_kmh` (km/h) over the rail profile (`None` = smooth rail).
    fn run(
        &self,
        speed_kmh: f64,
        profile: Option<&RailProfile>,
    ) -> Result<PassageSummary, DynamicsError>;

    /// The prepared reduced-order model behind this runner, if it is one (lets the growth
    /// procedure reuse the loaded modal bases instead of loading them again).
    fn prepared(&self) -> Option<&passage::PreparedModel> {
        None
    }
}

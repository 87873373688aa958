//! What a wheel passage is, whichever engine runs it (the reduced-order engine in
//! [`crate::dynamics`], the explicit FE path in [`crate::explicit`]): the runner and recorder
//! traits, the rail profile the wheel rolls over, the records and their summary analysis, the
//! contact line and frame on the rail and the wheel and the spreading of the contact force over
//! node planes, the static stiffness factorisation both engines start from, and the passage's
//! error type.
//!
//! - [`PassageRunner`]: runs passages of one model at any speed over any rail profile and
//!   summarises them (sweeps and studies take it; tests use cheap stand-ins).
//! - [`PassageRecorder`]: produces full passage records (histories, wear): the growth
//!   procedure takes it, so trial corrugations run on either engine.
//! - [`RailProfile`]: a rail-top height profile along the rail (the corrugation).
//! - [`record`], [`summary`], [`analysis`]: the passage's histories and wear, what it reports
//!   to growth, sweeps and studies, and the analysis between them (docs/theory.md §7.8, §9).
//! - [`planes`]: a load's spread over the rail's node planes (docs/theory.md §7.3).
//!
//! Assumptions: SI units throughout; the rail profile's heights are positive up.

// Numerical kernels index several parallel arrays with one loop index.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod contact_line;
pub mod fe_patch;
pub mod free_body;
pub mod planes;
pub mod record;
pub mod setup;
pub mod statics;
pub mod summary;

pub use summary::{PassageSummary, WavelengthComponent, WavelengthSpectrum};

use std::path::Path;

use crate::units::Speed;

/// Errors of the passage. Each variant says what to change.
#[derive(Debug, thiserror::Error)]
pub enum PassageError {
    /// A rail profile file could not be read or is malformed.
    #[error("rail profile {path}: {reason}")]
    Profile {
        /// The file.
        path: String,
        /// What is wrong and what to change.
        reason: String,
    },
    /// A rail profile that lies entirely off the rail the passage's contact passes over: it
    /// would change nothing but the contact grid.
    #[error("rail profile: its samples span x = {:.4} … {:.4} m, entirely off the rail the wheel's contact passes over in the passage, x = {:.4} … {:.4} m (the wheel's travel from its start through the solution zone, ± the contact grid's half-length); give the profile in track coordinates over that stretch", profile_m[0], profile_m[1], travel_m[0], travel_m[1])]
    ProfileOffTravel {
        /// First and last sample of the profile (m).
        profile_m: [f64; 2],
        /// The rail under the contact grid during the passage (m).
        travel_m: [f64; 2],
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
    /// The contact patch still reached the boundary of the contact grid after the passage
    /// was rerun on the widest grid [`setup::run_widening_grid`] tries.
    #[error("the contact patch still reaches the contact grid's boundary ({edge}) after the passage was rerun on grids widened {widenings} times (by 1.25 each) along it: {reason}")]
    GridOutgrown {
        /// Widenings tried along that edge's direction (−).
        widenings: u32,
        /// The edge reached (`"x"` or `"y"`).
        edge: &'static str,
        /// The last passage's error, with the model keys to change.
        reason: String,
    },
    /// A rail profile so deep that the contact grid lengthened for it
    /// ([`setup::grid_for_profile`]) is beyond `setup::MAX_PROFILE_GRID_WORK`.
    #[error("a rail profile of peak-to-trough {ptp_um} µm needs a contact grid of {nx:.3e} × {ny} elements (about {memory_gb:.3} GB and {work_ratio:.3e} times the default 32 × 24 grid's passage time; at most {limit_ratio:.0} times): corrugation is tens to hundreds of µm peak-to-trough (heights in µm)")]
    ProfileGrid {
        /// The profile's peak-to-trough (µm).
        ptp_um: f64,
        /// Elements along x the profile needs (−; a float: it may exceed any index).
        nx: f64,
        /// Elements across (−).
        ny: usize,
        /// Estimated memory of the grid (GB).
        memory_gb: f64,
        /// Estimated passage work over the default grid's (−).
        work_ratio: f64,
        /// The largest accepted work ratio (−).
        limit_ratio: f64,
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
    /// The caller stopped the passage ([`crate::progress::Progress::cancelled`]).
    #[error(transparent)]
    Cancelled(#[from] crate::progress::Cancelled),
    /// Building the track or the wheel substructure failed.
    #[error(transparent)]
    Structure(#[from] crate::structure::StructureError),
    /// Assembling or expanding the FE matrices and vectors failed.
    #[error(transparent)]
    Fe(#[from] crate::fe::FeError),
    /// The band-pass, PSD or peak search of a record failed.
    #[error(transparent)]
    Spectral(#[from] crate::spectral::SpectralError),
    /// The static Hertz contact under the wheel load failed.
    #[error("static Hertz contact: {0}")]
    StaticHertz(#[source] crate::contact::ContactError),
    /// The fe-patch of a contact grid would need more memory than the machine has; refused
    /// before it is built.
    #[error("contact.influence = \"fe-patch\" on a {nx} x {ny} contact grid: its submodels would need about {gb:.1} GB, {dofs} DOFs and {seconds:.0} s, {reason}: coarsen the grid (contact.grid_nx, contact.grid_ny; a larger contact.grid_margin makes the elements larger) or use contact.influence = \"half-space\"")]
    FePatchTooLarge {
        /// Grid elements along x.
        nx: usize,
        /// Grid elements across.
        ny: usize,
        /// Estimated peak memory (GB).
        gb: f64,
        /// Free DOFs of the larger submodel.
        dofs: usize,
        /// Estimated wall time (s).
        seconds: f64,
        /// Which bound it exceeds.
        reason: String,
    },
    /// The transient contact grid of the passage could not be set up.
    #[error("contact grid: {0}")]
    ContactGrid(#[source] crate::contact::ContactError),
    /// The sparse LDLᵀ of the track stiffness (residual flexibility, static checks) failed.
    #[error("sparse LDLᵀ of the track stiffness failed: {0}; the track must be supported (ballast stiffness > 0)")]
    StiffnessFactor(#[source] crate::eigen::EigenError),
    /// The track stiffness is singular or indefinite.
    #[error("the track stiffness is not positive definite ({negative_pivots} negative pivots, smallest relative pivot {min_rel_pivot:e}): the track must be supported in every direction (ballast.*_stiffness > 0, and the rail held by the railpad springs fastening.*_stiffness or the fastening's holds, fastening.hold_stiffness)")]
    StiffnessIndefinite {
        /// Negative pivots of the LDLᵀ.
        negative_pivots: usize,
        /// Smallest |pivot| relative to the largest (0 for a zero pivot).
        min_rel_pivot: f64,
    },
    /// A numeric argument outside its range.
    #[error("{name} = {value} is out of range: it must be {expected}")]
    OutOfRange {
        /// What the value is (with its unit).
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range.
        expected: &'static str,
    },
    /// A point outside the rail's node planes.
    #[error("{what} x = {x_m:.4} m is off the rail [{start_m:.3}, {end_m:.3}] m: lengthen the track (track.bays)")]
    OffRail {
        /// Which point (contact point, wheel start, …).
        what: &'static str,
        /// Position (m).
        x_m: f64,
        /// First node plane (m).
        start_m: f64,
        /// Last node plane (m).
        end_m: f64,
    },
    /// A mesh without the nodes a passage needs (running surface, journals, contact line).
    #[error("the mesh has no {what}")]
    MissingNodes {
        /// Which nodes.
        what: &'static str,
    },
    /// The journal nodes lie on the axle axis: no lever arm for the driving torque.
    #[error("journal nodes on the axle axis: cannot apply the driving torque")]
    JournalsOnAxis,
    /// The solution zone is too short for a spectrum.
    #[error(
        "the solution zone holds {steps} steps, fewer than 8: lengthen run.solution_zone_length"
    )]
    SolutionZoneTooShort {
        /// Steps in the zone.
        steps: usize,
    },
    /// A passage engine built on this module (the explicit FE path) failed.
    #[error("{engine} passage: {source}")]
    Engine {
        /// Which engine.
        engine: &'static str,
        /// Its error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The wheel's stiffness pattern could not be copied to hold it for its static flexibility
    /// (out of memory).
    #[error("the wheel's held stiffness for its static flexibility: {source}")]
    WheelStiffnessCopy {
        /// faer's error.
        #[source]
        source: faer::sparse::FaerError,
    },
    /// An error of the engine that ran the passage, outside this floor's (e.g. the reduced
    /// engine's residual flexibility), shown as that engine words it.
    #[error(transparent)]
    Specific(Box<dyn std::error::Error + Send + Sync>),
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

    /// Peak-to-trough height (m) of the profile on the stretch `[a, b]` (m) of the rail: of
    /// its samples inside it and its interpolated heights at `a` and `b` when they lie within
    /// the samples. On a stretch that holds every sample it is [`Self::peak_to_trough_m`].
    pub(crate) fn peak_to_trough_within_m(&self, [a, b]: [f64; 2]) -> f64 {
        let n = self.x_m.len();
        if n == 0 {
            return 0.0;
        }
        let inside = |x: f64| x >= self.x_m[0] && x <= self.x_m[n - 1];
        let ends = [a, b]
            .into_iter()
            .filter(|&x| inside(x))
            .map(|x| self.height_at(x));
        let (lo, hi) = self
            .x_m
            .iter()
            .zip(&self.height_m)
            .filter(|(x, _)| (a..=b).contains(*x))
            .map(|(_, h)| *h)
            .chain(ends)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            });
        if hi >= lo {
            hi - lo
        } else {
            0.0
        }
    }

    /// A profile from samples; checks lengths, finiteness and ascending `x`.
    pub fn new(x_m: Vec<f64>, height_m: Vec<f64>) -> Result<Self, PassageError> {
        let bad = |reason: String| PassageError::Profile {
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
        if let Some(reason) = crate::lists::strictly_ascending_error(&x_m) {
            return Err(bad(reason));
        }
        Ok(Self { x_m, height_m })
    }

    /// Reads a CSV file with a header line and two columns: `x` in m and the rail-top
    /// height in µm (the unit users measure corrugation in), converted here to m. A numeric
    /// first line is an error (a file without a header would lose its first row).
    pub fn read_csv_um(path: &Path) -> Result<Self, PassageError> {
        let err = |reason: String| PassageError::Profile {
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
            PassageError::Profile { reason, .. } => err(reason),
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
    /// One passage at `speed` over `profile` (`None` = smooth rail), without the energy
    /// ledger or the rail-point record.
    fn record(
        &self,
        speed: Speed,
        profile: Option<&RailProfile>,
    ) -> Result<record::PassageRecord, PassageError>;

    /// Hertz semi-axis across the rail at the static load (m): the width the wear is spread
    /// over in the iterative growth.
    fn hertz_b_m(&self) -> f64;
}

/// Runs passages of one prepared model (modal basis built once) at any speed over any rail
/// profile. The reduced-order engine implements it; the sweeps and studies take it so that
/// their logic is tested with cheap stand-ins.
pub trait PassageRunner: Sync {
    /// One passage at `speed` over the rail profile (`None` = smooth rail); the summary's
    /// `speed_kmh` is `speed.kmh()` exactly.
    fn run(
        &self,
        speed: Speed,
        profile: Option<&RailProfile>,
    ) -> Result<PassageSummary, PassageError>;
}

impl<T: PassageRunner + ?Sized> PassageRunner for Box<T> {
    fn run(
        &self,
        speed: Speed,
        profile: Option<&RailProfile>,
    ) -> Result<PassageSummary, PassageError> {
        (**self).run(speed, profile)
    }
}

/// What a passage records besides the wear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassageOptions {
    /// Keep the energy balance (O(modes) per step: the damper power comes with the
    /// integrator's implicit solve).
    pub energy: bool,
    /// Distance after the solution-zone start of the rail-top node whose displacement is
    /// recorded (m); `None` = no rail-point record. Default 0.6 m.
    pub rail_point_offset_m: Option<f64>,
    /// Run the track's implicit damping product on a second core beside the contact step
    /// (the reduced engine's `dynamics::passage::overlap`; for a passage that runs alone: it adds the damping products of
    /// the node planes the contact crosses, about a third more of that product's CPU; the
    /// second thread waits by spinning for at most 1 ms, then parks, and the passage falls
    /// back to one thread while the machine is oversubscribed, `dynamics::passage::spin`; it is used
    /// when the thread pool has at least two threads, e.g. not with `RAYON_NUM_THREADS=1`).
    /// The results do not depend on the thread count, and differ from those without it by
    /// the rounding of the split single-precision products. Default `false` (sweeps and
    /// studies, whose passages already fill the cores).
    pub overlap: bool,
}

impl Default for PassageOptions {
    fn default() -> Self {
        Self {
            energy: true,
            rail_point_offset_m: Some(0.6),
            overlap: false,
        }
    }
}

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

pub mod compliance;
pub mod coupled;
pub mod integrator;
pub mod passage;
pub mod prepared;
pub mod receptance;
pub mod reduced;
pub mod residual;
pub mod wheel_residual;

// What a passage is lives in the floor beneath both engines; these keep the reduced engine's
// paths.
pub use crate::passage::planes as patch;
pub use crate::passage::{analysis, fe_patch, record, setup, summary};
pub use crate::passage::{
    PassageError, PassageRecorder, PassageRunner, PassageSummary, RailProfile, WavelengthComponent,
    WavelengthSpectrum,
};

/// Errors of the reduced engine: a passage's ([`PassageError`], shown as it is) or the
/// engine's own (modal bases, residual flexibility, receptances, coupled modes). Each variant
/// says what to change.
#[derive(Debug, thiserror::Error)]
pub enum DynamicsError {
    /// An error of the passage, whichever engine runs it.
    #[error(transparent)]
    Passage(#[from] PassageError),
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
    /// The modal basis (eigenmodes, classification, cache) of a substructure failed.
    #[error(transparent)]
    Basis(#[from] crate::eigen::basis::BasisError),
    /// A mode shape or displacement could not be classified.
    #[error(transparent)]
    Classify(#[from] crate::eigen::classify::ClassifyError),
    /// Two inputs of different sizes that must match.
    #[error("{what}: {found} given, {expected} expected")]
    SizeMismatch {
        /// Which inputs (and what to change).
        what: &'static str,
        /// The size given.
        found: usize,
        /// The size required.
        expected: usize,
    },
    /// A modal basis whose shape does not fit the model.
    #[error("modal basis is {rows}×{cols} but there are {frequencies} frequencies and {dofs} DOFs: the cached modes do not belong to this model; clear the cache entry")]
    BasisShape {
        /// Rows of the mode matrix.
        rows: usize,
        /// Columns of the mode matrix.
        cols: usize,
        /// Frequencies given.
        frequencies: usize,
        /// Free DOFs of the substructure.
        dofs: usize,
    },
    /// A track mode at zero frequency: the track floats.
    #[error("track mode {mode} has ω² = {omega2_rad2_s2} rad²/s² (a rigid-body mode): the track must be supported in every direction (ballast.*_stiffness > 0, and the rail held by the railpad springs fastening.*_stiffness or the fastening's holds, fastening.hold_stiffness)")]
    TrackNotSupported {
        /// Index of the mode.
        mode: usize,
        /// Its eigenvalue (rad²/s²).
        omega2_rad2_s2: f64,
    },
    /// I + Δt/2·C of the modal integrator is not positive definite.
    #[error("I + Δt/2·C is not positive definite: the damping matrix has negative eigenvalues; check the damper inputs")]
    DampingIndefinite(#[source] faer::linalg::cholesky::llt::factor::LltError),
    /// The receptance at a frequency is singular.
    #[error("receptance at {frequency_hz} Hz is singular: the frequency coincides with an undamped (or rigid-body) mode; shift the frequency grid")]
    SingularReceptance {
        /// The frequency (Hz).
        frequency_hz: f64,
    },
    /// A point outside the rail stretch a residual flexibility was computed for.
    #[error("residual flexibility: x = {x_m:.4} m is outside the covered part of the rail [{start_m:.3}, {end_m:.3}] m (computed for the passage's travel; recompute for this range)")]
    OutsideResidual {
        /// Position (m).
        x_m: f64,
        /// First covered plane (m).
        start_m: f64,
        /// Last covered plane (m).
        end_m: f64,
    },
    /// A residual flexibility computed for another engine.
    #[error("residual flexibility of {modes} modes over [{start_m:.3}, {end_m:.3}] m does not fit the engine ({engine_modes} track modes, travel [{travel_start_m:.3}, {travel_end_m:.3}] m): recompute it")]
    ResidualMismatch {
        /// Modes it was computed for.
        modes: usize,
        /// First covered plane (m).
        start_m: f64,
        /// Last covered plane (m).
        end_m: f64,
        /// Track modes of the engine.
        engine_modes: usize,
        /// Start of the engine's travel (m).
        travel_start_m: f64,
        /// End of the engine's travel (m).
        travel_end_m: f64,
    },
    /// A residual flexibility record with inconsistent plane data.
    #[error("residual flexibility: inconsistent plane data (clear the modal cache entry)")]
    ResidualPlanes,
    /// A residual flexibility below its modal part: modes and stiffness do not belong together.
    #[error("residual flexibility at plane x = {x_m:.4} m, direction {direction}: FE {fe_m_per_n:.4e} m/N < modal {modal_m_per_n:.4e} m/N: the modes do not belong to this stiffness (clear the modal cache entry)")]
    ResidualBelowModal {
        /// Plane position (m).
        x_m: f64,
        /// Direction (0, 1, 2 = x, t, n of the contact frame).
        direction: usize,
        /// The FE flexibility (m/N).
        fe_m_per_n: f64,
        /// The modal flexibility (m/N).
        modal_m_per_n: f64,
    },
    /// The wheel's elastic static flexibility at the contact is not above its modal part.
    #[error("wheel residual flexibility, direction {direction}: FE {fe_m_per_n:.4e} m/N is not above the modal {modal_m_per_n:.4e} m/N: the wheel modes do not belong to this stiffness (clear the modal cache entry), the wheel's support is out of scale (vehicle.primary_stiffness) or run.wheel_residual_flexibility = false")]
    WheelResidualBelowModal {
        /// Direction (0, 1, 2 = x, t, n of the contact frame).
        direction: usize,
        /// The FE (elastic, inertia-relief) flexibility (m/N).
        fe_m_per_n: f64,
        /// The modal flexibility of the kept elastic modes (m/N).
        modal_m_per_n: f64,
    },
    /// The residual flexibility record could not be written or read back as JSON.
    #[error("residual flexibility record: {0}")]
    ResidualJson(#[from] serde_json::Error),
    /// A node plane index beyond the rail.
    #[error("node plane {plane} is out of range ({planes} planes)")]
    PlaneOutOfRange {
        /// The plane asked for.
        plane: usize,
        /// Planes of the rail.
        planes: usize,
    },
    /// A point of the static compliance check off the rail.
    #[error("longitudinal compliance: {what} at x = {x_m} m is off the rail (0 to {length_m} m)")]
    ComplianceOffRail {
        /// Which point (load, report point).
        what: &'static str,
        /// Position (m).
        x_m: f64,
        /// Track length (m).
        length_m: f64,
    },
    /// The linearised wheel–rail contact of the coupled modes is not usable.
    #[error("coupled modes: the contact linearisation is not usable: {reason}")]
    ContactLinearisation {
        /// Why, and what to change.
        reason: &'static str,
    },
    /// The dense eigensolver of the coupled wheel–track state matrix failed.
    #[error("coupled modes: the dense eigensolver failed ({error:?}); lower run.fmax to shrink the state matrix")]
    CoupledEigen {
        /// faer's error (not a `std::error::Error`, so a field, not a source).
        error: faer::linalg::evd::EvdError,
    },
}

impl DynamicsError {
    /// As a passage error for the engine-neutral traits: a passage's own error as it is, the
    /// engine's own wrapped unchanged in wording ([`PassageError::Specific`]).
    pub(crate) fn into_passage(self) -> PassageError {
        match self {
            DynamicsError::Passage(p) => p,
            other => PassageError::Specific(Box::new(other)),
        }
    }
}

/// The lower layers' errors a passage also raises reach the reduced engine through
/// [`PassageError`], so that each has one home.
macro_rules! via_passage {
    ($($t:ty),*) => {$(
        impl From<$t> for DynamicsError {
            fn from(e: $t) -> Self {
                DynamicsError::Passage(e.into())
            }
        }
    )*};
}
via_passage!(
    crate::progress::Cancelled,
    crate::structure::StructureError,
    crate::fe::FeError,
    crate::spectral::SpectralError
);

impl PassageRecorder for passage::PassageEngine {
    fn record(
        &self,
        speed: crate::units::Speed,
        profile: Option<&RailProfile>,
    ) -> Result<record::PassageRecord, PassageError> {
        let quiet = passage::PassageOptions {
            energy: false,
            rail_point_offset_m: None,
            overlap: false,
        };
        self.passage(speed.m_per_s(), profile, &quiet, None)
            .map_err(DynamicsError::into_passage)
    }

    fn hertz_b_m(&self) -> f64 {
        passage::PassageEngine::hertz_b_m(self)
    }
}

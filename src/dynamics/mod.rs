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
    PassageError as DynamicsError, PassageRecorder, PassageRunner, PassageSummary, RailProfile,
    WavelengthComponent, WavelengthSpectrum,
};

impl PassageRecorder for passage::PassageEngine {
    fn record(
        &self,
        speed: crate::units::Speed,
        profile: Option<&RailProfile>,
    ) -> Result<record::PassageRecord, DynamicsError> {
        let quiet = passage::PassageOptions {
            energy: false,
            rail_point_offset_m: None,
            overlap: false,
        };
        self.passage(speed.m_per_s(), profile, &quiet, None)
    }

    fn hertz_b_m(&self) -> f64 {
        passage::PassageEngine::hertz_b_m(self)
    }
}

//! The full explicit FE path: the wheel passage integrated on the untruncated `K`, `M`, `C` of
//! the same track and wheel substructures the reduced model is built from, to confirm or
//! refute the reduced model's frequency selection (docs/theory.md §8).
//!
//! - [`operator`]: the central-difference step of one substructure (lumped mass, lagged
//!   damper force, no numerical damping, state in f64).
//! - [`stable`]: the stable step, `Δt = safety · (2/ω_max)(√(1+ξ²) − ξ)`, with `ω_max` by
//!   Lanczos on `M^{-½}KM^{-½}` and Gershgorin's bound beside it.
//! - [`passage`]: the coupled passage. The track and the wheel are sub-cycled at their own
//!   stable steps inside the contact step `Δt_c = Δx/V` of the transient rolling contact; the
//!   coupling holds the last contact force over a contact step (predictor), solves the
//!   contact at the end of the step with the structures' one-step compliance as the series
//!   compliance, and corrects both structures by the response to the force change (exact:
//!   the FE is linear). Same static start, contact, wear accounting and analysis as the
//!   reduced passage, so the two differ only by what the reduced model approximates.
//!
//! - [`audit`]: the energy audit, a replay of every contact step that sums the nodal work as
//!   the central difference defines it, against which the passage's energy ledger is checked.
//! - [`rotating`]: the rotating wheel (`explicit.wheel = "rotating"`): its elastic motion in
//!   a frame spinning at `V/R` with the Coriolis and spin-softening terms, the contact point
//!   moving around the tread.
//!
//! Assumptions: small displacements (linear FE); by default the wheel is not rotating (its
//! contact point is fixed on the wheel, as in the reduced model).

// Numerical kernels index several parallel arrays with one loop index.
#![allow(clippy::needless_range_loop)]

pub mod audit;
pub mod contact_step;
pub mod coupling;
pub mod estimate;
mod ledger;
mod local;
pub mod model;
pub mod operator;
pub mod passage;
mod response;
pub mod rotating;
pub mod stable;
mod start;

pub use model::{ExplicitModel, ExplicitOptions};
pub use operator::ExplicitOperator;
pub use passage::{ExplicitRecord, ExplicitRunner};
pub use stable::StableStep;

/// Errors of the explicit path. Each variant says what to change.
#[derive(Debug, thiserror::Error)]
pub enum ExplicitError {
    /// A matrix does not have the operator's size.
    #[error(
        "matrix {what} is {rows}×{cols}, expected {n}×{n}: assemble K, M and C of one substructure"
    )]
    Shape {
        /// Which matrix.
        what: &'static str,
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
        /// The expected size.
        n: usize,
    },
    /// More DOFs than 32-bit indices hold.
    #[error("{dofs} DOFs exceed the explicit operator's 32-bit indices: coarsen the mesh (mesh.element_length, mesh.section_size)")]
    TooLarge {
        /// DOFs.
        dofs: usize,
    },
    /// A DOF without mass: the central difference needs a positive lumped mass everywhere.
    #[error("free DOF {dof} has lumped mass {mass_kg:e} kg: the explicit path needs mass at every free DOF (check the densities)")]
    Massless {
        /// The DOF (free index).
        dof: usize,
        /// Its lumped mass (kg).
        mass_kg: f64,
    },
    /// The ω_max estimate failed.
    #[error("the estimate of the highest natural frequency is {omega2:e} 1/s²: the stiffness matrix is empty or not finite")]
    NoStableStep {
        /// The estimate (1/s²).
        omega2: f64,
    },
    /// The user's time step is above `explicit.safety` × the computed critical step.
    #[error("explicit.time_step = {given_s:.4e} s is above the allowed step {limit_s:.4e} s of the {part} (explicit.safety = {safety} × its critical step {critical_s:.4e} s, ω_max ≈ {omega_max:.4e} rad/s): lower explicit.time_step, raise explicit.safety (at most 1), or leave explicit.time_step out (the step is then computed)")]
    TimeStepTooLarge {
        /// The user's step (s).
        given_s: f64,
        /// The allowed step, `safety × critical_s` (s).
        limit_s: f64,
        /// The safety factor (−).
        safety: f64,
        /// The critical step from the `ω_max` estimate (s).
        critical_s: f64,
        /// Which substructure.
        part: &'static str,
        /// The estimated ω_max (rad/s).
        omega_max: f64,
    },
    /// The passage's estimated time is beyond
    /// [`estimate::MAX_EXPLICIT_SECONDS`] ([`estimate::ExplicitEstimate`]).
    #[error("{key} = {value}: the explicit passage would take {estimate}, beyond the bound of {limit_h:.0} h; {advice}")]
    TooLong {
        /// The model key that drives the work (`explicit.time_step`, `run.speed_kmh`).
        key: &'static str,
        /// Its value, with its unit.
        value: String,
        /// The estimate, with its basis.
        estimate: String,
        /// The bound (h).
        limit_h: f64,
        /// What to change.
        advice: &'static str,
    },
    /// A static solve failed.
    #[error("static start of the {part}: {reason}")]
    Static {
        /// Which substructure.
        part: &'static str,
        /// What failed and what to change.
        reason: String,
    },
    /// The passage diverged.
    #[error("the explicit passage diverged at t = {t_s:.6} s (x = {x_m:.4} m): the {part}'s state is not finite; lower explicit.safety or set a smaller explicit.time_step")]
    Diverged {
        /// Time (s).
        t_s: f64,
        /// Contact position (m).
        x_m: f64,
        /// Which substructure.
        part: &'static str,
    },
    /// The contact patch's node-plane weights could not be formed.
    #[error(transparent)]
    Patch(#[from] crate::dynamics::patch::PatchError),
    /// The rotating wheel cannot be set up.
    #[error("rotating wheel (explicit.wheel = \"rotating\")")]
    Rotating(#[from] rotating::SpinError),
    /// An error of the shared passage machinery (contact, profile, structure).
    #[error(transparent)]
    Dynamics(#[from] crate::dynamics::DynamicsError),
    /// The caller's progress asked the passage to stop ([`crate::progress::Progress::cancelled`]).
    #[error(transparent)]
    Cancelled(#[from] crate::progress::Cancelled),
    /// The model's structures could not be built.
    #[error(transparent)]
    Structure(#[from] crate::structure::StructureError),
}

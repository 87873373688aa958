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
pub mod penalty;
mod response;
pub mod rotating;
pub mod stable;
mod start;

#[cfg(test)]
mod penalty_tests;

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
    /// `estimate::MAX_EXPLICIT_SECONDS` ([`estimate::ExplicitEstimate`]).
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
    /// `contact.influence = "fe-patch"` asked of the explicit engine.
    #[error("contact.influence = \"fe-patch\": not available on the explicit engine (its contact sees only the structures' one-step compliance, beside which the fe-patch's split, a negative uniform compliance of the global mesh's local share, is not positive definite; docs/theory.md §6.9): run the reduced engine, or set contact.influence = \"half-space\"")]
    FePatch,
    /// `explicit.safety` out of its range.
    #[error("explicit.safety = {safety} is out of range: allowed above 0, at most 1 (the fraction of the critical step used)")]
    Safety {
        /// The value given (−).
        safety: f64,
    },
    /// A rigid-body mode of the wheel has no mass after orthogonalisation (the wheel's lumped
    /// masses are zero where the mode moves).
    #[error("rigid-body mode {mode} of the {part} has no mass: check the wheel's density (wheel.density)")]
    RigidModeMassless {
        /// `wheel` or `wheel body` (sprung mass removed).
        part: &'static str,
        /// The mode's index (0–2: x, z translations, rotation about y).
        mode: usize,
    },
    /// A rigid-body mode of the wheel is resisted by its supports: the explicit path's
    /// rigid-mode model of the static start does not hold.
    #[error("rigid mode {mode} of the wheel is not free (relative elastic force {relative_force:.2e}): the wheel's supports are not those of the explicit path's rigid-mode model")]
    RigidModeNotFree {
        /// The mode's index.
        mode: usize,
        /// `‖M^{-½} K φ‖ / ω_bound²` of the M-normalised mode (−); above 1e-6 is refused.
        relative_force: f64,
    },
    /// The wheel's contact node has its x or z DOF held.
    #[error("the wheel's contact node has its x or z DOF held: the static start needs them free (check the wheel's supports)")]
    ContactNodeHeld,
    /// The wheel's stiffness has no stored diagonal entry at a support DOF (an assembly
    /// inconsistency: the assembled pattern always holds the diagonal).
    #[error("the wheel's stiffness has no stored diagonal entry at support DOF {dof} (free index): an assembly inconsistency, please report it")]
    MissingDiagonal {
        /// The DOF (free index).
        dof: usize,
    },
    /// The wheel's static stiffness (with its supports doubled) could not be factorised.
    #[error("static start of the wheel: its stiffness with the supports doubled")]
    WheelStaticFactor(#[source] crate::passage::PassageError),
    /// The rotating wheel's local tread compliance at the start angle is missing (an
    /// internal inconsistency of the rotating wheel's set-up).
    #[error("rotating wheel: the tread's local compliance at θ = 0 was not computed")]
    LocalComplianceMissing,
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
    Patch(#[from] crate::passage::planes::PatchError),
    /// The rotating wheel cannot be set up.
    #[error("rotating wheel (explicit.wheel = \"rotating\")")]
    Rotating(#[from] rotating::SpinError),
    /// An error of the shared passage machinery (contact, profile, structure).
    #[error(transparent)]
    Passage(#[from] crate::passage::PassageError),
    /// The caller's progress asked the passage to stop ([`crate::progress::Progress::cancelled`]).
    #[error(transparent)]
    Cancelled(#[from] crate::progress::Cancelled),
    /// The model's structures could not be built.
    #[error(transparent)]
    Structure(#[from] crate::structure::StructureError),
    /// The penalty contact's static start or its Kalker reference failed ([`penalty`]).
    #[error("penalty contact")]
    Contact(#[from] crate::contact::ContactError),
}

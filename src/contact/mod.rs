//! Wheel–rail rolling contact: Hertz closed form, a non-Hertzian normal solver on an
//! elastic half-space grid, Kalker's exact (transient and steady) tangential theory with
//! Coulomb friction, and the frictional work that drives wear.
//!
//! # Model and assumptions
//! * Both bodies are linear elastic half-spaces treated as "quasi-identical": the normal and
//!   tangential problems decouple (Kalker 1990, §1.4; Johnson 1985, §5.4). A wheel and rail
//!   of different steels enter through Kalker's combined constants
//!   ([`quasi_identical_pair`]), which keep Hertz's combined modulus exact.
//! * The potential contact area is a rectangular grid of `nx × ny` elements, uniform pressure
//!   and traction per element, displacements collocated at element centres (Kalker's
//!   "piecewise constant" discretisation, the one of CONTACT). Influence coefficients are the
//!   closed-form integrals of the Boussinesq (normal) and Cerruti (tangential) point-load
//!   solutions over a rectangle (Love 1929; Johnson 1985, eqs. 3.22, 3.86–3.87), see
//!   [`influence`]. Influence products are cyclic FFT convolutions on a zero-padded grid.
//! * Normal problem: p ≥ 0, gap ≥ 0, p·gap = 0, solved by the Polonsky–Keer (1999)
//!   constrained conjugate-gradient method, see [`normal`].
//! * Tangential problem: Coulomb friction with coefficient µ, per element
//!   |τ| ≤ µp; stick (|τ| < µp) ⇒ slip s = 0; slip ⇒ τ = −µp s/|s|. Each time step is a
//!   convex programme solved by an active-set method whose inner conjugate gradients also
//!   turn the slip directions (a Newton step on the circles), with Kalker's element test for
//!   state changes (FISTA as fallback), see [`tangential`]. Steady rolling is the
//!   fixed point of the transient map.
//!
//! # Sign conventions (defined once, here)
//! * Contact frame: `x` along the rail in the direction of travel, `y` lateral, origin at the
//!   nominal contact centre. The wheel moves in `+x` at speed `V`; in the contact frame the
//!   material of both bodies flows in `−x` (leading edge at `+x`).
//! * Tractions `τ = (τx, τy)` (Pa) and forces `Fx, Fy` (N) are those **acting on the wheel**
//!   (exerted by the rail). `Fx > 0` pushes the wheel forward (traction / driving).
//! * Creepages (dimensionless, spin in 1/m) are the rigid slip of the wheel relative to the rail
//!   divided by `V`: `ξ = (V − ωR + v_rail,x)/V` where `v_rail,x` is a rail surface velocity
//!   term the caller includes (a rail surface moving forward at the contact reduces the
//!   wheel's slip relative to it: pass `ξ = (V − ωR − v_rail,x)/V`), `η` lateral, `φ` spin.
//!   The rigid slip per unit rolling distance is `w = (ξ − φ y, η + φ x)`.
//! * Slip velocity (m/s) of the wheel surface relative to the rail surface:
//!   `s = V w + Du/Dt`, with `u = u_wheel − u_rail` the elastic displacement difference and
//!   `D/Dt = ∂/∂t − V ∂/∂x` the material derivative.
//! * With these conventions `Fx = −G c² C11 ξ` for small ξ (Kalker): **a positive creepage
//!   (braking, wheel slower than rolling) gives a negative (retarding) force on the wheel**.
//!   A driving torque (traction coefficient `+0.15`) needs a negative ξ.
//! * Frictional power (W) dissipated: `P = −∫ τ·s dA ≥ 0`; for steady rolling
//!   `P = −V (ξ Fx + η Fy + φ Mz)` with `Mz = ∫ (x τy − y τx) dA`.
//!
//! # References
//! * J.J. Kalker, *Three-dimensional elastic bodies in rolling contact*, Kluwer 1990
//!   (ch. 1–2 the exact theory; table of creep coefficients, Table E3).
//! * K.L. Johnson, *Contact Mechanics*, CUP 1985, ch. 4 (Hertz), 7 (Cattaneo–Mindlin),
//!   8 (Carter, rolling).
//! * I.A. Polonsky, L.M. Keer, Wear 231 (1999) 206–219 (CG normal solver).
//! * E.A.H. Vollebregt, CONTACT user guide (transient rolling discretisation).
//! * A.E.H. Love, Phil. Trans. R. Soc. A 228 (1929) 377–420.

// Numerical kernels index several parallel arrays with one loop index.
#![allow(clippy::needless_range_loop)]

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
#[cfg(target_arch = "x86_64")]
mod column_sums;
pub mod hertz;
pub mod influence;
pub mod normal;
pub mod penalty;
pub mod report;
pub mod rolling;
pub mod tangential;
pub mod transient;
pub mod wear;

pub use hertz::{HertzContact, HertzInput};
pub use report::{solve_case, ContactCase, ContactSolution, ContactSummary, TangentialLoading};
pub use rolling::{
    GridSpec, HertzGridParams, Longitudinal, NormalInput, StepInputs, StepResult, TransientConfig,
};
pub use tangential::TangentialAlgorithm;
pub use transient::TransientRolling;
pub use wear::{load_response_curve, LoadResponsePoint, WearAccumulator};

/// Errors of the contact module. Each variant says what to change.
#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    /// A parameter is out of its physical range.
    #[error("invalid contact parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
    /// An input array has the wrong length.
    #[error("input `{name}` has length {got}, expected {expected} (one value per grid {per})")]
    WrongLength {
        /// Input name.
        name: &'static str,
        /// Length given.
        got: usize,
        /// Length expected.
        expected: usize,
        /// What one value corresponds to.
        per: &'static str,
    },
    /// An iterative solver did not converge.
    #[error("{solver} did not converge in {iterations} iterations (residual {residual:e}); refine tolerance or increase max_iterations")]
    NotConverged {
        /// Which solver.
        solver: &'static str,
        /// Iterations performed.
        iterations: usize,
        /// Final residual (solver-specific relative measure).
        residual: f64,
    },
    /// The prescribed longitudinal force cannot be carried by friction.
    #[error("prescribed |Fx| = {fx_n} N exceeds the friction limit µ·N = {limit_n} N: lower the traction coefficient or raise µ")]
    TractionExceedsFriction {
        /// Prescribed force (N).
        fx_n: f64,
        /// Friction limit (N).
        limit_n: f64,
    },
    /// The contact patch touches the edge of the computational grid.
    #[error("contact patch reaches the grid boundary ({edge}) under a normal force of {normal_n:.0} N; enlarge the grid (GridSpec half-lengths)")]
    PatchAtGridEdge {
        /// Which edge.
        edge: &'static str,
        /// The normal force of the step's normal solve (N).
        normal_n: f64,
    },
    /// File output failed.
    #[error("writing contact fields to {path}: {source}")]
    Io {
        /// The file path.
        path: std::path::PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// Combined (plane-strain) modulus of two identical bodies, `E* = E / (2 (1 − ν²))` (Pa).
pub fn combined_modulus(youngs_pa: f64, poisson: f64) -> f64 {
    youngs_pa / (2.0 * (1.0 - poisson * poisson))
}

/// Shear modulus `G = E / (2 (1 + ν))` (Pa).
pub fn shear_modulus(youngs_pa: f64, poisson: f64) -> f64 {
    youngs_pa / (2.0 * (1.0 + poisson))
}

/// The elastic constants `(E (Pa), ν (−))` of the one steel the contact solvers take for a
/// rail `(E₁, ν₁)` and a wheel `(E₂, ν₂)`: Kalker's combined constants of quasi-identical
/// bodies, `1/G = (1/G₁ + 1/G₂)/2` and `ν/G = (ν₁/G₁ + ν₂/G₂)/2`, returned as
/// `E = 2G(1 + ν)`. With them [`combined_modulus`] is Hertz's
/// `1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂` exactly; what they leave out is the coupling of the
/// normal and tangential problems of dissimilar bodies (Dundurs' constant β, zero for
/// identical ones; Kalker 1990, §1.4). Two identical steels give `(E₁, ν₁)`.
pub fn quasi_identical_pair(rail: (f64, f64), wheel: (f64, f64)) -> (f64, f64) {
    let (g1, g2) = (
        shear_modulus(rail.0, rail.1),
        shear_modulus(wheel.0, wheel.1),
    );
    if g1 == g2 && rail.1 == wheel.1 {
        return rail;
    }
    let g = 2.0 / (1.0 / g1 + 1.0 / g2);
    let nu = 0.5 * g * (rail.1 / g1 + wheel.1 / g2);
    (2.0 * g * (1.0 + nu), nu)
}

pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), ContactError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ContactError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

pub(crate) fn check_poisson(value: f64) -> Result<(), ContactError> {
    if (0.0..0.5).contains(&value) {
        Ok(())
    } else {
        Err(ContactError::InvalidParameter {
            name: "poisson_ratio",
            value,
            reason: "must be in [0, 0.5)",
        })
    }
}

#[cfg(test)]
mod tests;

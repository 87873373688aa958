//! Finite elements and assembly.
//!
//! Sparse matrices are faer `SparseColMat<usize, f64>` in *full* symmetric storage (both
//! triangles present), indexed by free DOFs (constrained DOFs eliminated). DOF numbering of a
//! node `n` before elimination is `3 n + d`, `d = 0, 1, 2` for x, y, z.
//!
//! | file | content |
//! |---|---|
//! | [`hex8`] | 8-node hexahedron with Wilson–Taylor incompatible modes, mass, interpolation |
//! | [`material`] | isotropic linear elastic material |
//! | [`spring`] | multipoint spring-dampers, point masses |
//! | [`assembly`] | DOF map with constraints, parallel sparse K/M/C assembly, energies, reactions |
//! | [`interp`] | locating a point in the mesh, interpolating nodal fields there |
//! | [`mtx`] | Matrix Market output (atomic) and input |
//! | [`solve`] | sparse Cholesky static solve |
//! | [`block`] | structured block mesh for checks and benchmarks |

pub mod assembly;
pub mod block;
pub mod hex8;
pub mod interp;
pub mod material;
pub mod mtx;
pub mod ordering;
pub mod solve;
pub mod spring;

pub use assembly::{
    apply_full_stiffness, assemble, mass_per_part, reactions, spring_energy,
    strain_energy_per_part, strain_energy_per_part_many, AssemblyOptions, DofMap, FeMatrices,
    MassKind, PerPart,
};
pub use solve::static_solve;
pub use spring::{Direction, PointMass, Spring};

use thiserror::Error;

/// Errors of the finite-element module. Every variant says what to change.
#[derive(Debug, Error, Clone)]
pub enum FeError {
    /// The Jacobian determinant of a hexahedron is not positive at a point.
    #[error(
        "hexahedron {element:?}: Jacobian determinant {det_j:.3e} m³ ≤ 0 at natural point {xi:?}; \
         the element is inverted or too distorted: check the node order (nodes 0–3 counter-clockwise \
         on ζ = −1 seen from ζ = +1, 4–7 above them) and the mesh generator"
    )]
    NonPositiveJacobian {
        /// Element index in the mesh (None when called on a single element).
        element: Option<usize>,
        /// The offending determinant (m³).
        det_j: f64,
        /// Natural coordinates where it was found.
        xi: [f64; 3],
    },
    /// Invalid material constants.
    #[error(
        "material {index}: E = {youngs_modulus} Pa, ν = {poisson_ratio}, ρ = {density} kg/m³ is \
         not admissible: need E > 0, −1 < ν < 0.5, ρ ≥ 0 (all finite)"
    )]
    InvalidMaterial {
        /// Index in the material table.
        index: usize,
        /// Young's modulus (Pa).
        youngs_modulus: f64,
        /// Poisson's ratio (−).
        poisson_ratio: f64,
        /// Density (kg/m³).
        density: f64,
    },
    /// An element refers to a material that does not exist.
    #[error("element {element}: material index {material} but only {n_materials} materials given")]
    MaterialIndex {
        /// Element index.
        element: usize,
        /// Its material index.
        material: usize,
        /// Length of the material table.
        n_materials: usize,
    },
    /// An element or spring refers to a node or DOF that does not exist.
    #[error("{what}: index {index} out of range (only {len} exist)")]
    IndexOutOfRange {
        /// What referred to it (e.g. "element 12 node", "spring 3 DOF").
        what: String,
        /// The index.
        index: usize,
        /// Number of nodes / DOFs available.
        len: usize,
    },
    /// A vector or matrix has the wrong length.
    #[error("{what}: expected length {expected}, got {got}")]
    DimensionMismatch {
        /// Which argument.
        what: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// Bad spring or point-mass data.
    #[error("spring/mass {index}: {reason}")]
    InvalidSpring {
        /// Index in the spring (or point-mass) list.
        index: usize,
        /// What is wrong and what to change.
        reason: String,
    },
    /// Newton iteration for natural coordinates did not converge.
    #[error(
        "natural coordinates of point {point:?} m not found after {iterations} Newton iterations \
         (residual {residual:.3e} m): the point is probably far outside the element"
    )]
    NewtonNotConverged {
        /// The physical point (m).
        point: [f64; 3],
        /// Iterations used.
        iterations: usize,
        /// Final residual norm (m).
        residual: f64,
    },
    /// The stiffness matrix is not positive definite (sparse Cholesky failed).
    #[error(
        "stiffness matrix is not positive definite: the model has rigid-body modes or \
         mechanisms; add constraints or ground springs"
    )]
    NotPositiveDefinite(#[source] faer::sparse::linalg::LltError),
    /// A static solution is not finite (a stiffness that is singular to working precision).
    #[error(
        "the static solution is not finite: the stiffness is singular to working precision (a \
         mechanism or a spring many orders of magnitude stiffer than the rest)"
    )]
    NotFinite,
    /// `K + σM` of a dense generalised eigenproblem is not positive definite.
    #[error("K + σM (σ = {sigma:e} 1/s²) of the dense eigenproblem is not positive definite: K must be positive semi-definite and M positive definite")]
    DenseShiftNotPositiveDefinite {
        /// The shift (1/s²).
        sigma: f64,
        /// faer's error.
        #[source]
        source: faer::linalg::cholesky::llt::factor::LltError,
    },
    /// The dense symmetric eigensolver failed (faer's `EvdError` is not a
    /// `std::error::Error`, so it is a field, not a source).
    #[error("dense symmetric eigensolver: {error:?}")]
    DenseEigen {
        /// faer's error.
        error: faer::linalg::evd::EvdError,
    },
    /// The mass matrix of a dense generalised eigenproblem is not positive definite.
    #[error("mass matrix of the dense eigenproblem is not positive definite: eigenvalue {eigenvalue:e} of L⁻¹ M L⁻ᵀ")]
    DenseMassNotPositive {
        /// The offending eigenvalue (s²).
        eigenvalue: f64,
    },
    /// A sparse matrix could not be built from its triplets (index out of bounds, allocation).
    #[error("sparse matrix could not be built")]
    SparseCreation(#[from] faer::sparse::CreationError),
    /// The symbolic analysis of a sparse factorisation failed (index overflow or out of
    /// memory: the model is too large for this machine; coarsen the mesh).
    #[error("symbolic analysis of the sparse factorisation failed")]
    SparseSymbolic(#[from] faer::sparse::FaerError),
    /// An I/O error (Matrix Market files).
    #[error("I/O error on {path}: {message}")]
    Io {
        /// File path.
        path: String,
        /// Error message.
        message: String,
    },
    /// A Matrix Market file could not be parsed.
    #[error("Matrix Market file {path}, line {line}: {reason}")]
    MatrixMarketParse {
        /// File path.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
}

/// Checks that a material's constants are admissible (used by assembly and element routines).
pub(crate) fn check_material(index: usize, m: &material::IsotropicElastic) -> Result<(), FeError> {
    let ok = m.youngs_modulus.is_finite()
        && m.youngs_modulus > 0.0
        && m.poisson_ratio.is_finite()
        && m.poisson_ratio > -1.0
        && m.poisson_ratio < 0.5
        && m.density.is_finite()
        && m.density >= 0.0;
    if ok {
        Ok(())
    } else {
        Err(FeError::InvalidMaterial {
            index,
            youngs_modulus: m.youngs_modulus,
            poisson_ratio: m.poisson_ratio,
            density: m.density,
        })
    }
}

#[cfg(test)]
mod verification;

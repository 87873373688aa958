//! The assembled FE substructures of the wheel–track system.
//!
//! - The *track* substructure: rail (UIC54 solid, optionally inclined), half sleepers (solid
//!   blocks), railpads (a `rows × columns` grid of spring-dampers per fastening, each spread over
//!   its footprint cell by tributary area), rigid holds of the fastening model (fixed rail-foot
//!   DOFs), and ballast (spring-dampers from each sleeper's bottom face to the ground, spread by
//!   area).
//! - The *wheel* substructure: the wheel and half axle (solid of revolution), the symmetry
//!   plane of the wheelset (lateral DOF fixed), and the lumped sprung mass on the primary
//!   suspension.
//!
//! Springs are spread by area so that neither a spring nor a rigid hold acts on a single node
//! of a solid: point supports make the stiffness grow without bound under refinement
//! (docs/theory.md §3.3).

pub mod layout;
pub mod track;
pub mod wheel;

pub use track::TrackStructure;
pub use wheel::WheelStructure;

/// The FE mass-matrix kind of the model's `mesh.mass`.
fn mass_kind(k: crate::model::MassKind) -> crate::fe::assembly::MassKind {
    match k {
        crate::model::MassKind::Lumped => crate::fe::assembly::MassKind::Lumped,
        crate::model::MassKind::Consistent => crate::fe::assembly::MassKind::Consistent,
    }
}

/// Errors while building a substructure.
#[derive(Debug, thiserror::Error)]
pub enum StructureError {
    /// Mesh generation failed.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// Element or assembly failure.
    #[error(transparent)]
    Fe(#[from] crate::fe::FeError),
    /// Supports (fastenings, holds, ballast) cannot be placed on the mesh.
    #[error("supports: {0}")]
    Support(String),
}

#[cfg(test)]
mod hold_tests;

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

pub mod contact_patch;
pub mod ends;
pub mod layout;
pub mod test_problems;
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
    /// A parameter of the local FE contact patch out of its range.
    #[error("contact patch: {name} = {value} is out of range: allowed {allowed}")]
    PatchParameter {
        /// The parameter's name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        allowed: &'static str,
    },
    /// A local FE contact patch too large to factorise on this kind of machine.
    #[error("contact patch: the submodel would have {dofs} free DOFs, above the limit of {limit}: lower refine, half_elements or fine_depth_elements, or raise max_ratio")]
    PatchTooLarge {
        /// Free DOFs of the requested submodel.
        dofs: usize,
        /// The limit.
        limit: usize,
    },
    /// Mesh generation failed.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// Element or assembly failure.
    #[error(transparent)]
    Fe(#[from] crate::fe::FeError),
    /// The complex harmonic matrix of an end-reflection test could not be built.
    #[error("end reflection: the harmonic matrix")]
    HarmonicMatrix(#[source] faer::sparse::CreationError),
    /// The complex harmonic matrix of an end-reflection test could not be factorised.
    #[error("end reflection: the harmonic LU factorisation")]
    HarmonicLu(#[source] faer::sparse::linalg::LuError),
    /// A fastening footprint cell not fully covered by rail-foot nodes.
    #[error("supports: fastening cell (row {row}, column {column}) at x = {x_m} m is not covered by rail-foot nodes (covered {covered_m2:e} of {cell_m2:e} m²): the footprint must lie on the rail foot")]
    CellNotCovered {
        /// Footprint row.
        row: usize,
        /// Footprint column.
        column: usize,
        /// Sleeper position (m).
        x_m: f64,
        /// Area covered by the rail-foot nodes' tributary strips (m²).
        covered_m2: f64,
        /// Area of the cell (m²).
        cell_m2: f64,
    },
    /// A rail-foot node not above the sleeper's top face.
    #[error("supports: rail-foot node at (x, y) = ({x_m}, {y_m}) m is not above the sleeper top face: check sleeper.width, sleeper.rail_seat and fastening.footprint_length")]
    FootOffSleeper {
        /// Node position along the rail (m).
        x_m: f64,
        /// Lateral node position (m).
        y_m: f64,
    },
    /// A held strip, grid point or node line of the fastening's hold pattern that meets no rail node.
    #[error("supports: held {what} {index} at {axis} = {position_m} m contains no rail-foot node {lines} (with mesh.node_planes = \"lattice\" only planes on the lattice of mesh.fine_element_length exist in the fine zone)")]
    HoldMissesNodes {
        /// `column`, `row`, `grid point of column`, `grid point of row`, `column line`, `row line`.
        what: &'static str,
        /// Its index.
        index: usize,
        /// `x` or `y`.
        axis: &'static str,
        /// Its position (m).
        position_m: f64,
        /// `plane` or `line`.
        lines: &'static str,
    },
    /// An elastic hold whose patch holds no rail-foot nodes.
    #[error("supports: elastic hold: {what} contains no rail-foot nodes")]
    ElasticHoldEmpty {
        /// Which patch.
        what: String,
    },
    /// A wheel load below the weight of the wheel and half axle (no sprung mass left).
    #[error("vehicle.wheel_load = {wheel_load_n} N is less than the weight of the wheel and half axle ({unsprung_kg:.0} kg): raise vehicle.wheel_load")]
    WheelLoadBelowWheelWeight {
        /// The wheel load (N).
        wheel_load_n: f64,
        /// Mass of the wheel and half axle (kg).
        unsprung_kg: f64,
    },
    /// A wheel mesh without journal nodes for the primary suspension.
    #[error("supports: the wheel mesh has no journal nodes for the primary suspension")]
    NoJournalNodes,
    /// The model would be too large to build: refused before any allocation.
    #[error("the {part} model would have about {dofs} DOFs (~{gib:.1} GiB to assemble), more than the limit of {MAX_DOFS} DOFs per substructure: {reduce}")]
    TooLarge {
        /// `track` or `wheel`.
        part: &'static str,
        /// Estimated DOFs (3 per node).
        dofs: usize,
        /// Estimated memory to build and assemble (GiB), [`BYTES_PER_DOF`] per DOF.
        gib: f64,
        /// Which counts are large and the model keys that set them.
        reduce: String,
    },
}

/// Most DOFs (3 per node) of the track or the wheel substructure: 6.6 times the default
/// track's 152 000. Building and assembling takes about [`BYTES_PER_DOF`] per DOF and the
/// modal solution several times more, so this keeps a model within a 24 GiB machine.
pub(crate) const MAX_DOFS: usize = 1_000_000;

/// Memory to build and assemble one substructure, per DOF (bytes): `corrugation mesh` of the
/// default model peaks at 557 MB for 188 700 DOFs (track and wheel), 2.7 kB each.
pub const BYTES_PER_DOF: f64 = 3000.0;

/// [`StructureError::TooLarge`] when `nodes` exceed the limit.
pub(crate) fn check_size(
    part: &'static str,
    nodes: f64,
    reduce: impl FnOnce() -> String,
) -> Result<(), StructureError> {
    if (3.0 * nodes).is_finite() && 3.0 * nodes <= MAX_DOFS as f64 {
        return Ok(());
    }
    Err(too_large(part, nodes, reduce()))
}

/// [`StructureError::TooLarge`] of a substructure of `nodes` nodes.
pub(crate) fn too_large(part: &'static str, nodes: f64, reduce: String) -> StructureError {
    let dofs = 3.0 * nodes;
    StructureError::TooLarge {
        part,
        dofs: dofs.min(usize::MAX as f64) as usize,
        gib: dofs * BYTES_PER_DOF / (1u64 << 30) as f64,
        reduce,
    }
}

#[cfg(test)]
mod hold_tests;
#[cfg(test)]
mod lattice_tests;
#[cfg(test)]
mod node_line_tests;

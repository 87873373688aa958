//! The wheel substructure: wheel and half axle, the wheelset's symmetry plane, and the lumped
//! sprung mass on the primary suspension.
//!
//! - The wheel is a solid of revolution in a wheel frame (origin at the wheel centre in the
//!   nominal rolling-circle plane, y along the axle towards the field side, z up; the contact
//!   point of the undeformed wheel is (0, 0, −R)).
//! - Half wheelset on a symmetric track: the nodes of the axle's symmetry plane are held
//!   laterally (u_y = 0), which also removes roll and yaw.
//! - The car body and bogie above the primary suspension are one lumped mass (docs/theory.md §3.5:
//!   they matter only below tens of Hz) on a node above the journal centre, moving vertically
//!   only (its x and y are held: the vehicle frame guides it). Its mass is
//!   `wheel_load / g − unsprung mass`, so that the static load on the rail is `wheel_load`.
//!   The primary suspension is a vertical spring-damper from that node to the journal
//!   (bearing-seat) nodes, spread over them with [`balanced_journal_weights`]: the node
//!   angles are graded towards the contact, so equal shares would put the spring's line of
//!   action off the axle axis and couple bounce with wheel rotation.
//!
//! Rigid-body modes that remain (zero frequency): longitudinal translation, vertical
//! translation (wheel and sprung mass together) and rotation about the axle. The passage
//! prescribes or balances them (speed, gravity and contact, driving torque).

use crate::fe::assembly::{assemble, AssemblyOptions, DofMap, FeMatrices, MassKind};
use crate::fe::material::IsotropicElastic;
use crate::fe::spring::{PointMass, Spring};
use crate::mesh::wheel::{wheel, WheelParams, WheelTopology};
use crate::mesh::{Mesh, Part};
use crate::model::Model;

use super::StructureError;

/// The wheel substructure, before assembly.
#[derive(Debug, Clone)]
pub struct WheelStructure {
    /// Wheel and axle nodes and hexahedra, plus the sprung-mass node (last node, no element).
    pub mesh: Mesh,
    /// Materials (index 0: wheel steel).
    pub materials: Vec<IsotropicElastic>,
    /// The primary suspension springs.
    pub springs: Vec<Spring>,
    /// The sprung mass.
    pub point_masses: Vec<PointMass>,
    /// Free/constrained DOFs.
    pub dofmap: DofMap,
    /// Wheel node maps.
    pub topology: WheelTopology,
    /// Node index of the sprung mass.
    pub sprung_node: usize,
    /// Sprung mass (kg).
    pub sprung_mass: f64,
    /// Wheel and half-axle mass (kg).
    pub unsprung_mass: f64,
    /// Wheel geometry used.
    pub params: WheelParams,
    /// Mass matrix kind.
    pub mass: MassKind,
}

/// Weights `w_i` of the journal nodes (wheel frame, axle along y through x = z = 0) closest
/// to equal shares such that `Σ w_i = 1`, `Σ w_i x_i = 0` and `Σ w_i z_i = 0`: a force spread
/// with them acts on the axle axis (no moment about it), and the weighted mean displacement
/// is that of the axle centre (no rotation in it). Falls back to equal shares if the
/// constraints are degenerate (nodes on a line).
pub fn balanced_journal_weights(mesh: &Mesh, nodes: &[usize]) -> Vec<f64> {
    let n = nodes.len();
    if n == 0 {
        return Vec::new();
    }
    let w0 = 1.0 / n as f64;
    // Constraint rows a_k (k = 0: 1, 1: x, 2: z); w = w0 + Aᵀ λ with (A Aᵀ) λ = b − A w0.
    let rows: Vec<[f64; 3]> = nodes
        .iter()
        .map(|&i| [1.0, mesh.nodes[i][0], mesh.nodes[i][2]])
        .collect();
    let mut g = nalgebra::Matrix3::<f64>::zeros();
    let mut r = nalgebra::Vector3::<f64>::new(1.0, 0.0, 0.0);
    for a in &rows {
        for p in 0..3 {
            r[p] -= a[p] * w0;
            for q in 0..3 {
                g[(p, q)] += a[p] * a[q];
            }
        }
    }
    match g.lu().solve(&r) {
        Some(l) if l.iter().all(|v| v.is_finite()) => rows
            .iter()
            .map(|a| w0 + a[0] * l[0] + a[1] * l[1] + a[2] * l[2])
            .collect(),
        _ => vec![w0; n],
    }
}

impl WheelStructure {
    /// Builds the wheel substructure of a model.
    pub fn build(m: &Model) -> Result<WheelStructure, StructureError> {
        Self::with_params(m, Self::params_of(m))
    }

    /// The wheel's geometry and mesh parameters of a model: its radius and conicity, the
    /// web's shape, thickness and offset, the rim's width and thickness and the brake disc
    /// (the `[wheel]` geometry keys; unset ones give the default wheel's values exactly), the
    /// mesh keys `mesh.wheel_segments` and `mesh.wheel_element_size` (the contact zone at
    /// half that size), the rest of the geometry (hub, axle, journal, the disc's size) the
    /// default wheel's.
    pub fn params_of(m: &Model) -> WheelParams {
        let w = &m.wheel;
        let [rim_y_start_m, rim_y_end_m] = w.rim_y_m();
        WheelParams {
            radius_m: w.radius,
            conicity: w.conicity,
            rim_inner_radius_m: w.rim_inner_radius_m(),
            rim_y_start_m,
            rim_y_end_m,
            web_y_m: w.web_y_m(),
            web_bend_m: w.web_bend_m(),
            brake_disc: w.brake_disc(),
            circumferential_divisions: m.mesh.wheel_segments,
            axial_size_m: m.mesh.wheel_element_size,
            radial_size_m: m.mesh.wheel_element_size,
            contact_size_m: 0.5 * m.mesh.wheel_element_size,
            max_nodes: super::MAX_DOFS / 3,
            ..WheelParams::default()
        }
    }

    /// Builds the wheel substructure of a model on the wheel mesh of `params` instead of
    /// [`Self::params_of`]`(m)` (the model gives the material, the loads and the primary
    /// suspension). For meshes the model's keys do not reach, such as the tiny wheels of
    /// [`crate::structure::test_problems::all_modes_structures`].
    pub(crate) fn with_params(
        m: &Model,
        params: WheelParams,
    ) -> Result<WheelStructure, StructureError> {
        let (mut mesh, topology) = wheel(&params, 0).map_err(|e| match e {
            crate::mesh::MeshError::TooLarge {
                nodes,
                layers,
                per_layer,
                ..
            } => super::too_large(
                "wheel",
                nodes as f64,
                format!(
                    "{layers} circumferential layers (mesh.wheel_segments = {}) x {per_layer} meridian nodes (mesh.wheel_element_size = {} m); coarsen these",
                    m.mesh.wheel_segments, m.mesh.wheel_element_size
                ),
            ),
            e => e.into(),
        })?;
        let materials = vec![m.wheel_material()];
        let unsprung_mass = crate::fe::assembly::mass_per_part(&mesh, &materials)?.get(Part::Wheel);
        let sprung_mass = m.vehicle.wheel_load / m.vehicle.gravity - unsprung_mass;
        if sprung_mass.is_nan() || sprung_mass <= 0.0 {
            return Err(StructureError::WheelLoadBelowWheelWeight {
                wheel_load_n: m.vehicle.wheel_load,
                unsprung_kg: unsprung_mass,
            });
        }
        let bearing = topology.bearing_nodes();
        if bearing.is_empty() {
            return Err(StructureError::NoJournalNodes);
        }
        let yj = 0.5 * (params.journal_y_m[0] + params.journal_y_m[1]);
        let sprung_node = mesh.nodes.len();
        mesh.nodes.push([0.0, yj, 1.0]);
        let w = balanced_journal_weights(&mesh, &bearing);
        let springs = vec![Spring::new(
            vec![(3 * sprung_node + 2, 1.0)],
            bearing
                .iter()
                .zip(&w)
                .map(|(&n, &wn)| (3 * n + 2, wn))
                .collect(),
            m.vehicle.primary_stiffness,
            m.vehicle.primary_damping,
        )];
        let mut held: Vec<usize> = topology
            .symmetry_plane_nodes()
            .iter()
            .map(|&n| 3 * n + 1)
            .collect();
        held.extend([3 * sprung_node, 3 * sprung_node + 1]);
        held.sort_unstable();
        held.dedup();
        let dofmap = DofMap::with_constraints(mesh.nodes.len(), &held)?;
        Ok(WheelStructure {
            mesh,
            materials,
            springs,
            point_masses: vec![PointMass {
                node: sprung_node,
                mass: sprung_mass,
            }],
            dofmap,
            topology,
            sprung_node,
            sprung_mass,
            unsprung_mass,
            params,
            mass: super::mass_kind(m.mesh.mass),
        })
    }

    /// Assembles K, M, C over the free DOFs; returns them with the wall time (s).
    pub fn assemble(&self) -> Result<(FeMatrices, f64), StructureError> {
        let t = std::time::Instant::now();
        let mats = assemble(
            &self.mesh,
            &self.materials,
            &self.springs,
            &self.point_masses,
            &self.dofmap,
            AssemblyOptions { mass: self.mass },
        )?;
        Ok((mats, t.elapsed().as_secs_f64()))
    }
}

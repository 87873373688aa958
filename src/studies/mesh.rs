//! The outputs of the `mesh` command: the model's summary ([`MeshSummary`], the command's
//! `--json`), the track's and the wheel's matrices in Matrix Market form with their DOF tables
//! ([`write_track_matrices`], [`write_wheel_matrices`]), and the whole mesh for ParaView with
//! part and hold tags ([`write_mesh_vtu`]). Every file is written atomically.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::fe::assembly::{mass_per_part, DofMap, FeMatrices};
use crate::fe::mtx;
use crate::io::{write_csv, write_vtu, VtuField, VTK_HEXAHEDRON, VTK_LINE};
use crate::mesh::Part;
use crate::model::Model;
use crate::structure::track::SpringKind;
use crate::structure::{TrackStructure, WheelStructure};
use crate::studies::StudiesError;

/// The summary printed by `mesh` (`--json` keys).
#[derive(Debug, Serialize)]
pub struct MeshSummary {
    /// Nodes of the track mesh.
    pub nodes: usize,
    /// Hexahedra per part (rail, sleeper, wheel).
    pub elements: BTreeMap<String, usize>,
    /// Free DOFs of the track.
    pub free_dofs: usize,
    /// Held (eliminated) DOFs of the track.
    pub constrained_dofs: usize,
    /// Nodes of the wheel mesh.
    pub wheel_nodes: usize,
    /// Free DOFs of the wheel.
    pub wheel_free_dofs: usize,
    /// Held DOFs of the wheel.
    pub wheel_constrained_dofs: usize,
    /// Spring–dampers per kind.
    pub springs: BTreeMap<String, usize>,
    /// Area of the meshed rail section (m²).
    pub rail_area_m2: f64,
    /// Its second moment for vertical bending (m⁴).
    pub rail_i_vertical_m4: f64,
    /// Its second moment for lateral bending (m⁴).
    pub rail_i_lateral_m4: f64,
    /// Its centroid above the foot (m).
    pub rail_centroid_height_m: f64,
    /// The rail's mass per metre (kg/m).
    pub rail_mass_per_m_kg: f64,
    /// Mass per part (kg): rail, sleeper, wheel (unsprung) and sprung.
    pub mass_by_part_kg: BTreeMap<String, f64>,
    /// Rail length (m).
    pub track_length_m: f64,
    /// Node planes along the rail.
    pub rail_node_planes: usize,
    /// Nodes of the rail section.
    pub section_nodes: usize,
    /// The fastening model's name.
    pub fastening_model: String,
    /// Wall time of building both meshes (s).
    pub build_seconds: f64,
    /// Wall time of assembling both sets of matrices (s).
    pub assembly_seconds: f64,
    /// Non-zeros of the track's K.
    pub matrix_nonzeros: usize,
}

impl MeshSummary {
    /// The summary of the model `m` built as `track` and `wheel`, the track's matrices
    /// `mats`, and the wall times (s) of the build and the assembly.
    pub fn new(
        m: &Model,
        track: &TrackStructure,
        wheel: &WheelStructure,
        mats: &FeMatrices,
        build_seconds: f64,
        assembly_seconds: f64,
    ) -> Result<Self, StudiesError> {
        let mass = mass_per_part(&track.mesh, &track.materials)?;
        let mut elements = BTreeMap::new();
        for e in track.mesh.elements.iter().chain(&wheel.mesh.elements) {
            *elements.entry(e.part.name().to_string()).or_insert(0) += 1;
        }
        let mut springs = BTreeMap::new();
        for k in &track.spring_kinds {
            let name = match k {
                SpringKind::Fastening => "fastening",
                SpringKind::Ballast => "ballast",
                SpringKind::Hold => "elastic_hold",
                SpringKind::EndDashpot => "end_dashpot",
            };
            *springs.entry(name.to_string()).or_insert(0) += 1;
        }
        let mut mass_by_part_kg = BTreeMap::new();
        for p in [Part::Rail, Part::Sleeper] {
            mass_by_part_kg.insert(p.name().to_string(), mass.get(p));
        }
        mass_by_part_kg.insert(Part::Wheel.name().to_string(), wheel.unsprung_mass);
        mass_by_part_kg.insert("sprung".to_string(), wheel.sprung_mass);
        springs.insert("primary_suspension".to_string(), wheel.springs.len());
        let sp = track.section_properties;
        Ok(MeshSummary {
            nodes: track.mesh.nodes.len(),
            elements,
            free_dofs: track.dofmap.n_free(),
            constrained_dofs: track.dofmap.n_constrained(),
            wheel_nodes: wheel.mesh.nodes.len(),
            wheel_free_dofs: wheel.dofmap.n_free(),
            wheel_constrained_dofs: wheel.dofmap.n_constrained(),
            springs,
            rail_area_m2: sp.area_m2,
            rail_i_vertical_m4: sp.i_vertical_bending_m4,
            rail_i_lateral_m4: sp.i_lateral_bending_m4,
            rail_centroid_height_m: sp.centroid_z_m,
            rail_mass_per_m_kg: mass.get(Part::Rail) / track.layout.length,
            mass_by_part_kg,
            track_length_m: track.layout.length,
            rail_node_planes: track.rail.n_planes(),
            section_nodes: track.rail.n_section_nodes(),
            fastening_model: m.fastening.model().name().to_string(),
            build_seconds,
            assembly_seconds,
            matrix_nonzeros: mats.k.compute_nnz(),
        })
    }
}

/// Writes the track's `K.mtx`, `M.mtx`, `C.mtx` (free DOFs, Matrix Market, symmetric) and
/// `dofs.csv` (free DOF, node, direction, coordinates in m, part code 0 rail, 1 sleeper) into
/// `dir` (created if missing).
pub fn write_track_matrices(
    track: &TrackStructure,
    mats: &FeMatrices,
    dir: &Path,
) -> Result<(), StudiesError> {
    let part_of_node = node_parts(track);
    write_matrices(dir, "", mats, &track.dofmap, &track.mesh.nodes, |n| {
        part_of_node[n]
    })
}

/// Writes the wheel's `wheel_K.mtx`, `wheel_M.mtx`, `wheel_C.mtx` and `wheel_dofs.csv` (part
/// code 2 wheel, 3 the sprung mass) into `dir` (created if missing).
pub fn write_wheel_matrices(
    wheel: &WheelStructure,
    mats: &FeMatrices,
    dir: &Path,
) -> Result<(), StudiesError> {
    let sprung = wheel.sprung_node;
    write_matrices(dir, "wheel_", mats, &wheel.dofmap, &wheel.mesh.nodes, |n| {
        if n == sprung {
            3.0
        } else {
            2.0
        }
    })
}

/// `{prefix}K.mtx`, `{prefix}M.mtx`, `{prefix}C.mtx` and `{prefix}dofs.csv` (one row per free
/// DOF: its node, direction, the node's coordinates in m and `part(node)`) into `dir`.
fn write_matrices(
    dir: &Path,
    prefix: &str,
    mats: &FeMatrices,
    dofmap: &DofMap,
    nodes: &[[f64; 3]],
    part: impl Fn(usize) -> f64,
) -> Result<(), StudiesError> {
    std::fs::create_dir_all(dir).map_err(StudiesError::io(dir))?;
    for (name, a) in [("K", &mats.k), ("M", &mats.m), ("C", &mats.c)] {
        mtx::write_symmetric(&dir.join(format!("{prefix}{name}.mtx")), a)?;
    }
    let rows = (0..dofmap.n_free()).map(|f| {
        let g = dofmap.global_dof(f);
        let (n, d) = (g / 3, g % 3);
        let [x, y, z] = nodes[n];
        vec![f as f64, n as f64, d as f64, x, y, z, part(n)]
    });
    let path = dir.join(format!("{prefix}dofs.csv"));
    write_csv(
        &path,
        &["free_dof", "node", "direction", "x_m", "y_m", "z_m", "part"],
        rows,
    )
    .map_err(StudiesError::io(&path))
}

/// Part code per node: 0 rail, 1 sleeper, 2 wheel (as `Part::ALL`).
fn node_parts(track: &TrackStructure) -> Vec<f64> {
    let mut p = vec![0.0; track.mesh.nodes.len()];
    for e in &track.mesh.elements {
        let code = Part::ALL.iter().position(|&q| q == e.part).unwrap_or(0) as f64;
        for &n in &e.nodes {
            p[n] = code;
        }
    }
    p
}

/// Writes the track and the wheel (at its start, standing on the rail crown) as one `.vtu`
/// file at `path`: hexahedra, the spring–dampers as lines from their first node to their
/// first other-side node, a cell field `part` (0 rail, 1 sleeper, 2 wheel, 3 pad spring,
/// 4 ballast, 5 elastic hold, 6 rail-end dashpot, 7 primary suspension) and a point field
/// `held_xyz` (1 where a DOF is held).
pub fn write_mesh_vtu(
    track: &TrackStructure,
    wheel: &WheelStructure,
    path: &Path,
) -> Result<(), StudiesError> {
    // The wheel drawn at its start position, standing on the rail crown.
    let mut mesh = track.mesh.clone();
    let z_top = track
        .rail
        .running_surface_nodes(0)
        .iter()
        .map(|&n| track.mesh.nodes[n][2])
        .fold(f64::MIN, f64::max);
    let mut placed = wheel.mesh.clone();
    for p in &mut placed.nodes {
        p[0] += track.layout.wheel_start;
        p[2] += z_top + wheel.params.radius_m;
    }
    let offset = mesh.append(&placed);
    let mesh = &mesh;
    let mut cells: Vec<(u8, Vec<usize>)> = mesh
        .elements
        .iter()
        .map(|e| (VTK_HEXAHEDRON, e.nodes.to_vec()))
        .collect();
    let mut part: Vec<f64> = mesh
        .elements
        .iter()
        .map(|e| Part::ALL.iter().position(|&q| q == e.part).unwrap_or(0) as f64)
        .collect();
    // Springs drawn as lines from their first DOF's node to their first other-side node.
    for (s, kind) in track.springs.iter().zip(&track.spring_kinds) {
        if let (Some(a), Some(b)) = (s.side_a.first(), s.side_b.first()) {
            cells.push((VTK_LINE, vec![a.0 / 3, b.0 / 3]));
            part.push(match kind {
                SpringKind::Fastening => 3.0,
                SpringKind::Ballast => 4.0,
                SpringKind::Hold => 5.0,
                SpringKind::EndDashpot => 6.0,
            });
        }
    }
    for (s, _) in wheel.springs.iter().zip(0..) {
        if let (Some(a), Some(b)) = (s.side_a.first(), s.side_b.first()) {
            cells.push((VTK_LINE, vec![offset + a.0 / 3, offset + b.0 / 3]));
            part.push(7.0);
        }
    }
    let mut held = vec![0.0; 3 * mesh.nodes.len()];
    for d in track.dofmap.constrained_dofs() {
        held[d] = 1.0;
    }
    for d in wheel.dofmap.constrained_dofs() {
        held[3 * offset + d] = 1.0;
    }
    write_vtu(
        path,
        &mesh.nodes,
        &cells,
        &[VtuField {
            name: "held_xyz",
            components: 3,
            data: &held,
        }],
        &[VtuField {
            name:
                "part (0 rail, 1 sleeper, 2 wheel, 3 pad spring, 4 ballast, 5 elastic hold, 6 end dashpot, 7 primary suspension)",
            components: 1,
            data: &part,
        }],
    )
    .map_err(StudiesError::io(path))
}

//! `corrugation mesh`: build the FE model and summarise it.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::fe::mtx;
use corrugation::io::{write_csv, write_vtu, VtuField, VTK_HEXAHEDRON, VTK_LINE};
use corrugation::mesh::Part;
use corrugation::structure::track::SpringKind;
use corrugation::structure::{TrackStructure, WheelStructure};

use super::ModelArgs;

/// Builds the 3D FE model of the track and prints its summary.
#[derive(Debug, Args)]
pub struct MeshCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
    /// Write the mesh with part and constraint tags for ParaView (.vtu).
    #[arg(long, value_name = "FILE")]
    vtu: Option<PathBuf>,
    /// Write K.mtx, M.mtx (track, free DOFs, Matrix Market) and dofs.csv into DIR.
    #[arg(long, value_name = "DIR")]
    mtx: Option<PathBuf>,
}

/// The summary printed by `mesh` (`--json` keys).
#[derive(Debug, Serialize)]
pub struct MeshSummary {
    pub nodes: usize,
    pub elements: BTreeMap<String, usize>,
    pub free_dofs: usize,
    pub constrained_dofs: usize,
    pub wheel_nodes: usize,
    pub wheel_free_dofs: usize,
    pub wheel_constrained_dofs: usize,
    pub springs: BTreeMap<String, usize>,
    pub rail_area_m2: f64,
    pub rail_i_vertical_m4: f64,
    pub rail_i_lateral_m4: f64,
    pub rail_centroid_height_m: f64,
    pub rail_mass_per_m_kg: f64,
    pub mass_by_part_kg: BTreeMap<String, f64>,
    pub track_length_m: f64,
    pub rail_node_planes: usize,
    pub section_nodes: usize,
    pub fastening_model: String,
    pub build_seconds: f64,
    pub assembly_seconds: f64,
    pub matrix_nonzeros: usize,
}

impl MeshCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let m = self.model.load()?;
        let t = Instant::now();
        let track = TrackStructure::build(&m).context("building the track model")?;
        let wheel = WheelStructure::build(&m).context("building the wheel model")?;
        let build_seconds = t.elapsed().as_secs_f64();
        let (mats, assembly_seconds) = track.assemble().context("assembling the track matrices")?;
        let (wheel_mats, wheel_seconds) =
            wheel.assemble().context("assembling the wheel matrices")?;
        let assembly_seconds = assembly_seconds + wheel_seconds;
        let mass = corrugation::fe::assembly::mass_per_part(&track.mesh, &track.materials)?;
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
        let s = MeshSummary {
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
        };
        if let Some(dir) = &self.mtx {
            write_matrices(&track, &mats, dir)?;
            write_wheel_matrices(&wheel, &wheel_mats, dir)?;
        }
        if let Some(path) = &self.vtu {
            write_mesh_vtu(&track, &wheel, path)?;
        }
        if self.json {
            println!("{}", serde_json::to_string_pretty(&s)?);
        } else {
            print_summary(&s);
        }
        Ok(())
    }
}

fn print_summary(s: &MeshSummary) {
    println!(
        "wheel-track model ({}), track {:.2} m long",
        s.fastening_model, s.track_length_m
    );
    println!("  nodes                 {}", s.nodes);
    for (p, n) in &s.elements {
        println!("  elements ({p:<8})   {n}");
    }
    for (p, n) in &s.springs {
        println!("  springs ({p:<9})  {n}");
    }
    println!("  free DOFs (track)     {}", s.free_dofs);
    println!("  constrained (track)   {}", s.constrained_dofs);
    println!("  wheel nodes           {}", s.wheel_nodes);
    println!("  free DOFs (wheel)     {}", s.wheel_free_dofs);
    println!(
        "  rail node planes      {} x {} section nodes",
        s.rail_node_planes, s.section_nodes
    );
    println!("  rail area             {:.4e} m^2", s.rail_area_m2);
    println!("  rail I (vertical)     {:.4e} m^4", s.rail_i_vertical_m4);
    println!("  rail I (lateral)      {:.4e} m^4", s.rail_i_lateral_m4);
    println!("  rail centroid height  {:.4} m", s.rail_centroid_height_m);
    println!("  rail mass per metre   {:.3} kg/m", s.rail_mass_per_m_kg);
    for (p, kg) in &s.mass_by_part_kg {
        println!("  mass ({p:<8})       {kg:.1} kg");
    }
    println!("  K non-zeros (track)   {}", s.matrix_nonzeros);
    println!(
        "  build / assembly      {:.3} s / {:.3} s",
        s.build_seconds, s.assembly_seconds
    );
}

fn write_matrices(
    track: &TrackStructure,
    mats: &corrugation::fe::assembly::FeMatrices,
    dir: &std::path::Path,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    mtx::write_symmetric(&dir.join("K.mtx"), &mats.k)?;
    mtx::write_symmetric(&dir.join("M.mtx"), &mats.m)?;
    mtx::write_symmetric(&dir.join("C.mtx"), &mats.c)?;
    let part_of_node = node_parts(track);
    let rows = (0..track.dofmap.n_free()).map(|f| {
        let g = track.dofmap.global_dof(f);
        let (n, d) = (g / 3, g % 3);
        let [x, y, z] = track.mesh.nodes[n];
        vec![f as f64, n as f64, d as f64, x, y, z, part_of_node[n]]
    });
    write_csv(
        &dir.join("dofs.csv"),
        &["free_dof", "node", "direction", "x_m", "y_m", "z_m", "part"],
        rows,
    )?;
    Ok(())
}

fn write_wheel_matrices(
    wheel: &WheelStructure,
    mats: &corrugation::fe::assembly::FeMatrices,
    dir: &std::path::Path,
) -> anyhow::Result<()> {
    mtx::write_symmetric(&dir.join("wheel_K.mtx"), &mats.k)?;
    mtx::write_symmetric(&dir.join("wheel_M.mtx"), &mats.m)?;
    mtx::write_symmetric(&dir.join("wheel_C.mtx"), &mats.c)?;
    let rows = (0..wheel.dofmap.n_free()).map(|f| {
        let g = wheel.dofmap.global_dof(f);
        let (n, d) = (g / 3, g % 3);
        let [x, y, z] = wheel.mesh.nodes[n];
        let part = if n == wheel.sprung_node { 3.0 } else { 2.0 };
        vec![f as f64, n as f64, d as f64, x, y, z, part]
    });
    write_csv(
        &dir.join("wheel_dofs.csv"),
        &["free_dof", "node", "direction", "x_m", "y_m", "z_m", "part"],
        rows,
    )?;
    Ok(())
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

fn write_mesh_vtu(
    track: &TrackStructure,
    wheel: &WheelStructure,
    path: &std::path::Path,
) -> anyhow::Result<()> {
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
            part.push(5.0);
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
                "part (0 rail, 1 sleeper, 2 wheel, 3 pad spring, 4 ballast, 5 primary suspension)",
            components: 1,
            data: &part,
        }],
    )
    .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

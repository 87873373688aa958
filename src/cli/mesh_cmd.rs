//! `corrugation mesh`: build the FE model and summarise it.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;

use corrugation::structure::{TrackStructure, WheelStructure};
use corrugation::studies::mesh::{
    write_mesh_vtu, write_track_matrices, write_wheel_matrices, MeshSummary,
};

use super::ModelArgs;

/// Builds the 3D FE model of the track and prints its summary.
#[derive(Debug, Args)]
pub(crate) struct MeshCmd {
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
        let s = MeshSummary::new(&m, &track, &wheel, &mats, build_seconds, assembly_seconds)?;
        if let Some(dir) = &self.mtx {
            write_track_matrices(&track, &mats, dir)?;
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

//! Which part of a track sets the explicit path's stable step (a diagnosis recorded in
//! validation/log/reference_regime.md): the highest mode of the track's central-difference operator as the step's estimate
//! finds it (`explicit::stable::highest_mode`), its strain energy split over the rail's and the
//! sleepers' elements and each kind of spring, and the nodes that carry most of its kinetic
//! energy, with their position and the springs that hold them.
//!
//! Run: `cargo run --release --example stable_step_probe -- [--model FILE] [--set key=value]…`
//! (about half a minute and 3 GB for a 34-bay track on 2 cores).

use std::collections::BTreeMap;
use std::path::PathBuf;

use corrugation::explicit::operator::ExplicitOperator;
use corrugation::explicit::stable::highest_mode;
use corrugation::fe::assembly::strain_energy_per_part;
use corrugation::mesh::Part;
use corrugation::model::{load_model, ModelSource};
use corrugation::structure::track::{SpringKind, TrackStructure};

/// Nodes listed by kinetic share.
const TOP_NODES: usize = 6;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut source, mut sets) = (ModelSource::Builtin, Vec::new());
    while let Some(a) = args.next() {
        match a.as_str() {
            "--model" => source = ModelSource::File(PathBuf::from(need(args.next(), &a)?)),
            "--set" => sets.push(need(args.next(), &a)?),
            other => {
                anyhow::bail!("unknown argument {other}: expected --model FILE, --set key=value")
            }
        }
    }
    let model = load_model(&source, &sets)?;
    let track = TrackStructure::build(&model)?;
    let (mats, _) = track.assemble()?;
    let op = ExplicitOperator::new(mats.k.as_ref(), mats.m.as_ref(), mats.c.as_ref())?;
    let (step, u) = highest_mode(&op)?;
    println!(
        "{} {}: {} free DOFs; ω_max {:.4e} rad/s ({:.1} kHz; Gershgorin bound {:.4e}), ξ {:.3e}, critical step {:.4e} s",
        source.display(),
        sets.join(" "),
        op.n(),
        step.omega_max_estimate,
        step.omega_max_estimate / (2.0 * std::f64::consts::PI) / 1e3,
        step.omega_max_bound,
        step.damping_ratio,
        step.critical_s
    );
    let full = track.dofmap.expand(&u)?;
    let elements = strain_energy_per_part(&track.mesh, &track.materials, &full)?;
    let mut energy: BTreeMap<String, f64> = BTreeMap::new();
    energy.insert("rail elements".into(), elements.get(Part::Rail));
    energy.insert("sleeper elements".into(), elements.get(Part::Sleeper));
    for (s, kind) in track.springs.iter().zip(&track.spring_kinds) {
        *energy.entry(format!("{kind:?} springs")).or_default() += s.energy(&full);
    }
    let total: f64 = energy.values().sum();
    println!("strain energy of the highest mode:");
    for (part, e) in &energy {
        println!("  {part:<22} {:6.2} %", 100.0 * e / total);
    }
    // Kinetic share per node, and the kinds of spring attached to each node.
    let m = op.mass();
    let mut kinetic = vec![0.0; track.mesh.nodes.len()];
    for (i, (ui, mi)) in u.iter().zip(m).enumerate() {
        kinetic[track.dofmap.global_dof(i) / 3] += mi * ui * ui;
    }
    let ksum: f64 = kinetic.iter().sum();
    let mut attached: BTreeMap<usize, Vec<SpringKind>> = BTreeMap::new();
    for (s, kind) in track.springs.iter().zip(&track.spring_kinds) {
        for &(node, _) in s.side_a.iter().chain(&s.side_b) {
            let v = attached.entry(node).or_default();
            if !v.contains(kind) {
                v.push(*kind);
            }
        }
    }
    let mut order: Vec<usize> = (0..kinetic.len()).collect();
    order.sort_by(|&a, &b| kinetic[b].total_cmp(&kinetic[a]));
    println!("nodes with the largest kinetic share (x, y, z in m; the shortest edge of the elements around, mm):");
    for &n in order.iter().take(TOP_NODES) {
        let [x, y, z] = track.mesh.nodes[n];
        println!(
            "  node {n:>7}: {:5.2} %  at ({x:8.4}, {y:7.4}, {z:7.4}); shortest edge {:.2} mm; springs {:?}",
            100.0 * kinetic[n] / ksum,
            1e3 * shortest_edge_around(&track, n),
            attached.get(&n).map_or(&[][..], Vec::as_slice)
        );
    }
    Ok(())
}

/// The shortest edge (m) of the hexahedra that hold node `n`.
fn shortest_edge_around(track: &TrackStructure, n: usize) -> f64 {
    // the 12 edges of a hexahedron by its local node numbers
    const EDGES: [(usize, usize); 12] = [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 0),
        (4, 5),
        (5, 6),
        (6, 7),
        (7, 4),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    let p = &track.mesh.nodes;
    track
        .mesh
        .elements
        .iter()
        .filter(|e| e.nodes.contains(&n))
        .flat_map(|e| EDGES.iter().map(move |&(a, b)| (e.nodes[a], e.nodes[b])))
        .map(|(a, b)| {
            (0..3)
                .map(|d| (p[a][d] - p[b][d]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

fn need(v: Option<String>, flag: &str) -> anyhow::Result<String> {
    v.ok_or_else(|| anyhow::anyhow!("{flag} needs a value"))
}

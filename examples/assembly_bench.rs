//! Assembly benchmark: K, M (consistent) and C of a structured block of 50 000 hexahedra
//! (100 × 25 × 20, steel, bottom face clamped, 100 ground springs), timed with 1 thread and
//! with all rayon threads. Run: `cargo run --release --example assembly_bench`.

use std::time::Instant;

use corrugation::fe::block::{block_mesh, block_node};
use corrugation::fe::hex8;
use corrugation::fe::material::IsotropicElastic;
use corrugation::fe::{assemble, AssemblyOptions, Direction, DofMap, MassKind, Spring};
use corrugation::mesh::Part;
use rayon::prelude::*;

fn main() -> anyhow::Result<()> {
    let n = [100, 25, 20];
    let mesh = block_mesh(n, [2.0, 0.5, 0.4], 0, Part::Rail);
    let mut cons = Vec::new();
    for j in 0..=n[1] {
        for i in 0..=n[0] {
            let node = block_node(n[0], n[1], i, j, 0);
            cons.extend([3 * node, 3 * node + 1, 3 * node + 2]);
        }
    }
    let springs: Vec<Spring> = (0..=n[0])
        .map(|i| Spring::node_to_ground(block_node(n[0], n[1], i, 0, n[2]), Direction::Y, 1e8, 1e4))
        .collect();
    let dm = DofMap::with_constraints(mesh.nodes.len(), &cons)?;
    println!(
        "mesh: {} hexahedra, {} nodes, {} free DOFs",
        mesh.elements.len(),
        mesh.nodes.len(),
        dm.n_free()
    );
    let mats = [IsotropicElastic::STEEL];
    let max_threads = rayon::current_num_threads();
    for threads in [1, max_threads] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        // Element stiffness + mass alone (the parallel, compute-bound part).
        let t = Instant::now();
        let checksum: f64 = pool.install(|| {
            mesh.elements
                .par_iter()
                .map(|el| {
                    let c = el.nodes.map(|n| mesh.nodes[n]);
                    hex8::stiffness(&c, &mats[0])
                        .map(|k| k[(0, 0)])
                        .unwrap_or(f64::NAN)
                        + hex8::consistent_mass_scalar(&c, &mats[0])
                            .map(|m| m[(0, 0)])
                            .unwrap_or(f64::NAN)
                })
                .sum()
        });
        let dt = t.elapsed().as_secs_f64();
        println!(
            "threads {threads}: element K + M of {} hexahedra alone: {dt:.3} s ({:.2} µs/element, checksum {checksum:.6e})",
            mesh.elements.len(),
            1e6 * dt / mesh.elements.len() as f64
        );
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let mut best = f64::INFINITY;
            let mut nnz = 0;
            for _ in 0..2 {
                let t = Instant::now();
                let fm = pool.install(|| {
                    assemble(&mesh, &mats, &springs, &[], &dm, AssemblyOptions { mass })
                })?;
                best = best.min(t.elapsed().as_secs_f64());
                nnz = fm.k.compute_nnz();
            }
            println!(
                "threads {threads}: {mass:?} mass: assembly of K, M, C in {best:.3} s (best of 2), nnz = {nnz}"
            );
        }
    }
    Ok(())
}

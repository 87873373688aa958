//! A structured block of hexahedra, for tests, verification and benchmarks.
//!
//! The block spans `[0, lx] × [0, ly] × [0, lz]` (m) with `nx × ny × nz` equal elements;
//! node `(i, j, k)` has index `i + (nx + 1) (j + (ny + 1) k)`. Elements follow the node
//! order of [`crate::mesh`]. The production meshes (rail, sleepers, wheel) are built in
//! [`crate::mesh`]; this generator only serves checks against closed forms.

use crate::mesh::{Hex8, Mesh, Part};

/// Node index of grid point `(i, j, k)` in a block with `nx × ny` elements per layer.
pub fn block_node(nx: usize, ny: usize, i: usize, j: usize, k: usize) -> usize {
    i + (nx + 1) * (j + (ny + 1) * k)
}

/// A structured block mesh of `nx × ny × nz` hexahedra of size `lx/nx × ly/ny × lz/nz` (m),
/// all with material index `material` and part `part`.
pub fn block_mesh(n: [usize; 3], size_m: [f64; 3], material: usize, part: Part) -> Mesh {
    let axis = |k: usize| -> Vec<f64> {
        (0..=n[k])
            .map(|i| size_m[k] * i as f64 / n[k] as f64)
            .collect()
    };
    graded_block_mesh([&axis(0), &axis(1), &axis(2)], material, part)
}

/// A tensor-product block mesh on the node planes `x = xs[i]`, `y = ys[j]`, `z = zs[k]` (m,
/// each strictly increasing, at least two values): `(xs.len() − 1) × (ys.len() − 1) ×
/// (zs.len() − 1)` hexahedra, node `(i, j, k)` at index [`block_node`]`(nx, ny, i, j, k)`
/// with `nx = xs.len() − 1`, `ny = ys.len() − 1`. Used for graded blocks (fine at a loaded
/// face, coarse far away), e.g. the flat block of the local contact patch.
pub fn graded_block_mesh(planes_m: [&[f64]; 3], material: usize, part: Part) -> Mesh {
    let [xs, ys, zs] = planes_m;
    let (nx, ny, nz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
    let mut nodes = Vec::with_capacity(xs.len() * ys.len() * zs.len());
    for &z in zs {
        for &y in ys {
            for &x in xs {
                nodes.push([x, y, z]);
            }
        }
    }
    let mut elements = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let b =
                    |di: usize, dj: usize, dk: usize| block_node(nx, ny, i + di, j + dj, k + dk);
                elements.push(Hex8 {
                    nodes: [
                        b(0, 0, 0),
                        b(1, 0, 0),
                        b(1, 1, 0),
                        b(0, 1, 0),
                        b(0, 0, 1),
                        b(1, 0, 1),
                        b(1, 1, 1),
                        b(0, 1, 1),
                    ],
                    material,
                    part,
                });
            }
        }
    }
    Mesh { nodes, elements }
}

//! Finite elements and assembly.
//!
//! Sparse matrices are faer `SparseColMat<usize, f64>` in *full* symmetric storage (both
//! triangles present), indexed by free DOFs (constrained DOFs eliminated). DOF numbering of a
//! node `n` before elimination is `3 n + d`, `d = 0, 1, 2` for x, y, z.

pub mod material;

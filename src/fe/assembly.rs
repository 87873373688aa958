//! DOF numbering with constraints, and parallel sparse assembly of K, M and C.
//!
//! # Model
//! Three translational DOFs per node, global index `3 n + d`. Constraints are homogeneous
//! Dirichlet conditions (`u = 0`) imposed by *elimination*: the assembled matrices are
//! restricted to the free DOFs, numbered in increasing global order ([`DofMap`]).
//!
//! The global matrices are the usual direct-stiffness sums (Bathe, *Finite Element
//! Procedures*, 1996, §4.2.1): `K = Σ_e K_e + Σ_s k_s g_s g_sᵀ`, `M = Σ_e M_e + Σ_p m_p I₃`,
//! `C = Σ_s c_s g_s g_sᵀ` (springs: [`super::spring`]; hexahedra: [`super::hex8`]).
//! There is no material (Rayleigh) damping here: C holds only the discrete dampers.
//!
//! # Storage
//! K, M and C are faer `SparseColMat<usize, f64>` in full symmetric storage (both triangles)
//! and share **one** sparsity pattern: the node-graph pattern of the elements plus the node
//! couplings of the springs, expanded to 3×3 DOF blocks. The pattern may therefore hold
//! explicit zeros (e.g. the C entries of an element, the x–z entries of a z spring), which
//! keeps `K − σM` a value-wise operation for shift-invert.
//!
//! # Parallelism
//! Elements are processed in chunks: the element matrices of a chunk are computed in
//! parallel (rayon), then scattered in parallel by *column ranges* (each thread owns a
//! contiguous slice of the CSC value array), so the result does not depend on the number
//! of threads (every entry is summed in element order).

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use nalgebra::SMatrix;
use rayon::prelude::*;

use super::hex8::{self, Mat24};
use super::material::IsotropicElastic;
use super::spring::{PointMass, Spring};
use super::{check_material, FeError};
use crate::mesh::{Mesh, Part};

const NONE: usize = usize::MAX;

/// Maps global DOFs (`3 node + dir`) to free-DOF indices and back.
#[derive(Debug, Clone, PartialEq)]
pub struct DofMap {
    n_nodes: usize,
    constrained: Vec<bool>,
    free_of_global: Vec<usize>,
    global_of_free: Vec<usize>,
}

impl DofMap {
    /// All DOFs of `n_nodes` nodes free.
    pub fn new(n_nodes: usize) -> Self {
        Self::from_flags(n_nodes, vec![false; 3 * n_nodes])
    }

    /// `n_nodes` nodes with the listed global DOFs constrained to zero (duplicates allowed).
    pub fn with_constraints(n_nodes: usize, constrained_dofs: &[usize]) -> Result<Self, FeError> {
        let mut flags = vec![false; 3 * n_nodes];
        for &d in constrained_dofs {
            if d >= flags.len() {
                return Err(FeError::IndexOutOfRange {
                    what: "constrained DOF".into(),
                    index: d,
                    len: flags.len(),
                });
            }
            flags[d] = true;
        }
        Ok(Self::from_flags(n_nodes, flags))
    }

    fn from_flags(n_nodes: usize, constrained: Vec<bool>) -> Self {
        let mut free_of_global = vec![NONE; constrained.len()];
        let mut global_of_free = Vec::with_capacity(constrained.len());
        for (g, &c) in constrained.iter().enumerate() {
            if !c {
                free_of_global[g] = global_of_free.len();
                global_of_free.push(g);
            }
        }
        DofMap {
            n_nodes,
            constrained,
            free_of_global,
            global_of_free,
        }
    }

    /// Global DOF index of direction `dir` (0 = x, 1 = y, 2 = z) at `node`.
    pub fn dof(node: usize, dir: usize) -> usize {
        3 * node + dir
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.n_nodes
    }

    /// Number of global DOFs (`3 n_nodes`).
    pub fn n_dofs(&self) -> usize {
        self.constrained.len()
    }

    /// Number of free DOFs (the size of the assembled matrices).
    pub fn n_free(&self) -> usize {
        self.global_of_free.len()
    }

    /// Number of constrained DOFs.
    pub fn n_constrained(&self) -> usize {
        self.n_dofs() - self.n_free()
    }

    /// Whether a global DOF is constrained (false for out-of-range DOFs).
    pub fn is_constrained(&self, dof: usize) -> bool {
        self.constrained.get(dof).copied().unwrap_or(false)
    }

    /// Free index of a global DOF (None if constrained or out of range).
    pub fn free_index(&self, dof: usize) -> Option<usize> {
        match self.free_of_global.get(dof) {
            Some(&f) if f != NONE => Some(f),
            _ => None,
        }
    }

    /// Global DOF of a free index (panics if `free >= n_free()`: an index bug, not input).
    pub fn global_dof(&self, free: usize) -> usize {
        self.global_of_free[free]
    }

    /// Iterator over the constrained global DOFs, increasing.
    pub fn constrained_dofs(&self) -> impl Iterator<Item = usize> + '_ {
        self.constrained
            .iter()
            .enumerate()
            .filter(|(_, &c)| c)
            .map(|(g, _)| g)
    }

    /// Full vector (length `n_dofs`) from a free vector, zeros at constrained DOFs.
    pub fn expand(&self, u_free: &[f64]) -> Result<Vec<f64>, FeError> {
        check_len("free vector", self.n_free(), u_free.len())?;
        let mut out = vec![0.0; self.n_dofs()];
        for (f, &g) in self.global_of_free.iter().enumerate() {
            out[g] = u_free[f];
        }
        Ok(out)
    }

    /// Free vector from a full vector (drops constrained DOFs).
    pub fn restrict(&self, full: &[f64]) -> Result<Vec<f64>, FeError> {
        check_len("full vector", self.n_dofs(), full.len())?;
        Ok(self.global_of_free.iter().map(|&g| full[g]).collect())
    }
}

fn check_len(what: &str, expected: usize, got: usize) -> Result<(), FeError> {
    if expected == got {
        Ok(())
    } else {
        Err(FeError::DimensionMismatch {
            what: what.into(),
            expected,
            got,
        })
    }
}

/// Which element mass matrix to assemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MassKind {
    /// Consistent mass `ρ ∫ NᵀN dV`.
    #[default]
    Consistent,
    /// HRZ-lumped diagonal mass ([`hex8::lumped_mass`]).
    Lumped,
}

/// Assembly options.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AssemblyOptions {
    /// Element mass matrix kind.
    pub mass: MassKind,
}

/// Assembled global matrices over the free DOFs (full symmetric storage, one shared pattern).
#[derive(Debug, Clone)]
pub struct FeMatrices {
    /// Stiffness K (N/m).
    pub k: SparseColMat<usize, f64>,
    /// Mass M (kg).
    pub m: SparseColMat<usize, f64>,
    /// Damping C (N·s/m), discrete dampers only.
    pub c: SparseColMat<usize, f64>,
}

/// A value per [`Part`], in the order of [`Part::ALL`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PerPart(pub [f64; 3]);

impl PerPart {
    /// Value of one part.
    pub fn get(&self, part: Part) -> f64 {
        self.0[part_index(part)]
    }

    /// Sum over the parts.
    pub fn total(&self) -> f64 {
        self.0.iter().sum()
    }
}

fn part_index(part: Part) -> usize {
    match part {
        Part::Rail => 0,
        Part::Sleeper => 1,
        Part::Wheel => 2,
    }
}

/// Validates mesh references and materials; returns nothing on success.
fn validate(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    springs: &[Spring],
) -> Result<(), FeError> {
    for (i, m) in materials.iter().enumerate() {
        check_material(i, m)?;
    }
    let nn = mesh.nodes.len();
    for (e, el) in mesh.elements.iter().enumerate() {
        if el.material >= materials.len() {
            return Err(FeError::MaterialIndex {
                element: e,
                material: el.material,
                n_materials: materials.len(),
            });
        }
        for &n in &el.nodes {
            if n >= nn {
                return Err(FeError::IndexOutOfRange {
                    what: format!("element {e} node"),
                    index: n,
                    len: nn,
                });
            }
        }
    }
    for (i, s) in springs.iter().enumerate() {
        s.validate(i, 3 * nn)?;
    }
    Ok(())
}

fn coords_of(mesh: &Mesh, nodes: &[usize; 8]) -> [[f64; 3]; 8] {
    nodes.map(|n| mesh.nodes[n])
}

fn tag_element(e: usize, err: FeError) -> FeError {
    match err {
        FeError::NonPositiveJacobian { det_j, xi, .. } => FeError::NonPositiveJacobian {
            element: Some(e),
            det_j,
            xi,
        },
        other => other,
    }
}

/// Builds the shared free-DOF pattern: (col_ptr, row_idx).
fn build_pattern(mesh: &Mesh, springs: &[Spring], dofmap: &DofMap) -> (Vec<usize>, Vec<usize>) {
    let nn = mesh.nodes.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nn];
    for (n, a) in adj.iter_mut().enumerate() {
        a.push(n);
    }
    for el in &mesh.elements {
        for &a in &el.nodes {
            adj[a].extend_from_slice(&el.nodes);
        }
    }
    for s in springs {
        let nodes: Vec<usize> = s.weights().iter().map(|&(d, _)| d / 3).collect();
        for &a in &nodes {
            adj[a].extend_from_slice(&nodes);
        }
    }
    adj.par_iter_mut().for_each(|a| {
        a.sort_unstable();
        a.dedup();
    });
    let nf = dofmap.n_free();
    let mut col_ptr = Vec::with_capacity(nf + 1);
    col_ptr.push(0usize);
    let mut nnz = 0usize;
    for f in 0..nf {
        let node = dofmap.global_dof(f) / 3;
        for &m in &adj[node] {
            nnz += (0..3)
                .filter(|&d| dofmap.free_index(3 * m + d).is_some())
                .count();
        }
        col_ptr.push(nnz);
    }
    let mut row_idx = Vec::with_capacity(nnz);
    for f in 0..nf {
        let node = dofmap.global_dof(f) / 3;
        for &m in &adj[node] {
            for d in 0..3 {
                if let Some(r) = dofmap.free_index(3 * m + d) {
                    row_idx.push(r);
                }
            }
        }
    }
    (col_ptr, row_idx)
}

/// Element matrices of one element for the scatter.
#[derive(Clone)]
struct ElemBuf {
    k: Mat24,
    m: SMatrix<f64, 8, 8>,
}

/// Assembles K, M and C over the free DOFs of `dofmap` (see the module docs).
///
/// `materials[e.material]` gives each element's material; springs and point masses refer
/// to global node/DOF indices. Fails on inconsistent indices, inadmissible materials or
/// springs, and inverted elements (the error names the element).
///
/// Phases: the checks, the sparsity pattern (`build_pattern`), the elements' matrices
/// scattered in parallel by column range (`scatter_elements`), then the springs and
/// point masses (`add_springs_and_masses`).
pub fn assemble(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    springs: &[Spring],
    point_masses: &[PointMass],
    dofmap: &DofMap,
    opts: AssemblyOptions,
) -> Result<FeMatrices, FeError> {
    validate(mesh, materials, springs)?;
    check_len(
        "DofMap nodes vs mesh nodes",
        mesh.nodes.len(),
        dofmap.n_nodes(),
    )?;
    check_point_masses(mesh, point_masses)?;
    let nf = dofmap.n_free();
    let (col_ptr, row_idx) = build_pattern(mesh, springs, dofmap);
    let nnz = row_idx.len();
    let mut kv = vec![0.0f64; nnz];
    let mut mv = vec![0.0f64; nnz];
    let mut cv = vec![0.0f64; nnz];
    let pattern = ColumnSlab {
        col_ptr: &col_ptr,
        row_idx: &row_idx,
        c0: 0,
        c1: nf,
    };
    scatter_elements(
        mesh,
        materials,
        dofmap,
        opts.mass == MassKind::Lumped,
        &pattern,
        (&mut kv, &mut mv),
    )?;
    add_springs_and_masses(
        springs,
        point_masses,
        dofmap,
        &pattern,
        (&mut kv, &mut mv, &mut cv),
    );
    let symbolic = SymbolicSparseColMat::new_checked(nf, nf, col_ptr, None, row_idx);
    Ok(FeMatrices {
        k: SparseColMat::new(symbolic.clone(), kv),
        m: SparseColMat::new(symbolic.clone(), mv),
        c: SparseColMat::new(symbolic, cv),
    })
}

/// The damping matrix `C` alone (N·s/m, over the free DOFs): the discrete dampers of
/// `springs` on `n_nodes` nodes, stored on the pattern of the springs' own entries. Its
/// nonzero values are those of [`assemble`]'s `C` bit for bit (each entry sums the same
/// springs' terms in the same order, from 0); only the stored zeros of the elements' pattern
/// are left out. For a caller that needs `C` but neither `K` nor `M`.
pub fn assemble_damping(
    springs: &[Spring],
    n_nodes: usize,
    dofmap: &DofMap,
) -> Result<SparseColMat<usize, f64>, FeError> {
    check_len("DofMap nodes vs mesh nodes", n_nodes, dofmap.n_nodes())?;
    for (i, s) in springs.iter().enumerate() {
        s.validate(i, 3 * n_nodes)?;
    }
    let free = |s: &Spring| -> Vec<(usize, f64)> {
        s.weights()
            .into_iter()
            .filter_map(|(d, w)| dofmap.free_index(d).map(|f| (f, w)))
            .collect()
    };
    let mut entries: Vec<(usize, usize)> = Vec::new();
    for s in springs {
        let g = free(s);
        for &(c, _) in &g {
            entries.extend(g.iter().map(|&(r, _)| (c, r)));
        }
    }
    entries.sort_unstable();
    entries.dedup();
    let nf = dofmap.n_free();
    let mut col_ptr = vec![0usize; nf + 1];
    for &(c, _) in &entries {
        col_ptr[c + 1] += 1;
    }
    for c in 0..nf {
        col_ptr[c + 1] += col_ptr[c];
    }
    let row_idx: Vec<usize> = entries.iter().map(|&(_, r)| r).collect();
    let mut cv = vec![0.0f64; row_idx.len()];
    for s in springs {
        let g = free(s);
        for &(ci, wi) in &g {
            for &(ri, wj) in &g {
                let (a, b) = (col_ptr[ci], col_ptr[ci + 1]);
                let pos = a + row_idx[a..b].binary_search(&ri).unwrap_or(0);
                cv[pos] += s.damping * wi * wj;
            }
        }
    }
    let symbolic = SymbolicSparseColMat::new_checked(nf, nf, col_ptr, None, row_idx);
    Ok(SparseColMat::new(symbolic, cv))
}

/// Every point mass on an existing node, with a finite mass ≥ 0 (kg).
fn check_point_masses(mesh: &Mesh, point_masses: &[PointMass]) -> Result<(), FeError> {
    for (i, p) in point_masses.iter().enumerate() {
        if p.node >= mesh.nodes.len() {
            return Err(FeError::IndexOutOfRange {
                what: format!("point mass {i} node"),
                index: p.node,
                len: mesh.nodes.len(),
            });
        }
        if !(p.mass.is_finite() && p.mass >= 0.0) {
            return Err(FeError::InvalidSpring {
                index: i,
                reason: format!("point mass {} kg must be finite and ≥ 0", p.mass),
            });
        }
    }
    Ok(())
}

/// The element stiffness and mass matrices (`lumped` or consistent mass) added into the
/// values `kv`, `mv` of the `pattern` (all its columns): element matrices computed in
/// parallel in chunks, then scattered in parallel by column ranges balanced by nnz.
fn scatter_elements(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    dofmap: &DofMap,
    lumped: bool,
    pattern: &ColumnSlab<'_>,
    (kv, mv): (&mut [f64], &mut [f64]),
) -> Result<(), FeError> {
    let (col_ptr, row_idx) = (pattern.col_ptr, pattern.row_idx);
    let nf = pattern.c1;
    let nnz = row_idx.len();
    // Column ranges owned by the scatter tasks: balanced by nnz.
    let n_tasks = (4 * rayon::current_num_threads()).clamp(1, nf.max(1));
    let mut bounds = vec![0usize];
    for t in 1..n_tasks {
        let target = nnz * t / n_tasks;
        let c = col_ptr.partition_point(|&p| p < target).min(nf);
        if c > *bounds.last().unwrap() {
            bounds.push(c);
        }
    }
    if *bounds.last().unwrap() != nf {
        bounds.push(nf);
    }

    const CHUNK: usize = 4096;
    let mut buf = vec![
        ElemBuf {
            k: Mat24::zeros(),
            m: SMatrix::zeros(),
        };
        CHUNK.min(mesh.elements.len())
    ];
    // Local → free index map for each element of the chunk.
    let mut lfree = vec![[NONE; 24]; buf.len()];
    for (chunk_no, elems) in mesh.elements.chunks(CHUNK).enumerate() {
        let base = chunk_no * CHUNK;
        let nb = elems.len();
        buf[..nb]
            .par_iter_mut()
            .zip(lfree[..nb].par_iter_mut())
            .zip(elems.par_iter())
            .enumerate()
            .try_for_each(|(i, ((b, lf), el))| -> Result<(), FeError> {
                let e = base + i;
                let c = coords_of(mesh, &el.nodes);
                let mat = &materials[el.material];
                b.k = hex8::stiffness(&c, mat).map_err(|x| tag_element(e, x))?;
                if lumped {
                    let l = hex8::lumped_mass(&c, mat).map_err(|x| tag_element(e, x))?;
                    b.m = SMatrix::from_diagonal(&nalgebra::SVector::from(l));
                } else {
                    b.m = hex8::consistent_mass_scalar(&c, mat).map_err(|x| tag_element(e, x))?;
                }
                for a in 0..8 {
                    for d in 0..3 {
                        lf[3 * a + d] = dofmap.free_index(3 * el.nodes[a] + d).unwrap_or(NONE);
                    }
                }
                Ok(())
            })?;
        // Parallel scatter by column range.
        let bufs = &buf[..nb];
        let lfs = &lfree[..nb];
        let mut kslices = split_by_bounds(&mut *kv, col_ptr, &bounds);
        let mut mslices = split_by_bounds(&mut *mv, col_ptr, &bounds);
        kslices
            .par_iter_mut()
            .zip(mslices.par_iter_mut())
            .enumerate()
            .for_each(|(t, (ks, ms))| {
                let slab = ColumnSlab {
                    col_ptr,
                    row_idx,
                    c0: bounds[t],
                    c1: bounds[t + 1],
                };
                for (b, lf) in bufs.iter().zip(lfs) {
                    scatter_element(b, lf, &slab, ks, ms);
                }
            });
    }
    Ok(())
}

/// The springs (stiffness into `kv`, damping into `cv`) and the point masses (into `mv`)
/// added into the values of the `pattern` (serial: they are few).
fn add_springs_and_masses(
    springs: &[Spring],
    point_masses: &[PointMass],
    dofmap: &DofMap,
    pattern: &ColumnSlab<'_>,
    (kv, mv, cv): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let (col_ptr, row_idx) = (pattern.col_ptr, pattern.row_idx);
    let find = |row: usize, col: usize| -> usize {
        let (s, e) = (col_ptr[col], col_ptr[col + 1]);
        s + row_idx[s..e].binary_search(&row).unwrap_or(0)
    };
    for s in springs {
        let g: Vec<(usize, f64)> = s
            .weights()
            .into_iter()
            .filter_map(|(d, w)| dofmap.free_index(d).map(|f| (f, w)))
            .collect();
        for &(ci, wi) in &g {
            for &(ri, wj) in &g {
                let pos = find(ri, ci);
                kv[pos] += s.stiffness * wi * wj;
                cv[pos] += s.damping * wi * wj;
            }
        }
    }
    for p in point_masses {
        for d in 0..3 {
            if let Some(f) = dofmap.free_index(3 * p.node + d) {
                mv[find(f, f)] += p.mass;
            }
        }
    }
}

/// The columns `c0..c1` of a compressed-column sparsity pattern (`col_ptr`, `row_idx`) that
/// one thread fills.
#[derive(Clone, Copy)]
struct ColumnSlab<'a> {
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
    c0: usize,
    c1: usize,
}

/// Scatters one element's K and M into the value slices `ks`, `ms` of the slab's columns
/// `c0..c1` (whose first value sits at `col_ptr[c0]`). Uses that all free columns of one node share
/// the same row list and that the free rows of one node are contiguous in it: one binary
/// search per (row node, column node) pair.
fn scatter_element(
    b: &ElemBuf,
    lf: &[usize; 24],
    slab: &ColumnSlab<'_>,
    ks: &mut [f64],
    ms: &mut [f64],
) {
    let ColumnSlab {
        col_ptr,
        row_idx,
        c0,
        c1,
    } = *slab;
    let off = col_ptr[c0];
    // First free row of each local node (NONE if the node is fully constrained).
    let first: [usize; 8] = std::array::from_fn(|a| {
        lf[3 * a..3 * a + 3]
            .iter()
            .copied()
            .find(|&r| r != NONE)
            .unwrap_or(NONE)
    });
    for nb in 0..8 {
        let Some(col_any) = lf[3 * nb..3 * nb + 3].iter().copied().find(|&c| c != NONE) else {
            continue;
        };
        // Columns of a node are consecutive free indices: skip nodes outside the range.
        if lf[3 * nb..3 * nb + 3]
            .iter()
            .all(|&c| c == NONE || c < c0 || c >= c1)
        {
            continue;
        }
        let rows = &row_idx[col_ptr[col_any]..col_ptr[col_any + 1]];
        for na in 0..8 {
            if first[na] == NONE {
                continue;
            }
            // In the pattern by construction.
            let rel = rows.binary_search(&first[na]).unwrap_or(0);
            for dj in 0..3 {
                let col = lf[3 * nb + dj];
                if col == NONE || col < c0 || col >= c1 {
                    continue;
                }
                let base = col_ptr[col] + rel - off;
                let q = 3 * nb + dj;
                let mut k = 0;
                for di in 0..3 {
                    if lf[3 * na + di] == NONE {
                        continue;
                    }
                    let p = 3 * na + di;
                    ks[base + k] += b.k[(p, q)];
                    if di == dj {
                        ms[base + k] += b.m[(na, nb)];
                    }
                    k += 1;
                }
            }
        }
    }
}

/// Splits a CSC value array into the mutable slices of the column ranges `bounds`.
fn split_by_bounds<'a>(
    vals: &'a mut [f64],
    col_ptr: &[usize],
    bounds: &[usize],
) -> Vec<&'a mut [f64]> {
    let mut out = Vec::with_capacity(bounds.len() - 1);
    let mut rest = vals;
    for t in 0..bounds.len() - 1 {
        let len = col_ptr[bounds[t + 1]] - col_ptr[bounds[t]];
        let (a, b) = rest.split_at_mut(len);
        out.push(a);
        rest = b;
    }
    out
}

/// Element mass totals `Σ ρ V` (kg) per part (point masses not included).
pub fn mass_per_part(mesh: &Mesh, materials: &[IsotropicElastic]) -> Result<PerPart, FeError> {
    validate(mesh, materials, &[])?;
    let mut out = PerPart::default();
    for (e, el) in mesh.elements.iter().enumerate() {
        let v = hex8::volume(&coords_of(mesh, &el.nodes)).map_err(|x| tag_element(e, x))?;
        out.0[part_index(el.part)] += v * materials[el.material].density;
    }
    Ok(out)
}

/// Element strain energy `Σ_e ½ u_eᵀ K_e u_e` (J) per part for a full displacement vector
/// (m, length `3 n_nodes`, e.g. [`DofMap::expand`] of a mode shape). Springs are not
/// included: see [`spring_energy`].
pub fn strain_energy_per_part(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    u_full: &[f64],
) -> Result<PerPart, FeError> {
    Ok(strain_energy_per_part_many(mesh, materials, &[u_full])?[0])
}

/// [`strain_energy_per_part`] of several displacement vectors at once: each element
/// stiffness is built once and applied to every vector (classifying hundreds of modes costs
/// one pass over the elements instead of one per mode).
pub fn strain_energy_per_part_many(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    u_full: &[&[f64]],
) -> Result<Vec<PerPart>, FeError> {
    validate(mesh, materials, &[])?;
    for u in u_full {
        check_len("displacement vector", 3 * mesh.nodes.len(), u.len())?;
    }
    let nv = u_full.len();
    // Per element: U_e (24 × nv, the element's displacements of every vector), W = K_e U_e
    // by a dense product (the quadratic forms are most of the work: 1152 flops per element
    // and vector, e.g. 30 GFlop for the 746 modes of the default track to 5 kHz), then
    // ½ u_eᵀ w_e per column. The elements are taken in fixed chunks (buffers per chunk, none
    // per element), each summed in element order, and the chunk sums are added in chunk
    // order: the result does not depend on the thread count or on rayon's work split.
    const ENERGY_CHUNK: usize = 2048;
    let chunk_sums = mesh
        .elements
        .par_chunks(ENERGY_CHUNK)
        .enumerate()
        .map(|(ci, chunk)| -> Result<Vec<PerPart>, FeError> {
            let mut acc = vec![PerPart::default(); nv];
            let mut ue = faer::Mat::<f64>::zeros(24, nv);
            let mut w = faer::Mat::<f64>::zeros(24, nv);
            for (i, el) in chunk.iter().enumerate() {
                let e = ci * ENERGY_CHUNK + i;
                let k = hex8::stiffness(&coords_of(mesh, &el.nodes), &materials[el.material])
                    .map_err(|x| tag_element(e, x))?;
                let part = part_index(el.part);
                for (i, u) in u_full.iter().enumerate() {
                    for n in 0..8 {
                        for d in 0..3 {
                            ue[(3 * n + d, i)] = u[3 * el.nodes[n] + d];
                        }
                    }
                }
                let kr = faer::MatRef::from_column_major_slice(k.as_slice(), 24, 24);
                faer::linalg::matmul::matmul(
                    w.as_mut(),
                    faer::Accum::Replace,
                    kr,
                    ue.as_ref(),
                    1.0,
                    faer::Par::Seq,
                );
                for (i, a) in acc.iter_mut().enumerate() {
                    let mut q = 0.0;
                    for r in 0..24 {
                        q += ue[(r, i)] * w[(r, i)];
                    }
                    a.0[part] += 0.5 * q;
                }
            }
            Ok(acc)
        })
        .collect::<Result<Vec<_>, FeError>>()?;
    let mut out = vec![PerPart::default(); nv];
    for sums in &chunk_sums {
        for (x, y) in out.iter_mut().zip(sums) {
            for p in 0..3 {
                x.0[p] += y.0[p];
            }
        }
    }
    Ok(out)
}

/// Total spring strain energy `Σ ½ k r²` (J) for a full displacement vector (m).
pub fn spring_energy(springs: &[Spring], u_full: &[f64]) -> f64 {
    springs.iter().map(|s| s.energy(u_full)).sum()
}

/// Unreduced stiffness action `K_full u` (N) over all `3 n_nodes` DOFs, element by element
/// (no global matrix), springs included.
pub fn apply_full_stiffness(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    springs: &[Spring],
    u_full: &[f64],
) -> Result<Vec<f64>, FeError> {
    validate(mesh, materials, springs)?;
    let n = 3 * mesh.nodes.len();
    check_len("displacement vector", n, u_full.len())?;
    let mut out = mesh
        .elements
        .par_chunks(2048)
        .enumerate()
        .map(|(ci, chunk)| -> Result<Vec<f64>, FeError> {
            let mut acc = vec![0.0; n];
            for (i, el) in chunk.iter().enumerate() {
                let k = hex8::stiffness(&coords_of(mesh, &el.nodes), &materials[el.material])
                    .map_err(|x| tag_element(ci * 2048 + i, x))?;
                let mut ue = nalgebra::SVector::<f64, 24>::zeros();
                for a in 0..8 {
                    for d in 0..3 {
                        ue[3 * a + d] = u_full[3 * el.nodes[a] + d];
                    }
                }
                let fe = k * ue;
                for a in 0..8 {
                    for d in 0..3 {
                        acc[3 * el.nodes[a] + d] += fe[3 * a + d];
                    }
                }
            }
            Ok(acc)
        })
        .try_reduce(
            || vec![0.0; n],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                Ok(a)
            },
        )?;
    for s in springs {
        let g = s.weights();
        let r: f64 = g.iter().map(|&(d, w)| w * u_full[d]).sum();
        for (d, w) in g {
            out[d] += s.stiffness * r * w;
        }
    }
    Ok(out)
}

/// Reaction forces (N) at the constrained DOFs: `(K_full u − f)` restricted to them, as
/// `(global DOF, reaction)` in increasing DOF order. `u_full` (m) and `f_full` (N, the
/// applied loads) have length `3 n_nodes`. For a static solution of a model without ground
/// springs, `Σ R_d + Σ f_d = 0` in each direction `d` (the supports carry the load).
pub fn reactions(
    mesh: &Mesh,
    materials: &[IsotropicElastic],
    springs: &[Spring],
    dofmap: &DofMap,
    u_full: &[f64],
    f_full: &[f64],
) -> Result<Vec<(usize, f64)>, FeError> {
    check_len("load vector", dofmap.n_dofs(), f_full.len())?;
    let ku = apply_full_stiffness(mesh, materials, springs, u_full)?;
    Ok(dofmap
        .constrained_dofs()
        .map(|d| (d, ku[d] - f_full[d]))
        .collect())
}

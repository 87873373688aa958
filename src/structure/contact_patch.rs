//! The local FE contact patch: influence coefficients of the contact grid condensed from a
//! refined FE submodel instead of taken from the elastic half-space (theory §6.9).
//!
//! What it models: the surface displacement of a linear elastic body at the centre of each
//! contact-grid element per unit uniform traction (pressure and the two shear tractions) on
//! one source element, computed by a static FE solve of a submodel whose surface elements at
//! the contact are a fraction of the grid element (`refine` FE faces per grid element along
//! each axis), graded to coarse elements away from it. One sparse Cholesky factorisation
//! serves the three unit loads. The result, a [`SurfaceKernel`], is translation-invariant
//! over the offsets it holds (the body is a tensor-product block, uniform over the fine zone).
//!
//! This file holds the flat block: the check of the FE condensation against the closed forms
//! of Boussinesq and Cerruti ([`crate::contact::influence::single_body`]). Assumptions: linear
//! elasticity, small strain; the block's far faces (sides and bottom) are fixed, which stands
//! for the half-space's vanishing displacement at infinity and leaves an error of order
//! `r / extent` at distance `r` from the load (the reason the block is large and graded).
//! Surface values at a grid element's centre are interpolated bilinearly on the FE surface
//! face that contains it (the FE displacement is bilinear on a face; the incompatible modes
//! are internal to an element).
//!
//! References: K. L. Johnson, *Contact Mechanics* (1985), §3.2 and §3.6; J. J. Kalker,
//! *Three-Dimensional Elastic Bodies in Rolling Contact* (1990), ch. 5 (influence numbers).

use faer::Mat;
use nalgebra::DMatrix;

use crate::contact::penalty;
use crate::fe::assembly::{assemble, AssemblyOptions, DofMap, FeMatrices};
use crate::fe::block::{block_node, graded_block_mesh};
use crate::fe::material::IsotropicElastic;
use crate::fe::solve::Cholesky;
use crate::mesh::grading::{grade, FineZone, GradingSpec};
use crate::mesh::{Mesh, Part};

use super::StructureError;
pub(crate) use mirror::{half_planes, strip_kernel_by_halves, with_mirror_holds, Mirror};

/// The largest patch submodel built (free DOFs). The largest run so far, a 431,244-DOF flat
/// block, took 8.5 minutes on two cores; the factor's fill grows faster than the DOFs, so
/// this bound (about 3.5 times that) keeps a request from running for hours or exhausting a
/// 24 GiB machine (not measured at the bound). Larger requests are refused, naming the
/// parameters to lower.
pub const MAX_PATCH_DOFS: usize = 1_500_000;

/// A flat elastic block whose top face `z = 0` carries the contact grid, centred on the
/// source element at `(x, y) = (0, 0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlatBlockPatch {
    /// The block's material (Pa, −, kg/m³; density unused).
    pub material: IsotropicElastic,
    /// Contact-grid element size `a` (m), square; 0.8 mm in the reference study. Range
    /// 1e-5–1e-2 m.
    pub element_m: f64,
    /// FE faces per grid element along each axis over the source element and its neighbours
    /// (≥ 1; 1–5 in practice); the rest of the fine zone has faces of at most `a`.
    pub refine: usize,
    /// FE faces per grid element along each axis over the rest of the fine zone (≥ 1, at
    /// most `refine`; 1 by default).
    pub zone_refine: usize,
    /// Grid elements either side of the source element in the fine zone, along x and y
    /// (≥ 1): the kernel holds offsets `−half..=half`.
    pub half_elements: usize,
    /// Depth of the fine zone in grid elements (≥ 1).
    pub fine_depth_elements: usize,
    /// Half-width of the block along x and y and its depth (m), ≫ `half_elements · a`.
    pub extent_m: f64,
    /// Largest ratio of neighbouring FE element sizes (> 1, ≤ 3).
    pub max_ratio: f64,
}

impl FlatBlockPatch {
    /// Steel, grid element `a` (m), three FE faces per grid element over the source, ±8 grid
    /// elements, 8 deep, a block of 0.5 m, growth ratio 1.5.
    pub fn steel(element_m: f64) -> Self {
        FlatBlockPatch {
            material: IsotropicElastic::STEEL,
            element_m,
            refine: 3,
            zone_refine: 1,
            half_elements: 8,
            fine_depth_elements: 8,
            extent_m: 0.5,
            max_ratio: 1.5,
        }
    }

    fn check(&self) -> Result<(), StructureError> {
        let bad = out_of_range;
        let a = self.element_m;
        if !(1e-5..=1e-2).contains(&a) {
            return bad("element_m", a, "1e-5 to 1e-2 m");
        }
        if self.refine == 0 {
            return bad("refine", 0.0, "at least 1");
        }
        if self.zone_refine == 0 || self.zone_refine > self.refine {
            return bad(
                "zone_refine",
                self.zone_refine as f64,
                "at least 1, at most refine",
            );
        }
        if self.half_elements == 0 {
            return bad("half_elements", 0.0, "at least 1");
        }
        if self.fine_depth_elements == 0 {
            return bad("fine_depth_elements", 0.0, "at least 1");
        }
        let fine = (self.half_elements as f64 + 0.5) * a;
        if !self.extent_m.is_finite() || self.extent_m < 2.0 * fine {
            return bad(
                "extent_m",
                self.extent_m,
                "at least twice the fine zone's half-width (half_elements + 1/2) · element_m",
            );
        }
        check_ratio(self.max_ratio)
    }

    /// The FE node planes `[xs, ys, zs]` (m): faces of `a / refine` over the source element
    /// and its neighbours (±1.5 a, and 1.5 a deep), at most `a / zone_refine` over the rest of
    /// the fine zone
    /// (±(half + ½) a, `fine_depth_elements · a` deep), graded with ratio `max_ratio` to sizes
    /// of up to `extent / 4` at the far faces; the source element's edges `±a/2` are planes.
    pub fn planes(&self) -> Result<[Vec<f64>; 3], StructureError> {
        self.check()?;
        let a = self.element_m;
        let h = a / self.refine as f64;
        let x_f = (self.half_elements as f64 + 0.5) * a;
        let h_zone = a / self.zone_refine as f64;
        let across = graded_axis(
            [-self.extent_m, self.extent_m],
            self.extent_m / 4.0,
            &[(1.5 * a, h), (x_f, h_zone)],
            vec![-x_f, -0.5 * a, 0.5 * a, x_f],
            self.max_ratio,
        )?;
        let depth_f = self.fine_depth_elements as f64 * a;
        let down = graded_axis(
            [-self.extent_m, 0.0],
            self.extent_m / 4.0,
            &[(1.5 * a, h), (depth_f, h_zone)],
            vec![-depth_f],
            self.max_ratio,
        )?;
        Ok([across.clone(), across, down])
    }

    /// Free DOFs of the submodel (nodes of the fixed far faces removed).
    pub fn n_dofs(&self) -> Result<usize, StructureError> {
        Ok(block_free_dofs(&self.planes()?))
    }

    /// Builds and factorises the submodel: its top face as a [`FactorisedSurface`]. Refuses a
    /// submodel beyond [`MAX_PATCH_DOFS`] before building it.
    pub fn factorised_surface(&self) -> Result<FactorisedSurface, StructureError> {
        let planes = self.planes()?;
        check_size(block_free_dofs(&planes))?;
        let [xs, ys, zs] = &planes;
        let factorised = self.factorise(xs, ys, zs)?;
        Ok(FactorisedSurface::block_top(planes, 1.0, factorised))
    }

    /// The block on the node planes, its far faces fixed: the DOF map, the matrices and the
    /// factor.
    fn factorise(
        &self,
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
    ) -> Result<(DofMap, FeMatrices, Cholesky), StructureError> {
        let mesh = graded_block_mesh([xs, ys, zs], 0, Part::Rail);
        let (nx, ny, nz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
        let mut fixed = Vec::new();
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    let far = i == 0 || i == nx || j == 0 || j == ny || k == 0;
                    if far {
                        let n = block_node(nx, ny, i, j, k);
                        fixed.extend([3 * n, 3 * n + 1, 3 * n + 2]);
                    }
                }
            }
        }
        assemble_and_factorise(&mesh, &fixed, self.material)
    }

    /// Builds and solves the submodel: the kernel for offsets `−half..=half` along x and y.
    /// Refuses a submodel beyond [`MAX_PATCH_DOFS`] before building it.
    pub fn kernel(&self) -> Result<SurfaceKernel, StructureError> {
        let planes = self.planes()?;
        let n_dofs = block_free_dofs(&planes);
        check_size(n_dofs)?;
        let [xs, ys, zs] = planes;
        let (dofmap, _, factor) = self.factorise(&xs, &ys, &zs)?;
        let (nx, ny, nz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
        let a = self.element_m;
        let surface = Surface {
            xs: &xs,
            ys: &ys,
            node: &|i, j| block_node(nx, ny, i, j, nz),
        };
        let half = self.half_elements as isize;
        let field: Vec<[f64; 2]> = (-half..=half)
            .flat_map(|ox| (-half..=half).map(move |oy| [ox as f64 * a, oy as f64 * a]))
            .collect();
        let mut c = condense(
            &dofmap,
            &factor,
            &surface,
            &[[-0.5 * a, 0.5 * a, -0.5 * a, 0.5 * a]],
            &field,
        )?;
        let c = c.pop().expect("one source");
        Ok(SurfaceKernel {
            half: self.half_elements,
            element_m: a,
            c,
            n_dofs,
        })
    }
}

/// A factorised submodel with its contact surface: what the penalty contact's static
/// solution reads (the surface's point compliance, [`Self::point_compliance`]) and where its
/// FE surface nodes lie ([`Self::surface_points`]), in the contact frame (m: `x` along the
/// rail, `y` across; a body turned over about x, the tread, has the surface's y mirrored); and
/// the assembled matrices an explicit integration of the submodel takes
/// ([`Self::matrices`]).
pub struct FactorisedSurface {
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// Global node of surface grid point `(i, j)` at index `i · ys.len() + j`.
    nodes: Vec<usize>,
    /// +1, or −1 for a surface whose y axis is the contact frame's mirrored.
    y_sign: f64,
    /// Thickness of the surface's element layer (m), for the penalty's element volume.
    layer_m: f64,
    dofmap: DofMap,
    matrices: FeMatrices,
    factor: Cholesky,
}

/// An FE surface node in the contact frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position `(x, y)` (m, contact frame).
    pub at: [f64; 2],
    /// Tributary face area (m²).
    pub area_m2: f64,
    /// The mesh node.
    pub node: usize,
}

impl FactorisedSurface {
    /// The top face `z = zs.last()` of a tensor-product block on the node planes `planes`
    /// (m; [`graded_block_mesh`]'s node numbering), `y_sign` −1 for a block turned over about
    /// x, with the block's DOF map, matrices and factor.
    fn block_top(
        planes: [Vec<f64>; 3],
        y_sign: f64,
        (dofmap, matrices, factor): (DofMap, FeMatrices, Cholesky),
    ) -> Self {
        let [xs, ys, zs] = planes;
        let (nx, ny, nz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
        let nodes = (0..=nx)
            .flat_map(|i| (0..=ny).map(move |j| block_node(nx, ny, i, j, nz)))
            .collect();
        FactorisedSurface {
            layer_m: zs[nz] - zs[nz - 1],
            xs,
            ys,
            nodes,
            y_sign,
            dofmap,
            matrices,
            factor,
        }
    }

    /// Free DOFs of the submodel.
    pub fn n_dofs(&self) -> usize {
        self.dofmap.n_free()
    }

    /// Thickness of the element layer under the surface at the contact (m).
    pub fn layer_m(&self) -> f64 {
        self.layer_m
    }

    /// The submodel's DOF map (its held DOFs constrained).
    pub fn dofmap(&self) -> &DofMap {
        &self.dofmap
    }

    /// The submodel's assembled stiffness, mass and damping over its free DOFs.
    pub fn matrices(&self) -> &FeMatrices {
        &self.matrices
    }

    /// The mesh's axes in the contact frame: `+1` or `−1` per component (x, y, z), the
    /// contact frame's `z` the rail's up (a tread, turned over about x, has `[1, −1, −1]`).
    pub fn axes(&self) -> [f64; 3] {
        [1.0, self.y_sign, self.y_sign]
    }

    /// Solves `K u = f` in place for the columns of `rhs` (free DOFs).
    pub fn solve_in_place(&self, rhs: &mut Mat<f64>) -> Result<(), StructureError> {
        Ok(self.factor.solve_in_place(rhs)?)
    }

    /// The FE surface nodes within `|x| ≤ half_x_m`, `|y| ≤ half_y_m` (m, contact frame),
    /// ordered by x then y.
    pub fn surface_points(&self, half_x_m: f64, half_y_m: f64) -> Vec<SurfacePoint> {
        let tributary = |p: &[f64], i: usize| {
            let lo = if i > 0 { p[i] - p[i - 1] } else { 0.0 };
            let hi = if i + 1 < p.len() {
                p[i + 1] - p[i]
            } else {
                0.0
            };
            0.5 * (lo + hi)
        };
        let eps = 1e-12;
        let ny = self.ys.len();
        let mut out = Vec::new();
        for (i, &x) in self.xs.iter().enumerate() {
            if x.abs() > half_x_m + eps {
                continue;
            }
            let mut column: Vec<SurfacePoint> = (0..ny)
                .filter(|&j| self.ys[j].abs() <= half_y_m + eps)
                .map(|j| SurfacePoint {
                    at: [x, self.y_sign * self.ys[j]],
                    area_m2: tributary(&self.xs, i) * tributary(&self.ys, j),
                    node: self.nodes[i * ny + j],
                })
                .collect();
            column.sort_by(|p, q| p.at[1].total_cmp(&q.at[1]));
            out.extend(column);
        }
        out
    }

    /// The surface nodes that carry the point `p` (m, contact frame) and their bilinear
    /// weights on the face that contains it.
    pub fn weights(&self, p: [f64; 2]) -> [(usize, f64); 4] {
        let ny = self.ys.len();
        penalty::bilinear_weights(&self.xs, &self.ys, [p[0], self.y_sign * p[1]])
            .map(|(i, j, w)| (self.nodes[i * ny + j], w))
    }

    /// The normal point compliance among `points` (m, contact frame): entry `(i, j)` the
    /// approach along the inward normal at point `i` per unit force (N) pressing on point
    /// `j` (m/N), a point's force shared and its displacement read by the bilinear shape
    /// functions of the surface face that contains it. Symmetric by construction.
    pub fn point_compliance(&self, points: &[[f64; 2]]) -> Result<DMatrix<f64>, StructureError> {
        let weights: Vec<[(usize, f64); 4]> = points.iter().map(|&p| self.weights(p)).collect();
        // the inward normal is −z
        let dof = |node: usize| self.dofmap.free_index(3 * node + 2);
        let mut rhs = Mat::<f64>::zeros(self.dofmap.n_free(), points.len());
        for (c, w) in weights.iter().enumerate() {
            for &(node, wk) in w {
                if let Some(f) = dof(node) {
                    rhs[(f, c)] -= wk;
                }
            }
        }
        self.factor.solve_in_place(&mut rhs)?;
        Ok(DMatrix::from_fn(points.len(), points.len(), |r, c| {
            weights[r]
                .iter()
                .map(|&(node, wk)| dof(node).map_or(0.0, |f| -wk * rhs[(f, c)]))
                .sum()
        }))
    }
}

/// The parameter error of a patch: `name = value`, allowed `allowed`.
pub(crate) fn out_of_range<T>(
    name: &'static str,
    value: f64,
    allowed: &'static str,
) -> Result<T, StructureError> {
    Err(StructureError::PatchParameter {
        name,
        value,
        allowed,
    })
}

/// Free DOFs of a block on the node planes `[xs, ys, zs]` whose sides and bottom are fixed.
fn block_free_dofs([xs, ys, zs]: &[Vec<f64>; 3]) -> usize {
    3 * (xs.len() - 2) * (ys.len() - 2) * (zs.len() - 1)
}

/// Refuses a submodel of more than [`MAX_PATCH_DOFS`] free DOFs, before it is built.
fn check_size(n_dofs: usize) -> Result<(), StructureError> {
    if n_dofs > MAX_PATCH_DOFS {
        return Err(StructureError::PatchTooLarge {
            dofs: n_dofs,
            limit: MAX_PATCH_DOFS,
        });
    }
    Ok(())
}

/// The grading ratio's range check (> 1, ≤ 3).
fn check_ratio(max_ratio: f64) -> Result<(), StructureError> {
    if max_ratio > 1.0 && max_ratio <= 3.0 {
        Ok(())
    } else {
        out_of_range("max_ratio", max_ratio, "above 1, at most 3")
    }
}

/// The DOF map with the `fixed` DOFs held and the Cholesky factor of the stiffness of `mesh`
/// (one material).
fn factorise(
    mesh: &Mesh,
    fixed: &[usize],
    material: IsotropicElastic,
) -> Result<(DofMap, Cholesky), StructureError> {
    let (dofmap, _, factor) = assemble_and_factorise(mesh, fixed, material)?;
    Ok((dofmap, factor))
}

/// As [`factorise`], keeping the assembled matrices (`K`, `M`, `C`).
fn assemble_and_factorise(
    mesh: &Mesh,
    fixed: &[usize],
    material: IsotropicElastic,
) -> Result<(DofMap, FeMatrices, Cholesky), StructureError> {
    let dofmap = DofMap::with_constraints(mesh.nodes.len(), fixed)?;
    let fm = assemble(
        mesh,
        &[material],
        &[],
        &[],
        &dofmap,
        AssemblyOptions::default(),
    )?;
    let factor = Cholesky::new(&fm.k)?;
    Ok((dofmap, fm, factor))
}

/// Node positions (m) over `[start, end]`: elements of at most `size` within `±reach` of 0
/// (clipped to the interval) for each `(reach, size)` of `zones`, graded with `max_ratio` to
/// at most `coarse_m`, with the `breakpoints_m` as nodes.
pub(crate) fn graded_axis(
    [start_m, end_m]: [f64; 2],
    coarse_m: f64,
    zones: &[(f64, f64)],
    breakpoints_m: Vec<f64>,
    max_ratio: f64,
) -> Result<Vec<f64>, StructureError> {
    let mut spec = GradingSpec::new(start_m, end_m, coarse_m);
    spec.zones = zones
        .iter()
        .map(|&(reach, size_m)| FineZone {
            start_m: (-reach).max(start_m),
            end_m: reach.min(end_m),
            size_m,
        })
        .collect();
    spec.breakpoints_m = breakpoints_m;
    spec.max_ratio = max_ratio;
    Ok(grade(&spec)?)
}

/// The contact surface of a submodel: FE nodes on the tensor grid `xs × ys` (m, the surface
/// projected on the contact plane, `x` along the rail, `y` across), `node(i, j)` the global
/// node at `(xs[i], ys[j])`; the inward normal is −z.
pub(crate) struct Surface<'a> {
    pub xs: &'a [f64],
    pub ys: &'a [f64],
    pub node: &'a (dyn Fn(usize, usize) -> usize + Sync),
}

/// `∫ N_k` (m) over `[lo, hi]` of the 1D hat functions on the nodes `p`: `(k, integral)`.
fn interval_weights(p: &[f64], lo: f64, hi: f64) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = Vec::new();
    for k in 0..p.len() - 1 {
        let (a, b) = (lo.max(p[k]), hi.min(p[k + 1]));
        if b <= a {
            continue;
        }
        let h = p[k + 1] - p[k];
        let left = ((p[k + 1] - a).powi(2) - (p[k + 1] - b).powi(2)) / (2.0 * h);
        let right = ((b - p[k]).powi(2) - (a - p[k]).powi(2)) / (2.0 * h);
        for (node, w) in [(k, left), (k + 1, right)] {
            match out.last_mut() {
                Some(last) if last.0 == node => last.1 += w,
                _ => out.push((node, w)),
            }
        }
    }
    out
}

/// The influence coefficients of `sources` (rectangles `[x0, x1, y0, y1]`, m) seen at
/// `field` points (m): per source, per field point, `c[i][j]` the displacement `i` per unit
/// uniform traction `j` (components x, y, inward normal). A unit traction's consistent nodal
/// loads are the integrals of the surface's bilinear shape functions over the rectangle
/// (exact on the projected tensor grid); the field values are interpolated bilinearly.
pub(crate) fn condense(
    dofmap: &DofMap,
    factor: &Cholesky,
    surface: &Surface<'_>,
    sources: &[[f64; 4]],
    field: &[[f64; 2]],
) -> Result<Vec<Vec<[[f64; 3]; 3]>>, StructureError> {
    condense_loads(
        (dofmap, factor, surface),
        sources,
        field,
        (&[0, 1, 2], None),
    )
}

/// [`condense`] for the traction components `loads` only (the other columns zero), and, with
/// `mirror`, on the half `x ≥ 0` of a submodel mirror-symmetric about the plane `x = 0`
/// loaded by sources symmetric about it: the half model's surface starts at `x = 0`, a
/// source's share of `x < 0` is its mirror's (so the plane's nodes carry half their load, by
/// the interval weights), and the field at `x < 0` is the mirror image of the half's
/// ([`Mirror::sign`]).
fn condense_loads(
    (dofmap, factor, surface): (&DofMap, &Cholesky, &Surface<'_>),
    sources: &[[f64; 4]],
    field: &[[f64; 2]],
    (loads, mirror): (&[usize], Option<Mirror>),
) -> Result<Vec<Vec<[[f64; 3]; 3]>>, StructureError> {
    // the inward normal is −z
    const SIGN: [f64; 3] = [1.0, 1.0, -1.0];
    let nl = loads.len();
    let mut rhs = Mat::<f64>::zeros(dofmap.n_free(), nl * sources.len());
    for (s, r) in sources.iter().enumerate() {
        let wx = interval_weights(surface.xs, r[0], r[1]);
        let wy = interval_weights(surface.ys, r[2], r[3]);
        for &(i, fx) in &wx {
            for &(j, fy) in &wy {
                let node = (surface.node)(i, j);
                for (col, &dir) in loads.iter().enumerate() {
                    if let Some(f) = dofmap.free_index(3 * node + dir) {
                        rhs[(f, nl * s + col)] += SIGN[dir] * fx * fy;
                    }
                }
            }
        }
    }
    factor.solve_in_place(&mut rhs)?;
    let out = (0..sources.len())
        .map(|s| {
            field
                .iter()
                .map(|&[px, py]| {
                    let mut cij = [[0.0; 3]; 3];
                    for (dir, row) in cij.iter_mut().enumerate() {
                        for (col, &load) in loads.iter().enumerate() {
                            let (qx, sign) = match mirror {
                                Some(m) if px < 0.0 => (-px, m.sign(dir)),
                                _ => (px, 1.0),
                            };
                            row[load] = sign
                                * SIGN[dir]
                                * surface_value(surface.xs, surface.ys, qx, py, |i, j| {
                                    let node = (surface.node)(i, j);
                                    dofmap
                                        .free_index(3 * node + dir)
                                        .map_or(0.0, |f| rhs[(f, nl * s + col)])
                                });
                        }
                    }
                    cij
                })
                .collect()
        })
        .collect();
    Ok(out)
}

/// The bilinear interpolation at `(px, py)` (m) of a nodal field on the top surface's
/// tensor grid `xs × ys`, the nodal value given by `value(i, j)`.
fn surface_value(
    xs: &[f64],
    ys: &[f64],
    px: f64,
    py: f64,
    value: impl Fn(usize, usize) -> f64,
) -> f64 {
    let cell = |p: &[f64], v: f64| -> (usize, f64) {
        let i = p.partition_point(|&q| q <= v).clamp(1, p.len() - 1) - 1;
        (i, (v - p[i]) / (p[i + 1] - p[i]))
    };
    let (i, s) = cell(xs, px);
    let (j, t) = cell(ys, py);
    (1.0 - s) * (1.0 - t) * value(i, j)
        + s * (1.0 - t) * value(i + 1, j)
        + s * t * value(i + 1, j + 1)
        + (1.0 - s) * t * value(i, j + 1)
}

/// Influence coefficients of one body on a square contact grid (m/Pa), translation-invariant
/// over the offsets held: `get(ox, oy)[i][j]` is the displacement component `i` at the centre
/// of the element offset by `(ox, oy)` elements from a source element carrying a unit uniform
/// traction component `j`; components `(x, y, n)`, `n` the inward normal (approach under a
/// compressive pressure), the convention of [`crate::contact::influence::single_body`].
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceKernel {
    half: usize,
    element_m: f64,
    c: Vec<[[f64; 3]; 3]>,
    n_dofs: usize,
}

impl SurfaceKernel {
    /// Largest offset held along each axis (elements).
    pub fn half(&self) -> usize {
        self.half
    }

    /// The grid element size (m).
    pub fn element_m(&self) -> f64 {
        self.element_m
    }

    /// Free DOFs of the submodel it was condensed from.
    pub fn n_dofs(&self) -> usize {
        self.n_dofs
    }

    /// The 3 × 3 coefficients (m/Pa) at offset `(ox, oy)` (elements), `None` beyond `half`.
    pub fn get(&self, ox: isize, oy: isize) -> Option<[[f64; 3]; 3]> {
        let h = self.half as isize;
        if ox.abs() > h || oy.abs() > h {
            return None;
        }
        let side = 2 * h + 1;
        Some(self.c[((ox + h) * side + (oy + h)) as usize])
    }
}

/// The kernel of a patch invariant along the rolling direction (a rail head or a tread):
/// `get(o, j, jp)[a][b]` (m/Pa) is the displacement `a` at the centre of the element in row
/// offset `o` and column `j` per unit traction `b` on the element of column `jp`; components x
/// (rolling), y (the rail's lateral axis, columns ordered by it) and the body's inward normal.
#[derive(Debug, Clone, PartialEq)]
pub struct StripKernel {
    nx: usize,
    ny: usize,
    element_m: f64,
    element_y_m: f64,
    /// `[o + nx − 1][j][jp]`, flattened.
    c: Vec<[[f64; 3]; 3]>,
    n_dofs: usize,
}

impl StripKernel {
    /// Grid size `(nx, ny)`.
    pub fn dims(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// The grid element's length along x (m).
    pub fn element_m(&self) -> f64 {
        self.element_m
    }

    /// The grid element's width across (m).
    pub fn element_y_m(&self) -> f64 {
        self.element_y_m
    }

    /// Free DOFs of the submodel.
    pub fn n_dofs(&self) -> usize {
        self.n_dofs
    }

    /// The coefficients in storage order `[o + nx − 1][j][jp]` (m/Pa), for writing them out.
    pub fn values(&self) -> &[[[f64; 3]; 3]] {
        &self.c
    }

    /// A kernel from [`Self::values`] of a grid `nx × ny` of elements `dx × dy` (m) condensed
    /// from `n_dofs` free DOFs; `None` unless `values` has `2 nx ny²` entries, all finite.
    pub fn from_values(
        (nx, ny): (usize, usize),
        (dx, dy): (f64, f64),
        values: Vec<[[f64; 3]; 3]>,
        n_dofs: usize,
    ) -> Option<StripKernel> {
        let finite = values.iter().flatten().flatten().all(|v| v.is_finite());
        (values.len() == 2 * nx * ny * ny && finite && dx > 0.0 && dy > 0.0).then_some(
            StripKernel {
                nx,
                ny,
                element_m: dx,
                element_y_m: dy,
                c: values,
                n_dofs,
            },
        )
    }

    /// The kernel of two bodies pressed together (m/Pa): the displacement difference per
    /// traction on the first body (the rail), each kernel in the rail's frame (the tread's
    /// turned over, [`tread::TreadPatch::kernel`]) with its own inward normal. The second body
    /// carries the opposite tangential traction and the same pressure, so the tangential and
    /// the normal terms add (`K¹_tt + K²_tt`, `K¹_nn + K²_nn`) and the normal–tangential
    /// couplings subtract (`K¹_tn − K²_tn`, `K¹_nt − K²_nt`): they cancel for two identical
    /// bodies (Kalker's quasi-identity). `None` if the grids differ.
    pub fn sum(&self, other: &StripKernel) -> Option<StripKernel> {
        if (self.nx, self.ny) != (other.nx, other.ny)
            || self.element_m != other.element_m
            || self.element_y_m != other.element_y_m
        {
            return None;
        }
        let mut out = self.clone();
        for (c, o) in out.c.iter_mut().zip(&other.c) {
            for (a, (row, orow)) in c.iter_mut().zip(o).enumerate() {
                for (b, (v, ov)) in row.iter_mut().zip(orow).enumerate() {
                    // a coupling is one tangential and one normal component
                    let coupling = (a == 2) != (b == 2);
                    *v += if coupling { -ov } else { *ov };
                }
            }
        }
        out.n_dofs += other.n_dofs;
        Some(out)
    }

    /// The kernel the contact uses beside a global model whose compliance at the contact is
    /// `global` (m/N, components x, y, inward normal): every coefficient less `global · a²`,
    /// the global twin's displacement under the force `a²` of a unit traction on one element
    /// (theory §6.9, the split). `global` is the same patch's global twin's compliance
    /// (`rail_head::RailHeadPatch::global_compliance`, `tread::TreadPatch::global_compliance`).
    pub fn split(&self, global: &[[f64; 3]; 3]) -> StripKernel {
        let area = self.element_m * self.element_y_m;
        let mut out = self.clone();
        for c in &mut out.c {
            for (row, g) in c.iter_mut().zip(global) {
                for (v, gv) in row.iter_mut().zip(g) {
                    *v -= gv * area;
                }
            }
        }
        out
    }

    /// The compliance (m/N) of a traction distribution of the given `shape` on the `nx × ny`
    /// grid (row-major `i · ny + j`, `i` along x; non-negative, not all zero): `c[a][b]` is
    /// the displacement `a`, averaged with the shape as weights (work-conjugate), per unit
    /// total force of component `b` distributed as the shape. `None` if the shape's length is
    /// not `nx · ny` or its sum is not positive.
    pub fn patch_compliance(&self, shape: &[f64]) -> Option<[[f64; 3]; 3]> {
        let (nx, ny) = (self.nx, self.ny);
        let total: f64 = shape.iter().sum();
        if shape.len() != nx * ny || total.is_nan() || total <= 0.0 {
            return None;
        }
        let mut c = [[0.0; 3]; 3];
        for (f, &wf) in shape.iter().enumerate() {
            for (s, &ws) in shape.iter().enumerate() {
                let o = (f / ny) as isize - (s / ny) as isize;
                let k = self.get(o, f % ny, s % ny)?;
                for (row, krow) in c.iter_mut().zip(&k) {
                    for (v, kv) in row.iter_mut().zip(krow) {
                        *v += wf * ws * kv;
                    }
                }
            }
        }
        let scale = 1.0 / (total * total * self.element_m * self.element_y_m);
        Some(c.map(|row| row.map(|v| v * scale)))
    }

    /// The coefficients at row offset `o` (`−(nx−1)..=nx`), field column `j`, source column
    /// `jp`; `None` outside.
    pub fn get(&self, o: isize, j: usize, jp: usize) -> Option<[[f64; 3]; 3]> {
        let (nx, ny) = (self.nx as isize, self.ny);
        if o < -(nx - 1) || o > nx || j >= ny || jp >= ny {
            return None;
        }
        Some(self.c[((o + nx - 1) as usize * ny + j) * ny + jp])
    }
}

/// The strip kernel of a patch whose contact surface is `surface` (with its DOF map and
/// factor): unit tractions on each grid element of row 0 of an `nx × ny` grid of elements
/// `a × b` (m) centred on `(0, 0)`, the field read at the centres of rows `−(nx−1)..=nx`. With
/// `y_sign = −1` the surface's y axis is the grid's mirrored (a body turned over about x,
/// such as the tread): column `j` lies at surface `y = −y_j` and the y components change sign.
fn strip_kernel(
    (dofmap, factor, surface): (&DofMap, &Cholesky, &Surface<'_>),
    (nx, ny, a, b): (usize, usize, f64, f64),
    y_sign: f64,
    n_dofs: usize,
) -> Result<StripKernel, StructureError> {
    let (sources, field) = strip_sources_and_field((nx, ny, a, b), y_sign);
    let per_source = condense(dofmap, factor, surface, &sources, &field)?;
    strip_from_condensed(per_source, (nx, ny, a, b), y_sign, n_dofs)
}

/// The source row's elements (rectangles `[x0, x1, y0, y1]`, m) and the field points (the
/// element centres of every row offset `−(nx−1)..=nx`) of a strip kernel, y mirrored by
/// `y_sign`.
fn strip_sources_and_field(
    (nx, ny, a, b): (usize, usize, f64, f64),
    y_sign: f64,
) -> (Vec<[f64; 4]>, Vec<[f64; 2]>) {
    let y_of = |j: usize| y_sign * (j as f64 - 0.5 * (ny as f64 - 1.0)) * b;
    let sources: Vec<[f64; 4]> = (0..ny)
        .map(|jp| [-0.5 * a, 0.5 * a, y_of(jp) - 0.5 * b, y_of(jp) + 0.5 * b])
        .collect();
    let rows = -(nx as isize - 1)..=nx as isize;
    let field: Vec<[f64; 2]> = rows
        .flat_map(|o| (0..ny).map(move |j| [o as f64 * a, y_of(j)]))
        .collect();
    (sources, field)
}

/// The strip kernel from the condensed coefficients `per_source[jp][field point]`.
fn strip_from_condensed(
    per_source: Vec<Vec<[[f64; 3]; 3]>>,
    (nx, ny, a, b): (usize, usize, f64, f64),
    y_sign: f64,
    n_dofs: usize,
) -> Result<StripKernel, StructureError> {
    let sign = [1.0, y_sign, 1.0];
    // reorder [jp][o][j] → [o][j][jp]
    let mut c = vec![[[0.0; 3]; 3]; 2 * nx * ny * ny];
    for (jp, values) in per_source.iter().enumerate() {
        for (k, v) in values.iter().enumerate() {
            let (o, j) = (k / ny, k % ny);
            c[(o * ny + j) * ny + jp] =
                std::array::from_fn(|r| std::array::from_fn(|q| sign[r] * sign[q] * v[r][q]));
        }
    }
    Ok(StripKernel {
        nx,
        ny,
        element_m: a,
        element_y_m: b,
        c,
        n_dofs,
    })
}

/// The 3 × 3 compliance (m/N) of a global twin: a unit force in each direction shared among
/// the `load` nodes `(node, weight)` (weights summing to 1), the displacement read with the same
/// weights (work-conjugate). `sign[d]` maps the mesh's axis `d` onto the kernel's component `d`
/// (x, y of the rail's frame, the body's inward normal): ±1.
fn twin_compliance(
    dofmap: &DofMap,
    factor: &Cholesky,
    load: &[(usize, f64)],
    sign: [f64; 3],
) -> Result<[[f64; 3]; 3], StructureError> {
    let mut rhs = Mat::<f64>::zeros(dofmap.n_free(), 3);
    for &(node, wk) in load {
        for (dir, s) in sign.into_iter().enumerate() {
            if let Some(f) = dofmap.free_index(3 * node + dir) {
                rhs[(f, dir)] += s * wk;
            }
        }
    }
    factor.solve_in_place(&mut rhs)?;
    let mut g = [[0.0; 3]; 3];
    for (r, row) in g.iter_mut().enumerate() {
        for (q, v) in row.iter_mut().enumerate() {
            *v = load
                .iter()
                .map(|&(node, wk)| {
                    dofmap
                        .free_index(3 * node + r)
                        .map_or(0.0, |f| sign[r] * wk * rhs[(f, q)])
                })
                .sum();
        }
    }
    Ok(g)
}

mod mirror;
pub mod of_model;
pub(crate) mod rail_head;
pub mod tread;

#[cfg(test)]
mod penalty_tests;
#[cfg(test)]
mod tests;

//! The rail-head submodel of the local FE contact patch: the influence coefficients of a
//! contact grid on the running surface of a UIC54 rail, condensed from a refined FE segment.
//!
//! What it models: a straight, upright UIC54 segment of length `2 L` (the model's section
//! mesher with its running-surface zone refined to `a / refine`, extruded through node
//! planes graded from `a / refine` at the source row), its foot underside and both end
//! planes fixed. The contact grid is centred on the crown (`y = 0`), `nx` elements along x
//! and `ny` across; unit uniform tractions on each grid element of the row `x = 0` give the
//! kernel `K(o, j, j')` of every row offset `o = −(nx−1)..=nx` — translation-invariant along
//! the rail, dense across it ([`crate::contact::influence::strip`]).
//!
//! Assumptions: the running surface is taken in its projection on the contact plane `z =
//! const` (the crown's 300 mm radius tilts the normal by at most `y/R`, 2° at 10 mm); the
//! inward normal is −z; the fixed foot and ends stand for the track's support and continuity,
//! which the global model carries (the split against it is theory §6.9, not done here).

use crate::contact::hertz::lateral_weights;
use crate::fe::assembly::{DofMap, FeMatrices};
use crate::fe::material::IsotropicElastic;
use crate::fe::solve::Cholesky;
use crate::mesh::rail::{extrude_rail, RailTopology};
use crate::mesh::section::{SectionMesh, SectionParams};
use crate::model::Model;

use super::{
    assemble_and_factorise, check_ratio, check_size, graded_axis, half_planes, out_of_range,
    strip_kernel, strip_kernel_by_halves, twin_compliance, with_mirror_holds, FactorisedSurface,
    StripKernel, StructureError, Surface,
};

/// Free DOFs of a segment: every section node of the inner planes but the foot's.
fn free_dofs(section: &SectionMesh, planes: &[f64]) -> usize {
    3 * (section.nodes.len() - section.foot_underside.len()) * (planes.len() - 2)
}

/// The segment of `section` extruded through `planes`, its foot underside and both end
/// planes held: the topology, the DOF map and the stiffness factor.
fn segment(
    section: &SectionMesh,
    planes: &[f64],
    material: IsotropicElastic,
) -> Result<(RailTopology, DofMap, Cholesky), StructureError> {
    let (topo, dofmap, _, factor) = segment_with_matrices(section, planes, material)?;
    Ok((topo, dofmap, factor))
}

/// As [`segment`], keeping the assembled matrices.
fn segment_with_matrices(
    section: &SectionMesh,
    planes: &[f64],
    material: IsotropicElastic,
) -> Result<(RailTopology, DofMap, FeMatrices, Cholesky), StructureError> {
    let (mesh, topo) = extrude_rail(section, planes, 0)?;
    let fixed = holds(&topo, [true, true]);
    let (dofmap, matrices, factor) = assemble_and_factorise(&mesh, &fixed, material)?;
    Ok((topo, dofmap, matrices, factor))
}

/// The held DOFs of a segment of topology `topo`: the foot underside of every plane, and
/// every node of the first and the last plane where `ends` says so.
fn holds(topo: &RailTopology, ends: [bool; 2]) -> Vec<usize> {
    let last = topo.n_planes() - 1;
    let mut fixed = Vec::new();
    for p in 0..=last {
        let held: Vec<usize> = if (p == 0 && ends[0]) || (p == last && ends[1]) {
            plane_nodes(topo, p)
        } else {
            topo.foot_underside_nodes(p)
        };
        fixed.extend(held.iter().flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2]));
    }
    fixed
}

/// Every node of plane `p`.
fn plane_nodes(topo: &RailTopology, p: usize) -> Vec<usize> {
    (0..topo.n_section_nodes())
        .map(|j| topo.node(p, j))
        .collect()
}

/// A UIC54 rail-head segment carrying an `nx × ny` contact grid of square elements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RailHeadPatch {
    /// The rail's material.
    pub material: IsotropicElastic,
    /// Contact-grid element length along x, `a` (m), 1e-4–5e-3.
    pub element_m: f64,
    /// Contact-grid element width across, `b` (m), within a factor 2 of `a`; [`Self::steel`]
    /// makes it `a` (square elements).
    pub element_y_m: f64,
    /// FE faces per grid element over the source row and across the running band (≥ 1).
    pub refine: usize,
    /// Grid elements along the rail (≥ 1): offsets `−(nx−1)..=nx`.
    pub nx: usize,
    /// Grid elements across the rail (≥ 1), centred on the crown.
    pub ny: usize,
    /// Half-length of the segment (m), at least `5 nx · a` and four global element lengths.
    /// The segment's own structural flexibility (which depends on its length and its held
    /// ends) is taken off by the split against its global twin ([`StripKernel::split`]), so
    /// a short segment serves; the cost grows with it (every node plane carries the refined
    /// section).
    pub half_length_m: f64,
    /// Largest ratio of neighbouring element sizes along the rail (> 1, ≤ 3).
    pub max_ratio: f64,
    /// The global model's rail mesh: the section's foot and web and the element length along
    /// the rail away from the grid are the global model's, so that the patch differs from
    /// its global twin only near the contact.
    pub global: GlobalRailMesh,
}

/// How the global track model meshes the rail: the mesh a rail-head patch is graded to away
/// from the contact, and the mesh of the split's global twin (theory §6.9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalRailMesh {
    /// Target element size of the rail's foot and web (m), `mesh.section_size`; default
    /// model 0.02.
    pub section_size_m: f64,
    /// Element size at the running surface (m), `mesh.head_size`, at most `section_size_m`;
    /// default model 0.01.
    pub head_size_m: f64,
    /// Element length along the rail at the contact (m), `mesh.fine_element_length`; default
    /// model 0.01.
    pub element_length_m: f64,
}

impl Default for GlobalRailMesh {
    /// The default model's rail mesh.
    fn default() -> Self {
        GlobalRailMesh {
            section_size_m: 0.02,
            head_size_m: 0.01,
            element_length_m: 0.01,
        }
    }
}

impl GlobalRailMesh {
    /// The mesh of `model`'s rail at the contact.
    pub fn of(model: &Model) -> Self {
        GlobalRailMesh {
            section_size_m: model.mesh.section_size,
            head_size_m: model.mesh.head_size,
            element_length_m: model.mesh.fine_element_length,
        }
    }
}

impl RailHeadPatch {
    /// Steel, `a` (m), three FE faces per grid element, the given grid, a segment of
    /// half-length `max(5 nx · a, 0.1 m)` (at ±0.05 m the lateral split's error reached 2.3 %,
    /// at ±0.1 m 1.8 %: validation/contact_patch.md, P3), ratio 1.5, graded to the default model's rail mesh.
    pub fn steel(element_m: f64, nx: usize, ny: usize) -> Self {
        RailHeadPatch {
            material: IsotropicElastic::STEEL,
            element_m,
            element_y_m: element_m,
            refine: 3,
            nx,
            ny,
            half_length_m: (5.0 * nx as f64 * element_m).max(0.1),
            max_ratio: 1.5,
            global: GlobalRailMesh::default(),
        }
    }

    fn check(&self) -> Result<(), StructureError> {
        let bad = out_of_range;
        if !(1e-4..=5e-3).contains(&self.element_m) {
            return bad("element_m", self.element_m, "1e-4 to 5e-3 m");
        }
        let r = self.element_y_m / self.element_m;
        if !(0.5..=2.0).contains(&r) {
            return bad("element_y_m", self.element_y_m, "0.5 to 2 element_m");
        }
        if self.refine == 0 {
            return bad("refine", 0.0, "at least 1");
        }
        if self.nx == 0 || self.ny == 0 {
            return bad("nx, ny", 0.0, "at least 1");
        }
        // the grid must lie on the head's top (UIC54: 70 mm wide)
        if self.ny as f64 * self.element_y_m > 0.04 {
            return bad(
                "ny",
                self.ny as f64,
                "ny · element_y_m at most 40 mm (the running surface)",
            );
        }
        let shortest =
            (5.0 * self.nx as f64 * self.element_m).max(4.0 * self.global.element_length_m);
        if !self.half_length_m.is_finite() || self.half_length_m < shortest {
            return bad(
                "half_length_m",
                self.half_length_m,
                "finite, at least 5 nx · element_m and 4 global.element_length_m",
            );
        }
        let e = self.global.element_length_m;
        if !(e >= self.element_m && e <= 0.25 * self.half_length_m) {
            return bad(
                "global.element_length_m",
                e,
                "at least element_m, at most a quarter of half_length_m",
            );
        }
        check_ratio(self.max_ratio)
    }

    /// The section mesh: the running-surface zone of faces `a / refine` covers the grid and
    /// one element beyond each side, `2 a` deep; foot and web as the global model's.
    fn section(&self) -> Result<SectionMesh, StructureError> {
        let (a, b) = (self.element_m, self.element_y_m);
        let params = SectionParams {
            size_m: self.global.section_size_m,
            running_surface_size_m: a.min(b) / self.refine as f64,
            running_surface_half_width_m: (0.5 * self.ny as f64 + 1.0) * b,
            running_surface_depth_m: 2.0 * a.max(b),
            ..SectionParams::default()
        };
        Ok(SectionMesh::uic54(&params)?)
    }

    /// The node planes along the rail (m): `a / refine` over the source row and its
    /// neighbours, at most `a` over the grid's offsets, graded to the global model's element
    /// length.
    fn planes(&self) -> Result<Vec<f64>, StructureError> {
        let a = self.element_m;
        let h = a.min(self.element_y_m) / self.refine as f64;
        let x_f = (self.nx as f64 + 0.5) * a;
        graded_axis(
            [-self.half_length_m, self.half_length_m],
            self.global.element_length_m,
            &[(1.5 * a, h), (x_f, a)],
            vec![-x_f, -0.5 * a, 0.5 * a, x_f],
            self.max_ratio,
        )
    }

    /// The global twin's compliance (m/N, components x, y, inward normal): the same segment,
    /// held the same way, meshed as the global model meshes the rail ([`Self::global`]) and
    /// loaded and read as its passage does: the force spread across the running surface with
    /// the lateral weights of a Hertz pressure of semi-width `half_width_m` (m, above 0, below
    /// 35 mm), along the rail halfway between two node planes (theory §6.9, §7.7).
    /// [`StripKernel::split`] takes it off the refined kernel.
    pub(crate) fn global_compliance(
        &self,
        half_width_m: f64,
    ) -> Result<[[f64; 3]; 3], StructureError> {
        self.check()?;
        if !(half_width_m > 0.0 && half_width_m < 0.035) {
            return out_of_range("half_width_m", half_width_m, "above 0, below 35 mm");
        }
        let global = &self.global;
        let params = SectionParams {
            size_m: global.section_size_m,
            running_surface_size_m: global.head_size_m,
            ..SectionParams::default()
        };
        let section = SectionMesh::uic54(&params)?;
        // node planes at ±(k + ½) e: the contact point x = 0 halfway between two
        let e = global.element_length_m;
        let n = (self.half_length_m / e - 0.5).round().max(1.0) as isize;
        let planes: Vec<f64> = (-n - 1..=n).map(|k| (k as f64 + 0.5) * e).collect();
        let n_dofs = free_dofs(&section, &planes);
        check_size(n_dofs)?;
        let (topo, dofmap, factor) = segment(&section, &planes, self.material)?;
        // across: the running-surface nodes by their offset from the crown (the highest node)
        let running = &section.running_surface;
        let crown = running
            .iter()
            .map(|&j| section.nodes[j])
            .max_by(|p, q| p[1].total_cmp(&q[1]))
            .ok_or(StructureError::PatchParameter {
                name: "global section",
                value: 0.0,
                allowed: "a section with running-surface nodes",
            })?;
        let mut across: Vec<(f64, usize)> = running
            .iter()
            .map(|&j| (section.nodes[j][0] - crown[0], j))
            .collect();
        across.sort_by(|p, q| p.0.total_cmp(&q.0));
        let s: Vec<f64> = across.iter().map(|v| v.0).collect();
        let w = lateral_weights(&s, half_width_m);
        // the planes −e/2 and +e/2, each carrying half the load
        let mut load: Vec<(usize, f64)> = Vec::new();
        for p in [n as usize, n as usize + 1] {
            for (&(_, j), &wk) in across.iter().zip(&w) {
                if wk > 0.0 {
                    load.push((topo.node(p, j), 0.5 * wk));
                }
            }
        }
        // the inward normal is −z
        twin_compliance(&dofmap, &factor, &load, [1.0, 1.0, -1.0])
    }

    /// Free DOFs of the submodel (before building it).
    pub fn n_dofs(&self) -> Result<usize, StructureError> {
        let (section, planes) = self.geometry()?;
        Ok(free_dofs(&section, &planes))
    }

    /// The checked parameters' section mesh and node planes.
    fn geometry(&self) -> Result<(SectionMesh, Vec<f64>), StructureError> {
        self.check()?;
        Ok((self.section()?, self.planes()?))
    }

    /// Builds and factorises the segment: its running surface as a [`FactorisedSurface`]
    /// (the penalty contact's static solution reads it). Refuses a submodel beyond
    /// [`super::MAX_PATCH_DOFS`] before building it.
    pub fn factorised_surface(&self) -> Result<FactorisedSurface, StructureError> {
        let (section, planes) = self.geometry()?;
        check_size(free_dofs(&section, &planes))?;
        let (topo, dofmap, matrices, factor) =
            segment_with_matrices(&section, &planes, self.material)?;
        let mut running: Vec<(f64, usize)> = section
            .running_surface
            .iter()
            .map(|&j| (section.nodes[j][0], j))
            .collect();
        running.sort_by(|p, q| p.0.total_cmp(&q.0));
        let nodes = (0..planes.len())
            .flat_map(|i| running.iter().map(move |&(_, j)| (i, j)))
            .map(|(i, j)| topo.node(i, j))
            .collect();
        Ok(FactorisedSurface {
            xs: planes,
            ys: running.iter().map(|v| v.0).collect(),
            nodes,
            y_sign: 1.0,
            layer_m: self.element_m.min(self.element_y_m) / self.refine as f64,
            dofmap,
            matrices,
            factor,
        })
    }

    /// Builds, factorises and condenses the segment. Refuses a submodel beyond
    /// [`super::MAX_PATCH_DOFS`] before building it.
    ///
    /// The segment is mirror-symmetric about the source row's middle plane when the grid's
    /// source row has an even number of FE faces (`refine` even): it is then solved as its
    /// two half problems (`super::Mirror`), side by side, at about half the work, to the same
    /// kernel to rounding.
    pub fn kernel(&self) -> Result<StripKernel, StructureError> {
        self.kernel_solved(true)
    }

    /// [`Self::kernel`], by the two half problems only when `by_halves` (and the mirror
    /// symmetry) allows.
    pub(crate) fn kernel_solved(&self, by_halves: bool) -> Result<StripKernel, StructureError> {
        let (section, planes) = self.geometry()?;
        let n_dofs = free_dofs(&section, &planes);
        check_size(n_dofs)?;
        let running = &section.running_surface;
        let ys: Vec<f64> = running.iter().map(|&j| section.nodes[j][0]).collect();
        let grid = (self.nx, self.ny, self.element_m, self.element_y_m);
        if let Some(half) = half_planes(&planes).filter(|_| by_halves) {
            let (mesh, topo) = extrude_rail(&section, &half, 0)?;
            let (fixed, middle) = (holds(&topo, [false, true]), plane_nodes(&topo, 0));
            let node = |i: usize, j: usize| topo.node(i, running[j]);
            let surface = Surface {
                xs: &half,
                ys: &ys,
                node: &node,
            };
            let half_factor = |mirror| {
                let held = with_mirror_holds(&fixed, &middle, mirror);
                let (dofmap, _, factor) = assemble_and_factorise(&mesh, &held, self.material)?;
                Ok((dofmap, factor))
            };
            return strip_kernel_by_halves(half_factor, &surface, grid, 1.0, n_dofs);
        }
        let (topo, dofmap, factor) = segment(&section, &planes, self.material)?;
        let node = |i: usize, j: usize| topo.node(i, running[j]);
        let surface = Surface {
            xs: &planes,
            ys: &ys,
            node: &node,
        };
        strip_kernel((&dofmap, &factor, &surface), grid, 1.0, n_dofs)
    }
}

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

use crate::fe::material::IsotropicElastic;
use crate::mesh::rail::extrude_rail;
use crate::mesh::section::{SectionMesh, SectionParams};

use super::{
    check_ratio, check_size, condense, factorise, graded_axis, out_of_range, StructureError,
    Surface,
};

/// Free DOFs of a segment: every section node of the inner planes but the foot's.
fn free_dofs(section: &SectionMesh, planes: &[f64]) -> usize {
    3 * (section.nodes.len() - section.foot_underside.len()) * (planes.len() - 2)
}

/// A UIC54 rail-head segment carrying an `nx × ny` contact grid of square elements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RailHeadPatch {
    /// The rail's material.
    pub material: IsotropicElastic,
    /// Contact-grid element size `a` (m), 1e-4–5e-3.
    pub element_m: f64,
    /// FE faces per grid element over the source row and across the running band (≥ 1).
    pub refine: usize,
    /// Grid elements along the rail (≥ 1): offsets `−(nx−1)..=nx`.
    pub nx: usize,
    /// Grid elements across the rail (≥ 1), centred on the crown.
    pub ny: usize,
    /// Half-length of the segment (m), ≥ 20 `nx · a`.
    pub half_length_m: f64,
    /// Largest ratio of neighbouring element sizes along the rail (> 1, ≤ 3).
    pub max_ratio: f64,
}

/// The kernel of a rail-head patch: `get(o, j, jp)[a][b]` (m/Pa) is the displacement `a` at the
/// centre of the element in row offset `o` and column `j` per unit traction `b` on the element
/// of column `jp` (components x, y, inward normal).
#[derive(Debug, Clone, PartialEq)]
pub struct StripKernel {
    nx: usize,
    ny: usize,
    element_m: f64,
    /// `[o + nx − 1][j][jp]`, flattened.
    c: Vec<[[f64; 3]; 3]>,
    n_dofs: usize,
}

impl StripKernel {
    /// Grid size `(nx, ny)`.
    pub fn dims(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// The grid element size (m).
    pub fn element_m(&self) -> f64 {
        self.element_m
    }

    /// Free DOFs of the submodel.
    pub fn n_dofs(&self) -> usize {
        self.n_dofs
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

impl RailHeadPatch {
    /// Steel, `a` (m), three FE faces per grid element, the given grid, a 0.6 m segment,
    /// ratio 1.5.
    pub fn steel(element_m: f64, nx: usize, ny: usize) -> Self {
        RailHeadPatch {
            material: IsotropicElastic::STEEL,
            element_m,
            refine: 3,
            nx,
            ny,
            half_length_m: 0.3,
            max_ratio: 1.5,
        }
    }

    fn check(&self) -> Result<(), StructureError> {
        let bad = out_of_range;
        if !(1e-4..=5e-3).contains(&self.element_m) {
            return bad("element_m", self.element_m, "1e-4 to 5e-3 m");
        }
        if self.refine == 0 {
            return bad("refine", 0.0, "at least 1");
        }
        if self.nx == 0 || self.ny == 0 {
            return bad("nx, ny", 0.0, "at least 1");
        }
        // the grid must lie on the head's top (UIC54: 70 mm wide)
        if self.ny as f64 * self.element_m > 0.04 {
            return bad(
                "ny",
                self.ny as f64,
                "ny · element_m at most 40 mm (the running surface)",
            );
        }
        let shortest = 20.0 * self.nx as f64 * self.element_m;
        if !self.half_length_m.is_finite() || self.half_length_m < shortest {
            return bad(
                "half_length_m",
                self.half_length_m,
                "finite and at least 20 nx · element_m",
            );
        }
        check_ratio(self.max_ratio)
    }

    /// The section mesh: the running-surface zone of faces `a / refine` covers the grid and
    /// one element beyond each side, `2 a` deep.
    fn section(&self) -> Result<SectionMesh, StructureError> {
        let a = self.element_m;
        let params = SectionParams {
            running_surface_size_m: a / self.refine as f64,
            running_surface_half_width_m: (0.5 * self.ny as f64 + 1.0) * a,
            running_surface_depth_m: 2.0 * a,
            ..SectionParams::default()
        };
        Ok(SectionMesh::uic54(&params)?)
    }

    /// The node planes along the rail (m): `a / refine` over the source row and its
    /// neighbours, at most `a` over the grid's offsets, graded to 20 mm at the ends.
    fn planes(&self) -> Result<Vec<f64>, StructureError> {
        let a = self.element_m;
        let h = a / self.refine as f64;
        let x_f = (self.nx as f64 + 0.5) * a;
        graded_axis(
            [-self.half_length_m, self.half_length_m],
            0.02,
            [(1.5 * a, h), (x_f, a)],
            vec![-x_f, -0.5 * a, 0.5 * a, x_f],
            self.max_ratio,
        )
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

    /// Builds, factorises and condenses the segment. Refuses a submodel beyond
    /// [`super::MAX_PATCH_DOFS`] before building it.
    pub fn kernel(&self) -> Result<StripKernel, StructureError> {
        let (section, planes) = self.geometry()?;
        let n_dofs = free_dofs(&section, &planes);
        check_size(n_dofs)?;
        let (mesh, topo) = extrude_rail(&section, &planes, 0)?;
        let last = planes.len() - 1;
        let mut fixed = Vec::new();
        for p in 0..=last {
            let held: Vec<usize> = if p == 0 || p == last {
                (0..topo.n_section_nodes())
                    .map(|j| topo.node(p, j))
                    .collect()
            } else {
                topo.foot_underside_nodes(p)
            };
            fixed.extend(held.iter().flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2]));
        }
        let (dofmap, factor) = factorise(&mesh, &fixed, self.material)?;
        let running = &section.running_surface;
        let ys: Vec<f64> = running.iter().map(|&j| section.nodes[j][0]).collect();
        let node = |i: usize, j: usize| topo.node(i, running[j]);
        let surface = Surface {
            xs: &planes,
            ys: &ys,
            node: &node,
        };
        let (a, nx, ny) = (self.element_m, self.nx as isize, self.ny);
        let y_of = |j: usize| (j as f64 - 0.5 * (ny as f64 - 1.0)) * a;
        let sources: Vec<[f64; 4]> = (0..ny)
            .map(|jp| [-0.5 * a, 0.5 * a, y_of(jp) - 0.5 * a, y_of(jp) + 0.5 * a])
            .collect();
        let field: Vec<[f64; 2]> = (-(nx - 1)..=nx)
            .flat_map(|o| (0..ny).map(move |j| [o as f64 * a, y_of(j)]))
            .collect();
        let per_source = condense(&dofmap, &factor, &surface, &sources, &field)?;
        // reorder [jp][o][j] → [o][j][jp]
        let n_off = (2 * nx) as usize;
        let mut c = vec![[[0.0; 3]; 3]; n_off * ny * ny];
        for (jp, values) in per_source.iter().enumerate() {
            for (k, v) in values.iter().enumerate() {
                let (o, j) = (k / ny, k % ny);
                c[(o * ny + j) * ny + jp] = *v;
            }
        }
        Ok(StripKernel {
            nx: self.nx,
            ny,
            element_m: a,
            c,
            n_dofs,
        })
    }
}

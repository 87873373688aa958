//! The tread submodel of the local FE contact patch: the influence coefficients of the contact
//! grid on the wheel's tread, condensed from a refined FE model of a piece of the rim.
//!
//! What it models: a straight prism with the rim's cross-section — axially the rim's width,
//! radially its thickness from the rim's inner radius to the tread — and length `2 L` along
//! the rolling direction, as a graded hexahedral block (faces of `a / refine` over the source
//! row and across the grid, at most `a` over the grid's offsets, graded to the global wheel's
//! contact-zone element size). Held: the rim's inner face where the web joins it (the web and
//! the rest of the wheel stand behind it) and both end planes. Unit tractions on each grid
//! element of the row `x = 0` give a [`StripKernel`] in the rail's frame: the block is the rim
//! turned over about the rolling direction (its y axis the rail's mirrored, its inward normal
//! up into the wheel), and the columns and the y components are mapped back.
//!
//! Assumptions: the rim's curvature along the rolling direction (radius 0.46 m on the default
//! model, 1.9° over ±15 mm) and the tread's conicity (1/40) are neglected over the patch and
//! over the prism — the tread is a flat face; the web junction is held, not elastic. Both
//! change the structural flexibility, which the split against the global twin takes off
//! (theory §6.9); the local part under the patch, a few millimetres from the load, sees
//! neither the curvature nor the web 30 mm and more away.

use crate::contact::hertz::lateral_weights;
use crate::fe::assembly::DofMap;
use crate::fe::block::{block_node, graded_block_mesh};
use crate::fe::material::IsotropicElastic;
use crate::fe::solve::Cholesky;
use crate::mesh::Part;
use crate::model::Model;

use super::{
    assemble_and_factorise, check_ratio, check_size, factorise, graded_axis, half_planes,
    out_of_range, strip_kernel, strip_kernel_by_halves, twin_compliance, with_mirror_holds,
    FactorisedSurface, StripKernel, StructureError, Surface,
};

/// The rim's cross-section (m, wheel frame: y along the axle towards the field side, the
/// rolling circle at `y = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RimSection {
    /// Rim thickness from its inner radius to the tread at the rolling circle (m), > 0.
    pub thickness_m: f64,
    /// The rim's faces `[back, front]` (m), back < 0 < front.
    pub y_m: [f64; 2],
    /// Where the web joins the rim's inner face `[start, end]` (m), inside the rim's faces.
    pub web_y_m: [f64; 2],
}

impl Default for RimSection {
    /// The default model's rim: 70 mm thick, y −0.070 … 0.065, the web at −0.045 … −0.015.
    fn default() -> Self {
        RimSection {
            thickness_m: 0.07,
            y_m: [-0.070, 0.065],
            web_y_m: [-0.045, -0.015],
        }
    }
}

impl RimSection {
    /// The rim of `model`'s wheel (the web's faces at the rim, a bent web's included).
    pub fn of(model: &Model) -> Self {
        let p = crate::structure::wheel::WheelStructure::params_of(model);
        RimSection {
            thickness_m: p.radius_m - p.rim_inner_radius_m,
            y_m: [p.rim_y_start_m, p.rim_y_end_m],
            web_y_m: p.web_y_m.map(|y| y + p.web_bend_m),
        }
    }
}

/// How the global model meshes the wheel at the contact: the element size a tread patch is
/// graded to away from the grid, and the mesh of its global twin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalWheelMesh {
    /// Element size at the tread's contact zone, axially, radially and circumferentially (m):
    /// half of `mesh.wheel_element_size`; default model 0.03.
    pub contact_size_m: f64,
    /// Element size away from it (m): `mesh.wheel_element_size`; default model 0.06.
    pub size_m: f64,
    /// Half-width of the contact zone (m), axially, in depth and in arc length; default
    /// model 0.03.
    pub contact_half_width_m: f64,
}

impl Default for GlobalWheelMesh {
    /// The default model's wheel mesh.
    fn default() -> Self {
        GlobalWheelMesh {
            contact_size_m: 0.03,
            size_m: 0.06,
            contact_half_width_m: 0.03,
        }
    }
}

impl GlobalWheelMesh {
    /// The mesh of `model`'s wheel at the contact.
    pub fn of(model: &Model) -> Self {
        let p = crate::structure::wheel::WheelStructure::params_of(model);
        GlobalWheelMesh {
            contact_size_m: p.contact_size_m,
            size_m: p.axial_size_m,
            contact_half_width_m: p.contact_half_width_m,
        }
    }
}

/// A rim prism carrying an `nx × ny` contact grid of square elements on its tread.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreadPatch {
    /// The wheel's material.
    pub material: IsotropicElastic,
    /// Contact-grid element length along x, `a` (m), 1e-4–5e-3.
    pub element_m: f64,
    /// Contact-grid element width across, `b` (m), within a factor 2 of `a`; [`Self::steel`]
    /// makes it `a` (square elements).
    pub element_y_m: f64,
    /// FE faces per grid element over the source row and across the grid (≥ 1).
    pub refine: usize,
    /// Grid elements along the rolling direction (≥ 1): offsets `−(nx−1)..=nx`.
    pub nx: usize,
    /// Grid elements across (≥ 1), centred on the rolling circle, within the rim.
    pub ny: usize,
    /// Half-length of the prism (m), at least `5 nx · a` and two global contact-zone elements.
    pub half_length_m: f64,
    /// Largest ratio of neighbouring element sizes (> 1, ≤ 3).
    pub max_ratio: f64,
    /// The rim's cross-section.
    pub rim: RimSection,
    /// The global model's wheel mesh at the contact.
    pub global: GlobalWheelMesh,
}

/// The prism's node planes `[xs, ys, zs]` (m, block frame: `y` the wheel's mirrored, `z = 0`
/// the tread, `z = −thickness` the rim's inner face) and where the web holds it.
struct Prism {
    planes: [Vec<f64>; 3],
    /// The web's junction in block coordinates `[start, end]` (m).
    web: [f64; 2],
}

impl Prism {
    /// The held DOFs: every node of the end planes and the rim's inner face under the web.
    fn holds(&self) -> Vec<usize> {
        self.holds_with_ends([true, true])
    }

    /// The held DOFs: the rim's inner face under the web, and every node of the first and the
    /// last plane along x where `ends` says so.
    fn holds_with_ends(&self, ends: [bool; 2]) -> Vec<usize> {
        let [xs, ys, zs] = &self.planes;
        let (nx, ny) = (xs.len() - 1, ys.len() - 1);
        let eps = 1e-9;
        let mut fixed = Vec::new();
        for k in 0..zs.len() {
            for (j, &y) in ys.iter().enumerate() {
                let web = k == 0 && y >= self.web[0] - eps && y <= self.web[1] + eps;
                for i in 0..=nx {
                    if (i == 0 && ends[0]) || (i == nx && ends[1]) || web {
                        let n = block_node(nx, ny, i, j, k);
                        fixed.extend([3 * n, 3 * n + 1, 3 * n + 2]);
                    }
                }
            }
        }
        fixed
    }

    fn mesh(&self) -> crate::mesh::Mesh {
        let [xs, ys, zs] = &self.planes;
        graded_block_mesh([xs, ys, zs], 0, Part::Wheel)
    }

    fn free_dofs(&self) -> usize {
        let [xs, ys, zs] = &self.planes;
        3 * xs.len() * ys.len() * zs.len() - self.holds().len()
    }

    /// The checked size, the mesh, and its DOF map and stiffness factor.
    fn factorise(&self, material: IsotropicElastic) -> Result<(DofMap, Cholesky), StructureError> {
        check_size(self.free_dofs())?;
        factorise(&self.mesh(), &self.holds(), material)
    }
}

impl TreadPatch {
    /// Steel, `a` (m), three FE faces per grid element, the given grid, a prism of half-length
    /// `max(5 nx · a, 0.1 m)`, ratio 1.5, the default model's rim and wheel mesh.
    pub fn steel(element_m: f64, nx: usize, ny: usize) -> Self {
        TreadPatch {
            material: IsotropicElastic::STEEL,
            element_m,
            element_y_m: element_m,
            refine: 3,
            nx,
            ny,
            half_length_m: (5.0 * nx as f64 * element_m).max(0.1),
            max_ratio: 1.5,
            rim: RimSection::default(),
            global: GlobalWheelMesh::default(),
        }
    }

    fn check(&self) -> Result<(), StructureError> {
        let bad = out_of_range;
        let a = self.element_m;
        if !(1e-4..=5e-3).contains(&a) {
            return bad("element_m", a, "1e-4 to 5e-3 m");
        }
        let r = self.element_y_m / a;
        if !(0.5..=2.0).contains(&r) {
            return bad("element_y_m", self.element_y_m, "0.5 to 2 element_m");
        }
        if self.refine == 0 {
            return bad("refine", 0.0, "at least 1");
        }
        if self.nx == 0 || self.ny == 0 {
            return bad("nx, ny", 0.0, "at least 1");
        }
        let [back, front] = self.rim.y_m;
        let [w0, w1] = self.rim.web_y_m;
        if !(back < w0 && w0 < w1 && w1 < front && back < 0.0 && front > 0.0) {
            return bad(
                "rim.web_y_m",
                w0,
                "back face < web start < web end < front face, back < 0 < front",
            );
        }
        let half_width = (0.5 * self.ny as f64 + 2.0) * self.element_y_m;
        if half_width > (-back).min(front) {
            return bad(
                "ny",
                self.ny as f64,
                "the grid and two elements either side within the rim's faces",
            );
        }
        let thick = self.rim.thickness_m;
        if thick.is_nan() || thick <= 10.0 * a.max(self.element_y_m) {
            return bad(
                "rim.thickness_m",
                self.rim.thickness_m,
                "more than 10 element_m",
            );
        }
        let h = self.global.contact_size_m;
        if !(h >= a && self.global.size_m >= h && self.global.contact_half_width_m >= h) {
            return bad(
                "global.contact_size_m",
                h,
                "at least element_m, at most global.size_m and global.contact_half_width_m",
            );
        }
        let shortest = (5.0 * self.nx as f64 * a).max(2.0 * h);
        if !self.half_length_m.is_finite() || self.half_length_m < shortest {
            return bad(
                "half_length_m",
                self.half_length_m,
                "finite, at least 5 nx · element_m and 2 global.contact_size_m",
            );
        }
        check_ratio(self.max_ratio)
    }

    /// The web's junction and the rim's faces in block coordinates (`y_block = −y_wheel`).
    fn block_y(&self) -> ([f64; 2], [f64; 2]) {
        let [back, front] = self.rim.y_m;
        let [w0, w1] = self.rim.web_y_m;
        ([-front, -back], [-w1, -w0])
    }

    /// The refined prism: faces `a / refine` over ±1.5 a along x and across the grid and one
    /// element beyond (2 a deep), at most `a` over the grid's offsets (and 8 a deep), graded
    /// to the global mesh: its contact size within its contact zone, its size beyond; the web's
    /// faces and the grid's column edges are node lines.
    fn refined(&self) -> Result<Prism, StructureError> {
        self.check()?;
        let (a, b) = (self.element_m, self.element_y_m);
        let h = a.min(b) / self.refine as f64;
        let g = &self.global;
        let global_zone = (g.contact_half_width_m, g.contact_size_m);
        let x_f = (self.nx as f64 + 0.5) * a;
        let xs = graded_axis(
            [-self.half_length_m, self.half_length_m],
            g.size_m,
            &[(1.5 * a, h), (x_f, a), global_zone],
            vec![-x_f, -0.5 * a, 0.5 * a, x_f],
            self.max_ratio,
        )?;
        let (faces, web) = self.block_y();
        let w = (0.5 * self.ny as f64 + 1.0) * b;
        let mut y_breaks: Vec<f64> = (0..=self.ny)
            .map(|j| (j as f64 - 0.5 * self.ny as f64) * b)
            .collect();
        y_breaks.extend(web);
        let ys = graded_axis(
            faces,
            g.size_m,
            &[(w, h), (w + 4.0 * b, b), global_zone],
            y_breaks,
            self.max_ratio,
        )?;
        let t = self.rim.thickness_m;
        let zs = graded_axis(
            [-t, 0.0],
            g.size_m,
            &[(2.0 * a.max(b), h), (8.0 * a.max(b), a.max(b)), global_zone],
            vec![-2.0 * a],
            self.max_ratio,
        )?;
        Ok(Prism {
            planes: [xs, ys, zs],
            web,
        })
    }

    /// The global twin's prism: the global wheel's contact size within its contact zone (a
    /// node plane at `x = 0`, the contact ring of the fixed wheel), graded to its size beyond.
    fn twin(&self) -> Result<Prism, StructureError> {
        self.check()?;
        let g = &self.global;
        let zone = [(g.contact_half_width_m, g.contact_size_m)];
        let xs = graded_axis(
            [-self.half_length_m, self.half_length_m],
            g.size_m,
            &zone,
            vec![0.0],
            self.max_ratio,
        )?;
        let (faces, web) = self.block_y();
        let ys = graded_axis(
            faces,
            g.size_m,
            &zone,
            vec![0.0, web[0], web[1]],
            self.max_ratio,
        )?;
        let zs = graded_axis(
            [-self.rim.thickness_m, 0.0],
            g.size_m,
            &zone,
            vec![],
            self.max_ratio,
        )?;
        Ok(Prism {
            planes: [xs, ys, zs],
            web,
        })
    }

    /// Free DOFs of the refined prism (before building it).
    pub fn n_dofs(&self) -> Result<usize, StructureError> {
        Ok(self.refined()?.free_dofs())
    }

    /// Builds and factorises the prism: its tread as a [`FactorisedSurface`] (y mirrored
    /// into the rail's frame; the penalty contact's static solution reads it). Refuses a
    /// submodel beyond [`super::MAX_PATCH_DOFS`] before building it.
    pub fn factorised_surface(&self) -> Result<FactorisedSurface, StructureError> {
        let prism = self.refined()?;
        check_size(prism.free_dofs())?;
        let factorised = assemble_and_factorise(&prism.mesh(), &prism.holds(), self.material)?;
        Ok(FactorisedSurface::block_top(prism.planes, -1.0, factorised))
    }

    /// Builds, factorises and condenses the prism. Refuses a submodel beyond
    /// [`super::MAX_PATCH_DOFS`] before building it.
    ///
    /// The prism is mirror-symmetric about the source row's middle plane when the grid's
    /// source row has an even number of FE faces (`refine` even): it is then solved as its
    /// two half problems (`super::Mirror`), side by side, at about half the work, to the same
    /// kernel to rounding.
    pub fn kernel(&self) -> Result<StripKernel, StructureError> {
        self.kernel_solved(true)
    }

    /// [`Self::kernel`], by the two half problems only when `by_halves` (and the mirror
    /// symmetry) allows.
    pub(crate) fn kernel_solved(&self, by_halves: bool) -> Result<StripKernel, StructureError> {
        let prism = self.refined()?;
        let n_dofs = prism.free_dofs();
        check_size(n_dofs)?;
        let grid = (self.nx, self.ny, self.element_m, self.element_y_m);
        if let Some(half) = half_planes(&prism.planes[0]).filter(|_| by_halves) {
            let [_, ys, zs] = &prism.planes;
            let half = Prism {
                planes: [half, ys.clone(), zs.clone()],
                web: prism.web,
            };
            let [xs, ys, zs] = &half.planes;
            let (nbx, nby, nbz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
            let middle: Vec<usize> = (0..=nbz)
                .flat_map(|k| (0..=nby).map(move |j| block_node(nbx, nby, 0, j, k)))
                .collect();
            let (mesh, fixed) = (half.mesh(), half.holds_with_ends([false, true]));
            let node = |i: usize, j: usize| block_node(nbx, nby, i, j, nbz);
            let surface = Surface {
                xs,
                ys,
                node: &node,
            };
            let half_factor = |mirror| {
                factorise(
                    &mesh,
                    &with_mirror_holds(&fixed, &middle, mirror),
                    self.material,
                )
            };
            return strip_kernel_by_halves(half_factor, &surface, grid, -1.0, n_dofs);
        }
        let (dofmap, factor) = prism.factorise(self.material)?;
        let [xs, ys, zs] = &prism.planes;
        let (nbx, nby, nbz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
        let node = |i: usize, j: usize| block_node(nbx, nby, i, j, nbz);
        let surface = Surface {
            xs,
            ys,
            node: &node,
        };
        strip_kernel(
            (&dofmap, &factor, &surface),
            (self.nx, self.ny, self.element_m, self.element_y_m),
            -1.0,
            n_dofs,
        )
    }

    /// The global twin's compliance (m/N, the rail's frame: x, y, the wheel's inward normal):
    /// the prism held the same way, meshed as the global model meshes the wheel
    /// ([`Self::global`]) and loaded and read as its passage does — on the contact ring's
    /// tread nodes (`x = 0`) with the lateral weights of a Hertz pressure of semi-width
    /// `half_width_m` (m, above 0, below 35 mm) (theory §6.9, §7.7).
    pub(crate) fn global_compliance(
        &self,
        half_width_m: f64,
    ) -> Result<[[f64; 3]; 3], StructureError> {
        if !(half_width_m > 0.0 && half_width_m < 0.035) {
            return out_of_range("half_width_m", half_width_m, "above 0, below 35 mm");
        }
        let prism = self.twin()?;
        let (dofmap, factor) = prism.factorise(self.material)?;
        let [xs, ys, zs] = &prism.planes;
        let (nbx, nby, nbz) = (xs.len() - 1, ys.len() - 1, zs.len() - 1);
        let i0 = xs
            .iter()
            .position(|&x| x.abs() < 1e-12)
            .expect("x = 0 is a breakpoint");
        // lateral offsets in the wheel's (and the rail's) frame: y = −y_block, ascending
        let mut across: Vec<(f64, usize)> = ys.iter().enumerate().map(|(j, &y)| (-y, j)).collect();
        across.sort_by(|p, q| p.0.total_cmp(&q.0));
        let s: Vec<f64> = across.iter().map(|v| v.0).collect();
        let w = lateral_weights(&s, half_width_m);
        let load: Vec<(usize, f64)> = across
            .iter()
            .zip(&w)
            .filter(|(_, &wk)| wk > 0.0)
            .map(|(&(_, j), &wk)| (block_node(nbx, nby, i0, j, nbz), wk))
            .collect();
        // block frame → rail frame: y changes sign; the inward normal is the block's −z
        twin_compliance(&dofmap, &factor, &load, [1.0, -1.0, -1.0])
    }
}

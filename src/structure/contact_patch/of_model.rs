//! The fe-patch of a model's contact grid (`contact.influence = "fe-patch"`): the rail
//! head's and the tread's kernels on the passage's grid, built with the model's materials,
//! rail section mesh and wheel mesh (theory §6.9).
//!
//! What it gives: the two refined kernels summed ([`StripKernel::sum`]: the displacement
//! difference of the two bodies per traction on the rail) and the two global twins'
//! compliances summed — the part of the local compliance the global model already carries
//! at the contact, which the contact must not count again. The split (theory §6.9) is the
//! refined sum less the twins' compliance on every element pair; it is kept apart here so
//! that the contact can carry the twins' share as a (negative) uniform series compliance
//! beside the refined kernel, which stays positive definite on its own.
//!
//! Assumptions: those of the two submodels (`super::rail_head`, [`super::tread`]): a
//! straight segment and a straight rim prism, running surfaces in their projection on the
//! contact plane, the twins loaded with the lateral weights of the static Hertz patch.

use crate::model::Model;

use super::rail_head::{GlobalRailMesh, RailHeadPatch};
use super::tread::{GlobalWheelMesh, RimSection, TreadPatch};
use super::{StripKernel, StructureError};

/// FE faces per grid element at the source row of the passages' fe-patch. P1 (the flat block
/// against Boussinesq–Cerruti) put the loaded element's error at 50 % with one face, 4 % with
/// three, 1.7 % with five, and the field beyond it within 2 % from three on; two keep the
/// default grid's rail-head submodel within this machine's memory (validation/contact_patch.md).
pub const PASSAGE_REFINE: usize = 2;

/// The contact grid an fe-patch is built on: elements `nx × ny` of `dx × dy` (m), centred on
/// the crown and the rolling circle, and the static Hertz patch's lateral semi-axis (m) with
/// which the global twins are loaded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchGrid {
    /// Elements along the rolling direction (≥ 1).
    pub nx: usize,
    /// Elements across (≥ 1).
    pub ny: usize,
    /// Element length along x (m).
    pub dx_m: f64,
    /// Element width across (m), within a factor 2 of `dx_m`.
    pub dy_m: f64,
    /// Lateral semi-axis of the static Hertz patch (m), above 0, below 35 mm.
    pub hertz_half_width_m: f64,
    /// FE faces per grid element at the source row (≥ 1; [`PASSAGE_REFINE`]).
    pub refine: usize,
}

/// The fe-patch of a model on a grid: the refined kernels' sum and the twins' compliance.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelPatch {
    /// Rail head plus tread, refined (m/Pa; components x, y, the approach).
    pub refined: StripKernel,
    /// The rail's and the wheel's global twins' compliance summed (m/N, 3 × 3).
    pub twins_m_per_n: [[f64; 3]; 3],
    /// The rail's twin alone (m/N).
    pub rail_twin_m_per_n: [[f64; 3]; 3],
    /// The wheel's twin alone (m/N).
    pub wheel_twin_m_per_n: [[f64; 3]; 3],
}

impl ModelPatch {
    /// The split kernel the contact uses (the refined sum less the twins on every element
    /// pair; [`StripKernel::split`]).
    pub fn split(&self) -> StripKernel {
        self.refined.split(&self.twins_m_per_n)
    }
}

/// The two submodels of `model` on `grid`.
pub fn patches(model: &Model, grid: &PatchGrid) -> (RailHeadPatch, TreadPatch) {
    let mut rail = RailHeadPatch::steel(grid.dx_m, grid.nx, grid.ny);
    rail.material = model.rail_material();
    rail.element_y_m = grid.dy_m;
    rail.refine = grid.refine;
    rail.global = GlobalRailMesh::of(model);
    rail.half_length_m = rail.half_length_m.max(4.0 * rail.global.element_length_m);
    let mut tread = TreadPatch::steel(grid.dx_m, grid.nx, grid.ny);
    tread.material = model.wheel_material();
    tread.element_y_m = grid.dy_m;
    tread.refine = grid.refine;
    tread.rim = RimSection::of(model);
    tread.global = GlobalWheelMesh::of(model);
    tread.half_length_m = tread.half_length_m.max(2.0 * tread.global.contact_size_m);
    (rail, tread)
}

/// Free DOFs of the rail-head and the tread submodels of `model` on `grid` (before building
/// them): what [`model_patch`] will factorise.
pub fn patch_dofs(model: &Model, grid: &PatchGrid) -> Result<(usize, usize), StructureError> {
    let (rail, tread) = patches(model, grid);
    Ok((rail.n_dofs()?, tread.n_dofs()?))
}

/// Builds the fe-patch of `model` on `grid`: both submodels (each as two half problems where
/// it is mirror-symmetric) and both twins (sparse
/// factorisations; minutes and several GB on the default grid, see [`patch_dofs`]).
pub fn model_patch(model: &Model, grid: &PatchGrid) -> Result<ModelPatch, StructureError> {
    let (rail, tread) = patches(model, grid);
    let b = grid.hertz_half_width_m;
    let rail_twin = rail.global_compliance(b)?;
    let wheel_twin = tread.global_compliance(b)?;
    let refined = rail
        .kernel()?
        .sum(&tread.kernel()?)
        .ok_or(StructureError::PatchParameter {
            name: "grid",
            value: grid.nx as f64,
            allowed: "the same grid for the rail head and the tread",
        })?;
    let twins =
        std::array::from_fn(|a| std::array::from_fn(|b| rail_twin[a][b] + wheel_twin[a][b]));
    Ok(ModelPatch {
        refined,
        twins_m_per_n: twins,
        rail_twin_m_per_n: rail_twin,
        wheel_twin_m_per_n: wheel_twin,
    })
}

//! The half problems of a submodel mirror-symmetric about the plane `x = 0` (theory §6.9):
//! the rail head's segment and the tread's prism are, when the source row carries an even
//! number of FE faces, and every source of their strip kernel lies on that row. A traction
//! across or normal gives a symmetric field, one along x an antisymmetric one; each half
//! problem is the half `x ≥ 0` with the plane's holds of its symmetry, and the kernel is the
//! whole submodel's to rounding at about half its work.
//!
//! Assumptions: the planes are symmetric to 1e-9 of their span ([`half_planes`]); material,
//! holds and sources are symmetric about the plane.

use crate::fe::assembly::DofMap;
use crate::fe::solve::Cholesky;

use super::{
    condense_loads, strip_from_condensed, strip_sources_and_field, StripKernel, StructureError,
    Surface,
};

/// The two half problems of a submodel mirror-symmetric about the plane `x = 0` under loads
/// placed symmetrically about it (the contact grid's source row): a traction across or
/// normal is symmetric (`u_x` odd in x, `u_y`, `u_z` even: `u_x = 0` on the plane), one
/// along x antisymmetric (`u_y = u_z = 0` on the plane). Each half model has about half the
/// DOFs, and its factorisation about a quarter of the whole one's work (a 3D nested
/// dissection's grows about as the square of the DOFs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mirror {
    /// Tractions across and normal.
    Symmetric,
    /// Traction along x.
    Antisymmetric,
}

impl Mirror {
    /// The displacement components held on the plane `x = 0` (0 = x, 1 = y, 2 = z).
    pub(crate) fn held(self) -> &'static [usize] {
        match self {
            Mirror::Symmetric => &[0],
            Mirror::Antisymmetric => &[1, 2],
        }
    }

    /// The traction components of the half problem.
    pub(super) fn loads(self) -> &'static [usize] {
        match self {
            Mirror::Symmetric => &[1, 2],
            Mirror::Antisymmetric => &[0],
        }
    }

    /// The displacement component `dir`'s sign at `(−x, y)` against `(x, y)`: the held
    /// components are odd in x.
    pub(super) fn sign(self, dir: usize) -> f64 {
        if self.held().contains(&dir) {
            -1.0
        } else {
            1.0
        }
    }
}

/// The node planes `x ≥ 0` of `planes` (m, ascending), when they are mirror-symmetric about
/// `x = 0` with a plane there, each pair within `1e-9` of the span (grading rounds), the one
/// at the middle set to 0; `None` otherwise (an odd number of FE faces across the source row,
/// or an unsymmetric grading).
pub(crate) fn half_planes(planes: &[f64]) -> Option<Vec<f64>> {
    let n = planes.len();
    if n < 3 || n.is_multiple_of(2) {
        return None;
    }
    let tol = 1e-9 * (planes[n - 1] - planes[0]);
    let mid = n / 2;
    let symmetric = (0..=mid).all(|k| (planes[mid + k] + planes[mid - k]).abs() <= tol);
    if !symmetric || planes[mid].abs() > tol {
        return None;
    }
    let mut half = planes[mid..].to_vec();
    half[0] = 0.0;
    Some(half)
}

/// The DOFs of the nodes `plane_nodes` that the half problem `mirror` holds on the plane
/// `x = 0` (beside `fixed`, the submodel's own holds).
pub(crate) fn with_mirror_holds(
    fixed: &[usize],
    plane_nodes: &[usize],
    mirror: Mirror,
) -> Vec<usize> {
    let mut out = fixed.to_vec();
    out.extend(
        plane_nodes
            .iter()
            .flat_map(|&n| mirror.held().iter().map(move |&d| 3 * n + d)),
    );
    out
}

/// The strip kernel of a submodel mirror-symmetric about the plane `x = 0`, from its two half
/// problems ([`Mirror`]): `factorise(mirror)` builds and factorises the half `x ≥ 0` with the
/// plane's holds of `mirror`, the two side by side (`rayon::join`: their serial parts —
/// ordering, assembly, allocation — overlap), and `surface` is the half's running surface (its
/// `xs` from 0). The same kernel as [`strip_kernel`] on the whole submodel, to rounding, at
/// about half its work and 0.87 of its memory (the default model's patch); `n_dofs` is the
/// whole submodel's.
pub(crate) fn strip_kernel_by_halves(
    factorise: impl Fn(Mirror) -> Result<(DofMap, Cholesky), StructureError> + Sync,
    surface: &Surface<'_>,
    (nx, ny, a, b): (usize, usize, f64, f64),
    y_sign: f64,
    n_dofs: usize,
) -> Result<StripKernel, StructureError> {
    let (sources, field) = strip_sources_and_field((nx, ny, a, b), y_sign);
    let solve = |mirror: Mirror| {
        let (dofmap, factor) = factorise(mirror)?;
        condense_loads(
            (&dofmap, &factor, surface),
            &sources,
            &field,
            (mirror.loads(), Some(mirror)),
        )
    };
    let (sym, anti) = rayon::join(|| solve(Mirror::Symmetric), || solve(Mirror::Antisymmetric));
    let mut per_source = sym?;
    for (acc, values) in per_source.iter_mut().zip(anti?) {
        for (c, v) in acc.iter_mut().zip(values) {
            for (cr, vr) in c.iter_mut().zip(v) {
                for (x, y) in cr.iter_mut().zip(vr) {
                    *x += y;
                }
            }
        }
    }
    strip_from_condensed(per_source, (nx, ny, a, b), y_sign, n_dofs)
}

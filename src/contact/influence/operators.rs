//! The interface between the contact solvers and their influence operators: what the normal
//! solver needs ([`NormalInfluence`]), what the tangential solver needs
//! ([`TangentialInfluence`]), both as one object ([`Operators`]), and the operators a
//! contact grid holds ([`Influence`]: the half-space's [`Convolver`] or an FE patch's strip
//! operators, [`strip::StripInfluence`]). Units: displacements in m, tractions in Pa.

use super::{strip, Convolver};

/// The normal influence operator a normal contact solve needs ([`crate::contact::normal`]): the
/// half-space's [`Convolver`] or the kernel of an FE contact patch invariant along the rail
/// only ([`strip::StripNormal`]).
pub trait NormalInfluence {
    /// `u = C p` (m) on the grid, `p` in Pa (`nx · ny` values, element `i · ny + j`).
    fn normal(&mut self, p: &[f64], u: &mut [f64]);
    /// The largest self-influence `C_ii` (m/Pa).
    fn diag_n(&self) -> f64;
}

impl NormalInfluence for Convolver {
    fn normal(&mut self, p: &[f64], u: &mut [f64]) {
        Convolver::normal(self, p, u)
    }

    fn diag_n(&self) -> f64 {
        self.diag_n
    }
}

/// The tangential influence operator the tangential solver needs
/// (`crate::contact::tangential::TangentialSolver`): the half-space's [`Convolver`] or the kernel of an
/// FE contact patch invariant along the rail only ([`strip::StripInfluence`]). Components x
/// (rolling) and y (lateral) of the displacement difference (m) per traction (Pa), on an
/// `nx × ny` grid (element `i · ny + j`); symmetric positive definite.
pub trait TangentialInfluence {
    /// Grid size `(nx, ny)`.
    fn dims(&self) -> (usize, usize);
    /// The largest self-influence `C_xx` (m/Pa).
    fn diag_xx(&self) -> f64;
    /// The largest self-influence `C_yy` (m/Pa).
    fn diag_yy(&self) -> f64;
    /// The mean of [`Self::diag_xx`] and [`Self::diag_yy`] (m/Pa).
    fn diag_t(&self) -> f64 {
        0.5 * (self.diag_xx() + self.diag_yy())
    }
    /// An upper bound of the largest eigenvalue of the tangential operator (m/Pa).
    fn lambda_max_t(&self) -> f64;
    /// `u[i] = (C τ)(i + shift)` on the grid's rows (`shift` 0 or 1; [`Convolver::tangential`]).
    fn tangential(&mut self, tx: &[f64], ty: &[f64], ux: &mut [f64], uy: &mut [f64], shift: usize);
    /// `C τ` on the extended rows `0..=nx` (`ux, uy` of length `(nx + 1) · ny`;
    /// `Convolver::tangential_ext`).
    fn tangential_ext(&mut self, tx: &[f64], ty: &[f64], ux: &mut [f64], uy: &mut [f64]);
    /// `C τ` for a traction zero outside the box of rows `r0..r1`, columns `c0..c1`, on that
    /// box only: rows `r0..r1` outside the columns get 0, the other rows are left as they are
    /// (`Convolver::tangential_box`; it may be computed in single precision).
    fn tangential_box(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
        rows: (usize, usize),
        cols: (usize, usize),
    );
}

impl TangentialInfluence for Convolver {
    fn dims(&self) -> (usize, usize) {
        Convolver::dims(self)
    }
    fn diag_xx(&self) -> f64 {
        self.diag_xx
    }
    fn diag_yy(&self) -> f64 {
        self.diag_yy
    }
    fn diag_t(&self) -> f64 {
        self.diag_t
    }
    fn lambda_max_t(&self) -> f64 {
        self.lambda_max_t
    }
    fn tangential(&mut self, tx: &[f64], ty: &[f64], ux: &mut [f64], uy: &mut [f64], shift: usize) {
        Convolver::tangential(self, tx, ty, ux, uy, shift)
    }
    fn tangential_ext(&mut self, tx: &[f64], ty: &[f64], ux: &mut [f64], uy: &mut [f64]) {
        Convolver::tangential_ext(self, tx, ty, ux, uy)
    }
    fn tangential_box(
        &mut self,
        tx: &[f64],
        ty: &[f64],
        ux: &mut [f64],
        uy: &mut [f64],
        rows: (usize, usize),
        cols: (usize, usize),
    ) {
        Convolver::tangential_box(self, tx, ty, ux, uy, rows, cols)
    }
}

/// Both influence operators of a contact grid, as one object the two solvers can take.
pub trait Operators: NormalInfluence + TangentialInfluence {}

impl<T: NormalInfluence + TangentialInfluence> Operators for T {}

/// The influence operators of a contact grid: the quasi-identical half-spaces' (the default)
/// or an FE contact patch's kernel invariant along the rail only (theory §6.9). Both solvers
/// take either, through [`Influence::ops_mut`].
// One value per contact engine, built once per passage and never moved in a loop: the
// variants' size difference (a few hundred bytes of vector headers) costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone)]
pub enum Influence {
    /// Kalker's two quasi-identical elastic half-spaces.
    HalfSpace(Convolver),
    /// The rail head's and the tread's FE kernels, split against the global model.
    Strip(strip::StripInfluence),
}

impl Influence {
    /// The operators.
    pub(crate) fn ops(&self) -> &dyn Operators {
        match self {
            Influence::HalfSpace(c) => c,
            Influence::Strip(c) => c,
        }
    }

    /// The operators, for a product.
    pub fn ops_mut(&mut self) -> &mut dyn Operators {
        match self {
            Influence::HalfSpace(c) => c,
            Influence::Strip(c) => c,
        }
    }

    /// Grid size `(nx, ny)`.
    pub fn dims(&self) -> (usize, usize) {
        self.ops().dims()
    }

    /// The uniform compliance under the whole patch that goes with the operators (m/N; x,
    /// y, normal): 0 for the half-space, [`strip::StripInfluence::uniform`] for an FE patch.
    pub fn uniform(&self) -> [f64; 3] {
        match self {
            Influence::HalfSpace(_) => [0.0; 3],
            Influence::Strip(c) => c.uniform(),
        }
    }
}

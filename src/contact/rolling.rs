//! What a transient rolling contact is set up with and what each step takes and gives
//! (docs/theory.md §6.5): the contact grid, the configuration around the Hertz patch, the
//! step inputs (normal approach or load, creepages, spin) and the step result (forces,
//! traction and slip fields, frictional power).

use super::hertz::{HertzContact, HertzInput};
use super::{check_poisson, check_positive, ContactError};

/// The computational grid: `nx × ny` elements covering `[−Lx, Lx] × [−Ly, Ly]` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    /// Number of elements along x (rolling direction).
    pub nx: usize,
    /// Number of elements along y (lateral).
    pub ny: usize,
    /// Half-length of the grid along x, `Lx` (m).
    pub half_length_x_m: f64,
    /// Half-length of the grid along y, `Ly` (m).
    pub half_length_y_m: f64,
}

impl GridSpec {
    /// Element size along x (m).
    pub fn dx(&self) -> f64 {
        2.0 * self.half_length_x_m / self.nx as f64
    }
    /// Element size along y (m).
    pub fn dy(&self) -> f64 {
        2.0 * self.half_length_y_m / self.ny as f64
    }
    /// Element-centre x coordinate of column `i` (m).
    pub fn x(&self, i: usize) -> f64 {
        -self.half_length_x_m + (i as f64 + 0.5) * self.dx()
    }
    /// Element-centre y coordinate of row `j` (m).
    pub fn y(&self, j: usize) -> f64 {
        -self.half_length_y_m + (j as f64 + 0.5) * self.dy()
    }
}

/// What a contact grid around the Hertz patch is made from
/// ([`TransientConfig::around_hertz`]). The default is the reference case: wheel R 0.46 m
/// flat laterally on the R300 crown, steel, µ 0.4, 140 km/h, 100 kN, a 40 × 32 grid with
/// margin 1.2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzGridParams {
    /// Relative radius of curvature along x (m, > 0; the wheel rolling radius on a straight
    /// rail).
    pub radius_x_m: f64,
    /// Relative radius of curvature along y (m, > 0).
    pub radius_y_m: f64,
    /// Young's modulus of wheel and rail (Pa, > 0).
    pub youngs_pa: f64,
    /// Poisson's ratio (−, 0 to 0.5).
    pub poisson: f64,
    /// Coulomb friction coefficient µ (−, ≥ 0).
    pub friction: f64,
    /// Rolling speed V (m/s, > 0).
    pub speed_m_per_s: f64,
    /// Normal load that sizes the patch (N, > 0).
    pub load_n: f64,
    /// Elements along x (rolling direction).
    pub nx: usize,
    /// Elements along y (lateral).
    pub ny: usize,
    /// Grid half lengths over the Hertz semi-axes (−; about 1.15–1.4, larger if the load
    /// varies).
    pub margin: f64,
}

impl Default for HertzGridParams {
    fn default() -> Self {
        HertzGridParams {
            radius_x_m: 0.46,
            radius_y_m: 0.3,
            youngs_pa: 210e9,
            poisson: 0.3,
            friction: 0.4,
            speed_m_per_s: crate::units::kmh_to_ms(140.0),
            load_n: 100e3,
            nx: 40,
            ny: 32,
            margin: 1.2,
        }
    }
}

/// Configuration of the transient rolling engine (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransientConfig {
    /// The grid.
    pub grid: GridSpec,
    /// Young's modulus of wheel and rail (Pa).
    pub youngs_pa: f64,
    /// Poisson's ratio (−).
    pub poisson: f64,
    /// Coulomb friction coefficient µ (−).
    pub friction: f64,
    /// Relative radius of curvature along x (m) (the wheel rolling radius on a straight rail).
    pub radius_x_m: f64,
    /// Relative radius of curvature along y (m) (`1/Ry = 1/R_crown + 1/R_wheel,lat`).
    pub radius_y_m: f64,
    /// Rolling speed V (m/s); the time step is `Δx / V`.
    pub speed_m_per_s: f64,
    /// Relative tolerance of the normal CG (pressure change).
    pub normal_tol: f64,
    /// Relative tolerance of the tangential solver (traction update / µ p_max).
    pub tangential_tol: f64,
}

impl TransientConfig {
    /// Grid sized around the Hertz patch of `p.load_n`: `nx × ny` elements covering
    /// `margin · a` by `margin · b`, the solver tolerances 1e-6.
    pub fn around_hertz(p: &HertzGridParams) -> Result<Self, ContactError> {
        let HertzGridParams {
            radius_x_m,
            radius_y_m,
            youngs_pa,
            poisson,
            friction,
            speed_m_per_s,
            load_n,
            nx,
            ny,
            margin,
        } = *p;
        check_positive("load_n", load_n)?;
        let h = HertzContact::solve(&HertzInput {
            radius_x_m,
            radius_y_m,
            youngs_pa,
            poisson,
            load_n,
        })?;
        Ok(TransientConfig {
            grid: GridSpec {
                nx,
                ny,
                half_length_x_m: margin * h.a_m,
                half_length_y_m: margin * h.b_m,
            },
            youngs_pa,
            poisson,
            friction,
            radius_x_m,
            radius_y_m,
            speed_m_per_s,
            // 1e-6: forces within 4e-7 (F_N) of the 1e-9 solution on the 2,500-step passage
            // sequence of `examples/contact_bench.rs`, 11 fewer products per step
            normal_tol: 1e-6,
            tangential_tol: 1e-6,
        })
    }

    /// The reference case ([`HertzGridParams::default`]).
    pub fn reference() -> Self {
        Self::around_hertz(&HertzGridParams::default()).expect("reference parameters are valid")
    }

    pub(super) fn validate(&self) -> Result<(), ContactError> {
        check_positive("youngs_pa", self.youngs_pa)?;
        check_poisson(self.poisson)?;
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(ContactError::InvalidParameter {
                name: "friction",
                value: self.friction,
                reason: "must be finite and ≥ 0",
            });
        }
        check_positive("speed_m_per_s", self.speed_m_per_s)?;
        check_positive("half_length_x_m", self.grid.half_length_x_m)?;
        check_positive("half_length_y_m", self.grid.half_length_y_m)?;
        check_positive("normal_tol", self.normal_tol)?;
        check_positive("tangential_tol", self.tangential_tol)?;
        for (name, r) in [
            ("radius_x_m", self.radius_x_m),
            ("radius_y_m", self.radius_y_m),
        ] {
            if r.is_nan() || r <= 0.0 {
                return Err(ContactError::InvalidParameter {
                    name,
                    value: r,
                    reason: "must be > 0 (INFINITY = flat)",
                });
            }
        }
        if self.grid.nx < 2 || self.grid.ny < 1 {
            return Err(ContactError::InvalidParameter {
                name: "grid.nx",
                value: self.grid.nx as f64,
                reason: "need nx ≥ 2 and ny ≥ 1",
            });
        }
        Ok(())
    }
}

/// Normal input of a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalInput {
    /// Rigid approach of wheel into rail (m), relative to the nominal rail surface.
    Approach(f64),
    /// Normal force (N).
    Force(f64),
}

/// Longitudinal input of a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Longitudinal {
    /// Longitudinal creepage ξ (−), see the sign convention in the module root.
    Creepage(f64),
    /// Longitudinal force on the wheel Fx (N); ξ is solved for.
    Force(f64),
}

/// Inputs of one time step.
#[derive(Debug, Clone, Copy)]
pub struct StepInputs<'a> {
    /// Normal approach or force.
    pub normal: NormalInput,
    /// Longitudinal creepage or force.
    pub longitudinal: Longitudinal,
    /// Lateral creepage η (−).
    pub lateral_creepage: f64,
    /// Spin φ (1/m).
    pub spin_per_m: f64,
    /// Rail surface height under the grid columns (m, positive up = less gap), one value per
    /// grid column `i` (length `nx`), or `None` for a smooth rail.
    pub rail_height_m: Option<&'a [f64]>,
}

impl StepInputs<'_> {
    /// Smooth rail, normal force `n` (N), longitudinal creepage `xi`.
    pub fn force_creepage(n: f64, xi: f64) -> StepInputs<'static> {
        StepInputs {
            normal: NormalInput::Force(n),
            longitudinal: Longitudinal::Creepage(xi),
            lateral_creepage: 0.0,
            spin_per_m: 0.0,
            rail_height_m: None,
        }
    }
}

/// Scalar results of one step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepResult {
    /// Normal force (N).
    pub normal_force_n: f64,
    /// Rigid approach (m).
    pub approach_m: f64,
    /// Longitudinal force on the wheel (N).
    pub fx_n: f64,
    /// Lateral force on the wheel (N).
    pub fy_n: f64,
    /// Spin moment `∫ (x τy − y τx) dA` (N·m).
    pub mz_nm: f64,
    /// Longitudinal creepage used (prescribed or solved) (−).
    pub creepage: f64,
    /// Number of elements in contact (p > 0).
    pub contact_elements: usize,
    /// Number of slipping elements.
    pub slip_elements: usize,
    /// Contact area (m²).
    pub area_m2: f64,
    /// Total frictional power `−∫ τ̄·s dA` (W), `τ̄` the path-mean traction (module doc).
    pub frictional_power_w: f64,
    /// Normal CG iterations.
    pub normal_iterations: usize,
    /// Tangential influence products (FFT pairs), summed over creepage iterations in force
    /// mode.
    pub tangential_iterations: usize,
    /// All influence products (FFT pairs) of the step, normal and tangential.
    pub influence_products: usize,
}

impl StepResult {
    /// Fraction of the contact area that slips (0 if no contact).
    pub fn slip_area_fraction(&self) -> f64 {
        if self.contact_elements == 0 {
            0.0
        } else {
            self.slip_elements as f64 / self.contact_elements as f64
        }
    }
}

/// Element state: outside the contact area.
pub const STATE_EXTERIOR: u8 = 0;
/// Element state: adhesion (stick).
pub const STATE_STICK: u8 = 1;
/// Element state: slip.
pub const STATE_SLIP: u8 = 2;

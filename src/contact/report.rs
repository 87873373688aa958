//! The engine behind `corrugation contact`: a plain parameter struct [`ContactCase`], the
//! solver [`solve_case`], the printable/JSON [`ContactSummary`] and field output (CSV + .npy).
//!
//! `steps = 1` solves steady rolling (transient stepping to the fixed point); `steps = K > 1`
//! rolls `K` steps from rest (Δt = Δx / V) with constant inputs and reports the last step.
//! Reported semi-axes are the pressure-moment equivalents `a = √(5 ⟨(x − x̄)²⟩_p)`, exact for a
//! Hertzian (semi-ellipsoidal) distribution and defined for any patch.

use super::hertz::{HertzContact, HertzInput};
use super::transient::{
    GridSpec, HertzGridParams, Longitudinal, NormalInput, StepInputs, StepResult, TransientConfig,
    TransientRolling,
};
use super::ContactError;
use crate::units;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Tangential loading of a case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TangentialLoading {
    /// Prescribed longitudinal creepage ξ (−); positive = braking (see module root).
    Creepage(f64),
    /// Prescribed traction coefficient `Fx / N` (−); positive = driving (force on the wheel
    /// in the direction of travel).
    TractionCoefficient(f64),
}

/// Parameters of one wheel–rail contact case (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactCase {
    /// Wheel rolling radius (m).
    pub wheel_radius_m: f64,
    /// Rail crown radius: lateral curvature radius of the rail head (m).
    pub crown_radius_m: f64,
    /// Wheel lateral (profile) radius (m); `f64::INFINITY` = flat (conical tread).
    pub wheel_lateral_radius_m: f64,
    /// Young's modulus of wheel and rail (Pa).
    pub youngs_pa: f64,
    /// Poisson's ratio (−).
    pub poisson: f64,
    /// Normal load (N).
    pub normal_load_n: f64,
    /// Coulomb friction coefficient µ (−).
    pub friction: f64,
    /// Creepage or traction coefficient.
    pub tangential: TangentialLoading,
    /// Rolling speed (m/s).
    pub speed_m_per_s: f64,
    /// `1` = steady state; `K > 1` = transient rolling from rest for K steps.
    pub steps: usize,
    /// Grid elements along the rolling direction.
    pub grid_nx: usize,
    /// Grid elements laterally.
    pub grid_ny: usize,
    /// Grid half-lengths as multiples of the Hertz semi-axes (−), e.g. 1.25.
    pub grid_margin: f64,
}

impl Default for ContactCase {
    /// The reference case: R 0.46 m (flat laterally) on the R300 crown, E 210 GPa, ν 0.3,
    /// N 100 kN, µ 0.4, traction coefficient 0.15, 140 km/h, steady state, 40 × 32 grid.
    fn default() -> Self {
        ContactCase {
            wheel_radius_m: 0.46,
            crown_radius_m: 0.3,
            wheel_lateral_radius_m: f64::INFINITY,
            youngs_pa: 210e9,
            poisson: 0.3,
            normal_load_n: 100e3,
            friction: 0.4,
            tangential: TangentialLoading::TractionCoefficient(0.15),
            speed_m_per_s: units::kmh_to_ms(140.0),
            steps: 1,
            grid_nx: 40,
            grid_ny: 32,
            grid_margin: 1.25,
        }
    }
}

impl ContactCase {
    /// Relative lateral radius `1/(1/R_crown + 1/R_wheel,lat)` (m).
    pub(crate) fn relative_lateral_radius_m(&self) -> f64 {
        1.0 / (1.0 / self.crown_radius_m + 1.0 / self.wheel_lateral_radius_m)
    }

    /// The Hertz closed form of this case.
    pub fn hertz(&self) -> Result<HertzContact, ContactError> {
        HertzContact::solve(&HertzInput::wheel_on_rail(
            self.wheel_radius_m,
            self.wheel_lateral_radius_m,
            self.crown_radius_m,
            self.youngs_pa,
            self.poisson,
            self.normal_load_n,
        ))
    }
}

/// A solved case: the grid fields of the last step and its scalar results.
#[derive(Debug, Clone)]
pub struct ContactSolution {
    /// The grid.
    pub grid: GridSpec,
    /// Element-centre x (m), length nx.
    pub x_m: Vec<f64>,
    /// Element-centre y (m), length ny.
    pub y_m: Vec<f64>,
    /// Pressure (Pa), index `i * ny + j`.
    pub pressure_pa: Vec<f64>,
    /// Traction on the wheel x (Pa).
    pub traction_x_pa: Vec<f64>,
    /// Traction on the wheel y (Pa).
    pub traction_y_pa: Vec<f64>,
    /// Slip velocity x (m/s).
    pub slip_x_m_per_s: Vec<f64>,
    /// Slip velocity y (m/s).
    pub slip_y_m_per_s: Vec<f64>,
    /// States (0 exterior, 1 stick, 2 slip).
    pub state: Vec<u8>,
    /// Frictional power density (W/m²).
    pub power_w_per_m2: Vec<f64>,
    /// Scalar results of the last step.
    pub result: StepResult,
    /// Pressure-moment equivalent semi-axis along x (m).
    pub a_m: f64,
    /// Pressure-moment equivalent semi-axis along y (m).
    pub b_m: f64,
    /// Maximum pressure (Pa).
    pub p_max_pa: f64,
    /// The Hertz closed form of the case, for comparison.
    pub hertz: HertzContact,
}

/// Summary printed by the CLI; JSON keys are the field names (units in the names).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ContactSummary {
    /// Equivalent semi-axis along the rail (mm).
    pub a_mm: f64,
    /// Equivalent semi-axis across the rail (mm).
    pub b_mm: f64,
    /// Maximum pressure (MPa).
    pub p0_mpa: f64,
    /// Rigid approach (µm).
    pub approach_um: f64,
    /// Contact area (mm²).
    pub area_mm2: f64,
    /// Longitudinal force on the wheel (N).
    pub fx_n: f64,
    /// Lateral force on the wheel (N).
    pub fy_n: f64,
    /// Longitudinal creepage (−).
    pub creepage: f64,
    /// Slip-area fraction (−).
    pub slip_area_fraction: f64,
}

/// Pressure-moment equivalent semi-axes `(a, b)` (m): `a = √(5 ⟨(x − x̄)²⟩_p)` and likewise
/// for b (for the Hertz distribution `p0 √(1 − x²/a² − y²/b²)`, `⟨x²⟩_p = a²/5`).
/// Returns `(0, 0)` for zero pressure.
pub fn equivalent_semi_axes(x: &[f64], y: &[f64], p: &[f64]) -> (f64, f64) {
    let ny = y.len();
    let (mut s, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for (i, xi) in x.iter().enumerate() {
        for (j, yj) in y.iter().enumerate() {
            let w = p[i * ny + j];
            s += w;
            sx += w * xi;
            sy += w * yj;
        }
    }
    if s <= 0.0 {
        return (0.0, 0.0);
    }
    let (mx, my) = (sx / s, sy / s);
    let (mut vx, mut vy) = (0.0, 0.0);
    for (i, xi) in x.iter().enumerate() {
        for (j, yj) in y.iter().enumerate() {
            let w = p[i * ny + j];
            vx += w * (xi - mx) * (xi - mx);
            vy += w * (yj - my) * (yj - my);
        }
    }
    ((5.0 * vx / s).sqrt(), (5.0 * vy / s).sqrt())
}

/// Solve a case (see the module doc for steady vs transient) on the half-spaces.
pub fn solve_case(case: &ContactCase) -> Result<ContactSolution, ContactError> {
    solve_case_on(case, None)
}

/// The contact configuration of a case: its grid sized on the Hertz patch of its normal load
/// (or of 1 kN when unloaded).
pub fn case_config(case: &ContactCase) -> Result<TransientConfig, ContactError> {
    let sizing_load = case.normal_load_n.max(1e3);
    TransientConfig::around_hertz(&HertzGridParams {
        radius_x_m: case.wheel_radius_m,
        radius_y_m: case.relative_lateral_radius_m(),
        youngs_pa: case.youngs_pa,
        poisson: case.poisson,
        friction: case.friction,
        speed_m_per_s: case.speed_m_per_s,
        load_n: sizing_load,
        nx: case.grid_nx,
        ny: case.grid_ny,
        margin: case.grid_margin,
    })
}

/// Solve a case on the given influence operators (on the grid of [`case_config`]; `None`:
/// the half-spaces).
pub fn solve_case_on(
    case: &ContactCase,
    influence: Option<super::influence::Influence>,
) -> Result<ContactSolution, ContactError> {
    if case.steps == 0 {
        return Err(ContactError::InvalidParameter {
            name: "steps",
            value: 0.0,
            reason: "must be ≥ 1 (1 = steady state)",
        });
    }
    let hertz = case.hertz()?;
    let cfg = case_config(case)?;
    let mut eng = match influence {
        None => TransientRolling::new(cfg)?,
        Some(op) => TransientRolling::with_influence(cfg, op)?,
    };
    let longitudinal = match case.tangential {
        TangentialLoading::Creepage(x) => Longitudinal::Creepage(x),
        TangentialLoading::TractionCoefficient(t) => Longitudinal::Force(t * case.normal_load_n),
    };
    let inp = StepInputs {
        normal: NormalInput::Force(case.normal_load_n),
        longitudinal,
        lateral_creepage: 0.0,
        spin_per_m: 0.0,
        rail_height_m: None,
    };
    let result = if case.steps == 1 {
        eng.solve_steady(&inp, 1e-7, 50 * case.grid_nx)?
    } else {
        let mut r = eng.step(&inp)?;
        for _ in 1..case.steps {
            r = eng.step(&inp)?;
        }
        r
    };
    let (a_m, b_m) = equivalent_semi_axes(eng.x_m(), eng.y_m(), eng.pressure_pa());
    Ok(ContactSolution {
        grid: cfg.grid,
        x_m: eng.x_m().to_vec(),
        y_m: eng.y_m().to_vec(),
        pressure_pa: eng.pressure_pa().to_vec(),
        traction_x_pa: eng.traction_x_pa().to_vec(),
        traction_y_pa: eng.traction_y_pa().to_vec(),
        slip_x_m_per_s: eng.slip_x_m_per_s().to_vec(),
        slip_y_m_per_s: eng.slip_y_m_per_s().to_vec(),
        state: eng.states().to_vec(),
        power_w_per_m2: eng.power_density_w_per_m2().to_vec(),
        result,
        a_m,
        b_m,
        p_max_pa: eng.pressure_pa().iter().cloned().fold(0.0, f64::max),
        hertz,
    })
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ContactError + '_ {
    move |source| ContactError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Write `bytes` to `dir/name` atomically (`name.tmp`, then rename).
fn write_atomic(
    dir: &Path,
    name: &str,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<PathBuf, ContactError> {
    let path = dir.join(name);
    let tmp = dir.join(format!("{name}.tmp"));
    let mut f = std::fs::File::create(&tmp).map_err(io_err(&tmp))?;
    fill(&mut f).map_err(io_err(&tmp))?;
    f.sync_all().map_err(io_err(&tmp))?;
    drop(f);
    std::fs::rename(&tmp, &path).map_err(io_err(&path))?;
    Ok(path)
}

impl ContactSolution {
    /// The CLI summary in the units of its key names.
    pub fn summary(&self) -> ContactSummary {
        let r = &self.result;
        ContactSummary {
            a_mm: units::m_to_mm(self.a_m),
            b_mm: units::m_to_mm(self.b_m),
            p0_mpa: units::pa_to_mpa(self.p_max_pa),
            approach_um: units::m_to_um(r.approach_m),
            area_mm2: r.area_m2 / (units::M_PER_MM * units::M_PER_MM),
            fx_n: r.fx_n,
            fy_n: r.fy_n,
            creepage: r.creepage,
            slip_area_fraction: r.slip_area_fraction(),
        }
    }

    /// Write `contact_fields.csv` (one row per element: x_mm, y_mm, pressure_mpa, tx_mpa,
    /// ty_mpa, slip_x, slip_y (m/s), state (0 exterior, 1 stick, 2 slip), power (W/m²)) and
    /// one `.npy` 2D array (nx × ny, f64) per field, atomically. Returns the written paths.
    pub fn write_fields(&self, dir: &Path) -> Result<Vec<PathBuf>, ContactError> {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let (nx, ny) = (self.x_m.len(), self.y_m.len());
        let mut out = Vec::new();
        out.push(write_atomic(dir, "contact_fields.csv", |f| {
            let mut w = csv::Writer::from_writer(f);
            w.write_record([
                "x_mm",
                "y_mm",
                "pressure_mpa",
                "tx_mpa",
                "ty_mpa",
                "slip_x",
                "slip_y",
                "state",
                "power",
            ])
            .map_err(std::io::Error::other)?;
            for i in 0..nx {
                for j in 0..ny {
                    let e = i * ny + j;
                    w.write_record(&[
                        format!("{:.6}", units::m_to_mm(self.x_m[i])),
                        format!("{:.6}", units::m_to_mm(self.y_m[j])),
                        format!("{:.6}", units::pa_to_mpa(self.pressure_pa[e])),
                        format!("{:.6}", units::pa_to_mpa(self.traction_x_pa[e])),
                        format!("{:.6}", units::pa_to_mpa(self.traction_y_pa[e])),
                        format!("{:.9e}", self.slip_x_m_per_s[e]),
                        format!("{:.9e}", self.slip_y_m_per_s[e]),
                        format!("{}", self.state[e]),
                        format!("{:.9e}", self.power_w_per_m2[e]),
                    ])
                    .map_err(std::io::Error::other)?;
                }
            }
            w.flush()
        })?);
        let state_f: Vec<f64> = self.state.iter().map(|&s| s as f64).collect();
        let fields: [(&str, &[f64], f64); 7] = [
            (
                "pressure_mpa.npy",
                &self.pressure_pa,
                1.0 / units::PA_PER_MPA,
            ),
            ("tx_mpa.npy", &self.traction_x_pa, 1.0 / units::PA_PER_MPA),
            ("ty_mpa.npy", &self.traction_y_pa, 1.0 / units::PA_PER_MPA),
            ("slip_x.npy", &self.slip_x_m_per_s, 1.0),
            ("slip_y.npy", &self.slip_y_m_per_s, 1.0),
            ("state.npy", &state_f, 1.0),
            ("power.npy", &self.power_w_per_m2, 1.0),
        ];
        for (name, data, scale) in fields {
            out.push(write_atomic(dir, name, |f| {
                use npyz::WriterBuilder;
                let mut w = npyz::WriteOptions::new()
                    .default_dtype()
                    .shape(&[nx as u64, ny as u64])
                    .writer(f)
                    .begin_nd()?;
                w.extend(data.iter().map(|v| v * scale))?;
                w.finish()?;
                Ok(())
            })?);
        }
        let _ = std::io::stdout().flush();
        Ok(out)
    }
}

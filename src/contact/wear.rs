//! Frictional work along the rail (docs/theory.md §6.6): the rail-fixed accumulator of a
//! passage's frictional work per area, and the normal-load → longitudinal-force frequency
//! response of the transient contact.

use super::hertz::{HertzContact, HertzInput};
use super::rolling::{Longitudinal, NormalInput, StepInputs, TransientConfig};
use super::transient::TransientRolling;
use super::{check_positive, ContactError};

/// Rail-fixed accumulator of frictional work `W_f(x, y)` (J/m²): bins of width `dx` along the
/// rail starting at `x_start_m`, and the grid's `ny` lateral rows.
#[derive(Debug, Clone)]
pub struct WearAccumulator {
    x_start_m: f64,
    dx_m: f64,
    nbins: usize,
    ny: usize,
    dy_m: f64,
    work: Vec<f64>,
}

impl WearAccumulator {
    /// Accumulator over `[x_start_m, x_start_m + nbins·dx)` for an engine's grid (bin width =
    /// the grid's Δx, so one step moves the contact by one bin).
    pub fn new(engine: &TransientRolling, x_start_m: f64, nbins: usize) -> Self {
        WearAccumulator {
            x_start_m,
            dx_m: engine.dx,
            nbins,
            ny: engine.ny,
            dy_m: engine.cfg.grid.dy(),
            work: vec![0.0; nbins * engine.ny],
        }
    }

    /// Add the work of the engine's last step (power density × Δt) with the contact centre at
    /// rail coordinate `contact_x_m` (m). No allocation.
    pub fn add_step(&mut self, engine: &TransientRolling, contact_x_m: f64) {
        let dt = engine.time_step_s();
        let ny = self.ny;
        for i in 0..engine.nx {
            let x = contact_x_m + engine.xs[i] - self.x_start_m;
            let k = (x / self.dx_m).floor();
            if k < 0.0 || k >= self.nbins as f64 {
                continue;
            }
            let k = k as usize;
            for j in 0..ny {
                self.work[k * ny + j] += engine.power[i * ny + j] * dt;
            }
        }
    }

    /// `W_f(x, y)` (J/m²), index `bin * ny + j`.
    pub fn work_xy(&self) -> &[f64] {
        &self.work
    }

    /// Bin centres along the rail (m).
    pub fn x_m(&self) -> Vec<f64> {
        (0..self.nbins)
            .map(|k| self.x_start_m + (k as f64 + 0.5) * self.dx_m)
            .collect()
    }

    /// `W_f(x) = Σ_y W_f(x, y) Δy` (J/m) into `out` (length nbins).
    pub fn work_x(&self, out: &mut [f64]) {
        for (k, o) in out.iter_mut().enumerate().take(self.nbins) {
            *o = self.work[k * self.ny..(k + 1) * self.ny]
                .iter()
                .sum::<f64>()
                * self.dy_m;
        }
    }

    /// Total frictional work (J).
    pub fn total_j(&self) -> f64 {
        self.work.iter().sum::<f64>() * self.dx_m * self.dy_m
    }
}

/// One point of the normal-load → longitudinal-force frequency response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadResponsePoint {
    /// Wavelength of the load variation along the rail (m).
    pub wavelength_m: f64,
    /// Wavelength over contact length `λ / (2a)` (−).
    pub wavelength_over_contact_length: f64,
    /// Frequency `V / λ` (Hz).
    pub frequency_hz: f64,
    /// |F̂x| / |dFx/dN|_steady · N̂| (1 = quasi-steady).
    pub amplitude_ratio: f64,
    /// Phase lag of Fx behind the quasi-steady response (rad, positive = lags).
    pub phase_lag_rad: f64,
}

/// Frequency response of the longitudinal force to a sinusoidal normal load
/// `N(x) = N0 (1 + ε sin(2π x/λ))` at constant creepage (the creepage that gives
/// `Fx = traction · N0` in steady rolling), for each wavelength `λ` (m). The quasi-steady
/// reference is `dFx/dN` from two steady solves at `N0 (1 ± ε)`. The response is the first
/// Fourier coefficient of Fx over the last two of three periods (the first absorbs the start).
pub fn load_response_curve(
    cfg: &TransientConfig,
    load_n: f64,
    traction: f64,
    rel_amplitude: f64,
    wavelengths_m: &[f64],
) -> Result<Vec<LoadResponsePoint>, ContactError> {
    check_positive("load_n", load_n)?;
    check_positive("rel_amplitude", rel_amplitude)?;
    let mut eng = TransientRolling::new(*cfg)?;
    let st = eng.solve_steady(
        &StepInputs {
            normal: NormalInput::Force(load_n),
            longitudinal: Longitudinal::Force(traction * load_n),
            lateral_creepage: 0.0,
            spin_per_m: 0.0,
            rail_height_m: None,
        },
        1e-7,
        20 * cfg.grid.nx,
    )?;
    let xi = st.creepage;
    let mut fs = [0.0; 2];
    for (k, s) in [1.0, -1.0].iter().enumerate() {
        eng.reset();
        let r = eng.solve_steady(
            &StepInputs::force_creepage(load_n * (1.0 + s * rel_amplitude), xi),
            1e-8,
            20 * cfg.grid.nx,
        )?;
        fs[k] = r.fx_n;
    }
    let dfdn = (fs[0] - fs[1]) / (2.0 * rel_amplitude * load_n);
    let h = HertzContact::solve(&HertzInput {
        radius_x_m: cfg.radius_x_m,
        radius_y_m: cfg.radius_y_m,
        youngs_pa: cfg.youngs_pa,
        poisson: cfg.poisson,
        load_n,
    })?;
    let dx = cfg.grid.dx();
    let mut out = Vec::with_capacity(wavelengths_m.len());
    for &lam in wavelengths_m {
        check_positive("wavelength", lam)?;
        eng.reset();
        eng.solve_steady(
            &StepInputs::force_creepage(load_n, xi),
            1e-8,
            20 * cfg.grid.nx,
        )?;
        let per = (lam / dx).round().max(4.0) as usize;
        let lam_eff = per as f64 * dx;
        let (mut re, mut im) = (0.0, 0.0);
        for k in 0..3 * per {
            let th = 2.0 * std::f64::consts::PI * (k as f64 + 1.0) / per as f64;
            let n = load_n * (1.0 + rel_amplitude * th.sin());
            let r = eng.step(&StepInputs::force_creepage(n, xi))?;
            if k >= per {
                re += r.fx_n * th.sin();
                im += r.fx_n * th.cos();
            }
        }
        // Fx ≈ mean + A sin(θ − lag): re ∝ A cos(lag), im ∝ −A sin(lag)
        let scale = 2.0 / (2 * per) as f64;
        let (re, im) = (re * scale, im * scale);
        let resp = dfdn * rel_amplitude * load_n;
        // normalise by the quasi-steady response (which is in phase with N)
        let (cr, ci) = (re / resp, im / resp);
        out.push(LoadResponsePoint {
            wavelength_m: lam_eff,
            wavelength_over_contact_length: lam_eff / (2.0 * h.a_m),
            frequency_hz: cfg.speed_m_per_s / lam_eff,
            amplitude_ratio: (cr * cr + ci * ci).sqrt(),
            phase_lag_rad: (-ci).atan2(cr),
        });
    }
    Ok(out)
}

//! `corrugation contact`: solve the wheel–rail contact of the model.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use corrugation::contact::report::{case_config, solve_case_on, ContactCase, TangentialLoading};

use super::ModelArgs;
use corrugation::model::MAX_WHEEL_LOAD_N;

/// Most transient steps of `contact --steps`: the patch is crossed in about `grid_nx` (40)
/// steps, so this is hundreds of crossings, seconds of work, and no hang.
const MAX_STEPS: usize = 10_000;

/// Solves the wheel–rail contact (Hertz + half-space grid, Kalker's exact tangential theory)
/// for the model's wheel, rail crown, steels (combined as quasi-identical bodies), load,
/// friction and contact grid (`contact.grid_nx`, `grid_ny`, `grid_margin`).
#[derive(Debug, Args)]
pub(crate) struct ContactCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Normal load (N). Default: vehicle.wheel_load.
    #[arg(allow_hyphen_values = true, long, value_name = "N")]
    normal_load: Option<f64>,
    /// Prescribed longitudinal creepage (−; positive = braking).
    #[arg(
        allow_hyphen_values = true,
        long,
        value_name = "X",
        conflicts_with = "traction_coefficient"
    )]
    creepage: Option<f64>,
    /// Prescribed traction coefficient F_x/N (−; positive = driving). Default:
    /// contact.traction_coefficient.
    #[arg(allow_hyphen_values = true, long, value_name = "T")]
    traction_coefficient: Option<f64>,
    /// Friction coefficient (−). Default: contact.friction.
    #[arg(allow_hyphen_values = true, long, value_name = "MU")]
    friction: Option<f64>,
    /// 1 = steady rolling; K > 1 = transient rolling from rest over K grid steps (at most
    /// 10000: a grid point crosses the patch in about 40 steps).
    #[arg(
        allow_hyphen_values = true,
        long,
        value_name = "K",
        default_value_t = 1
    )]
    steps: usize,
    /// Print the result as one JSON object.
    #[arg(long)]
    json: bool,
    /// Write pressure, traction, slip and frictional-power fields (CSV and .npy) into DIR.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

impl ContactCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let m = self.model.load()?;
        if let Some(n) = self.normal_load {
            if !(n.is_finite() && n > 0.0 && n <= MAX_WHEEL_LOAD_N) {
                anyhow::bail!(
                    "--normal-load {n}: out of range, allowed greater than 0 and at most {MAX_WHEEL_LOAD_N} N (as vehicle.wheel_load)"
                );
            }
        }
        if let Some(mu) = self.friction {
            if !(mu.is_finite() && mu > 0.0 && mu <= 2.0) {
                anyhow::bail!(
                    "--friction {mu}: out of range, allowed greater than 0 and at most 2 (as contact.friction)"
                );
            }
        }
        if self.steps == 0 || self.steps > MAX_STEPS {
            anyhow::bail!(
                "--steps {}: out of range, allowed 1 (steady rolling) to {MAX_STEPS} (transient from rest)",
                self.steps
            );
        }
        if let Some(x) = self.creepage {
            if !(x.is_finite() && x.abs() <= 1.0) {
                anyhow::bail!(
                    "--creepage {x}: out of range, allowed -1 to 1 (−; -1 is a locked wheel sliding at the rolling speed, beyond ±1 the tread slips faster than the train moves)"
                );
            }
        }
        if let Some(t) = self.traction_coefficient {
            let mu = self.friction.unwrap_or(m.contact.friction);
            if !(t.is_finite() && t.abs() <= mu) {
                anyhow::bail!(
                    "--traction-coefficient {t}: out of range, allowed -{mu} to {mu} (−; F_x/N cannot exceed the friction coefficient {mu}, --friction or contact.friction)"
                );
            }
        }
        let tangential = match (self.creepage, self.traction_coefficient) {
            (Some(x), _) => TangentialLoading::Creepage(x),
            (None, Some(t)) => TangentialLoading::TractionCoefficient(t),
            (None, None) => TangentialLoading::TractionCoefficient(m.contact.traction_coefficient),
        };
        let (youngs_pa, poisson) = corrugation::passage::setup::contact_steel(&m);
        let case = ContactCase {
            wheel_radius_m: m.wheel.radius,
            crown_radius_m: m.contact.rail_crown_radius,
            youngs_pa,
            poisson,
            normal_load_n: self.normal_load.unwrap_or(m.vehicle.wheel_load),
            friction: self.friction.unwrap_or(m.contact.friction),
            tangential,
            speed_m_per_s: m.run.speed(),
            steps: self.steps,
            grid_nx: m.contact.grid_nx,
            grid_ny: m.contact.grid_ny,
            grid_margin: m.contact.grid_margin,
            ..ContactCase::default()
        };
        if let Some(dir) = &self.out {
            super::check_out_dir(dir)?;
        }
        // the model's influence coefficients (`contact.influence`): the fe-patch's refined
        // submodels, built on first use and kept beside the modes
        let cfg = case_config(&case).context("the contact grid")?;
        let hertz_b_m = corrugation::passage::setup::static_hertz(&m, m.vehicle.wheel_load)?.b_m;
        let progress = super::progress::bar("contact");
        let op = corrugation::passage::fe_patch::influence_for(
            &m,
            (&cfg, hertz_b_m),
            corrugation::passage::fe_patch::Beside::Nothing,
            Some(&progress),
        )
        .context("the contact's influence coefficients")?;
        let sol = solve_case_on(&case, op).context("solving the contact")?;
        let s = sol.summary();
        if let Some(dir) = &self.out {
            // the error names the file
            sol.write_fields(dir)?;
        }
        if self.json {
            println!("{}", serde_json::to_string_pretty(&s)?);
        } else {
            println!(
                "wheel-rail contact: N = {:.1} kN, mu = {}",
                corrugation::units::n_to_kn(case.normal_load_n),
                case.friction
            );
            println!("  a (along rail)      {:.3} mm", s.a_mm);
            println!("  b (across)          {:.3} mm", s.b_mm);
            println!("  p0                  {:.1} MPa", s.p0_mpa);
            println!("  approach            {:.2} um", s.approach_um);
            println!("  contact area        {:.2} mm^2", s.area_mm2);
            println!("  F_x (on the wheel)  {:.1} N", s.fx_n);
            println!("  F_y                 {:.1} N", s.fy_n);
            println!("  creepage            {:.6e}", s.creepage);
            println!("  slip-area fraction  {:.3}", s.slip_area_fraction);
        }
        Ok(())
    }
}

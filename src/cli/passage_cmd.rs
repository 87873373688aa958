//! `corrugation passage`: one reduced-order passage of the wheel over the track
//! (docs/theory.md §7).
//!
//! Outputs in `--out DIR` (default `corrugation-out/passage`), all written atomically:
//! * `forces.csv` — per time step: `t_s, x_m, fn_n, fl_n, flat_n, creepage, approach_m,
//!   contact_length_m, slip_fraction, frictional_power_w, peak_pressure_pa` (forces on the
//!   wheel; F_L > 0 forward);
//! * `wear.csv` — `x_m, wf_j_per_m, wf_band_j_per_m` in the solution zone (W_f integrated
//!   across the rail head, and its 20–80 mm band-passed part);
//! * `rail_point.csv` — `t_s, ux_m, uy_m, uz_m` of the rail-top node nearest 0.6 m into the
//!   solution zone;
//! * `psd_wear.csv`, `psd_fl.csv`, `psd_fn.csv` — `wavelength_m, frequency_hz, psd` of the
//!   band-passed signals in the solution zone (one-sided, per unit wavenumber);
//! * `summary.json` — the `--json` object;
//! * plots `*.svg` / `*.png` of F_L, F_N and W_f along the rail and their PSDs.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::passage::record::PassageRecord;
use corrugation::passage::summary::PassageSummary;
use corrugation::studies::passage::{summary_lines, write_passage};

use super::ModelArgs;

/// One passage of the wheel over the track: contact forces, wear along the rail, PSDs.
#[derive(Debug, Args)]
pub(crate) struct PassageCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Rail-top profile (CSV with a header: x in m, height in µm), e.g. a corrugation.
    #[arg(long, value_name = "FILE.csv")]
    corrugation: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/passage", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Passage engine: `reduced` (modal, default) or `explicit` (the full explicit FE
    /// path, minutes per passage).
    #[arg(long, value_enum, default_value = "reduced")]
    engine: super::engine::Engine,
    #[command(flatten)]
    reference: super::reference_outputs::ReferenceArgs,
}

impl PassageCmd {
    /// With `--engine explicit`: refuses the flags only the reduced passage reads (the
    /// modal cache, the coupled-mode attribution and the nodal spectrum, which need the
    /// modal bases), instead of ignoring them.
    fn refuse_reduced_only_flags(&self) -> anyhow::Result<()> {
        let r = &self.reference;
        let given = [
            ("--cache", self.cache.is_some()),
            ("--no-coupled", r.no_coupled),
            ("--no-nodal", r.no_nodal),
            ("--nodal-at", !r.nodal_at_m.is_empty()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, on)| *on) {
            anyhow::bail!(
                "{flag} is for the reduced engine: `passage --engine explicit` writes no coupled-mode or nodal-spectrum files and reads no modal cache"
            );
        }
        Ok(())
    }

    pub fn run(self) -> anyhow::Result<()> {
        if self.engine == super::engine::Engine::Explicit {
            self.refuse_reduced_only_flags()?;
        }
        let m = self.model.load()?;
        self.reference.check(&m)?;
        let profile = match &self.corrugation {
            Some(p) => Some(super::read_profile(p, &m)?),
            None => None,
        };
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        if self.engine == super::engine::Engine::Explicit {
            return super::explicit_cmd::run_explicit(
                &m,
                corrugation::explicit::ExplicitOptions::from_model(&m),
                profile.as_ref(),
                &self.out,
                self.json,
            );
        }
        // a passage that runs alone: the track's damping product on the second core
        let opts = PassageOptions {
            overlap: true,
            ..PassageOptions::default()
        };
        let mut prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        if let (Some(p), Some(path)) = (&profile, &self.corrugation) {
            let travel = prepared.engine.rail_under_contact_m(m.run.speed())?;
            corrugation::passage::setup::check_profile_on_travel(p, travel)
                .with_context(|| format!("--corrugation {}", path.display()))?;
        }
        let pb = super::progress::bar("passage (time steps)");
        let rec = prepared
            .engine
            .passage(m.run.speed(), profile.as_ref(), &opts, Some(&pb))
            .context("running the passage")?;
        pb.finish_and_clear();
        let summary = corrugation::passage::analysis::summarise(&rec)?;
        write_passage(&self.out, &rec, &summary, m.mesh.fine_element_length)?;
        if self.json {
            println!("{}", serde_json::to_string_pretty(&summary)?);
        } else {
            print_summary(&summary, &rec, &self.out);
        }
        use super::reference_outputs::{coupled_attribution, nodal_outputs_printed};
        if !self.reference.no_coupled {
            coupled_attribution(&prepared, &summary, &self.out, self.json)?;
        }
        if !self.reference.no_nodal {
            let v = m.run.speed();
            nodal_outputs_printed(
                &mut prepared,
                v,
                profile.as_ref(),
                &self.reference,
                &self.out,
                self.json,
            )?;
        }
        Ok(())
    }
}

/// Prints the passage's summary lines and where its outputs are.
pub(crate) fn print_summary(s: &PassageSummary, rec: &PassageRecord, out: &Path) {
    for line in summary_lines(s, rec) {
        println!("{line}");
    }
    println!("  outputs in {}", out.display());
}

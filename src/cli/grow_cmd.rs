//! `corrugation grow`: trial-amplitude growth (docs/theory.md §10.1–§10.4, the reference
//! procedure) and, with `--rounds`, iterative growth (§10.5).
//!
//! Outputs in `--out DIR` (default `corrugation-out/grow`), written atomically:
//! * `consistency.csv` — per amplitude and reference component: the matched W_f, F_L, F_N
//!   wavelengths (mm), frequencies (Hz), deviations, case, class;
//! * `phase.csv` — per amplitude: correlation of the new wear with the corrugation, phase,
//!   growing, consistent growth;
//! * `eigen_comparison.csv` — every component vs the nearest longitudinal-compression,
//!   vertical-bending and wheel eigenfrequency (relative difference);
//! * `trial_shape.csv` — `x_m, wear_band_j_per_m, height_per_um`: the band-passed smooth wear
//!   and the trial corrugation shape for 2A_max = 1 µm (scale by the amplitude);
//! * `growth_rate.csv`, `growth_rate.svg`/`.png` — the growth-rate spectrum (docs/theory.md
//!   §10.6; `--no-rate` skips it);
//! * `rate_check.csv` (with `--rate-check`): the spectrum's linear theory against passages over
//!   1 µm sinusoidal corrugations at the given wavelengths;
//! * `iterative.csv` (with `--rounds`): round, passages, amplitude_um, dominant_wavelength_mm;
//! * `coupled_modes.csv/.npy/.json` — the coupled wheel–track modes at the speed
//!   (`--no-coupled` skips them and the attribution);
//! * `grow.json` — the `--json` object, with the dominant wear frequency of every passage
//!   and the growth-rate spectrum's fastest wavelength attributed to coupled modes, and the
//!   spectrum's summary (`growth_rate`: fastest wavelength, its rate per passage, the count
//!   of growing wavelengths).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use corrugation::dynamics::coupled::attribution_text;
use corrugation::growth::verdict::{sig, Verdict};
use corrugation::studies::grow::{
    run_grow, GrowJson, GrowOptions, GrowOutcome, GrowRun, DEFAULT_AMPLITUDES_UM,
    DEFAULT_PASSAGES_PER_ROUND,
};

use super::ModelArgs;

/// Trial-amplitude growth: smooth passage, trial corrugations, consistency, limiting amplitude.
#[derive(Debug, Args)]
pub(crate) struct GrowCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Trial amplitudes 2A_max (peak-to-trough, µm), comma separated.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_delimiter = ',',
        default_values_t = DEFAULT_AMPLITUDES_UM,
        value_name = "UM,..."
    )]
    amplitudes_um: Vec<f64>,
    /// Also run iterative growth for this many rounds (0 = off), at most 1000.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = 0,
        value_name = "N"
    )]
    rounds: usize,
    /// Passages per round of the iterative growth (1 or more).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = DEFAULT_PASSAGES_PER_ROUND,
        value_name = "N"
    )]
    passages_per_round: usize,
    /// Skip the growth-rate spectrum (`growth_rate.csv`).
    #[arg(long)]
    no_rate: bool,
    /// Check the growth-rate spectrum against passages over 1 µm sinusoidal corrugations at
    /// these wavelengths (mm, within 20–80), comma separated: `rate_check.csv`.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_delimiter = ',',
        value_name = "MM,..."
    )]
    rate_check: Vec<f64>,
    /// Skip the coupled wheel–track modes and the attribution of the selected frequencies.
    #[arg(long)]
    no_coupled: bool,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/grow", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory.
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Passage engine: `reduced` (modal, default) or `explicit` (the full explicit FE
    /// path, minutes per passage).
    #[arg(long, value_enum, default_value = "reduced")]
    engine: super::engine::Engine,
}

/// Prints the verdict as the last lines on stdout.
pub(crate) fn print_verdict(v: &Verdict) {
    println!();
    for l in &v.lines {
        println!("{l}");
    }
}

/// The growth table on stdout (figures to 3–4 significant digits).
fn print_growth(j: &GrowJson) {
    println!(
        "trial-amplitude growth at {} km/h: reference wavelengths {} mm",
        sig(j.speed_kmh, 4),
        j.reference_wavelengths_mm
            .iter()
            .map(|&v| sig(v, 3))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (i, a) in j.amplitudes_um.iter().enumerate() {
        println!(
            "  2A_max {:>5} µm: {} (r = {:+.2}), consistent growth: {}, F_L band RMS {} N, F_N band RMS {} N",
            sig(*a, 4),
            j.phase[i],
            j.correlation[i],
            if j.grows_consistently[i] { "yes" } else { "no" },
            sig(j.fl_band_rms_n[i], 3),
            sig(j.fn_band_rms_n[i], 3)
        );
    }
    for w in &j.widened_contact_grids {
        println!(
            "  {}: the contact patch reached the boundary of the model's contact grid; the passage ran on {}",
            corrugation::studies::grow::widened_passage_name(w.amplitude_um),
            w.grid
        );
    }
    match j.limiting_amplitude_um {
        Some(a) => println!("  limiting amplitude (2A_max)_l = {} µm", sig(a, 4)),
        None => println!(
            "  limiting amplitude: none (the smallest trial amplitude does not grow consistently)"
        ),
    }
}

impl GrowCmd {
    /// Runs the command: the library's grow run ([`run_grow`]), then the summary.
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let opts = GrowOptions {
            amplitudes_um: self.amplitudes_um.clone(),
            rounds: self.rounds,
            passages_per_round: self.passages_per_round,
            rate: !self.no_rate,
            rate_check_mm: self.rate_check.clone(),
            coupled: !self.no_coupled,
        };
        opts.check()?;
        let m = self.model.load()?;
        super::check_trial_profile_grid(&self.amplitudes_um, &m)?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let explicit = match self.engine {
            super::engine::Engine::Explicit => Some(super::engine::explicit_model(&m)?),
            super::engine::Engine::Reduced => None,
        };
        let recorder: &dyn corrugation::dynamics::PassageRecorder = match &explicit {
            Some(e) => e,
            None => &prepared.engine,
        };
        let pb = super::progress::bar("grow");
        let run = run_grow(&m, &prepared, recorder, &opts, &self.out, t0, &pb)?;
        pb.finish_and_clear();
        drop(pb);
        if self.json {
            println!("{}", run.json_text);
        } else {
            print_rate(&run);
        }
        match run.outcome {
            GrowOutcome::NoInitiation { verdict } => {
                if !self.json {
                    print_verdict(&verdict);
                }
                Ok(())
            }
            GrowOutcome::Grown { json, stopped } => {
                if !self.json {
                    print_growth(&json);
                    for a in &json.coupled {
                        if let Some(x) = &a.mode {
                            println!(
                                "  2A_max {} µm: {}",
                                sig(a.amplitude_um, 4),
                                attribution_text(x)
                            );
                        }
                    }
                    println!("  outputs in {}", self.out.display());
                    print_verdict(&json.verdict);
                }
                match stopped {
                    None => Ok(()),
                    Some(s) => anyhow::bail!(
                        "trial amplitude {} µm: {} (the amplitudes below it are written to {}; \
                         grow.json's stopped_at_um marks where the procedure stopped)",
                        s.amplitude_um,
                        s.reason,
                        self.out.display()
                    ),
                }
            }
        }
    }
}

/// The growth-rate spectrum's sentence, its fastest wavelength's coupled mode and the rate
/// checks.
fn print_rate(run: &GrowRun) {
    if let Some(r) = &run.rate {
        println!("{}", r.sentence);
        if let Some(a) = r.summary.as_ref().and_then(|s| s.fastest_mode.as_ref()) {
            println!(
                "  fastest wavelength by coupled mode: {}",
                attribution_text(a)
            );
        }
    }
    for r in &run.rate_checks {
        println!(
            "  rate check {} mm: |G| linear {} passage {} J/m per m (ratio {}), phase linear {}° passage {}° (difference {}°)",
            sig(r.wavelength_mm, 3),
            sig(r.linear_gain_j_per_m2, 4),
            sig(r.passage_gain_j_per_m2, 4),
            sig(r.amplitude_ratio, 3),
            sig(r.linear_phase_deg, 3),
            sig(r.passage_phase_deg, 3),
            sig(r.phase_difference_deg, 3)
        );
    }
}

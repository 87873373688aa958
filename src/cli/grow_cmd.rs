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

use corrugation::dynamics::coupled::{attribution_text, CoupledMode};
use corrugation::dynamics::prepared::PreparedModel;
use corrugation::growth::procedure::{iterative_growth, GrowthRound, IterativeOptions};
use corrugation::growth::verdict::{growth_verdict, no_initiation_verdict, sig, Verdict};
use corrugation::io::write_csv;
use corrugation::model::Model;
use corrugation::studies::coupled::write_coupled_modes;
use corrugation::studies::grow::{
    grow_json, growth_attribution, growth_rate, initiation_check, mode_lines, rate_check,
    rate_summary, trial_growth_if_any, write_grow_json, write_growth_files, write_growth_rate,
    GrowJson, RateSummary,
};

use super::ModelArgs;

/// Most rounds of iterative growth (`--rounds`): each round runs one passage.
pub const MAX_ROUNDS: usize = 1000;

/// Trial-amplitude growth: smooth passage, trial corrugations, consistency, limiting amplitude.
#[derive(Debug, Args)]
pub struct GrowCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Trial amplitudes 2A_max (peak-to-trough, µm), comma separated.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_delimiter = ',',
        default_values_t = corrugation::studies::grow::DEFAULT_AMPLITUDES_UM,
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
        default_value_t = 1000,
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
pub fn print_verdict(v: &Verdict) {
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
    /// Runs the command: the coupled modes, the growth-rate spectrum and its check, the
    /// trial-amplitude growth, the iterative rounds, then `grow.json` and the summary.
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        self.check_args()?;
        let m = self.model.load()?;
        super::check_trial_profile_grid(&self.amplitudes_um, &m)?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let coupled = if self.no_coupled {
            Vec::new()
        } else {
            let cm = prepared.coupled_modes(m.run.speed(), &[])?;
            write_coupled_modes(&self.out, &cm)?;
            cm.modes
        };
        let rate = if self.no_rate {
            None
        } else {
            self.rate_spectrum(&m, &prepared, &coupled)?
        };
        if !self.rate_check.is_empty() {
            self.check_rate(&prepared, m.run.speed())?;
        }
        let modes = mode_lines(&prepared);
        let explicit = match self.engine {
            super::engine::Engine::Explicit => Some(super::engine::explicit_model(&m)?),
            super::engine::Engine::Reduced => None,
        };
        let recorder: &dyn corrugation::dynamics::PassageRecorder = match &explicit {
            Some(e) => e,
            None => &prepared.engine,
        };
        let pb = super::progress::bar("trial-amplitude growth");
        let g = trial_growth_if_any(recorder, m.run.speed(), &self.amplitudes_um, &modes, &pb)?;
        pb.finish_and_clear();
        drop(pb);
        let Some(g) = g else {
            return self.no_initiation(m.run.speed_kmh, rate);
        };
        let verdict = growth_verdict(
            &g,
            m.run.speed_kmh,
            &modes,
            Some(initiation_check(&m, &g.smooth)),
        );
        write_growth_files(&self.out, &g)?;
        let rounds = if self.rounds > 0 {
            self.iterative(recorder, m.run.speed(), m.wear.coefficient)?
        } else {
            Vec::new()
        };
        let mut j = grow_json(
            &g,
            m.run.speed_kmh,
            rounds,
            verdict,
            t0.elapsed().as_secs_f64(),
        );
        j.coupled = growth_attribution(&g, &coupled);
        j.growth_rate = rate;
        let text = serde_json::to_string_pretty(&j)?;
        write_grow_json(&self.out, &text)?;
        if self.json {
            println!("{text}");
        } else {
            print_growth(&j);
            for a in &j.coupled {
                if let Some(x) = &a.mode {
                    println!(
                        "  2A_max {} µm: {}",
                        sig(a.amplitude_um, 4),
                        attribution_text(x)
                    );
                }
            }
            println!("  outputs in {}", self.out.display());
            print_verdict(&j.verdict);
        }
        match &g.stopped {
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

    /// The trial amplitudes and the rate-check wavelengths.
    fn check_args(&self) -> anyhow::Result<()> {
        super::check_trial_amplitudes(&self.amplitudes_um)?;
        if let Some(l) = self
            .rate_check
            .iter()
            .find(|l| !(l.is_finite() && (20.0..=80.0).contains(*l)))
        {
            anyhow::bail!("--rate-check wavelengths must lie in [20, 80] mm (got {l})");
        }
        corrugation::lists::check_no_repeats("--rate-check", "mm", &self.rate_check)?;
        if self.passages_per_round == 0 {
            anyhow::bail!(
                "--passages-per-round 0: out of range, allowed at least 1 passage (a round's wear is one passage's times this count)"
            );
        }
        if self.rounds > MAX_ROUNDS {
            anyhow::bail!(
                "--rounds {}: out of range, at most {MAX_ROUNDS} rounds (0 = off; each round runs one passage, about half a second on the default model, so {MAX_ROUNDS} rounds take about 10 minutes)",
                self.rounds
            );
        }
        Ok(())
    }

    /// The growth-rate spectrum (written, and its sentence printed) and its summary with the
    /// fastest wavelength attributed to a `coupled` mode.
    fn rate_spectrum(
        &self,
        m: &Model,
        prepared: &PreparedModel,
        coupled: &[CoupledMode],
    ) -> anyhow::Result<Option<RateSummary>> {
        let pb = super::progress::bar("growth-rate spectrum");
        let s = growth_rate(m, prepared, m.run.requested_speed(), &pb)?;
        pb.finish_and_clear();
        write_growth_rate(&self.out, &s)?;
        if !self.json {
            println!("{}", s.sentence());
        }
        let rate = rate_summary(&s, coupled);
        if let Some(a) = rate.as_ref().and_then(|r| r.fastest_mode.as_ref()) {
            if !self.json {
                println!(
                    "  fastest wavelength by coupled mode: {}",
                    attribution_text(a)
                );
            }
        }
        Ok(rate)
    }

    /// The spectrum's linear theory against passages over 1 µm sinusoidal corrugations at
    /// the `--rate-check` wavelengths (`rate_check.csv`), printed.
    fn check_rate(&self, prepared: &PreparedModel, speed_m_per_s: f64) -> anyhow::Result<()> {
        let l: Vec<f64> = self
            .rate_check
            .iter()
            .map(|&v| corrugation::units::mm_to_m(v))
            .collect();
        let rows = rate_check(
            prepared,
            speed_m_per_s,
            &l,
            corrugation::units::um_to_m(1.0),
            &self.out,
        )?;
        for r in &rows {
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
        Ok(())
    }

    /// No trial grows from a smooth rail without initiation: `grow.json` with the verdict
    /// and the rate summary, printed.
    fn no_initiation(&self, speed_kmh: f64, rate: Option<RateSummary>) -> anyhow::Result<()> {
        let v = no_initiation_verdict(speed_kmh, None);
        let text = serde_json::to_string_pretty(&serde_json::json!({
            "speed_kmh": speed_kmh,
            "verdict": v,
            "growth_rate": rate,
        }))?;
        write_grow_json(&self.out, &text)?;
        if self.json {
            println!("{text}");
        } else {
            print_verdict(&v);
        }
        Ok(())
    }

    /// `--rounds` rounds of iterative growth (`iterative.csv`).
    fn iterative(
        &self,
        recorder: &dyn corrugation::dynamics::PassageRecorder,
        speed_m_per_s: f64,
        wear_coefficient_m3_per_j: f64,
    ) -> anyhow::Result<Vec<GrowthRound>> {
        let pb = super::progress::bar("iterative growth (rounds)");
        pb.set_length(self.rounds as u64);
        let (r, _) = iterative_growth(
            recorder,
            speed_m_per_s,
            &IterativeOptions {
                passages_per_round: self.passages_per_round,
                max_rounds: self.rounds,
                saturation: 0.01,
                wear_coefficient_m3_per_j,
            },
            |r| pb.set_position(r.round as u64),
        )?;
        pb.finish_and_clear();
        let rows: Vec<Vec<f64>> = r
            .iter()
            .map(|r| {
                vec![
                    r.round as f64,
                    r.passages as f64,
                    r.amplitude_um,
                    r.dominant_wavelength_mm.unwrap_or(f64::NAN),
                ]
            })
            .collect();
        write_csv(
            &self.out.join("iterative.csv"),
            &[
                "round",
                "passages",
                "amplitude_um",
                "dominant_wavelength_mm",
            ],
            rows,
        )?;
        Ok(r)
    }
}

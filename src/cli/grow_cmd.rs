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
//! * `iterative.csv` (with `--rounds`): round, passages, amplitude_um, dominant_wavelength_mm;
//! * `grow.json` — the `--json` object.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use corrugation::growth::procedure::{iterative_growth, IterativeOptions};
use corrugation::growth::verdict::{growth_verdict, no_initiation_verdict, sig, Verdict};
use corrugation::io::write_csv;
use corrugation::studies::grow::{
    grow_json, initiation_check, mode_lines, trial_growth_if_any, write_grow_json,
    write_growth_files, GrowJson,
};

use super::ModelArgs;

/// Trial-amplitude growth: smooth passage, trial corrugations, consistency, limiting amplitude.
#[derive(Debug, Args)]
pub struct GrowCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Trial amplitudes 2A_max (peak-to-trough, µm), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "10,40,80,160",
        value_name = "UM,..."
    )]
    amplitudes_um: Vec<f64>,
    /// Also run iterative growth for this many rounds (0 = off).
    #[arg(long, default_value_t = 0, value_name = "N")]
    rounds: usize,
    /// Passages per round of the iterative growth.
    #[arg(long, default_value_t = 1000, value_name = "N")]
    passages_per_round: usize,
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
    match j.limiting_amplitude_um {
        Some(a) => println!("  limiting amplitude (2A_max)_l = {} µm", sig(a, 4)),
        None => println!(
            "  limiting amplitude: none (the smallest trial amplitude does not grow consistently)"
        ),
    }
}

impl GrowCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        super::check_trial_amplitudes(&self.amplitudes_um)?;
        let m = self.model.load()?;
        super::check_out_dir(&self.out)?;
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
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
            let v = no_initiation_verdict(m.run.speed_kmh, None);
            let text = serde_json::to_string_pretty(&serde_json::json!({
                "speed_kmh": m.run.speed_kmh,
                "verdict": v,
            }))?;
            write_grow_json(&self.out, &text)?;
            if self.json {
                println!("{text}");
            } else {
                print_verdict(&v);
            }
            return Ok(());
        };
        let verdict = growth_verdict(
            &g,
            m.run.speed_kmh,
            &modes,
            Some(initiation_check(&m, &g.smooth)),
        );
        write_growth_files(&self.out, &g)?;
        let mut rounds = Vec::new();
        if self.rounds > 0 {
            let pb = super::progress::bar("iterative growth (rounds)");
            pb.set_length(self.rounds as u64);
            let (r, _) = iterative_growth(
                recorder,
                m.run.speed(),
                &IterativeOptions {
                    passages_per_round: self.passages_per_round,
                    max_rounds: self.rounds,
                    saturation: 0.01,
                    wear_coefficient_m3_per_j: m.wear.coefficient,
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
            rounds = r;
        }
        let j = grow_json(
            &g,
            m.run.speed_kmh,
            rounds,
            verdict,
            t0.elapsed().as_secs_f64(),
        );
        let text = serde_json::to_string_pretty(&j)?;
        write_grow_json(&self.out, &text)?;
        if self.json {
            println!("{text}");
        } else {
            print_growth(&j);
            println!("  outputs in {}", self.out.display());
            print_verdict(&j.verdict);
        }
        Ok(())
    }
}

//! `corrugation receptance`: the reduced model's receptances at the contact (rail at the
//! mid-span and over the sleeper nearest the solution-zone centre, the wheel at its contact
//! point) and the normal contact force per unit roughness, with their peaks: which
//! resonances a sweep's frequency selection can lock on (docs/theory.md §7.6).
//!
//! Outputs in `--out DIR` (default `corrugation-out/receptance`), written atomically:
//! * `receptance.csv` — `frequency_hz`, then for each rail position `P` (`mid`, `sleeper`, or
//!   `x<m>` for `--at`) `rail_P_{x,t,n}_m_per_n` (|H|) and `rail_P_{x,t,n}_phase_rad`, then
//!   `wheel_{x,t,n}_m_per_n`, `wheel_{x,t,n}_phase_rad`, and
//!   `force_per_roughness_P_n_per_m` (|1/(H_nn^rail + H_nn^wheel + c_H)|);
//! * `receptance.json` — the `--json` object (positions, peaks, mode lines, seconds);
//! * `receptance_rail.{svg,png}`, `receptance_wheel.{svg,png}`,
//!   `force_per_roughness.{svg,png}`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::dynamics::receptance::peaks;
use corrugation::io::{write_atomic, write_csv};
use corrugation::report::plot::{line_plot_log_y, Series};

use super::ModelArgs;

/// Receptances of the track and the wheel at the contact, and their peaks.
#[derive(Debug, Args)]
pub struct ReceptanceCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Lowest frequency (Hz).
    #[arg(long, default_value_t = 20.0, value_name = "HZ")]
    from_hz: f64,
    /// Highest frequency (Hz); default: the smaller of run.fmax and 3000 Hz (the top of a
    /// 54.8–219 km/h sweep map: 219 km/h / 20 mm ≈ 3.04 kHz).
    #[arg(long, value_name = "HZ")]
    to_hz: Option<f64>,
    /// Frequency step (Hz).
    /// (One complex LU of the m × m modal dynamic stiffness per frequency: ≈ 0.05 s at the
    /// default model's 746 track modes, 2 cores.)
    #[arg(long, default_value_t = 4.0, value_name = "HZ")]
    step_hz: f64,
    /// Rail positions (m along the rail); default: the mid-span and the sleeper nearest the
    /// centre of the solution zone.
    #[arg(long = "at", value_name = "M")]
    at_m: Vec<f64>,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/receptance", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

/// One peak of a receptance curve.
#[derive(Debug, Serialize)]
struct Peak {
    frequency_hz: f64,
    value: f64,
}

/// Peaks of one rail position.
#[derive(Debug, Serialize)]
struct RailPeaks {
    label: String,
    x_m: f64,
    /// |H_xx| (m/N).
    longitudinal: Vec<Peak>,
    /// |H_nn| (m/N).
    normal: Vec<Peak>,
    /// |1/(H_nn^rail + H_nn^wheel + c_H)| (N/m).
    force_per_roughness: Vec<Peak>,
}

#[derive(Debug, Serialize)]
struct Summary {
    fmax_hz: f64,
    frequencies: [f64; 3],
    hertz_compliance_m_per_n: f64,
    series_compliance_m_per_n: [f64; 3],
    /// The wheel's flexibility at the contact (static, modal, residual; m/N), when used.
    wheel_residual: Option<corrugation::dynamics::wheel_residual::WheelResidual>,
    rail: Vec<RailPeaks>,
    wheel_longitudinal: Vec<Peak>,
    wheel_normal: Vec<Peak>,
    /// Elastic wheel modes with their contact participation.
    wheel_modes: Vec<WheelMode>,
    longitudinal_compression_hz: Vec<f64>,
    vertical_bending_hz: Vec<f64>,
    seconds: f64,
}

/// One elastic wheel mode as the contact sees it.
#[derive(Debug, Serialize)]
struct WheelMode {
    frequency_hz: f64,
    /// r_x² (1/kg): squared mass-normalised x displacement at the wheel's contact point.
    rx2_per_kg: f64,
    /// r_n² (1/kg), normal direction.
    rn2_per_kg: f64,
}

const PEAKS: usize = 10;

fn to_peaks(f: &[f64], y: &[f64]) -> Vec<Peak> {
    peaks(f, y, PEAKS)
        .into_iter()
        .map(|(frequency_hz, value)| Peak {
            frequency_hz,
            value,
        })
        .collect()
}

impl ReceptanceCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = std::time::Instant::now();
        let m = self.model.load()?;
        let to_hz = self.to_hz.unwrap_or(m.run.fmax.min(3000.0));
        if !(self.from_hz >= 0.0 && self.step_hz > 0.0 && to_hz > self.from_hz) {
            anyhow::bail!(
                "receptance: need 0 <= --from-hz < --to-hz and --step-hz > 0 (got {} .. {} step {} Hz)",
                self.from_hz,
                to_hz,
                self.step_hz
            );
        }
        let n = ((to_hz - self.from_hz) / self.step_hz).floor() as usize + 1;
        if n > 200_000 {
            anyhow::bail!("receptance: {n} frequencies; raise --step-hz");
        }
        // Half a step off the grid's round numbers keeps exact mode frequencies (rigid
        // wheel modes at 0 Hz) off the grid.
        let freqs: Vec<f64> = (0..n)
            .map(|i| self.from_hz + i as f64 * self.step_hz)
            .map(|f| if f == 0.0 { 0.25 * self.step_hz } else { f })
            .collect();
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let eng = &prepared.engine;
        let (labels, positions): (Vec<String>, Vec<f64>) = if self.at_m.is_empty() {
            let [mid, sl] = eng.midspan_and_sleeper_m();
            (vec!["mid".into(), "sleeper".into()], vec![mid, sl])
        } else {
            (
                self.at_m.iter().map(|x| format!("x{x}")).collect(),
                self.at_m.clone(),
            )
        };
        let pb = super::progress::bar(&format!(
            "receptance ({n} frequencies, {} modes)",
            prepared.track_frequencies_hz.len()
        ));
        let r = eng
            .contact_receptance(&positions, &freqs)
            .context("computing the receptances")?;
        pb.finish_and_clear();
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("creating {}", self.out.display()))?;
        let dirs = ["x", "t", "n"];
        let mut header = vec!["frequency_hz".to_string()];
        for l in &labels {
            for d in dirs {
                header.push(format!("rail_{l}_{d}_m_per_n"));
            }
            for d in dirs {
                header.push(format!("rail_{l}_{d}_phase_rad"));
            }
        }
        for d in dirs {
            header.push(format!("wheel_{d}_m_per_n"));
        }
        for d in dirs {
            header.push(format!("wheel_{d}_phase_rad"));
        }
        for l in &labels {
            header.push(format!("force_per_roughness_{l}_n_per_m"));
        }
        let fpr: Vec<Vec<f64>> = (0..positions.len())
            .map(|p| r.normal_force_per_roughness(p))
            .collect();
        let hdr: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
        write_csv(
            &self.out.join("receptance.csv"),
            &hdr,
            (0..n).map(|k| {
                let mut row = vec![freqs[k]];
                for p in 0..positions.len() {
                    let h = &r.rail[p][k];
                    row.extend((0..3).map(|d| h[d][d].norm()));
                    row.extend((0..3).map(|d| h[d][d].arg()));
                }
                let w = &r.wheel[k];
                row.extend((0..3).map(|d| w[d][d].norm()));
                row.extend((0..3).map(|d| w[d][d].arg()));
                row.extend(fpr.iter().map(|v| v[k]));
                row
            }),
        )?;
        let rail: Vec<RailPeaks> = (0..positions.len())
            .map(|p| RailPeaks {
                label: labels[p].clone(),
                x_m: positions[p],
                longitudinal: to_peaks(&freqs, &r.rail_abs(p, 0)),
                normal: to_peaks(&freqs, &r.rail_abs(p, 2)),
                force_per_roughness: to_peaks(&freqs, &fpr[p]),
            })
            .collect();
        let summary = Summary {
            fmax_hz: m.run.fmax,
            frequencies: [self.from_hz, to_hz, self.step_hz],
            hertz_compliance_m_per_n: r.hertz_compliance_m_per_n,
            series_compliance_m_per_n: eng.series_compliance(),
            wheel_residual: eng.wheel_residual().cloned(),
            rail,
            wheel_longitudinal: to_peaks(&freqs, &r.wheel_abs(0)),
            wheel_normal: to_peaks(&freqs, &r.wheel_abs(2)),
            wheel_modes: eng
                .wheel_contact_participation()
                .into_iter()
                .map(|(i, [x, n])| WheelMode {
                    frequency_hz: prepared.wheel_frequencies_hz[i],
                    rx2_per_kg: x,
                    rn2_per_kg: n,
                })
                .collect(),
            longitudinal_compression_hz: prepared.longitudinal_compression_hz(),
            vertical_bending_hz: prepared.vertical_bending_hz(),
            seconds: t0.elapsed().as_secs_f64(),
        };
        let mut rail_series = Vec::new();
        for (p, l) in labels.iter().enumerate() {
            rail_series.push(Series::new(
                format!("rail {l} x"),
                freqs.clone(),
                r.rail_abs(p, 0),
            ));
            rail_series.push(Series::new(
                format!("rail {l} n"),
                freqs.clone(),
                r.rail_abs(p, 2),
            ));
        }
        line_plot_log_y(
            &self.out.join("receptance_rail"),
            "Rail receptance at the contact point",
            "frequency (Hz)",
            "|H| (m/N)",
            &rail_series,
        )?;
        line_plot_log_y(
            &self.out.join("receptance_wheel"),
            "Wheel receptance at the contact point",
            "frequency (Hz)",
            "|H| (m/N)",
            &[
                Series::new("wheel x", freqs.clone(), r.wheel_abs(0)),
                Series::new("wheel n", freqs.clone(), r.wheel_abs(2)),
            ],
        )?;
        line_plot_log_y(
            &self.out.join("force_per_roughness"),
            "Normal contact force per unit roughness |1/(H_rail + H_wheel + c_Hertz)|",
            "frequency (Hz)",
            "N/m",
            &labels
                .iter()
                .zip(&fpr)
                .map(|(l, v)| Series::new(l.clone(), freqs.clone(), v.clone()))
                .collect::<Vec<_>>(),
        )?;
        let json = serde_json::to_string_pretty(&summary)?;
        write_atomic(&self.out.join("receptance.json"), |f| {
            use std::io::Write;
            f.write_all(json.as_bytes())
        })?;
        if self.json {
            println!("{json}");
        } else {
            let fmt = |v: &[Peak]| {
                v.iter()
                    .take(5)
                    .map(|p| format!("{:.0} Hz ({:.2e})", p.frequency_hz, p.value))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            for rp in &summary.rail {
                println!("rail {} (x = {:.3} m):", rp.label, rp.x_m);
                println!("  |H_xx| peaks (m/N): {}", fmt(&rp.longitudinal));
                println!("  |H_nn| peaks (m/N): {}", fmt(&rp.normal));
                println!(
                    "  force per roughness peaks (N/m): {}",
                    fmt(&rp.force_per_roughness)
                );
            }
            println!("wheel |H_xx| peaks: {}", fmt(&summary.wheel_longitudinal));
            println!("wheel |H_nn| peaks: {}", fmt(&summary.wheel_normal));
            println!(
                "{} frequencies in {:.1} s; outputs in {}",
                n,
                summary.seconds,
                self.out.display()
            );
        }
        Ok(())
    }
}

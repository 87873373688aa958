//! The receptance product (`corrugation receptance`): the reduced model's receptances at the
//! contact (rail at the mid-span and over the sleeper nearest the solution-zone centre, or at
//! given positions, the wheel at its contact point) and the normal contact force per unit
//! roughness, with their peaks: which resonances a sweep's frequency selection can lock on
//! (docs/theory.md §7.6).
//!
//! [`ReceptanceOptions::grid`] checks the frequency grid (before the model is prepared),
//! [`receptances`] computes on a prepared model, and [`Receptances::write`] writes the files
//! into a directory, atomically:
//! * `receptance.csv` — `frequency_hz`, then for each rail position `P` (`mid`, `sleeper`, or
//!   `x<m>` for given positions) `rail_P_{x,t,n}_m_per_n` (|H|) and
//!   `rail_P_{x,t,n}_phase_rad`, then `wheel_{x,t,n}_m_per_n`, `wheel_{x,t,n}_phase_rad`, and
//!   `force_per_roughness_P_n_per_m` (|1/(H_nn^rail + H_nn^wheel + c_H)|);
//! * `receptance.json` — the [`ReceptanceSummary`] (positions, peaks, mode lines, seconds);
//! * `receptance_rail.{svg,png}`, `receptance_wheel.{svg,png}`,
//!   `force_per_roughness.{svg,png}`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::receptance::{peaks, ContactReceptance};
use crate::dynamics::wheel_residual::WheelResidual;
use crate::dynamics::DynamicsError;
use crate::io::{write_atomic, write_csv};
use crate::report::plot::{line_plot_log_y, Series};
use crate::report::ReportError;

/// Largest number of frequencies of one receptance run.
pub(crate) const MAX_FREQUENCIES: usize = 200_000;

/// Peaks kept per curve.
pub(crate) const PEAKS: usize = 10;

/// Errors of the receptance product.
#[derive(Debug, thiserror::Error)]
pub enum ReceptanceError {
    /// A frequency grid that cannot be used.
    #[error("receptance: need finite 0 <= --from-hz < --to-hz <= run.fmax ({fmax_hz} Hz: the modal basis ends there) and --step-hz > 0 (got {from_hz} .. {to_hz} step {step_hz} Hz)")]
    Grid {
        /// Lowest frequency (Hz).
        from_hz: f64,
        /// Highest frequency (Hz).
        to_hz: f64,
        /// Frequency step (Hz).
        step_hz: f64,
        /// The model's frequency limit `run.fmax` (Hz).
        fmax_hz: f64,
    },
    /// More than `MAX_FREQUENCIES` frequencies.
    #[error("receptance: {0} frequencies; raise --step-hz")]
    TooManyFrequencies(usize),
    /// The receptances could not be computed.
    #[error("computing the receptances: {0}")]
    Dynamics(#[from] DynamicsError),
    /// A file or directory could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] ReportError),
    /// The summary could not be serialised.
    #[error("receptance.json: {0}")]
    Json(#[from] serde_json::Error),
    /// A position off the track.
    #[error(transparent)]
    Position(#[from] crate::model::ModelError),
}

/// What a receptance run computes.
#[derive(Clone, Debug, PartialEq)]
pub struct ReceptanceOptions {
    /// Lowest frequency (Hz, ≥ 0; default 20).
    pub from_hz: f64,
    /// Highest frequency (Hz, above `from_hz`); `None`: the smaller of `run.fmax` and
    /// 3000 Hz (the top of a 54.8–219 km/h sweep map: 219 km/h / 20 mm ≈ 3.04 kHz).
    pub to_hz: Option<f64>,
    /// Frequency step (Hz, > 0; default 4).
    pub step_hz: f64,
    /// Rail positions (m along the rail); empty (default): the mid-span and the sleeper
    /// nearest the centre of the solution zone.
    pub at_m: Vec<f64>,
}

impl Default for ReceptanceOptions {
    fn default() -> Self {
        ReceptanceOptions {
            from_hz: 20.0,
            to_hz: None,
            step_hz: 4.0,
            at_m: Vec::new(),
        }
    }
}

/// The frequency grid of a run (Hz).
#[derive(Clone, Debug, PartialEq)]
pub struct FrequencyGrid {
    /// The model's frequency limit `run.fmax` (Hz).
    pub fmax_hz: f64,
    /// Lowest, highest frequency and step (Hz), as requested.
    pub range_hz: [f64; 3],
    /// The frequencies (Hz); a 0 Hz point is moved to a quarter step.
    pub frequencies_hz: Vec<f64>,
}

impl ReceptanceOptions {
    /// The frequency grid for a model of frequency limit `fmax_hz` (Hz): `from_hz` to the
    /// highest frequency (at most `fmax_hz`, where the modal basis ends) in steps of
    /// `step_hz`, at most `MAX_FREQUENCIES`.
    pub fn grid(&self, fmax_hz: f64) -> Result<FrequencyGrid, ReceptanceError> {
        let to_hz = self.to_hz.unwrap_or(fmax_hz.min(3000.0));
        let finite = self.from_hz.is_finite() && to_hz.is_finite() && self.step_hz.is_finite();
        if !(finite
            && self.from_hz >= 0.0
            && self.step_hz > 0.0
            && to_hz > self.from_hz
            && to_hz <= fmax_hz)
        {
            return Err(ReceptanceError::Grid {
                from_hz: self.from_hz,
                to_hz,
                step_hz: self.step_hz,
                fmax_hz,
            });
        }
        let n = ((to_hz - self.from_hz) / self.step_hz).floor() as usize + 1;
        if n > MAX_FREQUENCIES {
            return Err(ReceptanceError::TooManyFrequencies(n));
        }
        // Half a step off the grid's round numbers keeps exact mode frequencies (rigid
        // wheel modes at 0 Hz) off the grid.
        let frequencies_hz = (0..n)
            .map(|i| self.from_hz + i as f64 * self.step_hz)
            .map(|f| if f == 0.0 { 0.25 * self.step_hz } else { f })
            .collect();
        Ok(FrequencyGrid {
            fmax_hz,
            range_hz: [self.from_hz, to_hz, self.step_hz],
            frequencies_hz,
        })
    }
}

/// One peak of a receptance curve.
#[derive(Clone, Debug, Serialize)]
pub struct Peak {
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// The curve's value (its unit).
    pub value: f64,
}

/// Peaks of one rail position.
#[derive(Clone, Debug, Serialize)]
pub struct RailPeaks {
    /// `mid`, `sleeper`, or `x<m>`.
    pub label: String,
    /// Position along the rail (m).
    pub x_m: f64,
    /// |H_xx| (m/N).
    pub longitudinal: Vec<Peak>,
    /// |H_nn| (m/N).
    pub normal: Vec<Peak>,
    /// |1/(H_nn^rail + H_nn^wheel + c_H)| (N/m).
    pub force_per_roughness: Vec<Peak>,
}

/// One elastic wheel mode as the contact sees it.
#[derive(Clone, Debug, Serialize)]
pub struct WheelMode {
    /// Eigenfrequency (Hz).
    pub frequency_hz: f64,
    /// r_x² (1/kg): squared mass-normalised x displacement at the wheel's contact point.
    pub rx2_per_kg: f64,
    /// r_n² (1/kg), normal direction.
    pub rn2_per_kg: f64,
}

/// The summary of a receptance run (`receptance.json`).
#[derive(Clone, Debug, Serialize)]
pub struct ReceptanceSummary {
    /// The model's frequency limit (Hz).
    pub fmax_hz: f64,
    /// Lowest, highest frequency and step (Hz).
    pub frequencies: [f64; 3],
    /// Linearised Hertz normal compliance at the static load (m/N).
    pub hertz_compliance_m_per_n: f64,
    /// The residual compliance of the truncated track modes (m/N; x, t, n).
    pub series_compliance_m_per_n: [f64; 3],
    /// The wheel's flexibility at the contact (static, modal, residual; m/N), when used.
    pub wheel_residual: Option<WheelResidual>,
    /// Peaks per rail position.
    pub rail: Vec<RailPeaks>,
    /// Peaks of the wheel's |H_xx| (m/N).
    pub wheel_longitudinal: Vec<Peak>,
    /// Peaks of the wheel's |H_nn| (m/N).
    pub wheel_normal: Vec<Peak>,
    /// Elastic wheel modes with their contact participation.
    pub wheel_modes: Vec<WheelMode>,
    /// The rail's longitudinal compression lines (Hz).
    pub longitudinal_compression_hz: Vec<f64>,
    /// The rail's vertical bending lines (Hz).
    pub vertical_bending_hz: Vec<f64>,
    /// Wall time of the run (s).
    pub seconds: f64,
}

/// The receptances of a run and their summary.
#[derive(Clone, Debug)]
pub struct Receptances {
    /// Labels of the rail positions (`mid`, `sleeper`, or `x<m>`).
    pub labels: Vec<String>,
    /// The receptances (frequencies, positions, rail, wheel, Hertz compliance).
    pub receptance: ContactReceptance,
    /// Normal contact force per unit roughness per position and frequency (N/m).
    pub force_per_roughness: Vec<Vec<f64>>,
    /// The peaks and lines.
    pub summary: ReceptanceSummary,
}

/// The peaks of the curve `y` over the frequencies `f` (Hz), at most [`PEAKS`].
fn to_peaks(f: &[f64], y: &[f64]) -> Vec<Peak> {
    peaks(f, y, PEAKS)
        .into_iter()
        .map(|(frequency_hz, value)| Peak {
            frequency_hz,
            value,
        })
        .collect()
}

/// The receptances of a prepared model on `grid` at the rail positions of `opts`, with
/// their peaks; `started` is when the run began (for the summary's seconds).
pub fn receptances(
    prepared: &PreparedModel,
    opts: &ReceptanceOptions,
    grid: &FrequencyGrid,
    started: Instant,
) -> Result<Receptances, ReceptanceError> {
    let eng = &prepared.engine;
    eng.model().check_on_track("--at", &opts.at_m)?;
    let freqs = &grid.frequencies_hz;
    let (labels, positions): (Vec<String>, Vec<f64>) = if opts.at_m.is_empty() {
        let [mid, sl] = eng.midspan_and_sleeper_m();
        (vec!["mid".into(), "sleeper".into()], vec![mid, sl])
    } else {
        (
            opts.at_m.iter().map(|x| format!("x{x}")).collect(),
            opts.at_m.clone(),
        )
    };
    let r = eng.contact_receptance(&positions, freqs)?;
    let fpr: Vec<Vec<f64>> = (0..positions.len())
        .map(|p| r.normal_force_per_roughness(p))
        .collect();
    let rail: Vec<RailPeaks> = (0..positions.len())
        .map(|p| RailPeaks {
            label: labels[p].clone(),
            x_m: positions[p],
            longitudinal: to_peaks(freqs, &r.rail_abs(p, 0)),
            normal: to_peaks(freqs, &r.rail_abs(p, 2)),
            force_per_roughness: to_peaks(freqs, &fpr[p]),
        })
        .collect();
    let summary = ReceptanceSummary {
        fmax_hz: grid.fmax_hz,
        frequencies: grid.range_hz,
        hertz_compliance_m_per_n: r.hertz_compliance_m_per_n,
        series_compliance_m_per_n: eng.series_compliance(),
        wheel_residual: eng.wheel_residual().cloned(),
        rail,
        wheel_longitudinal: to_peaks(freqs, &r.wheel_abs(0)),
        wheel_normal: to_peaks(freqs, &r.wheel_abs(2)),
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
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok(Receptances {
        labels,
        receptance: r,
        force_per_roughness: fpr,
        summary,
    })
}

impl Receptances {
    /// The CSV's header (module doc).
    fn csv_header(&self) -> Vec<String> {
        let dirs = ["x", "t", "n"];
        let mut header = vec!["frequency_hz".to_string()];
        for l in &self.labels {
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
        for l in &self.labels {
            header.push(format!("force_per_roughness_{l}_n_per_m"));
        }
        header
    }

    /// The CSV's row of frequency `k`.
    fn csv_row(&self, k: usize) -> Vec<f64> {
        let r = &self.receptance;
        let mut row = vec![r.frequencies_hz[k]];
        for h in &r.rail {
            let h = &h[k];
            row.extend((0..3).map(|d| h[d][d].norm()));
            row.extend((0..3).map(|d| h[d][d].arg()));
        }
        let w = &r.wheel[k];
        row.extend((0..3).map(|d| w[d][d].norm()));
        row.extend((0..3).map(|d| w[d][d].arg()));
        row.extend(self.force_per_roughness.iter().map(|v| v[k]));
        row
    }

    /// The three plots: the rail's and the wheel's receptances and the force per roughness.
    fn plot(&self, out: &Path) -> Result<(), ReceptanceError> {
        let r = &self.receptance;
        let freqs = &r.frequencies_hz;
        let mut rail_series = Vec::new();
        for (p, l) in self.labels.iter().enumerate() {
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
            &out.join("receptance_rail"),
            "Rail receptance at the contact point",
            "frequency (Hz)",
            "|H| (m/N)",
            &rail_series,
        )?;
        line_plot_log_y(
            &out.join("receptance_wheel"),
            "Wheel receptance at the contact point",
            "frequency (Hz)",
            "|H| (m/N)",
            &[
                Series::new("wheel x", freqs.clone(), r.wheel_abs(0)),
                Series::new("wheel n", freqs.clone(), r.wheel_abs(2)),
            ],
        )?;
        line_plot_log_y(
            &out.join("force_per_roughness"),
            "Normal contact force per unit roughness |1/(H_rail + H_wheel + c_Hertz)|",
            "frequency (Hz)",
            "N/m",
            &self
                .labels
                .iter()
                .zip(&self.force_per_roughness)
                .map(|(l, v)| Series::new(l.clone(), freqs.clone(), v.clone()))
                .collect::<Vec<_>>(),
        )?;
        Ok(())
    }

    /// Writes the CSV, the plots and the JSON summary (last) into `out` (created if needed);
    /// returns the JSON text.
    pub fn write(&self, out: &Path) -> Result<String, ReceptanceError> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| ReceptanceError::Io { path, source }
        };
        std::fs::create_dir_all(out).map_err(io(out))?;
        let header = self.csv_header();
        let hdr: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
        let csv = out.join("receptance.csv");
        let n = self.receptance.frequencies_hz.len();
        write_csv(&csv, &hdr, (0..n).map(|k| self.csv_row(k))).map_err(io(&csv))?;
        self.plot(out)?;
        let json = serde_json::to_string_pretty(&self.summary)?;
        let path = out.join("receptance.json");
        write_atomic(&path, |f| {
            use std::io::Write;
            f.write_all(json.as_bytes())
        })
        .map_err(io(&path))?;
        Ok(json)
    }
}

#[cfg(test)]
mod tests {
    use super::{ReceptanceError, ReceptanceOptions, MAX_FREQUENCIES};
    /// The grid holds `floor((to − from)/step) + 1` frequencies from `from_hz`, its 0 Hz
    /// point moved to a quarter step, and the highest frequency defaults to
    /// `min(fmax, 3000 Hz)`.
    #[test]
    fn frequency_grid() {
        let opts = ReceptanceOptions {
            from_hz: 0.0,
            step_hz: 4.0,
            ..ReceptanceOptions::default()
        };
        let g = opts.grid(5000.0).unwrap();
        assert_eq!(g.range_hz, [0.0, 3000.0, 4.0]);
        assert_eq!(g.frequencies_hz.len(), 751);
        assert_eq!(g.frequencies_hz[0], 1.0);
        assert_eq!(g.frequencies_hz[1], 4.0);
        assert_eq!(*g.frequencies_hz.last().unwrap(), 3000.0);
        let g = ReceptanceOptions::default().grid(1000.0).unwrap();
        assert_eq!(g.range_hz, [20.0, 1000.0, 4.0]);
        assert_eq!(g.frequencies_hz.len(), 246);
    }

    /// An empty or reversed range, a non-positive or non-finite step, a top above the modal
    /// basis's `run.fmax` and a grid beyond [`MAX_FREQUENCIES`] are refused with the values
    /// named.
    #[test]
    fn bad_grids_are_refused() {
        for (from_hz, to_hz, step_hz) in [
            (100.0, 50.0, 4.0),
            (-1.0, 50.0, 4.0),
            (0.0, 50.0, 0.0),
            (0.0, 5001.0, 4.0),
            (0.0, f64::INFINITY, 4.0),
            (f64::NAN, 50.0, 4.0),
            (0.0, 50.0, f64::INFINITY),
        ] {
            let opts = ReceptanceOptions {
                from_hz,
                to_hz: Some(to_hz),
                step_hz,
                at_m: Vec::new(),
            };
            let e = opts.grid(5000.0).unwrap_err();
            assert!(matches!(e, ReceptanceError::Grid { .. }), "{e}");
            assert!(e.to_string().contains(&format!("step {step_hz} Hz")), "{e}");
        }
        let opts = ReceptanceOptions {
            step_hz: 1e-3,
            ..ReceptanceOptions::default()
        };
        let e = opts.grid(5000.0).unwrap_err();
        assert!(matches!(e, ReceptanceError::TooManyFrequencies(n) if n > MAX_FREQUENCIES));
    }
}

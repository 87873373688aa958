//! The `roughness` product: a measured rail roughness (a profile or a one-third-octave band
//! spectrum, [`crate::roughness`]) carried forward by the model's growth-rate spectrum at each
//! speed, and its output files: which bands grow on this rail at these speeds, how fast, the
//! band levels after the given traffic against the ISO 3095 limit (docs/theory.md §10.7).

use std::path::Path;

use serde::Serialize;

use super::grow::growth_rate;
use super::StudiesError;
use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::DynamicsError;
use crate::model::Model;
use crate::progress::Progress;
use crate::report::doc::Document;
use crate::report::plot::{line_plot, Series};
use crate::roughness::{forecast, BandSpectrum, Forecast};
use crate::units::Speed;

/// The measured spectrum and its forecasts, one per speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughnessOutcome {
    /// What was measured: the file (a profile or a band spectrum).
    pub source: String,
    /// The measured band spectrum (from the profile, or as read).
    pub measured: BandSpectrum,
    /// Wheel passages forecast (−).
    pub passages: f64,
    /// One forecast per speed, in the order given.
    pub forecasts: Vec<Forecast>,
}

impl RoughnessOutcome {
    /// The answer in plain lines: one sentence per speed.
    pub fn summary_lines(&self) -> Vec<String> {
        self.forecasts.iter().map(Forecast::sentence).collect()
    }
}

/// The forecasts of `measured` at `speeds_kmh` (km/h) after `passages` wheel passages: the
/// growth-rate spectrum of the prepared model `p` of `m` at each speed (one stage each on
/// `progress`), applied to the measured bands.
pub fn roughness_forecasts(
    m: &Model,
    p: &PreparedModel,
    source: &str,
    measured: &BandSpectrum,
    speeds_kmh: &[f64],
    passages: f64,
    progress: &dyn Progress,
) -> Result<RoughnessOutcome, DynamicsError> {
    let forecasts = speeds_kmh
        .iter()
        .map(|&v| {
            let rates = growth_rate(m, p, Speed::from_kmh(v), progress)?;
            Ok(forecast(measured, &rates, passages))
        })
        .collect::<Result<Vec<_>, DynamicsError>>()?;
    Ok(RoughnessOutcome {
        source: source.to_string(),
        measured: measured.clone(),
        passages,
        forecasts,
    })
}

/// Writes `roughness.csv` (per band: nominal centre, measured level, ISO 3095 limit, and per
/// speed the change per passage and the level after the passages), `roughness.json` (the
/// outcome), the plot `roughness.svg/.png` (measured, limit, forecast per speed) and
/// `report.md/.html` (the sentences first) into `out`.
pub fn write_roughness(out: &Path, o: &RoughnessOutcome) -> Result<(), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let mut header = vec![
        "wavelength_mm".to_string(),
        "measured_db".into(),
        "iso3095_limit_db".into(),
    ];
    for f in &o.forecasts {
        header.push(format!("db_per_passage_{}kmh", f.speed_kmh));
        header.push(format!("after_db_{}kmh", f.speed_kmh));
    }
    let nan = |v: Option<f64>| v.unwrap_or(f64::NAN);
    let rows: Vec<Vec<f64>> = (0..o.measured.bands.len())
        .map(|i| {
            let b = &o.forecasts.first().map(|f| &f.bands[i]);
            let mut r = vec![
                crate::units::m_to_mm(o.measured.bands[i].nominal_m()),
                o.measured.level_db[i],
                nan(b.and_then(|b| b.limit_db)),
            ];
            for f in &o.forecasts {
                r.push(nan(f.bands[i].db_per_passage));
                r.push(nan(f.bands[i].level_after_db));
            }
            r
        })
        .collect();
    let csv = out.join("roughness.csv");
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    crate::io::write_csv(&csv, &h, rows).map_err(StudiesError::io(&csv))?;
    let json = out.join("roughness.json");
    let text = serde_json::to_string_pretty(o).map_err(|source| StudiesError::Json {
        what: "roughness.json",
        source,
    })?;
    crate::io::write_text(&json, &(text + "\n")).map_err(StudiesError::io(&json))?;

    let mm: Vec<f64> = o
        .measured
        .bands
        .iter()
        .map(|b| crate::units::m_to_mm(b.nominal_m()))
        .collect();
    let mut series = vec![Series::new(
        "measured",
        mm.clone(),
        o.measured.level_db.clone(),
    )];
    let limit: Vec<(f64, f64)> = o
        .measured
        .bands
        .iter()
        .filter_map(|b| {
            crate::roughness::iso3095_limit_db(b.centre_m())
                .map(|l| (crate::units::m_to_mm(b.nominal_m()), l))
        })
        .collect();
    if !limit.is_empty() {
        series.push(Series::new(
            "ISO 3095 limit",
            limit.iter().map(|p| p.0).collect(),
            limit.iter().map(|p| p.1).collect(),
        ));
    }
    for f in &o.forecasts {
        let pts: Vec<(f64, f64)> = f
            .bands
            .iter()
            .filter_map(|b| {
                b.level_after_db
                    .map(|l| (crate::units::m_to_mm(b.centre_m), l))
            })
            .collect();
        if !pts.is_empty() {
            series.push(Series::new(
                format!("after {:.3e} passages, {} km/h", o.passages, f.speed_kmh),
                pts.iter().map(|p| p.0).collect(),
                pts.iter().map(|p| p.1).collect(),
            ));
        }
    }
    line_plot(
        &out.join("roughness"),
        "Rail roughness: measured and forecast (one-third-octave bands)",
        "wavelength (mm)",
        "roughness level (dB re 1 µm)",
        &series,
    )?;

    let mut d = Document::new("Rail roughness: which wavelengths grow");
    d.paragraph(format!("**Summary.** {}", o.summary_lines().join(" ")));
    d.paragraph(format!(
        "Measured: {}. Forecast: the growth-rate spectrum of the model's linear wear loop at \
         each speed applied to the measured band levels over {:.3e} wheel passages \
         (docs/theory.md §10.7); bands outside the growth-rate spectrum's wavelengths are \
         shown as measured. The forecast is linear: it holds while the roughness stays small \
         against the contact's approach.",
        o.source, o.passages
    ));
    d.image("Measured and forecast band levels", "roughness.png");
    let mut th = vec![
        "λ (mm)".to_string(),
        "measured (dB)".into(),
        "ISO 3095 limit (dB)".into(),
    ];
    for f in &o.forecasts {
        th.push(format!("dB/passage at {} km/h", f.speed_kmh));
        th.push(format!("after (dB) at {} km/h", f.speed_kmh));
    }
    let fmt = |v: Option<f64>, p: usize| v.map_or("–".into(), |x| format!("{x:.p$}"));
    let body = (0..o.measured.bands.len())
        .map(|i| {
            let mut r = vec![
                format!("{}", crate::units::m_to_mm(o.measured.bands[i].nominal_m())),
                format!("{:.1}", o.measured.level_db[i]),
                fmt(o.forecasts.first().and_then(|f| f.bands[i].limit_db), 1),
            ];
            for f in &o.forecasts {
                r.push(
                    f.bands[i]
                        .db_per_passage
                        .map_or("–".into(), |x| format!("{x:.2e}")),
                );
                r.push(fmt(f.bands[i].level_after_db, 1));
            }
            r
        })
        .collect();
    d.table(&th, body);
    d.write(&out.join("report"))?;
    Ok(())
}

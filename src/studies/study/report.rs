//! The study's table, report and plots.

use std::collections::BTreeMap;
use std::path::Path;

use super::CaseResult;
use super::{value_text, Case, Study};
use crate::report::doc::{sentences, Document};
use crate::report::plot::{line_plot, Series};
use crate::studies::initiation::{
    criterion_text, indicator_cells, indicator_header, readable_cells, readable_header,
    write_table_csv, InitiationRow,
};
use crate::studies::StudiesError;

fn growth_keys(cases: &[(Case, CaseResult)]) -> Vec<String> {
    let mut k: Vec<String> = cases
        .iter()
        .flat_map(|(_, r)| r.growth.keys().cloned())
        .collect();
    k.sort();
    k.dedup();
    k
}

/// The indicators plotted against the parameters: (file suffix, label, value).
type Indicator = (
    &'static str,
    &'static str,
    fn(&InitiationRow) -> Option<f64>,
);

const INDICATORS: [Indicator; 5] = [
    ("relative_wear", "wear band RMS / mean (%)", |r| {
        r.relative_wear.map(|v| 100.0 * v)
    }),
    ("fl_band_rms", "F_L band RMS (N)", |r| Some(r.fl_band_rms_n)),
    ("fn_band_rms", "F_N band RMS (N)", |r| Some(r.fn_band_rms_n)),
    (
        "dominant_wavelength",
        "dominant wear wavelength (mm)",
        |r| r.wear_peaks.first().map(|c| c.wavelength_mm),
    ),
    ("dominant_frequency", "dominant wear frequency (Hz)", |r| {
        r.wear_peaks.first().map(|c| c.frequency_hz)
    }),
];

/// The unit of a model key for axis labels ("−" for dimensionless keys), from the naming
/// conventions of the model file (`models/dutch-base.toml` states each); `None` if unknown.
pub(crate) fn key_unit(key: &str) -> Option<&'static str> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let ends = |s: &str| last.ends_with(s);
    Some(match last {
        "speed_kmh" => "km/h",
        "fmax" => "Hz",
        "wheel_load" => "N",
        "gravity" => "m/s²",
        "coefficient" => "m³/J",
        "time_step" => "s",
        _ if ends("damping_ratio") => "−",
        _ if ends("stiffness") => "N/m",
        _ if ends("damping") => "N·s/m",
        _ if ends("modulus") => "Pa",
        _ if ends("density") => "kg/m³",
        _ if ends("ratio")
            || ends("conicity")
            || ends("friction")
            || ends("traction_coefficient")
            || ends("inclination")
            || ends("threshold")
            || ends("safety")
            || ends("margin")
            || ends("bays")
            || ends("rows")
            || ends("columns")
            || ends("segments")
            || ends("grid_nx")
            || ends("grid_ny") =>
        {
            "−"
        }
        _ if ends("length")
            || ends("width")
            || ends("height")
            || ends("radius")
            || ends("spacing")
            || ends("thickness")
            || ends("size")
            || ends("offset")
            || ends("rail_seat") =>
        {
            "m"
        }
        _ => return None,
    })
}

/// Axis label of a growth column of a study.
fn growth_label(k: &str) -> String {
    match k {
        "limiting_amplitude_um" => "limiting amplitude (2A_max)_l (µm; 0: none)".into(),
        "consistent_amplitudes" => "trial amplitudes growing consistently (of 4)".into(),
        "widened_contact_grids" => {
            "growth passages rerun on a widened contact grid (docs/theory.md §6.8)".into()
        }
        _ => k.to_string(),
    }
}

fn as_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The criterion paragraph of a study: the file's values, or where each case's comes from.
fn study_criterion_text(c: &super::StudyCriterion) -> String {
    let dev = c.max_wavelength_deviation.unwrap_or(
        crate::studies::initiation::InitiationCriterion::DEFAULT_MAX_WAVELENGTH_DEVIATION,
    );
    match c.min_relative_wear {
        Some(w) => criterion_text(&crate::studies::initiation::InitiationCriterion {
            min_relative_wear: w,
            max_wavelength_deviation: dev,
        }),
        None => format!(
            "Criterion: a case initiates corrugation when the RMS of the 20–80 mm band-passed \
             differential wear is at least its model's wear.initiation_threshold (1 % unless \
             the model or a study parameter sets it) of the mean wear, and the dominant \
             wavelength of F_L deviates at most {:.1} % from the dominant wear wavelength (the \
             wear follows F_L, docs/theory.md §2.4 and §11.4).",
            100.0 * dev
        ),
    }
}

/// Writes a finished study into `out`: `study.csv` (one row per case and speed), the plots
/// of every indicator against the first parameter, and the report `study` with the cases'
/// table.
/// The study's result in a few plain lines (what `corrugation study` prints on stdout and
/// the report opens with): how many case–speed rows initiate corrugation by the study's
/// criterion, and the cases of the lowest and the highest wear band RMS (and F_L band RMS)
/// with their parameter values.
pub fn summary_lines(cases: &[(Case, CaseResult)]) -> Vec<String> {
    let rows: Vec<(&Case, &InitiationRow)> = cases
        .iter()
        .flat_map(|(c, r)| r.rows.iter().map(move |row| (c, row)))
        .collect();
    if rows.is_empty() {
        return vec!["no case has a result".into()];
    }
    let initiating = rows.iter().filter(|(_, r)| r.initiates).count();
    let mut out = vec![format!(
        "{} case(s), {} case–speed row(s): corrugation initiates in {initiating} of them",
        cases.len(),
        rows.len()
    )];
    let label = |c: &Case, r: &InitiationRow| {
        let l = c.label();
        format!(
            "case {} ({}{}at {} km/h)",
            c.index,
            l,
            if l.is_empty() { "" } else { ", " },
            r.speed_kmh
        )
    };
    for (what, unit, get) in [
        (
            "wear band RMS",
            "J/m",
            (|r: &InitiationRow| r.wear_band_rms) as fn(&InitiationRow) -> f64,
        ),
        ("F_L band RMS", "N", |r: &InitiationRow| r.fl_band_rms_n),
    ] {
        let lo = rows.iter().min_by(|a, b| get(a.1).total_cmp(&get(b.1)));
        let hi = rows.iter().max_by(|a, b| get(a.1).total_cmp(&get(b.1)));
        if let (Some(lo), Some(hi)) = (lo, hi) {
            if rows.len() > 1 {
                out.push(format!(
                    "lowest {what} {} {unit}: {}; highest {} {unit}: {}",
                    crate::growth::verdict::sig(get(lo.1), 3),
                    label(lo.0, lo.1),
                    crate::growth::verdict::sig(get(hi.1), 3),
                    label(hi.0, hi.1)
                ));
            } else {
                out.push(format!(
                    "{what} {} {unit}",
                    crate::growth::verdict::sig(get(lo.1), 3)
                ));
            }
        }
    }
    out
}

pub(super) fn write_study(
    study: &Study,
    cases: &[(Case, CaseResult)],
    out: &Path,
) -> Result<(), StudiesError> {
    let gk = growth_keys(cases);
    let readable = write_study_csv(study, cases, &gk, out)?;
    let mut doc = Document::new(format!("Design study: {}", study.title));
    doc.paragraph(format!("**Summary.** {}", sentences(&summary_lines(cases))));
    doc.paragraph(format!(
        "Study file {}; base model {}; {} case(s); parameters: {}.",
        study.file,
        study.base.display(),
        cases.len(),
        study
            .parameters
            .iter()
            .map(|p| p.key.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    if !study.set.is_empty() {
        doc.paragraph(format!(
            "Overrides of every case: {}.",
            study
                .set
                .iter()
                .map(|(_, t)| t.as_str())
                .collect::<Vec<_>>()
                .join(" ")
        ));
    }
    doc.paragraph(study_criterion_text(&study.criterion));
    doc.heading(2, "Indicators vs parameters");
    write_study_plots(study, cases, &gk, out, &mut doc)?;
    doc.heading(2, "Cases");
    let mut rh: Vec<String> = vec!["case".into()];
    rh.extend(readable_header().iter().map(|s| s.to_string()));
    rh.extend(gk.iter().cloned());
    doc.table(&rh, readable);
    doc.write(&out.join("study"))?;
    Ok(())
}

/// The study's table as `study.csv` holds it: the header (`case`, the parameters' keys, the
/// indicators' columns, the growth keys) and one row of text cells per case and speed
/// (numbers as written; an empty cell where a value is undefined).
pub fn study_table(study: &Study, cases: &[(Case, CaseResult)]) -> (Vec<String>, Vec<Vec<String>>) {
    let gk = growth_keys(cases);
    let mut header = vec!["case".to_string()];
    header.extend(study.parameters.iter().map(|p| p.key.clone()));
    header.extend(indicator_header(study.peaks));
    header.extend(gk.iter().cloned());
    let mut rows = Vec::new();
    for (c, r) in cases {
        for row in &r.rows {
            let mut cells = vec![c.index.to_string()];
            cells.extend(c.assignments.iter().map(|(_, v)| value_text(v)));
            cells.extend(indicator_cells(row, study.peaks));
            cells.extend(
                gk.iter()
                    .map(|k| r.growth.get(k).map(|v| v.to_string()).unwrap_or_default()),
            );
            rows.push(cells);
        }
    }
    (header, rows)
}

/// Writes `study.csv` ([`study_table`]); returns the rows of the report's readable table
/// (with the growth keys `gk`).
fn write_study_csv(
    study: &Study,
    cases: &[(Case, CaseResult)],
    gk: &[String],
    out: &Path,
) -> Result<Vec<Vec<String>>, StudiesError> {
    let (header, rows) = study_table(study, cases);
    let mut readable = Vec::new();
    for (c, r) in cases {
        for row in &r.rows {
            let mut rc = vec![c.index.to_string()];
            rc.extend(readable_cells(row));
            rc.extend(gk.iter().map(|k| {
                r.growth
                    .get(k)
                    .map(|v| format!("{v:.4}"))
                    .unwrap_or_default()
            }));
            readable.push(rc);
        }
    }
    write_table_csv(&out.join("study.csv"), &header, &rows)?;
    Ok(readable)
}

/// The plots of every indicator and growth key `gk` against the first parameter, one curve
/// per (other parameters, speed), written into `out` and added to `doc`.
fn write_study_plots(
    study: &Study,
    cases: &[(Case, CaseResult)],
    gk: &[String],
    out: &Path,
    doc: &mut Document,
) -> Result<(), StudiesError> {
    let first = &study.parameters[0];
    let numeric = first.values.iter().all(|v| as_number(v).is_some());
    let x_label = if numeric {
        match key_unit(&first.key) {
            Some(u) => format!("{} ({u})", first.key),
            None => first.key.clone(),
        }
    } else {
        format!("case ({} not numeric)", first.key)
    };
    let mut plots = Vec::new();
    for (stem, label, f) in INDICATORS {
        plots.push((stem.to_string(), label.to_string(), Some(f), None));
    }
    // the count of widened contact grids is a note in the table, not an indicator to plot
    for k in gk.iter().filter(|k| k.as_str() != "widened_contact_grids") {
        plots.push((
            format!("growth_{k}"),
            growth_label(k),
            None,
            Some(k.clone()),
        ));
    }
    for (stem, label, f, gkey) in plots {
        let mut series: BTreeMap<String, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
        for (c, r) in cases {
            let x = if numeric {
                as_number(&c.assignments[0].1).unwrap_or(f64::NAN)
            } else {
                c.index as f64
            };
            let rest: Vec<String> = c.assignments[1..]
                .iter()
                .map(|(k, v)| format!("{}={}", k.rsplit('.').next().unwrap_or(k), value_text(v)))
                .collect();
            for row in &r.rows {
                let mut name = rest.join(", ");
                if r.rows.len() > 1 || study.speeds_kmh.as_ref().is_some_and(|s| s.len() > 1) {
                    if !name.is_empty() {
                        name.push_str(", ");
                    }
                    name.push_str(&format!("{} km/h", row.speed_kmh));
                }
                let y = match (f, &gkey) {
                    (Some(f), _) => f(row),
                    (None, Some(k)) => r.growth.get(k).copied(),
                    _ => None,
                };
                let e = series.entry(name).or_default();
                e.0.push(x);
                e.1.push(y.unwrap_or(f64::NAN));
            }
        }
        let mut s: Vec<Series> = series
            .into_iter()
            .map(|(n, (x, y))| Series::new(n, x, y))
            .collect();
        if stem == "relative_wear" {
            s.extend(threshold_line(cases, &s));
        }
        let file = format!("study_{stem}");
        line_plot(
            &out.join(&file),
            &format!("{label} vs {}", first.key),
            &x_label,
            &label,
            &s,
        )?;
        doc.image(format!("{label} vs {}", first.key), format!("{file}.png"));
    }
    Ok(())
}

/// The initiation threshold on the relative-wear plot (%), a horizontal line over the
/// plotted abscissae, when every row was judged against the same one.
fn threshold_line(cases: &[(Case, CaseResult)], plotted: &[Series]) -> Option<Series> {
    let mut t = cases
        .iter()
        .flat_map(|(_, r)| r.rows.iter().map(|row| row.threshold));
    let first = t.next()??;
    if !t.all(|x| x == Some(first)) {
        return None;
    }
    let xs = plotted
        .iter()
        .flat_map(|s| s.x.iter().copied())
        .filter(|x| x.is_finite());
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
        (l.min(x), h.max(x))
    });
    (lo <= hi).then(|| {
        Series::new(
            format!("initiation threshold ({:.1} %)", 100.0 * first),
            vec![lo, hi],
            vec![100.0 * first; 2],
        )
    })
}

#[cfg(test)]
mod unit_tests {
    use super::key_unit;

    #[test]
    fn study_axis_units_follow_the_model_keys() {
        for (k, u) in [
            ("fastening.vertical_stiffness", Some("N/m")),
            ("fastening.vertical_damping", Some("N·s/m")),
            ("wheel.damping_ratio", Some("−")),
            ("run.speed_kmh", Some("km/h")),
            ("rail.youngs_modulus", Some("Pa")),
            ("fastening.pad_thickness", Some("m")),
            ("track.bays", Some("−")),
            ("fastening.model", None),
        ] {
            assert_eq!(key_unit(k), u, "{k}");
        }
    }
}

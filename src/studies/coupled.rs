//! The selected frequencies of a passage, sweep or growth run attributed to the coupled
//! wheel–track modes (docs/theory.md §7.10), and the coupled-mode files, shared by
//! `passage`, `coupled-modes`, `sweep`, `grow` and `predict`.
//!
//! Files:
//! * `coupled_modes.csv` — one row per mode: `position_m, frequency_hz, damping_ratio`, the
//!   shares (`wheel_elastic, wheel_rigid, rail_<family>…, support, contact`),
//!   `rail_x_to_n`, `rail_x_m_per_sqrt_j, rail_n_m_per_sqrt_j, wheel_x_m_per_sqrt_j,
//!   wheel_n_m_per_sqrt_j`, and `dominant`: the mode's name by the attribution rule
//!   (`ModeShares::dominant`) as the index of its share column, 0 (`wheel_elastic`) standing
//!   for the wheel's two parts together;
//!   `coupled_modes.npy` the same numbers; `coupled_modes.json` the linearisation, positions
//!   and modes ([`write_coupled_modes`]);
//! * `coupled_attribution.json` of a passage — `{wear, fl, fn}`: each component's frequency
//!   attributed to a coupled mode with its energy shares ([`passage_attribution`]).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::StudiesError;
use crate::dynamics::coupled::{CoupledMode, CoupledModes, ModeAttribution, ModeShares};
use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::WavelengthComponent;
use crate::eigen::classify::TrackFamily;
use crate::io::{write_csv, write_npy, write_text};
use crate::passage::summary::PassageSummary;

/// The default upper frequency (Hz) of the coupled modes listed by `coupled-modes`.
pub const DEFAULT_LIST_TO_HZ: f64 = 3000.0;

/// The components of a passage summary attributed to coupled modes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SummaryAttribution {
    /// Wear components, strongest first.
    pub wear: Vec<ModeAttribution>,
    /// F_L components, strongest first.
    pub fl: Vec<ModeAttribution>,
    /// F_N components, strongest first.
    #[serde(rename = "fn")]
    pub fn_: Vec<ModeAttribution>,
}

/// Attributes every wear, F_L and F_N component of `s` to the coupled modes `modes`
/// ([`crate::dynamics::coupled::attribute`], window
/// [`crate::dynamics::coupled::ATTRIBUTION_WINDOW`]).
pub(crate) fn attribute_summary(modes: &[CoupledMode], s: &PassageSummary) -> SummaryAttribution {
    let f = |c: &[WavelengthComponent]| {
        crate::dynamics::coupled::attribute(
            &c.iter().map(|c| c.frequency_hz).collect::<Vec<_>>(),
            modes,
            crate::dynamics::coupled::ATTRIBUTION_WINDOW,
        )
    };
    SummaryAttribution {
        wear: f(&s.wear_components),
        fl: f(&s.fl_components),
        fn_: f(&s.fn_components),
    }
}

/// One frequency attributed (`None` without a frequency or without modes).
pub(crate) fn attribute_one(
    modes: &[CoupledMode],
    frequency_hz: Option<f64>,
) -> Option<ModeAttribution> {
    let f = frequency_hz.filter(|f| f.is_finite() && *f > 0.0)?;
    crate::dynamics::coupled::attribute(&[f], modes, crate::dynamics::coupled::ATTRIBUTION_WINDOW)
        .pop()
}

/// The coupled modes of `prepared` at the summary's speed (contact at the mid-span and the
/// sleeper nearest the zone centre), written to `out` ([`write_coupled_modes`]), and the
/// summary's components attributed to them, written to `out/coupled_attribution.json`.
pub fn passage_attribution(
    prepared: &PreparedModel,
    s: &PassageSummary,
    out: &Path,
) -> Result<(CoupledModes, SummaryAttribution), StudiesError> {
    let cm = prepared.coupled_modes(crate::units::kmh_to_ms(s.speed_kmh), &[])?;
    let a = write_passage_attribution(out, &cm, s)?;
    Ok((cm, a))
}

/// Writes the coupled modes `cm` to `out` ([`write_coupled_modes`]) and the summary's
/// components attributed to them to `out/coupled_attribution.json`.
pub(crate) fn write_passage_attribution(
    out: &Path,
    cm: &CoupledModes,
    s: &PassageSummary,
) -> Result<SummaryAttribution, StudiesError> {
    write_coupled_modes(out, cm)?;
    let a = attribute_summary(&cm.modes, s);
    let text = serde_json::to_string_pretty(&a).map_err(|source| StudiesError::Json {
        what: "coupled_attribution.json",
        source,
    })?;
    let p = out.join("coupled_attribution.json");
    write_text(&p, &text).map_err(StudiesError::io(&p))?;
    Ok(a)
}

/// The columns of `coupled_modes.csv`.
pub(crate) fn coupled_mode_columns() -> Vec<String> {
    let mut c: Vec<String> = ["position_m", "frequency_hz", "damping_ratio"]
        .map(String::from)
        .to_vec();
    c.extend(ModeShares::labels());
    c.extend(
        [
            "rail_x_to_n",
            "rail_x_m_per_sqrt_j",
            "rail_n_m_per_sqrt_j",
            "wheel_x_m_per_sqrt_j",
            "wheel_n_m_per_sqrt_j",
            "dominant",
        ]
        .map(String::from),
    );
    c
}

/// One row of `coupled_modes.csv` (see [`coupled_mode_columns`]).
fn coupled_mode_row(m: &CoupledMode) -> Vec<f64> {
    let mut r = vec![m.position_m, m.frequency_hz, m.damping_ratio];
    let dom = m.shares.dominant_index();
    r.extend(m.shares.values());
    r.push(m.rail_x_to_n);
    r.extend(m.contact_amplitudes_m_per_sqrt_j);
    r.push(dom as f64);
    r
}

/// Writes `coupled_modes.csv`, `.npy` and `.json` into `out` (created).
pub fn write_coupled_modes(out: &Path, cm: &CoupledModes) -> Result<(), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let cols = coupled_mode_columns();
    let names: Vec<&str> = cols.iter().map(String::as_str).collect();
    let rows: Vec<Vec<f64>> = cm.modes.iter().map(coupled_mode_row).collect();
    let p = out.join("coupled_modes.csv");
    write_csv(&p, &names, rows.iter().cloned()).map_err(StudiesError::io(&p))?;
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    let p = out.join("coupled_modes.npy");
    write_npy(&p, &[rows.len(), cols.len()], &flat).map_err(StudiesError::io(&p))?;
    let json = serde_json::to_string_pretty(cm).map_err(|source| StudiesError::Json {
        what: "coupled_modes.json",
        source,
    })?;
    let p = out.join("coupled_modes.json");
    write_text(&p, &json).map_err(StudiesError::io(&p))
}

/// Columns of an attribution in a per-speed table, each prefixed by `prefix` (e.g. `""` for
/// the wear, `"fl_"` for F_L): the mode's frequency (Hz) and damping ratio (−), its energy
/// offset from the selected frequency `(f_mode − f)/f` (−; beyond ±0.03 no coupled mode is
/// within the attribution window and the nearest visible one was taken), its energy
/// shares (−) in the wheel (total and elastic), the rail (total and by family), the support
/// and the contact, and the rail's longitudinal-to-normal motion at the contact (−).
pub(crate) fn attribution_columns(prefix: &str) -> Vec<String> {
    let mut c = vec![
        "coupled_mode_hz".to_string(),
        "coupled_offset".into(),
        "coupled_damping_ratio".into(),
        "coupled_wheel_share".into(),
        "coupled_wheel_elastic_share".into(),
        "coupled_rail_share".into(),
    ];
    c.extend(
        TrackFamily::ALL
            .iter()
            .map(|f| format!("coupled_rail_{}_share", f.name())),
    );
    c.extend([
        "coupled_support_share".into(),
        "coupled_contact_share".into(),
        "coupled_rail_x_to_n".into(),
    ]);
    c.into_iter().map(|c| format!("{prefix}{c}")).collect()
}

/// The values of [`attribution_columns`]; `NaN` throughout without an attribution.
pub(crate) fn attribution_values(a: Option<&ModeAttribution>) -> Vec<f64> {
    let n = attribution_columns("").len();
    let Some(a) = a else {
        return vec![f64::NAN; n];
    };
    let s = &a.shares;
    let mut v = vec![
        a.mode_frequency_hz,
        a.relative_offset(),
        a.damping_ratio,
        s.wheel_total(),
        s.wheel_elastic,
        s.rail_total(),
    ];
    v.extend(s.rail);
    v.extend([s.support, s.contact, a.rail_x_to_n]);
    v
}

/// The speed (km/h) at which a sweep's coupled modes are computed: the model's speed when it
/// lies within the swept range, else the geometric middle of the range. The creep terms of
/// the linearised contact depend on the speed (docs/theory.md §7.10, "Speed"); one set of
/// modes serves the whole sweep.
pub fn sweep_reference_speed_kmh(model_speed_kmh: f64, speeds_kmh: &[f64]) -> f64 {
    let lo = speeds_kmh.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds_kmh.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !(lo.is_finite() && hi.is_finite()) || (lo..=hi).contains(&model_speed_kmh) {
        model_speed_kmh
    } else {
        (lo * hi).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::{
        attribute_one, attribution_columns, attribution_values, sweep_reference_speed_kmh,
        CoupledMode, ModeShares, TrackFamily,
    };
    fn mode(f: f64, amp: f64, wheel: f64) -> CoupledMode {
        let mut shares = ModeShares {
            wheel_elastic: wheel,
            ..ModeShares::default()
        };
        shares.rail[TrackFamily::LongitudinalCompression.code()] = 1.0 - wheel;
        CoupledMode {
            position_m: 0.5,
            frequency_hz: f,
            damping_ratio: 0.01,
            dominant: shares.dominant().0,
            shares,
            contact_amplitudes_m_per_sqrt_j: [amp, 0.0, 0.0, 0.0],
            rail_x_to_n: 2.0,
        }
    }

    /// A constructed set of modes: each selected frequency goes to the nearest mode the
    /// contact sees (600 Hz → 610 Hz, 1000 Hz → 1020 Hz rather than the invisible 1001 Hz),
    /// and the table row carries that mode's numbers; no frequency gives `NaN`s.
    #[test]
    fn a_selected_frequency_goes_to_the_nearest_seen_mode_and_fills_its_row() {
        let modes = [
            mode(610.0, 1.0, 0.9),
            mode(1001.0, 1e-5, 0.0),
            mode(1020.0, 0.5, 0.2),
            mode(1500.0, 0.8, 0.5),
        ];
        let a = attribute_one(&modes, Some(600.0)).unwrap();
        assert_eq!(a.mode_frequency_hz, 610.0);
        let b = attribute_one(&modes, Some(1000.0)).unwrap();
        assert_eq!(b.mode_frequency_hz, 1020.0);
        assert!(attribute_one(&modes, None).is_none());
        assert!(attribute_one(&[], Some(600.0)).is_none());
        let cols = attribution_columns("fl_");
        let row = attribution_values(Some(&b));
        assert_eq!(cols.len(), row.len());
        let at = |name: &str| row[cols.iter().position(|c| c == name).unwrap()];
        assert_eq!(at("fl_coupled_mode_hz"), 1020.0);
        assert!((at("fl_coupled_wheel_share") - 0.2).abs() < 1e-12);
        assert!((at("fl_coupled_rail_longitudinal_compression_share") - 0.8).abs() < 1e-12);
        assert_eq!(at("fl_coupled_rail_x_to_n"), 2.0);
        assert!((at("fl_coupled_offset") - 0.02).abs() < 1e-12);
        assert!(!b.is_distant());
        // 1300 Hz has no mode within 3 %: the nearest visible (1500 Hz, +15.4 %) is taken
        // and flagged as distant, in the row and in the text.
        let c = attribute_one(&modes, Some(1300.0)).unwrap();
        assert_eq!(c.mode_frequency_hz, 1500.0);
        assert!(c.is_distant() && (c.relative_offset() - 200.0 / 1300.0).abs() < 1e-12);
        let text = crate::dynamics::coupled::attribution_text(&c);
        assert!(
            text.contains("no coupled mode within 3 %") && text.contains("+15 %"),
            "{text}"
        );
        assert!(!crate::dynamics::coupled::attribution_text(&b).contains("no coupled mode"));
        assert!(attribution_values(None).iter().all(|v| v.is_nan()));
        assert_eq!(b.shares.dominant().0, "rail LC");
        assert_eq!(a.shares.dominant().0, "wheel");
        // The CSV's `dominant` column is the same rule: rail LC's column, the wheel as 0.
        assert_eq!(b.shares.dominant_index(), 2);
        assert_eq!(a.shares.dominant_index(), 0);
        // The wheel's two parts count together against a larger single share elsewhere.
        let split = ModeShares {
            wheel_elastic: 0.3,
            wheel_rigid: 0.2,
            support: 0.4,
            contact: 0.1,
            ..ModeShares::default()
        };
        assert_eq!(split.dominant().0, "wheel");
        assert_eq!(split.dominant_index(), 0);
    }

    /// The seen modes: residue share ≥ 3 % of the largest, in the band, duplicates within
    /// 0.5 % merged (the stronger kept).
    #[test]
    fn seen_modes_are_the_strong_ones_in_the_band_without_duplicates() {
        let modes = [
            mode(400.0, 1.0, 1.0),
            mode(402.0, 0.5, 1.0),
            mode(800.0, 0.05, 0.0),
            mode(900.0, 0.3, 0.0),
            mode(5000.0, 1.0, 0.0),
        ];
        // Residues ∝ (f a)²: 1.6e5, 4.0e4, 1.6e3, 7.3e4, 2.5e7 → 3 % of the largest is 7.5e5;
        // without the 5 kHz mode 4.8e3.
        let seen = crate::dynamics::coupled::seen_by_contact(&modes, [100.0, 6000.0]);
        let f: Vec<f64> = seen.iter().map(|m| m.frequency_hz).collect();
        assert_eq!(f, vec![5000.0]);
        let seen = crate::dynamics::coupled::seen_by_contact(&modes[..4], [100.0, 3000.0]);
        let f: Vec<f64> = seen.iter().map(|m| m.frequency_hz).collect();
        assert_eq!(f, vec![400.0, 900.0]);
    }

    #[test]
    fn the_reference_speed_is_the_model_speed_inside_the_range() {
        assert_eq!(sweep_reference_speed_kmh(140.0, &[60.0, 220.0]), 140.0);
        assert!((sweep_reference_speed_kmh(300.0, &[50.0, 200.0]) - 100.0).abs() < 1e-12);
    }
}

//! Tests of the consistency logic on constructed inputs with known deviations, and of the
//! growth phase on constructed wear signals.

use super::{
    classify, consistency_table, growth_phase, match_nearest, relative_deviation, ConsistencyCase,
    ConsistencyClass, ConsistencyRow, ConsistencyThresholds, GrowthError, Peak, PhaseRelation,
    Signal,
};
use crate::growth::trial_corrugation;
use crate::spectral::{band_pass, BandPass};
use std::f64::consts::PI;

const V: f64 = 140.0 / 3.6;

fn peak(lam: f64) -> Peak {
    Peak {
        wavelength_m: lam,
        wavenumber_per_m: 1.0 / lam,
        frequency_hz: V / lam,
        psd: 1.0,
        amplitude: 1.0,
    }
}

fn peaks(l: &[f64]) -> Vec<Peak> {
    l.iter().map(|&x| peak(x)).collect()
}

#[test]
fn each_class_hit_exactly() {
    // Reference components and constructed peaks with known deviations (closed form).
    let refs = [0.040, 0.060, 0.030, 0.050, 0.025];
    // W_f: 0.5 %, 0.5 %, 0.5 %, 4 %, 0.4 %
    let wf = peaks(&[0.0402, 0.0603, 0.03015, 0.052, 0.0251, 0.075]);
    // F_L: 0.5 %, 2 %, 2 %, 0 %, 0.8 %
    let fl = peaks(&[0.0398, 0.0612, 0.0306, 0.050, 0.0252]);
    // F_N: 0.9 %, 0.5 %, 10 %, 10 %, 20 % (nearest of several)
    let fnp = peaks(&[0.04036, 0.0597, 0.033, 0.055, 0.020]);
    let rows = consistency_table(
        40e-6,
        &refs,
        &wf,
        &fl,
        &fnp,
        &ConsistencyThresholds::default(),
    )
    .unwrap();
    let got: Vec<_> = rows
        .iter()
        .map(|r| (r.case, r.class, r.consistent_signals.as_str()))
        .collect();
    use ConsistencyCase::{Case1, Case2};
    use ConsistencyClass::{DarkGreen, Grey, LightGreen};
    assert_eq!(
        got,
        vec![
            (Case1, LightGreen, "W_f+F_L+F_N"), // 0.5, 0.5, 0.9 % → all ≤ 1 %
            (Case1, DarkGreen, "W_f+F_L+F_N"),  // 0.5, 2, 0.5 % → governed by 2 %
            (Case2, DarkGreen, "W_f+F_L"),      // 0.5, 2, 10 %
            (ConsistencyCase::None, Grey, "F_L"), // 4, 0, 10 %: only one consistent
            (Case2, LightGreen, "W_f+F_L"),     // 0.4, 0.8, 20 %
        ]
    );
    assert!((rows[1].governing_deviation.unwrap() - 0.02).abs() < 1e-12);
    assert!((rows[0].wf_deviation.unwrap() - 0.005).abs() < 1e-12);
    assert!((rows[0].fn_deviation.unwrap() - 0.009).abs() < 1e-12);
    assert!((rows[2].fn_deviation.unwrap() - 0.1).abs() < 1e-12);
    assert!((rows[0].wf_frequency_hz.unwrap() - V / 0.0402).abs() < 1e-9);
    assert_eq!(rows[3].governing_deviation, Option::None);
}

#[test]
fn boundaries_at_1_and_3_percent_are_inclusive() {
    let t = ConsistencyThresholds::default();
    let d = |lam: f64| relative_deviation(lam, 0.040).unwrap();
    // 0.0404 → 1 % (computed 0.01000000000000001 in binary): strong.
    let one = d(0.0404);
    let three = d(0.0412); // 0.030000000000000027 in binary
    eprintln!("1 % boundary computed as {one:e}, 3 % as {three:e}");
    assert_eq!(
        classify([Some(one); 3], &t).unwrap().1,
        ConsistencyClass::LightGreen
    );
    assert_eq!(
        classify([Some(three); 3], &t).unwrap().1,
        ConsistencyClass::DarkGreen
    );
    assert_eq!(
        classify([Some(three); 3], &t).unwrap().0,
        ConsistencyCase::Case1
    );
    // Rounding just above the decimal boundary still counts as on it (the 1e-12 allowance).
    assert_eq!(
        classify([Some(0.010000000000000009); 3], &t).unwrap().1,
        ConsistencyClass::LightGreen
    );
    assert_eq!(
        classify([Some(0.030000000000000027); 3], &t).unwrap().0,
        ConsistencyCase::Case1
    );
    // Just above: 1.0001 % → dark green; 3.0001 % → not consistent.
    assert_eq!(
        classify([Some(0.010001); 3], &t).unwrap().1,
        ConsistencyClass::DarkGreen
    );
    let (case, class, ok, _) = classify([Some(0.030001), Some(0.0), Some(0.0)], &t).unwrap();
    assert_eq!(
        (case, class, ok),
        (
            ConsistencyCase::Case2,
            ConsistencyClass::LightGreen,
            vec![1, 2]
        )
    );
    // A signal without peaks is inconsistent.
    let (case, class, _, _) = classify([None, Some(0.0), Some(0.02)], &t).unwrap();
    assert_eq!(
        (case, class),
        (ConsistencyCase::Case2, ConsistencyClass::DarkGreen)
    );
    let (case, class, _, _) = classify([None, None, Some(0.0)], &t).unwrap();
    assert_eq!(
        (case, class),
        (ConsistencyCase::None, ConsistencyClass::Grey)
    );
}

#[test]
fn nearest_match_and_errors() {
    let m = match_nearest(0.040, &peaks(&[0.030, 0.0415, 0.0392, 0.060])).unwrap();
    assert_eq!(m.wavelength_m, Some(0.0392)); // 2 % beats 3.75 %
    assert_eq!(match_nearest(0.04, &[]).unwrap().deviation, Option::None);
    let t = ConsistencyThresholds::default();
    assert_eq!(
        consistency_table(0.0, &[], &[], &[], &[], &t),
        Err(GrowthError::EmptyReference)
    );
    assert!(matches!(
        consistency_table(0.0, &[0.0], &[], &[], &[], &t),
        Err(GrowthError::BadReference { index: 0, .. })
    ));
    let bad = ConsistencyThresholds {
        strong: 0.05,
        consistent: 0.03,
    };
    assert!(matches!(
        classify([None; 3], &bad),
        Err(GrowthError::BadThreshold { .. })
    ));
}

#[test]
fn rows_serialise_to_json_and_csv() {
    let rows = consistency_table(
        10e-6,
        &[0.040],
        &peaks(&[0.0402]),
        &[],
        &peaks(&[0.0401]),
        &ConsistencyThresholds::default(),
    )
    .unwrap();
    let json = serde_json::to_string(&rows).unwrap();
    assert!(
        json.contains("\"case\":\"case2\"") && json.contains("\"class\":\"light_green\""),
        "{json}"
    );
    let back: Vec<ConsistencyRow> = serde_json::from_str(&json).unwrap();
    // serde_json's default float parser may differ in the last ulp: compare to 1e-15.
    assert_eq!((back[0].case, back[0].class), (rows[0].case, rows[0].class));
    assert!(
        (back[0].wf_frequency_hz.unwrap() / rows[0].wf_frequency_hz.unwrap() - 1.0).abs() < 1e-15
    );
    assert_eq!(back[0].fl_deviation, Option::None);
    let mut w = csv::Writer::from_writer(vec![]);
    for r in &rows {
        w.serialize(r).unwrap();
    }
    let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
    let mut lines = text.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("two_a_max_m,reference_index,reference_wavelength_m,wf_wavelength_m"));
    let line = lines.next().unwrap();
    assert!(
        line.contains(",,,") && line.contains("case2") && line.contains("W_f+F_N"),
        "{line}"
    );
}

/// Band-passed multi-sine "initial wear" on a 1 m grid.
fn initial_wear(shift_m: f64) -> Signal {
    let v: Vec<f64> = (0..2000)
        .map(|i| {
            let x = 0.3 + i as f64 * 0.0005 - shift_m;
            (2.0 * PI * x / 0.041).sin()
                + 0.6 * (2.0 * PI * x / 0.0273 + 0.4).sin()
                + 0.3 * (2.0 * PI * x / 0.063).sin()
        })
        .collect();
    band_pass(&Signal::new(0.3, 0.0005, v).unwrap(), &BandPass::default()).unwrap()
}

#[test]
fn growth_phase_antiphase_grows_inphase_decays() {
    let w0 = initial_wear(0.0);
    let corr = trial_corrugation(&w0, 40e-6).unwrap().height;
    // New wear in phase with the initial wear (scaled, plus noise) = anti-phase with the
    // corrugation → growing.
    let mut nz = crate::spectral::tests::Noise::new(3);
    let grow = Signal::new(
        w0.x0_m,
        w0.dx_m,
        w0.values
            .iter()
            .map(|v| 0.5 * v + 0.2 * nz.next())
            .collect(),
    )
    .unwrap();
    let g = growth_phase(&grow, &corr, 0.2).unwrap();
    eprintln!("in phase with initial wear: r = {:.4}", g.correlation);
    assert_eq!(g.relation, PhaseRelation::AntiPhase);
    assert_eq!(g.growing, Some(true));
    // New wear in phase with the corrugation (= −initial wear) → decaying.
    let decay = Signal::new(
        w0.x0_m,
        w0.dx_m,
        w0.values.iter().map(|v| -0.5 * v).collect(),
    )
    .unwrap();
    let g = growth_phase(&decay, &corr, 0.2).unwrap();
    assert!((g.correlation - 1.0).abs() < 1e-12);
    assert_eq!(
        (g.relation, g.growing),
        (PhaseRelation::InPhase, Some(false))
    );
    // A single 41 mm wave shifted by a quarter wavelength against a 41 mm corrugation:
    // correlation ≈ 0 → indeterminate.
    let sine = |s: f64| {
        let v = (0..2000)
            .map(|i| (2.0 * PI * (i as f64 * 0.0005 - s) / 0.041).sin())
            .collect();
        Signal::new(0.0, 0.0005, v).unwrap()
    };
    let g = growth_phase(
        &sine(0.041 / 4.0),
        &trial_corrugation(&sine(0.0), 40e-6).unwrap().height,
        0.2,
    )
    .unwrap();
    eprintln!("quarter-wave shift: r = {:.4}", g.correlation);
    assert_eq!(
        (g.relation, g.growing),
        (PhaseRelation::Indeterminate, Option::None)
    );
    assert!(matches!(
        growth_phase(&w0, &corr, 1.0),
        Err(GrowthError::BadThreshold { .. })
    ));
}

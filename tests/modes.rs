//! `corrugation modes` end to end on a small model: JSON keys, Sturm count = mode count,
//! CSV columns, modal cache hit (identical CSV) and miss on a changed parameter.
//! Runs the real binary.

use std::path::Path;

mod common;

use common::{run, SMALL_MODEL};

fn modes(dir: &Path, out: &str, extra: &[&str]) -> serde_json::Value {
    let o = dir.join(out);
    let c = dir.join("cache");
    let mut args: Vec<&str> = vec!["modes", "--json", "--fmax", "1000"];
    args.extend(SMALL_MODEL);
    args.extend(extra);
    args.extend(["--out", o.to_str().unwrap(), "--cache", c.to_str().unwrap()]);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(&out).expect("JSON on stdout")
}

#[test]
fn modes_json_csv_and_cache() {
    let dir = std::env::temp_dir().join(format!("corrugation-modes-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let a = modes(&dir, "a", &[]);
    for k in [
        "count",
        "fmax_hz",
        "sturm_count",
        "max_residual",
        "seconds",
        "families",
        "cached",
        "wheel",
    ] {
        assert!(a.get(k).is_some(), "key {k} missing: {a}");
    }
    let count = a["count"].as_u64().unwrap();
    assert!(count > 0);
    assert_eq!(a["sturm_count"].as_u64().unwrap(), count);
    assert_eq!(a["wheel"]["sturm_count"], a["wheel"]["count"]);
    assert_eq!(a["cached"], false);
    assert!(a["max_residual"].as_f64().unwrap() < 1e-4, "{a}");
    let fam_sum: u64 = a["families"]
        .as_object()
        .unwrap()
        .values()
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(fam_sum, count);
    // The wheel's in-plane and out-of-plane modes in 0.5 kHz to --fmax (1 kHz here).
    let band = &a["wheel_band"];
    assert_eq!(band["band_hz"], serde_json::json!([500.0, 1000.0]), "{a}");
    let listed = band["in_plane_hz"].as_array().unwrap().len()
        + band["out_of_plane_hz"].as_array().unwrap().len();
    assert!(listed > 0, "{a}");
    for f in ["in_plane_hz", "out_of_plane_hz"] {
        for v in band[f].as_array().unwrap() {
            assert!((500.0..1000.0).contains(&v.as_f64().unwrap()), "{a}");
        }
    }

    let csv_a = std::fs::read_to_string(dir.join("a/modes.csv")).unwrap();
    let header: Vec<&str> = csv_a.lines().next().unwrap().split(',').collect();
    for col in [
        "index",
        "frequency_hz",
        "family",
        "rail_x_head",
        "rail_x_web",
        "rail_x_foot",
        "wavelength_m",
        "energy_rail",
        "energy_sleepers",
        "energy_fastening",
        "energy_ballast",
        "relative_residual",
    ] {
        assert!(header.contains(&col), "column {col} missing: {header:?}");
    }
    assert_eq!(csv_a.lines().count() as u64, count + 1);
    // Energy shares of each row sum to 1 (or are all 0).
    for line in csv_a.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        let s: f64 = v[7..11].iter().map(|s| s.parse::<f64>().unwrap()).sum();
        assert!(
            [
                "longitudinal_compression",
                "longitudinal_shear",
                "vertical_bending",
                "lateral_bending",
                "torsion",
                "sleeper",
                "local",
                "other"
            ]
            .contains(&v[2]),
            "{line}"
        );
        assert!((s - 1.0).abs() < 1e-9 || s == 0.0, "{line}");
    }

    // Second run: from the cache, identical output.
    let b = modes(&dir, "b", &[]);
    assert_eq!(b["cached"], true);
    assert_eq!(b["wheel"]["cached"], true);
    assert_eq!(b["count"], a["count"]);
    assert_eq!(
        csv_a,
        std::fs::read_to_string(dir.join("b/modes.csv")).unwrap()
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("a/wheel_modes.csv")).unwrap(),
        std::fs::read_to_string(dir.join("b/wheel_modes.csv")).unwrap()
    );

    // A changed parameter misses (the track; the wheel does not depend on it, but the key is
    // the whole model, so it misses too).
    let c = modes(&dir, "c", &["--set", "ballast.vertical_stiffness=5e7"]);
    assert_eq!(c["cached"], false);
    let _ = std::fs::remove_dir_all(&dir);
}

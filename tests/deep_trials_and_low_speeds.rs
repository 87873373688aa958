//! Two failures of the robustness campaign, on the small test model (the real binary; about
//! 20 s of CPU with the small model's modes in the shared test cache (`common::small_model_cache`), about 30 s
//! when they are solved first):
//!
//! - `grow` from rest (`run.start = "rest"`) with the default trial amplitudes stopped at
//!   160 µm with "contact patch reaches the grid boundary (y)": the dynamic load over the deep
//!   trial outgrows the room `contact.grid_margin` leaves. The passage is now rerun on a
//!   widened grid (`passage::setup::run_widening_grid`) and the output names the grid.
//! - `run.speed_kmh` of 1–10 km/h failed the same way at any grid margin: the contact step
//!   `Δx/V` is then too long for the explicit contact coupling. Such speeds are refused with
//!   the key, its unit and the range, and the range's lowest speed runs.

mod common;

use common::{is_one_line_error, run, small_model_cache, SMALL_MODEL};

/// The output directory of these tests.
fn workdir() -> std::path::PathBuf {
    std::env::temp_dir().join("corrugation-test-deep-trials")
}

/// Held by each test while it runs the binary: the first to run solves the small model's
/// modes into the shared cache, the other then loads them instead of solving them too.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// `cmd` on the small model with `sets` (`key=value`), the tests' cache and `--out`.
fn run_small(cmd: &[&str], sets: &[&str], out: &str) -> (i32, String, String) {
    let dir = workdir();
    let cache = small_model_cache().display().to_string();
    let out = dir.join(out).display().to_string();
    let mut args: Vec<&str> = cmd.to_vec();
    args.extend(SMALL_MODEL);
    for s in sets {
        args.extend(["--set", s]);
    }
    args.extend(["--cache", &cache, "--out", &out]);
    run(&args)
}

/// `grow` from rest with the default trial amplitudes 10, 40, 80, 160 µm runs every one of
/// them: the 160 µm trial's contact patch reaches the y edge of the model's grid, and the
/// passage is rerun on a grid widened along y at the same element size, which `grow.json` and
/// stdout name. The smaller trials run on the model's grid as before.
#[test]
fn grow_from_rest_runs_the_160_um_trial_on_a_widened_grid() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (code, out, err) = run_small(
        &["grow", "--no-rate", "--no-coupled"],
        &["run.start=rest"],
        "grow-rest",
    );
    assert_eq!(code, 0, "grow from rest failed: {err}");
    let text = std::fs::read_to_string(workdir().join("grow-rest/grow.json")).unwrap();
    let g: serde_json::Value = serde_json::from_str(&text).unwrap();
    let amps: Vec<f64> = g["amplitudes_um"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_f64().unwrap())
        .collect();
    assert_eq!(amps, [10.0, 40.0, 80.0, 160.0], "{text}");
    assert!(g["stopped_at_um"].is_null(), "{text}");
    // only the 160 µm trial needed more room, across the rail
    let widened = g["widened_contact_grids"]
        .as_array()
        .expect("widened grids");
    assert_eq!(widened.len(), 1, "{text}");
    assert_eq!(widened[0]["amplitude_um"].as_f64(), Some(160.0));
    let grid = &widened[0]["grid"];
    assert_eq!(grid["widenings"][0].as_u64(), Some(0), "{grid}");
    assert!(grid["widenings"][1].as_u64().unwrap() >= 1, "{grid}");
    // the small model's grid is 24 elements across: widened at the same element size
    assert!(grid["elements"][1].as_u64().unwrap() > 24, "{grid}");
    assert!(
        out.contains("trial amplitude 160 µm: the contact patch reached the boundary")
            && out.contains("along y at the same element size"),
        "{out}"
    );
    assert!(
        err.contains("warning: trial amplitude 160 µm") && err.contains("rerun on a contact grid"),
        "{err}"
    );
}

/// A speed below the range of `run.speed_kmh` is refused before anything runs, with the key,
/// its unit and the range (and why); a sweep's speeds likewise. The range's lowest speed,
/// 40 km/h, runs on the small model from either start, inside the model's contact grid.
#[test]
fn low_speeds_are_refused_with_the_range_and_its_lowest_speed_runs() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for v in ["1", "10", "39"] {
        let set = format!("run.speed_kmh={v}");
        let (code, _, err) = run_small(&["passage"], &[&set], "never-written");
        assert!(code != 0 && code != 101, "{v} km/h: {code} {err}");
        assert!(is_one_line_error(&err), "{err}");
        for needle in ["run.speed_kmh", "40 to 500 km/h", "contact step"] {
            assert!(err.contains(needle), "{v} km/h: `{err}` lacks `{needle}`");
        }
    }
    let (code, _, err) = run_small(&["sweep", "--speeds", "10:50:10"], &[], "never-written");
    assert!(code != 0 && code != 101, "{err}");
    assert!(
        err.contains("speed 10 km/h out of range") && err.contains("40 to 500 km/h"),
        "{err}"
    );
    assert!(!workdir().join("never-written").exists());
    for start in ["static", "rest"] {
        let start = format!("run.start={start}");
        let (code, out, err) = run_small(
            &["passage", "--no-coupled", "--no-nodal", "--json"],
            &["run.speed_kmh=40", &start],
            "passage-40",
        );
        assert_eq!(code, 0, "40 km/h, {start}: {err}");
        let s: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert!(s.get("contact_grid_widened").is_none(), "{start}: {s}");
        let mean_fn = s["mean_fn_n"].as_f64().unwrap();
        assert!(
            (mean_fn / 100e3 - 1.0).abs() < 0.02,
            "{start}: mean F_N {mean_fn}"
        );
    }
}

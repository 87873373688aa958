//! Sweeps, shards, merge, resume, initiation and design studies, driven by stand-in passage
//! runners whose spectra are known in closed form (the real engine plugs into the same
//! `PassageRunner` interface).

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use common::tree;
use corrugation::dynamics::{
    PassageError, PassageRunner, PassageSummary, RailProfile, WavelengthComponent,
    WavelengthSpectrum,
};
use corrugation::model::Model;
use corrugation::progress::Silent;
use corrugation::studies::initiation::{
    evaluate, run_initiation, write_initiation, InitiationCriterion,
};
use corrugation::studies::speeds::{parse_speeds, Shard};
use corrugation::studies::study::{run_study, Study};
use corrugation::studies::sweep::{
    merge, read_summary, speed_file, sweep, sweep_beside, write_shard_plan, MapOptions,
};
use corrugation::studies::{BoxError, StudiesError};
use corrugation::units::kmh_to_ms;

/// The "longitudinal compression modes" of the frequency-selection stand-in (Hz).
const MODES_HZ: [f64; 4] = [400.0, 600.0, 900.0, 1350.0];
/// The wavelength the stand-in's contact "prefers" (m): the mode whose wavelength v/f_i is
/// nearest to it (in log) is excited.
const PREFERRED_WAVELENGTH_M: f64 = 0.04;
/// Half-width of the Gaussian resonance peak in frequency (Hz).
const PEAK_WIDTH_HZ: f64 = 20.0;

/// A fresh temporary directory for the test `tag`, removed when the guard drops.
fn tmpdir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("corrugation-studies-{tag}-"))
        .tempdir()
        .unwrap()
}

/// The mode selected at a speed (km/h): nearest (in log) to the preferred wavelength.
fn selected_mode_hz(speed_kmh: f64) -> f64 {
    let v = kmh_to_ms(speed_kmh);
    MODES_HZ
        .iter()
        .copied()
        .min_by(|a, b| {
            let d = |f: f64| (v / f / PREFERRED_WAVELENGTH_M).ln().abs();
            d(*a).total_cmp(&d(*b))
        })
        .unwrap()
}

/// A spectrum on the 20–80 mm band (151 points uniform in wavenumber, wavelength descending)
/// with one Gaussian peak at `f0` in frequency `f = v k`.
fn spectrum(speed_kmh: f64, f0: f64, height: f64) -> WavelengthSpectrum {
    let v = kmh_to_ms(speed_kmh);
    let n = 151;
    let (k0, k1) = (12.5, 50.0);
    let mut wavelength_m = Vec::new();
    let mut psd = Vec::new();
    for i in 0..n {
        let k = k0 + (k1 - k0) * i as f64 / (n - 1) as f64;
        wavelength_m.push(1.0 / k);
        psd.push(height * (-((v * k - f0) / PEAK_WIDTH_HZ).powi(2)).exp() + 1e-12 * height);
    }
    WavelengthSpectrum { wavelength_m, psd }
}

fn component(speed_kmh: f64, f: f64, psd: f64) -> WavelengthComponent {
    WavelengthComponent {
        wavelength_mm: kmh_to_ms(speed_kmh) / f * 1e3,
        frequency_hz: f,
        psd,
    }
}

/// A summary whose wear and F_L peak at `f_wear`, `f_fl` and F_N at `f_fn` (Hz), with the
/// given relative wear; `seconds` is a deterministic function of the speed.
fn summary(
    speed_kmh: f64,
    f_wear: f64,
    f_fl: f64,
    f_fn: f64,
    relative_wear: f64,
) -> PassageSummary {
    let wear_mean = 2.0;
    PassageSummary {
        speed_kmh,
        mean_fn_n: 100e3,
        mean_fl_n: 20e3,
        fl_band_rms_n: 500.0,
        fn_band_rms_n: 300.0,
        wear_band_rms: relative_wear * wear_mean,
        fl_inside_band_rms_n: 250.0,
        fn_inside_band_rms_n: 150.0,
        wear_inside_band_rms: 0.5 * relative_wear * wear_mean,
        wear_mean,
        wear_components: vec![
            component(speed_kmh, f_wear, 1.0),
            component(speed_kmh, f_wear * 1.3, 0.2),
        ],
        fl_components: vec![component(speed_kmh, f_fl, 5.0)],
        fn_components: vec![component(speed_kmh, f_fn, 3.0)],
        dominant_wavelength_mm: Some(kmh_to_ms(speed_kmh) / f_wear * 1e3),
        dominant_frequency_hz: Some(f_wear),
        wear_psd: spectrum(speed_kmh, f_wear, 1.0),
        fl_psd: spectrum(speed_kmh, f_fl, 5.0),
        fn_psd: spectrum(speed_kmh, f_fn, 3.0),
        steps: 1000,
        seconds: 0.25 + speed_kmh * 1e-3,
        contact_grid_widened: None,
    }
}

/// Frequency-selection stand-in: wear and F_L resonate at the selected mode. Counts calls,
/// and fails (error or panic) at the speeds listed in `fail`.
#[derive(Default)]
struct ModeLocked {
    calls: AtomicUsize,
    speeds_run: Mutex<Vec<f64>>,
    fail: Vec<f64>,
    panic: bool,
}

impl PassageRunner for ModeLocked {
    fn run(
        &self,
        speed: corrugation::units::Speed,
        _p: Option<&RailProfile>,
    ) -> Result<PassageSummary, PassageError> {
        let speed_kmh = speed.kmh();
        self.calls.fetch_add(1, Ordering::SeqCst);
        self.speeds_run.lock().unwrap().push(speed_kmh);
        if self.fail.contains(&speed_kmh) {
            if self.panic {
                panic!("stand-in killed at {speed_kmh} km/h");
            }
            return Err(PassageError::Engine {
                engine: "stand-in",
                source: format!("fails at {speed_kmh} km/h").into(),
            });
        }
        let f = selected_mode_hz(speed_kmh);
        Ok(summary(speed_kmh, f, f, 2.0 * f, 0.05))
    }
}

/// The run key of the stand-in sweeps.
const KEY: &str = "stand-in";

fn opts() -> MapOptions {
    MapOptions {
        frequency_lines_hz: MODES_HZ.to_vec(),
        ..MapOptions::default()
    }
}

/// Two summaries are equal up to the last bit lost by serde_json's float parsing (the
/// crate's default parser is not exactly round-trip; the files themselves are compared byte
/// for byte elsewhere).
fn assert_same_numbers(a: &PassageSummary, b: &PassageSummary) {
    fn walk(a: &serde_json::Value, b: &serde_json::Value, at: &str) {
        use serde_json::Value::{Array, Number, Object};
        match (a, b) {
            (Number(x), Number(y)) => {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!(
                    (x - y).abs() <= 4.0 * f64::EPSILON * x.abs().max(y.abs()),
                    "{at}: {x} vs {y}"
                );
            }
            (Array(x), Array(y)) => {
                assert_eq!(x.len(), y.len(), "{at}");
                for (i, (p, q)) in x.iter().zip(y).enumerate() {
                    walk(p, q, &format!("{at}[{i}]"));
                }
            }
            (Object(x), Object(y)) => {
                assert_eq!(
                    x.keys().collect::<Vec<_>>(),
                    y.keys().collect::<Vec<_>>(),
                    "{at}"
                );
                for (k, p) in x {
                    walk(p, &y[k], &format!("{at}.{k}"));
                }
            }
            _ => assert_eq!(a, b, "{at}"),
        }
    }
    walk(
        &serde_json::to_value(a).unwrap(),
        &serde_json::to_value(b).unwrap(),
        "summary",
    );
}

/// Frequency selection: the wear map's ridge (per-speed maximum) lies on the drawn mode
/// lines — on the frequency map at `f_i`, on the wavelength map at `λ = v/f_i` — within the
/// grid resolution; the dominant frequency stays at the modes while the wavelength changes
/// with speed (wavelength range ratio well below the speed range ratio).
#[test]
fn map_ridges_lie_on_the_mode_lines() {
    let tmp = tmpdir("ridges");
    let dir = tmp.path().to_path_buf();
    let speeds = parse_speeds("54.8:219:8").unwrap();
    let runner = ModeLocked::default();
    let out = sweep(&runner, &speeds, &dir, &opts(), KEY, &Silent).unwrap();
    let m = &out.maps;
    let (nl, nf) = (m.wavelength_mm.len(), m.frequency_hz.len());
    let df_grid = m.frequency_hz[1] - m.frequency_hz[0];
    let dl_grid = m.wavelength_mm[1] - m.wavelength_mm[0];
    let argmax = |row: &[f64]| {
        (0..row.len())
            .max_by(|&a, &b| row[a].total_cmp(&row[b]))
            .unwrap()
    };
    let mut worst_f = 0.0f64;
    for (i, &v) in m.speeds_kmh.iter().enumerate() {
        let f_sel = selected_mode_hz(v);
        let vms = kmh_to_ms(v);
        // The spectrum is sampled every 0.25 1/m, i.e. every 0.25 v Hz.
        let df_spec = 0.25 * vms;
        let f_ridge = m.frequency_hz[argmax(&m.wear_frequency[i * nf..(i + 1) * nf])];
        let nearest_line = MODES_HZ
            .iter()
            .map(|f| (f - f_ridge).abs())
            .fold(f64::MAX, f64::min);
        assert!(
            nearest_line <= df_grid + df_spec,
            "{v} km/h: ridge at {f_ridge:.1} Hz, {nearest_line:.1} Hz from a line"
        );
        assert!((f_ridge - f_sel).abs() <= df_grid + df_spec);
        worst_f = worst_f.max(nearest_line / f_sel);
        let l_ridge = m.wavelength_mm[argmax(&m.wear_wavelength[i * nl..(i + 1) * nl])];
        let l_line = vms / f_sel * 1e3;
        let dl_spec = l_line * df_spec / f_sel; // |dλ| = λ df / f
        assert!(
            (l_ridge - l_line).abs() <= dl_grid + dl_spec,
            "{v} km/h: wavelength ridge {l_ridge:.2} mm, line {l_line:.2} mm"
        );
    }
    eprintln!(
        "largest ridge-to-line distance: {:.2} % of the mode frequency",
        100.0 * worst_f
    );
    let r = &out.record;
    assert_eq!(r.speeds_kmh, speeds);
    for (f, v) in r.dominant_frequency_hz.iter().zip(&speeds) {
        assert_eq!(f.unwrap(), selected_mode_hz(*v));
    }
    let wr = r.wavelength_range_ratio.unwrap();
    assert!((r.speed_range_ratio - 214.8 / 54.8).abs() < 1e-12);
    assert!(
        wr < 1.6 && r.speed_range_ratio > 3.9,
        "λ ratio {wr}, v ratio {}",
        r.speed_range_ratio
    );
    // More than one mode is used over the speed range (the frequency jumps).
    let mut used: Vec<f64> = r.dominant_frequency_hz.iter().map(|f| f.unwrap()).collect();
    used.dedup();
    assert!(used.len() >= 3, "{used:?}");
    // Outputs exist: maps as npy (shape in the header), CSV, plots.
    let npy = std::fs::read(dir.join("map_wear_frequency.npy")).unwrap();
    let arr = npyz::NpyFile::new(&npy[..]).unwrap();
    assert_eq!(arr.shape(), &[speeds.len() as u64, nf as u64]);
    assert_eq!(arr.into_vec::<f64>().unwrap(), m.wear_frequency);
    let csv = std::fs::read_to_string(dir.join("map_wavelength.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + speeds.len() * nl);
    for stem in [
        "map_wear_wavelength",
        "map_wear_frequency",
        "map_fl_wavelength",
        "map_fl_frequency",
        "dominant_wavelength",
        "dominant_frequency",
    ] {
        let png = std::fs::read(dir.join(format!("{stem}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert!(png.len() > 5_000, "{stem}.png {} bytes", png.len());
        assert!(
            std::fs::metadata(dir.join(format!("{stem}.svg")))
                .unwrap()
                .len()
                > 1_000
        );
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("sweep.json")).unwrap()).unwrap();
    for k in [
        "speeds_kmh",
        "dominant_wavelength_mm",
        "dominant_frequency_hz",
        "speed_range_ratio",
        "wavelength_range_ratio",
        "seconds",
    ] {
        assert!(json.get(k).is_some(), "sweep.json lacks {k}");
    }
    // seconds = sum of the passages' own times (deterministic, see the module doc).
    let expect: f64 = speeds.iter().map(|v| 0.25 + v * 1e-3).sum();
    assert!((r.seconds - expect).abs() < 1e-9);
    assert!(std::fs::read_to_string(dir.join("report.md"))
        .unwrap()
        .contains("map_wear_wavelength.png"));
    std::fs::remove_dir_all(dir).ok();
}

/// Shards 0/3, 1/3, 2/3 merged (library and CLI) give exactly the files of the unsharded
/// sweep, byte for byte, sweep.json included.
/// The map options made beside the passages (`sweep_beside`, as the `sweep` command makes
/// the coupled modes) give the files of `sweep` with the same options byte for byte, each
/// speed is run once, and a failing option maker is reported after the passages, which are
/// saved (a rerun resumes them).
#[test]
fn options_made_beside_the_passages_give_the_sweep_files() {
    let tmp = tmpdir("beside");
    let base = tmp.path().to_path_buf();
    let speeds = parse_speeds("60:200:10").unwrap();
    let runner = ModeLocked::default();
    let (plain, beside) = (base.join("plain"), base.join("beside"));
    sweep(&runner, &speeds, &plain, &opts(), KEY, &Silent).unwrap();
    sweep_beside(&runner, &speeds, &beside, || Ok(opts()), KEY, &Silent).unwrap();
    assert_eq!(runner.calls.load(Ordering::SeqCst), 2 * speeds.len());
    let (a, b) = (tree(&plain), tree(&beside));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(v == &b[k], "{} differs", k.display());
    }
    let failing = base.join("failing");
    let e = sweep_beside(
        &runner,
        &speeds,
        &failing,
        || Err("no coupled modes".into()),
        KEY,
        &Silent,
    )
    .unwrap_err();
    assert!(
        matches!(e, StudiesError::MapLines(_)) && e.to_string().contains("no coupled modes"),
        "{e}"
    );
    assert_eq!(runner.calls.load(Ordering::SeqCst), 3 * speeds.len());
    let out = sweep_beside(&runner, &speeds, &failing, || Ok(opts()), KEY, &Silent).unwrap();
    assert_eq!(out.stats.reused.len(), speeds.len());
    assert_eq!(runner.calls.load(Ordering::SeqCst), 3 * speeds.len());
}

#[test]
fn merged_shards_equal_the_unsharded_sweep_file_by_file() {
    let tmp = tmpdir("merge");
    let base = tmp.path().to_path_buf();
    let speeds = parse_speeds("60:200:10").unwrap();
    let runner = ModeLocked::default();
    let whole = base.join("whole");
    sweep(&runner, &speeds, &whole, &opts(), KEY, &Silent).unwrap();
    write_shard_plan(&whole, &speeds, Shard::ALL).unwrap();
    let mut shard_dirs = Vec::new();
    for i in 0..3 {
        let d = base.join(format!("shard{i}"));
        let shard = Shard { index: i, count: 3 };
        sweep(&runner, &shard.select(&speeds), &d, &opts(), KEY, &Silent).unwrap();
        write_shard_plan(&d, &speeds, shard).unwrap();
        shard_dirs.push(d);
    }
    assert_eq!(runner.calls.load(Ordering::SeqCst), 2 * speeds.len());
    let merged = base.join("merged");
    let (rec, _) = merge(&shard_dirs, &merged).unwrap();
    assert_eq!(rec.speeds_kmh, speeds);
    let (a, b) = (tree(&whole), tree(&merged));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(v == &b[k], "{} differs", k.display());
    }
    // The same through the command line.
    let cli_out = base.join("cli");
    let mut args = vec!["merge".to_string()];
    args.extend(shard_dirs.iter().map(|d| d.display().to_string()));
    args.extend([
        "--out".into(),
        cli_out.display().to_string(),
        "--json".into(),
    ]);
    let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
    let (code, stdout, stderr) = common::run(&args);
    assert_eq!(code, 0, "{stderr}");
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(j["speeds_kmh"].as_array().unwrap().len(), speeds.len());
    assert!(j["wall_seconds"].is_number());
    let c = tree(&cli_out);
    assert_eq!(a.keys().collect::<Vec<_>>(), c.keys().collect::<Vec<_>>());
    assert!(a.iter().all(|(k, v)| v == &c[k]));
    // Shards made with different eigenfrequency lines are refused.
    let odd = base.join("odd");
    let other = MapOptions {
        frequency_lines_hz: vec![500.0],
        ..MapOptions::default()
    };
    sweep(&runner, &[70.0], &odd, &other, KEY, &Silent).unwrap();
    let e = merge(&[shard_dirs[0].clone(), odd], &base.join("x"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("different map options"), "{e}");
    // ... and so are shards of another model (run key).
    let foreign = base.join("foreign");
    sweep(&runner, &[70.0], &foreign, &opts(), "other-model", &Silent).unwrap();
    let e = merge(&[shard_dirs[0].clone(), foreign], &base.join("y"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("different models"), "{e}");
    // The shards must form one complete sweep: a missing shard, a shard given twice, a
    // shard of another sweep and an unfinished shard are refused.
    let e = merge(&shard_dirs[..2], &base.join("m1")).unwrap_err();
    assert!(
        matches!(&e, StudiesError::ShardsMissing { count: 3, missing } if missing == &[2]),
        "{e}"
    );
    let twice = [
        shard_dirs[0].clone(),
        shard_dirs[1].clone(),
        shard_dirs[1].clone(),
        shard_dirs[2].clone(),
    ];
    let e = merge(&twice, &base.join("m2")).unwrap_err();
    assert!(
        matches!(
            e,
            StudiesError::ShardTwice {
                index: 1,
                count: 3,
                ..
            }
        ),
        "{e}"
    );
    let other = base.join("other");
    let other_speeds = parse_speeds("60:200:20").unwrap();
    let shard = Shard { index: 2, count: 3 };
    sweep(
        &runner,
        &shard.select(&other_speeds),
        &other,
        &opts(),
        KEY,
        &Silent,
    )
    .unwrap();
    write_shard_plan(&other, &other_speeds, shard).unwrap();
    let mixed = [shard_dirs[0].clone(), shard_dirs[1].clone(), other];
    let e = merge(&mixed, &base.join("m3")).unwrap_err();
    assert!(
        matches!(e, StudiesError::ShardsOfDifferentSweeps { .. }),
        "{e}"
    );
    // Shard 2 of 60:200:10 is 80, 110, 140, 170, 200 (5 speeds); a run of only 2 is unfinished.
    let short = base.join("short");
    let shard = Shard { index: 2, count: 3 };
    sweep(&runner, &[80.0, 110.0], &short, &opts(), KEY, &Silent).unwrap();
    write_shard_plan(&short, &speeds, shard).unwrap();
    let e = merge(
        &[shard_dirs[0].clone(), shard_dirs[1].clone(), short],
        &base.join("m4"),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            StudiesError::ShardUnfinished {
                have: 2,
                want: 5,
                ..
            }
        ),
        "{e}"
    );
    // A failed merge leaves nothing behind: no output directory (no `run.key` in it), no
    // staging directory.
    let left_behind = |base: &Path| -> Vec<String> {
        std::fs::read_dir(base)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('m') || n == "x" || n == "y" || n.contains("merging"))
            .filter(|n| n != "merged")
            .collect()
    };
    assert_eq!(left_behind(&base), Vec::<String>::new());
    // Merging again into the merged directory (same sweep) gives the same files.
    merge(&shard_dirs, &merged).unwrap();
    assert_eq!(tree(&merged), a);
    merge_refuses_overlaps_bad_files_and_other_folders(&base, &shard_dirs);
    assert_eq!(left_behind(&base), Vec::<String>::new());
    std::fs::remove_dir_all(base).ok();
}

/// `merge --out` that is, lies inside or contains a shard (also spelled with `..`) is
/// refused and the shard left as it was; a corrupt speed file is named in its own shard; a
/// folder that is not a sweep is named as such.
fn merge_refuses_overlaps_bad_files_and_other_folders(base: &Path, shard_dirs: &[PathBuf]) {
    let before = tree(&shard_dirs[1]);
    for (out, rel) in [
        (shard_dirs[1].clone(), "is"),
        (shard_dirs[0].join("..").join("shard1"), "is"),
        (shard_dirs[1].join("sub"), "lies inside"),
        (base.to_path_buf(), "contains"),
    ] {
        let e = merge(shard_dirs, &out).unwrap_err();
        assert!(
            matches!(&e, StudiesError::OutputOverlapsShard { relation, .. } if *relation == rel),
            "{}: {e}",
            out.display()
        );
        assert_eq!(tree(&shard_dirs[1]), before);
    }
    assert!(!shard_dirs[1].join("sub").exists());
    // a truncated speed file of shard 2 is blamed on that file, not on its merged copy
    let plan: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(shard_dirs[2].join("speeds").join("shard.json")).unwrap(),
    )
    .unwrap();
    let all: Vec<f64> = serde_json::from_value(plan["speeds_kmh"].clone()).unwrap();
    let bad = speed_file(&shard_dirs[2], Shard { index: 2, count: 3 }.select(&all)[0]);
    let saved = std::fs::read(&bad).unwrap();
    std::fs::write(&bad, b"{ \"speed_kmh\": 8").unwrap();
    let e = merge(shard_dirs, &base.join("m5")).unwrap_err();
    assert!(
        matches!(&e, StudiesError::BadFile { path, .. } if path == &bad),
        "{e}"
    );
    std::fs::write(&bad, saved).unwrap();
    // a folder that is not a sweep output
    let plain = base.join("plain");
    std::fs::create_dir_all(plain.join("data")).unwrap();
    let e = merge(&[shard_dirs[0].clone(), plain.clone()], &base.join("m6")).unwrap_err();
    assert!(
        matches!(&e, StudiesError::NotASweep { dir, .. } if dir == &plain),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("is not a sweep output directory")
            && text.contains("speeds/run.key")
            && text.contains("corrugation sweep"),
        "{text}"
    );
}

/// A sweep whose passages fail (error, then panic) at some speeds keeps every finished speed;
/// temp files and a truncated speed file left by a killed run are never taken as results;
/// the rerun computes only the missing speeds.
#[test]
fn interrupted_sweep_resumes_without_recomputing() {
    let tmp = tmpdir("resume");
    let dir = tmp.path().to_path_buf();
    let speeds = parse_speeds("60:150:10").unwrap(); // 10 speeds
    let fail: Vec<f64> = speeds[6..].to_vec();
    for panic in [false, true] {
        let _ = std::fs::remove_dir_all(&dir);
        let broken = ModeLocked {
            fail: fail.clone(),
            panic,
            ..Default::default()
        };
        let e = sweep(&broken, &speeds, &dir, &opts(), KEY, &Silent).unwrap_err();
        let StudiesError::Passages { failures } = &e else {
            panic!("{e}")
        };
        assert_eq!(failures.len(), 4, "{e}");
        if panic {
            assert!(e.to_string().contains("panicked: stand-in killed"), "{e}");
        }
        assert!(
            !dir.join("sweep.json").exists(),
            "no assembled result after a failure"
        );
        // Every speed file present is complete and is the stand-in's exact result.
        let names: Vec<String> = std::fs::read_dir(dir.join("speeds"))
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 7, "6 speeds and run.key: {names:?}");
        for &v in &speeds[..6] {
            let s = read_summary(&speed_file(&dir, v)).unwrap();
            let f = selected_mode_hz(v);
            assert_same_numbers(&s, &summary(v, f, f, 2.0 * f, 0.05));
        }
    }
    // What a kill leaves behind: a temp file, and (e.g. from a copy) a truncated speed file.
    let done = speed_file(&dir, speeds[5]);
    let text = std::fs::read_to_string(&done).unwrap();
    std::fs::write(
        dir.join("speeds").join(format!(
            "{}.tmp.4242",
            speed_file(&dir, speeds[7])
                .file_name()
                .unwrap()
                .to_string_lossy()
        )),
        &text[..text.len() / 2],
    )
    .unwrap();
    std::fs::write(&done, &text[..text.len() - 40]).unwrap();
    assert!(
        read_summary(&done).is_err(),
        "truncated file does not parse"
    );
    let good = ModeLocked::default();
    let out = sweep(&good, &speeds, &dir, &opts(), KEY, &Silent).unwrap();
    let mut ran = good.speeds_run.lock().unwrap().clone();
    ran.sort_by(f64::total_cmp);
    let mut expect = vec![speeds[5]];
    expect.extend(&fail);
    assert_eq!(
        ran, expect,
        "only the failed and the truncated speeds are recomputed"
    );
    assert_eq!(out.stats.reused.len(), 5);
    assert_eq!(out.stats.computed.len(), 5);
    assert_eq!(out.record.speeds_kmh, speeds);
    // A rerun for another model into the same directory is refused, nothing is reused.
    let e = sweep(
        &ModeLocked::default(),
        &speeds,
        &dir,
        &opts(),
        "another model",
        &Silent,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("another model or program version"), "{e}");
    // A third run computes nothing.
    let idle = ModeLocked::default();
    sweep(&idle, &speeds, &dir, &opts(), KEY, &Silent).unwrap();
    assert_eq!(idle.calls.load(Ordering::SeqCst), 0);
    // The temp file of a killed run with a pid above any pid_max (2^22) is removed: a finished
    // sweep leaves no orphan `*.tmp.<pid>` (the file of pid 4242 above is not asserted: a
    // process of that pid may be running on the test machine, whose files are kept).
    let orphan = dir.join("map_wear_wavelength.npy.tmp.4294967000");
    std::fs::write(&orphan, b"partial").unwrap();
    sweep(&idle, &speeds, &dir, &opts(), KEY, &Silent).unwrap();
    for d in [dir.clone(), dir.join("speeds")] {
        let tmp: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|n| n.contains(".tmp.") && !n.ends_with(&format!(".tmp.{}", 4242)))
            .collect();
        assert!(tmp.is_empty(), "orphan temp files: {tmp:?}");
    }
    // sweep.json is the commit marker: a run that fails (here: is killed) in its output stage
    // leaves none, even where an earlier run had written one.
    assert!(dir.join("sweep.json").exists());
    let blocker = dir.join("map_wavelength.csv");
    std::fs::remove_file(&blocker).unwrap();
    std::fs::create_dir(&blocker).unwrap();
    assert!(sweep(&idle, &speeds, &dir, &opts(), KEY, &Silent).is_err());
    assert!(
        !dir.join("sweep.json").exists(),
        "sweep.json beside an unfinished output stage"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// The initiation criterion on constructed summaries: significant wear following F_L
/// initiates; tiny wear, or wear not at F_L's wavelength, does not.
#[test]
fn initiation_table_applies_the_stated_criterion() {
    let c = InitiationCriterion::default();
    let v = 140.0;
    let strong = summary(v, 900.0, 900.0, 1800.0, 0.05);
    let tiny = summary(v, 900.0, 900.0, 1800.0, 0.001);
    let mismatch = summary(v, 900.0, 1000.0, 1800.0, 0.05);
    let near = summary(v, 900.0, 900.0 * 1.02, 1800.0, 0.05); // λ deviation 1/1.02 − 1 ≈ 1.96 %
    let r = evaluate("strong", &strong, &c, 3);
    assert!(r.initiates, "{}", r.reason);
    assert_eq!(r.fl_wear_deviation, Some(0.0));
    assert!((r.relative_wear.unwrap() - 0.05).abs() < 1e-12);
    assert_eq!(r.wear_peaks.len(), 2);
    assert!(!evaluate("tiny", &tiny, &c, 3).initiates);
    let m = evaluate("mismatch", &mismatch, &c, 3);
    assert!(
        !m.initiates && m.reason.contains("deviates"),
        "{}",
        m.reason
    );
    assert!((m.fl_wear_deviation.unwrap() - 0.1).abs() < 1e-12);
    let n = evaluate("near", &near, &c, 3);
    assert!(n.initiates);
    assert!((n.fl_wear_deviation.unwrap() - (1.0 - 1.0 / 1.02)).abs() < 1e-12);

    struct Fixed(PassageSummary);
    impl PassageRunner for Fixed {
        fn run(
            &self,
            speed: corrugation::units::Speed,
            _: Option<&RailProfile>,
        ) -> Result<PassageSummary, PassageError> {
            Ok(PassageSummary {
                speed_kmh: speed.kmh(),
                ..self.0.clone()
            })
        }
    }
    let (a, b) = (Fixed(strong), Fixed(tiny));
    let cases: Vec<(String, &dyn PassageRunner)> = vec![("RPM3".into(), &a), ("RPM2".into(), &b)];
    let rows = run_initiation(&cases, v, &c, 3, &Silent).unwrap();
    assert_eq!(
        rows.iter().map(|r| r.initiates).collect::<Vec<_>>(),
        vec![true, false]
    );
    let tmp = tmpdir("initiation");
    let dir = tmp.path().to_path_buf();
    write_initiation(&dir, &rows, &c, 3).unwrap();
    let csv = std::fs::read_to_string(dir.join("initiation.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3);
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .contains("wear_peak1_wavelength_mm"));
    let md = std::fs::read_to_string(dir.join("initiation.md")).unwrap();
    assert!(md.contains("| RPM3 |") && md.contains("Criterion"), "{md}");
    std::fs::remove_dir_all(dir).ok();
}

/// A stand-in whose relative wear grows with the railpad damping (known closed form), used
/// to check a study's table, plots, growth hook and resume.
struct DampingRunner(f64);
impl PassageRunner for DampingRunner {
    fn run(
        &self,
        speed: corrugation::units::Speed,
        _: Option<&RailProfile>,
    ) -> Result<PassageSummary, PassageError> {
        let speed_kmh = speed.kmh();
        let f = selected_mode_hz(speed_kmh);
        Ok(summary(speed_kmh, f, f, 2.0 * f, self.0 / 1e6))
    }
}

#[test]
fn study_runs_every_case_writes_table_and_plots_and_resumes() {
    let tmp = tmpdir("study");
    let dir = tmp.path().to_path_buf();
    let file = dir.join("s.toml");
    std::fs::write(
        &file,
        r#"
        title = "pad"
        model = "builtin:dutch"
        speeds_kmh = [100.0, 140.0]
        growth = true
        [[parameter]]
        key = "fastening.vertical_damping"
        range = { start = 15e3, stop = 45e3, step = 15e3 }
        [[parameter]]
        key = "fastening.vertical_stiffness"
        values = [1.0e9, 2.0e9]
        "#,
    )
    .unwrap();
    let study = Study::load(&file).unwrap();
    assert_eq!(study.cases().len(), 6);
    let built = AtomicUsize::new(0);
    let factory = |m: &Model| -> Result<DampingRunner, BoxError> {
        built.fetch_add(1, Ordering::SeqCst);
        Ok(DampingRunner(m.fastening.springs.vertical_damping))
    };
    let growth = |m: &Model, r: &DampingRunner| -> Result<BTreeMap<String, f64>, BoxError> {
        let s = r.run(corrugation::units::Speed::from_kmh(140.0), None)?;
        Ok(BTreeMap::from([(
            "limiting_amplitude_um".to_string(),
            m.fastening.springs.vertical_stiffness / 1e7 + s.wear_band_rms,
        )]))
    };
    // Growth requested but not available: an error naming the key, before anything runs.
    let e = run_study(
        &study,
        &factory,
        None,
        &dir.join("out"),
        Shard::ALL,
        &Silent,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("s.toml") && e.contains("`growth`"), "{e}");
    assert_eq!(built.load(Ordering::SeqCst), 0);

    let out = dir.join("out");
    let o = run_study(&study, &factory, Some(&growth), &out, Shard::ALL, &Silent).unwrap();
    assert_eq!((o.computed, o.reused), (6, 0));
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 1 + 6 * 2, "one row per case and speed");
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(
        &header[..4],
        &[
            "case",
            "fastening.vertical_damping",
            "fastening.vertical_stiffness",
            "speed_kmh"
        ]
    );
    assert_eq!(*header.last().unwrap(), "limiting_amplitude_um");
    // Case 3 = damping 30e3 (second value), stiffness 2e9: relative wear 0.03 by construction.
    let (c3, _) = &o.cases[3];
    assert_eq!(
        c3.label(),
        "fastening.vertical_damping=30000.0, fastening.vertical_stiffness=2000000000.0"
    );
    let r3 = &o.cases[3].1;
    assert!((r3.rows[0].relative_wear.unwrap() - 0.03).abs() < 1e-12);
    assert!((r3.growth["limiting_amplitude_um"] - (200.0 + 0.06)).abs() < 1e-9);
    for stem in [
        "study_relative_wear",
        "study_fl_band_rms",
        "study_growth_limiting_amplitude_um",
    ] {
        assert!(
            out.join(format!("{stem}.png")).exists() && out.join(format!("{stem}.svg")).exists(),
            "{stem}"
        );
    }
    assert!(std::fs::read_to_string(out.join("study.md"))
        .unwrap()
        .contains("study_relative_wear.png"));
    // Rerun: every case reused, no runner built.
    let before = built.load(Ordering::SeqCst);
    let o2 = run_study(&study, &factory, Some(&growth), &out, Shard::ALL, &Silent).unwrap();
    assert_eq!((o2.computed, o2.reused), (0, 6));
    assert_eq!(built.load(Ordering::SeqCst), before);
    // Other speeds: every case is recomputed, none is taken from the old files.
    let mut other = study.clone();
    other.speeds_kmh = Some(vec![120.0]);
    let o3 = run_study(&other, &factory, Some(&growth), &out, Shard::ALL, &Silent).unwrap();
    assert_eq!((o3.computed, o3.reused), (6, 0));
    std::fs::remove_dir_all(dir).ok();
}

/// A sharded study (2 shards into one directory) saves its cases and writes no table; the
/// last unsharded run reuses every case and writes the same `study.csv` as one run; the
/// report opens with a summary that names the cases of the lowest and highest wear; and a
/// case whose runner reports stages of its own (its modal bases) leaves the sink in the
/// "study cases" stage with the count so far.
#[test]
fn sharded_study_equals_one_run_and_stages_come_back_to_the_cases() {
    let tmp = tmpdir("study-shard");
    let dir = tmp.path().to_path_buf();
    let file = dir.join("s.toml");
    std::fs::write(
        &file,
        r#"
        title = "pad"
        model = "builtin:dutch"
        speeds_kmh = [100.0]
        [[parameter]]
        key = "fastening.vertical_damping"
        values = [15e3, 30e3, 45e3]
        "#,
    )
    .unwrap();
    let study = Study::load(&file).unwrap();
    let stages = std::sync::Mutex::new(Vec::<(String, u64)>::new());
    struct Rec<'a>(&'a std::sync::Mutex<Vec<(String, u64)>>);
    impl corrugation::progress::Progress for Rec<'_> {
        fn stage(&self, name: &str, _total: u64) {
            self.0.lock().unwrap().push((name.to_string(), 0));
        }
        fn done(&self, done: u64) {
            if let Some(l) = self.0.lock().unwrap().last_mut() {
                l.1 = done;
            }
        }
    }
    let rec = Rec(&stages);
    let factory = |m: &Model| -> Result<Box<dyn PassageRunner>, BoxError> {
        // as a case computing its bases: a stage of its own on the same sink
        corrugation::progress::Progress::stage(&rec, "track modes below 1500 Hz (Lanczos)", 0);
        Ok(Box::new(DampingRunner(
            m.fastening.springs.vertical_damping,
        )))
    };
    let one = dir.join("one");
    let o = run_study(&study, &factory, None, &one, Shard::ALL, &rec).unwrap();
    assert_eq!(o.computed, 3);
    let st = stages.lock().unwrap().clone();
    assert_eq!(
        st.last().unwrap(),
        &("study cases".to_string(), 3),
        "{st:?}"
    );
    assert!(
        st.iter().any(|(n, _)| n.starts_with("track modes")),
        "{st:?}"
    );
    let md = std::fs::read_to_string(one.join("study.md")).unwrap();
    // relative wear grows with the damping (DampingRunner): lowest case 0, highest case 2
    assert!(
        md.contains("**Summary.** 3 case(s), 3 case–speed row(s)")
            && md.contains("Lowest wear band RMS")
            && md.contains("case 0 (fastening.vertical_damping=15000.0, at 100 km/h)")
            && md.contains("case 2 (fastening.vertical_damping=45000.0, at 100 km/h)"),
        "{md}"
    );

    let shared = dir.join("shared");
    for i in 0..2 {
        let sh = Shard { index: i, count: 2 };
        let o = run_study(&study, &factory, None, &shared, sh, &Silent).unwrap();
        assert_eq!(o.computed, if i == 0 { 2 } else { 1 }, "shard {i}");
        assert!(
            !shared.join("study.csv").exists(),
            "a shard writes no table"
        );
    }
    let last = run_study(&study, &factory, None, &shared, Shard::ALL, &Silent).unwrap();
    assert_eq!((last.computed, last.reused), (0, 3));
    assert_eq!(
        std::fs::read(shared.join("study.csv")).unwrap(),
        std::fs::read(one.join("study.csv")).unwrap()
    );
    std::fs::remove_dir_all(dir).ok();
}

/// The shipped studies parse and every case builds a valid model.
#[test]
fn shipped_studies_are_valid() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/studies");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let s = Study::load(&p).unwrap_or_else(|e| panic!("{e}"));
            let models = s.case_models().unwrap_or_else(|e| panic!("{e}"));
            assert!(models.len() >= 2, "{}", p.display());
            n += 1;
        }
    }
    assert!(n >= 2, "at least two shipped studies");
}

/// A bad model value stops a sweep before any passage, naming the key and its range; a bad
/// speed range and a bad study file are named too.
#[test]
fn cli_reports_bad_models_speeds_and_study_keys() {
    let tmp = tmpdir("cli");
    let dir = tmp.path().to_path_buf();
    let (code, _, err) = common::run(&[
        "sweep",
        "--set",
        "run.fmax=10",
        "--speeds",
        "100,120",
        "--out",
        dir.join("s").to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("run.fmax") && err.contains("Hz"), "{err}");
    let (code, _, err) = common::run(&["sweep", "--speeds", "100:90:1"]);
    assert_ne!(code, 0);
    assert!(err.contains("below start"), "{err}");
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "model = \"builtin:dutch\"\n[[parameter]]\nkey = \"a.b\"\nvalue = [1]\n",
    )
    .unwrap();
    let (code, _, err) = common::run(&["study", bad.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(
        err.contains("bad.toml") && err.contains("parameter[0].value"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// A list that gives a value twice is refused before any work, naming the flag or key and
/// the value: speeds (command line and study file), trial amplitudes, rate-check
/// wavelengths, variants, contact positions, nodal points, study parameter values and cases.
#[test]
fn a_list_that_gives_a_value_twice_is_refused() {
    let tmp = tmpdir("twice");
    let dir = tmp.path().to_path_buf();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let study = |name: &str, speeds: &str, values: &str| {
        let p = dir.join(name);
        let text = format!(
            "model = \"builtin:dutch\"\n{speeds}\n[[parameter]]\nkey = \"fastening.model\"\nvalues = {values}\n"
        );
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    let speeds = study("speeds.toml", "speeds_kmh = [100, 120, 100]", r#"["RPM1"]"#);
    let values = study("values.toml", "", r#"["RPM1", "RPM2", "RPM1"]"#);
    // (command line, the list's flag or key, the repeated value)
    let cases = [
        ("sweep --speeds 100,120,100", "speeds", "100 km/h"),
        ("predict --speeds 100,100", "speeds", "100 km/h"),
        ("grow --amplitudes-um 40,80,40", "--amplitudes-um", "40 µm"),
        ("predict --amplitudes-um 40,40", "--amplitudes-um", "40 µm"),
        ("grow --rate-check 41,41", "--rate-check", "41 mm"),
        ("initiation --variants RPM1,RPM1", "--variants", "RPM1"),
        ("compliance --variants RPM2,RPM2", "--variants", "RPM2"),
        ("coupled-modes --at 1.5 --at 1.5", "--at", "1.5 m"),
        ("receptance --at 2 --at 2", "--at", "2 m"),
        (
            "passage --nodal-at 1.2 --nodal-at 1.2",
            "--nodal-at",
            "1.2 m",
        ),
        ("study SPEEDS", "speeds_kmh", "100 km/h"),
        ("study VALUES", "parameter[0].values", "RPM1"),
    ];
    for (line, list, value) in cases {
        let mut args: Vec<&str> = line
            .split(' ')
            .map(|a| match a {
                "SPEEDS" => speeds.as_str(),
                "VALUES" => values.as_str(),
                a => a,
            })
            .collect();
        if args[0] != "study" {
            args.extend(["--out", out]);
        }
        let (code, _, err) = common::run(&args);
        assert!(code != 0 && code != 101, "{line}: {err}");
        assert!(common::is_one_line_error(&err), "{line}: {err}");
        for w in [list, value, "twice"] {
            assert!(err.contains(w), "{line}: `{err}` lacks `{w}`");
        }
    }
    std::fs::remove_dir_all(dir).ok();
}

/// The small passage model as `--set` arguments, with the cache and output directory.
fn small_cli_args(cmd: &[&str], out: &Path) -> Vec<String> {
    let mut a: Vec<String> = cmd.iter().map(|s| s.to_string()).collect();
    a.extend(common::SMALL_MODEL.iter().map(|s| s.to_string()));
    for s in corrugation::model::test_problems::SMALL_PASSAGE {
        a.extend(["--set".to_string(), s.to_string()]);
    }
    let cache = std::env::temp_dir().join("corrugation-test-cache-passage-cli");
    a.extend([
        "--cache".into(),
        cache.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ]);
    a
}

/// Runs the CLI on the small model; returns its stdout.
fn run_small(cmd: &[&str], out: &Path) -> String {
    let args = small_cli_args(cmd, out);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, stdout, stderr) = common::run(&refs);
    assert_eq!(code, 0, "{cmd:?} failed: {stderr}");
    stdout
}

/// On the small test model a sweep attributes every speed's dominant wear and F_L frequency
/// to a coupled wheel–track mode: `dominant.csv` has the attribution columns, finite where the
/// speed has a dominant frequency, each mode within reach of its frequency and the shares
/// summing to 1; `grow.json` carries the growth-rate spectrum's summary and the attribution of
/// every passage's dominant wear frequency.
#[test]
fn sweep_and_grow_attribute_the_selected_frequencies_to_coupled_modes() {
    let tmp = tmpdir("coupled");
    let dir = tmp.path().to_path_buf();
    let stdout = run_small(&["sweep", "--speeds", "100,140,180"], &dir.join("sweep"));
    let text = std::fs::read_to_string(dir.join("sweep/dominant.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 3);
    let col = |name: &str| {
        header
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("dominant.csv lacks {name}: {header:?}"))
    };
    // stdout: the summary, its wavelength range that of dominant.csv, and the coupled mode
    // of each speed range
    let lam: Vec<f64> = rows
        .iter()
        .map(|r| r[col("dominant_wavelength_mm")])
        .filter(|x| x.is_finite())
        .collect();
    let (lo, hi) = lam
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &x| {
            (l.min(x), u.max(x))
        });
    assert!(
        stdout.starts_with(&format!(
            "3 speed(s), 100–180 km/h: dominant wear wavelength {lo:.1}–{hi:.1} mm"
        )) && stdout.contains("wavelength range ratio")
            && stdout.contains("km/h: the wear selects the coupled mode at"),
        "{stdout}"
    );
    for p in ["", "fl_"] {
        let signal = if p.is_empty() {
            "dominant_frequency_hz".to_string()
        } else {
            "fl_dominant_frequency_hz".to_string()
        };
        let shares: Vec<usize> = [
            "coupled_wheel_share",
            "coupled_rail_share",
            "coupled_support_share",
            "coupled_contact_share",
        ]
        .iter()
        .map(|c| col(&format!("{p}{c}")))
        .collect();
        for r in &rows {
            let f = r[col(&signal)];
            if !f.is_finite() {
                continue;
            }
            let fm = r[col(&format!("{p}coupled_mode_hz"))];
            assert!(fm.is_finite() && fm > 0.0, "{p}: {r:?}");
            assert!(
                (fm - f).abs() < 0.5 * f,
                "{p}: {f} Hz attributed to {fm} Hz"
            );
            let total: f64 = shares.iter().map(|&i| r[i]).sum();
            assert!((total - 1.0).abs() < 1e-9, "{p}: shares sum to {total}");
            let zeta = r[col(&format!("{p}coupled_damping_ratio"))];
            let xn = r[col(&format!("{p}coupled_rail_x_to_n"))];
            assert!(zeta.is_finite() && xn.is_finite() && xn >= 0.0, "{r:?}");
        }
    }
    assert!(rows.iter().any(|r| r[col("coupled_mode_hz")].is_finite()));
    let rec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep/sweep.json")).unwrap())
            .unwrap();
    assert_eq!(rec["map"]["coupled_speed_kmh"], 140.0);
    assert!(!rec["map"]["coupled_modes"].as_array().unwrap().is_empty());
    let report = std::fs::read_to_string(dir.join("sweep/report.md")).unwrap();
    assert!(
        report.contains("Wear: coupled mode by speed range"),
        "{report}"
    );

    run_small(&["grow", "--amplitudes-um", "10"], &dir.join("grow"));
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("grow/grow.json")).unwrap())
            .unwrap();
    let r = &g["growth_rate"];
    let lam = r["fastest_wavelength_mm"].as_f64().unwrap();
    assert!((20.0..=80.0).contains(&lam), "{r}");
    assert!(r["max_rate_per_passage"].as_f64().unwrap().is_finite());
    let n = r["wavelengths"].as_u64().unwrap();
    assert!(
        r["growing_wavelengths"].as_u64().unwrap() <= n && n > 0,
        "{r}"
    );
    assert!(r["fastest_mode"]["mode_frequency_hz"].as_f64().unwrap() > 0.0);
    let c = g["coupled"].as_array().unwrap();
    assert_eq!(c.len(), 2, "smooth rail and one trial amplitude: {g}");
    assert!(dir.join("grow/coupled_modes.csv").is_file());
}

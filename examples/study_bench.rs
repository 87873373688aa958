//! Design-study benchmark and the substructured-basis validation (docs/performance.md §7,
//! validation/substructure.md).
//!
//! ```text
//! cargo run --example study_bench -- study [--basis substructured|full] [--key K] [--values a,b,…] [--speed KMH]
//! cargo run --example study_bench -- validate [--key K] [--value V] [--speed KMH] [--fmax-check HZ] [--ballast-degree D] [--list N]
//! ```
//!
//! `study`: a one-parameter study of the default model (default: ten railpad vertical
//! stiffnesses 0.4–2.2 GN/m at 140 km/h) through the library's study runner; prints the
//! basis plan, wall and CPU time, the machine's load and a digest of `study.csv`.
//! `validate`: for one value, the substructured basis against the full Lanczos basis
//! (frequencies below `--fmax-check`, default 3 kHz) and one passage on each basis (band RMS
//! of F_L, F_N and wear, dominant wavelength).

mod common;

use common::{cpu_seconds, machine_load};

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use corrugation::dynamics::PassageRunner;
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::basis::track_basis;
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::eigen::substructure::{
    substructured_track_basis, track_components, SubstructureOptions,
};
use corrugation::model::{load_model, ModelSource};
use corrugation::structure::TrackStructure;
use corrugation::studies::study::{basis_plan, run_study, CaseRunners, Study};
use corrugation::studies::BoxError;

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let key = arg(&args, "--key").unwrap_or_else(|| "fastening.vertical_stiffness".into());
    let speed: f64 = arg(&args, "--speed").map_or(Ok(140.0), |s| s.parse())?;
    match args.first().map(String::as_str) {
        Some("study") => study(&args, &key, speed),
        Some("validate") => validate(&args, &key, speed),
        _ => bail!("usage: study_bench study|validate [options] (see the file's doc)"),
    }
}

fn study(args: &[String], key: &str, speed: f64) -> anyhow::Result<()> {
    let basis = arg(args, "--basis").unwrap_or_else(|| "substructured".into());
    let values = arg(args, "--values").unwrap_or_else(|| {
        (0..10)
            .map(|i| format!("{:e}", 0.4e9 + 0.2e9 * i as f64))
            .collect::<Vec<_>>()
            .join(",")
    });
    let values: Vec<String> = values.split(',').map(|v| v.trim().to_string()).collect();
    let text = format!(
        "title = \"study_bench\"\nmodel = \"builtin:dutch\"\nspeeds_kmh = [{speed:?}]\nbasis = \"{basis}\"\n[[parameter]]\nkey = \"{key}\"\nvalues = [{}]\n",
        values.join(", ")
    );
    let dir = std::env::temp_dir().join(format!("study_bench-{}", std::process::id()));
    let study = Study::parse_str(&text, "study_bench.toml", &dir, "study_bench")?;
    let models = study.case_models()?;
    let cache_dir: PathBuf = default_cache_dir();
    let plan = basis_plan(&study, &models, &ModalCache::new(&cache_dir))?;
    println!("plan: {plan}");
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let runners = CaseRunners::new(&study, &cache_dir);
    let factory = |m: &corrugation::model::Model| -> Result<Box<dyn PassageRunner>, BoxError> {
        Ok(Box::new(runners.prepared(m)?))
    };
    let out = run_study(&study, &factory, None, &dir, &corrugation::progress::Silent)?;
    let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    let csv = std::fs::read(dir.join("study.csv")).context("study.csv")?;
    println!(
        "study: {} cases ({basis} basis), wall {wall:.1} s, CPU {cpu:.1} s, load {}, study.csv blake3 {}",
        out.cases.len(),
        machine_load(),
        &blake3::hash(&csv).to_hex()[..16]
    );
    for (c, r) in &out.cases {
        for row in &r.rows {
            println!(
                "  {}: F_L band {:.2} N, F_N band {:.2} N, dominant {:?}",
                c.label(),
                row.fl_band_rms_n,
                row.fn_band_rms_n,
                row.wear_peaks.first().map(|p| p.wavelength_mm)
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

fn validate(args: &[String], key: &str, speed: f64) -> anyhow::Result<()> {
    let value = arg(args, "--value").unwrap_or_else(|| "1.3e9".into());
    let fcheck: f64 = arg(args, "--fmax-check").map_or(Ok(3000.0), |s| s.parse())?;
    let m = load_model(&ModelSource::Builtin, &[format!("{key}={value}")])?;
    let cache = ModalCache::new(default_cache_dir());
    let fmax = m.run.fmax;
    let track = TrackStructure::build(&m)?;
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let mut opts = SubstructureOptions::default();
    if let Some(d) = arg(args, "--ballast-degree") {
        opts.ballast_pattern_degree = d.parse()?;
    }
    opts.validate()?;
    let comp = track_components(&m, &track, &cache, fmax, &opts)?;
    println!(
        "components: rail {} vectors ({} modes), sleeper {} ({} modes), reduced size {}, {} ({:.1} s wall, {:.1} s CPU)",
        comp.rail.omega2.len(),
        comp.rail.modes,
        comp.sleeper.omega2.len(),
        comp.sleeper.modes,
        comp.reduced_size(),
        if comp.cached { "cached" } else { "built" },
        t0.elapsed().as_secs_f64(),
        cpu_seconds() - c0
    );
    let (t1, c1) = (Instant::now(), cpu_seconds());
    let sub = substructured_track_basis(&track, &comp, fmax)?;
    println!(
        "substructured basis: {} modes below {fmax} Hz in {:.1} s wall, {:.1} s CPU",
        sub.frequencies_hz.len(),
        t1.elapsed().as_secs_f64(),
        cpu_seconds() - c1
    );
    let full = track_basis(&m, &track, &cache, fmax)?;
    let n = full.frequencies_hz.iter().filter(|&&f| f < fcheck).count();
    let mut worst = (0.0f64, 0usize);
    for i in 0..n.min(sub.frequencies_hz.len()) {
        let e = (sub.frequencies_hz[i] - full.frequencies_hz[i]) / full.frequencies_hz[i];
        if e.abs() > worst.0.abs() {
            worst = (e, i);
        }
    }
    let ns = sub.frequencies_hz.iter().filter(|&&f| f < fcheck).count();
    println!(
        "frequencies below {fcheck} Hz: full {n} modes, substructured {ns}; largest relative difference {:+.3e} (mode {}, {:.1} Hz); full basis {} modes below {fmax} Hz, substructured {}",
        worst.0,
        worst.1,
        full.frequencies_hz.get(worst.1).copied().unwrap_or(f64::NAN),
        full.frequencies_hz.len(),
        sub.frequencies_hz.len()
    );
    if let Some(k) = arg(args, "--list") {
        let k: usize = k.parse()?;
        println!("mode,full_hz,substructured_hz,relative_difference");
        for i in 0..k.min(n).min(ns) {
            let (a, b) = (full.frequencies_hz[i], sub.frequencies_hz[i]);
            println!("{i},{a:.6},{b:.6},{:+.3e}", (b - a) / a);
        }
    }
    let popts = PassageOptions::default();
    let t2 = Instant::now();
    let pf = PreparedModel::with_track_basis(&m, &track, full, &cache, None, &popts)?;
    let ps = PreparedModel::with_track_basis(&m, &track, sub, &cache, None, &popts)?;
    println!(
        "prepared both engines in {:.1} s",
        t2.elapsed().as_secs_f64()
    );
    for (name, p) in [("full", &pf), ("substructured", &ps)] {
        let s = p.run(corrugation::units::Speed::from_kmh(speed), None)?;
        println!(
            "passage {speed} km/h, {name}: F_L band {:.3} N, F_N band {:.3} N, wear band/mean {:.5}, dominant {:?} mm ({:?} Hz)",
            s.fl_band_rms_n,
            s.fn_band_rms_n,
            s.wear_band_rms / s.wear_mean,
            s.dominant_wavelength_mm,
            s.dominant_frequency_hz
        );
    }
    Ok(())
}

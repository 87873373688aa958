//! The reduced-order passage on a small model (4 bays, coarse mesh, modes below 1.5 kHz, a
//! coarse contact grid): conservation and equilibrium checks that hold at any resolution.
//! The resolution-dependent checks (convergence, RPM comparisons) are in validation/.

mod common;

use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::ModalCache;

fn small_model() -> corrugation::model::Model {
    corrugation::model::test_problems::small_passage_model(&[]).expect("valid model")
}

/// One passage of `m` over the smooth rail with the default options.
fn smooth_passage(m: &corrugation::model::Model) -> corrugation::passage::record::PassageRecord {
    let opts = PassageOptions::default();
    let p = PreparedModel::new(m, &cache(), &opts).expect("modal model");
    p.engine
        .passage(m.run.speed(), None, &opts, None)
        .expect("passage runs")
}

fn cache() -> ModalCache {
    ModalCache::new(std::env::temp_dir().join("corrugation-test-cache-passage"))
}

/// The passage of a prepared model over the smooth rail with `opts`, and its summary.
fn run_passage(
    p: &PreparedModel,
    m: &corrugation::model::Model,
    opts: &PassageOptions,
) -> (
    corrugation::passage::record::PassageRecord,
    corrugation::dynamics::PassageSummary,
) {
    let rec = p
        .engine
        .passage(m.run.speed(), None, opts, None)
        .expect("passage runs");
    let s = corrugation::passage::analysis::summarise(&rec).unwrap();
    (rec, s)
}

/// Mean normal force `W / cos α` and mean longitudinal force `μ_t W` in the zone within 1 %,
/// and the energy ledger balanced within 1 % (docs/theory.md §7.4–§7.8).
fn assert_load_traction_and_energy(
    m: &corrugation::model::Model,
    s: &corrugation::dynamics::PassageSummary,
    e: &corrugation::passage::record::EnergyBalance,
) {
    assert_load_and_traction(m, s);
    assert!(e.relative_error().abs() < 0.01, "{e:?}");
}

/// Mean normal force `W / cos α` and mean longitudinal force `μ_t W` in the zone within 1 %
/// (docs/theory.md §7.4–§7.5).
fn assert_load_and_traction(
    m: &corrugation::model::Model,
    s: &corrugation::dynamics::PassageSummary,
) {
    let w = m.vehicle.wheel_load;
    let cos_a = m.rail.inclination.atan().cos();
    assert!(
        (s.mean_fn_n - w / cos_a).abs() / w < 0.01,
        "{}",
        s.mean_fn_n
    );
    let traction = m.contact.traction_coefficient * w;
    assert!(
        (s.mean_fl_n - traction).abs() / traction < 0.01,
        "{}",
        s.mean_fl_n
    );
}

/// Static equilibrium and the driving torque: in the solution zone the mean normal force is
/// the static wheel load along the inclined contact normal, W / cos α, and the mean
/// longitudinal force is the traction coefficient times W, both within 1 % (docs/theory.md §7.4–§7.5).
/// The energy of the passage balances within 1 %, and on the structural side alone:
/// external work + contact work = Δ(kinetic + strain) + damper dissipation (to 0.1 %: the
/// damper and contact powers are integrated by the trapezoidal rule).
#[test]
fn passage_holds_the_static_load_and_the_traction_and_balances_energy() {
    let m = small_model();
    let rec = smooth_passage(&m);
    let s = corrugation::passage::analysis::summarise(&rec).unwrap();
    let w = m.vehicle.wheel_load;
    let cos_a = m.rail.inclination.atan().cos();
    let fn_err = (s.mean_fn_n - w / cos_a).abs() / w;
    let fl_err = (s.mean_fl_n - m.contact.traction_coefficient * w).abs()
        / (m.contact.traction_coefficient * w);
    assert!(fn_err < 0.01, "mean F_N {} vs {}", s.mean_fn_n, w / cos_a);
    assert!(fl_err < 0.01, "mean F_L {} vs {}", s.mean_fl_n, 0.15 * w);
    let e = &rec.energy;
    let structural =
        (e.external_work_j + e.contact_work_j) - (e.stored_change_j + e.damper_dissipation_j);
    assert!(
        structural.abs() < 1e-3 * e.external_work_j.abs(),
        "structural energy residual {structural} J ({e:?})"
    );
    // The whole balance (docs/theory.md §7.8): work of the driving torque, gravity and train resistance,
    // plus the inputs of the nominal motion (spin creepage, rolling over the deflected rail)
    // = stored + dampers + frictional work + contact elastic energy, within 1 %.
    assert!(
        e.relative_error().abs() < 0.01,
        "energy balance error {:.3} % ({e:?})",
        100.0 * e.relative_error()
    );
    assert!(s.wear_mean > 0.0 && s.wear_band_rms.is_finite());
    // Rail point record: one displacement per step, finite, the rail deflects downwards
    // when the wheel is over it.
    let rp = rec.rail_point.as_ref().unwrap();
    assert_eq!(rp.displacement_m.len(), rec.steps);
    let min_uz = rp
        .displacement_m
        .iter()
        .map(|u| u[2])
        .fold(f64::INFINITY, f64::min);
    assert!(min_uz < -1e-5, "rail point min u_z {min_uz}");
}

/// The passage on the fe-patch (`contact.influence = "fe-patch"`; a 12 × 10 contact grid so
/// that the patch builds in seconds, and the default wheel mesh, which the tread's twin needs)
/// holds the static load and the traction within 1 %, as on the half-space. Its static start
/// used to fail: the creepage for the prescribed F_L stalled at 1.7e-6 µN of the force, above
/// the secant's 1e-6 but within the force's own precision (the passage's tangential
/// tolerance, 1e-5), which it now accepts. The energy ledger closes within 5 % only (measured
/// −4.2 %; the half-space passages close within 1 %): on this coarse mesh the split is large
/// against the compliance beside it (the default model's fe-patch passage closes within
/// 0.11 %), probably because the ledger's frictional work carries part of the series
/// spring's exchange (docs/theory.md §6.7), not shown; open in validation/contact_patch.md.
#[test]
fn fe_patch_passage_holds_the_static_load_and_the_traction() {
    let m = corrugation::model::test_problems::small_model(&[
        "run.solution_zone_offset=0.2",
        "run.solution_zone_length=0.3",
        "contact.influence=\"fe-patch\"",
        "contact.grid_nx=12",
        "contact.grid_ny=10",
        "mesh.wheel_element_size=0.06",
    ])
    .expect("valid model");
    let rec = smooth_passage(&m);
    let s = corrugation::passage::analysis::summarise(&rec).unwrap();
    assert_load_and_traction(&m, &s);
    let e = rec.energy.relative_error();
    eprintln!("fe-patch passage: energy balance {:+.2} %", 100.0 * e);
    assert!(e.abs() < 0.05, "{:?}", rec.energy);
}

/// The small model as `--set` arguments for the CLI (a wider contact grid: trial
/// corrugations of 160 µm make the patch grow).
fn small_args() -> Vec<String> {
    let mut a: Vec<String> = common::SMALL_MODEL.iter().map(|s| s.to_string()).collect();
    for s in [
        "track.bays=6",
        "run.fmax=1500",
        "run.solution_zone_length=0.4",
        "contact.grid_nx=16",
        "contact.grid_ny=12",
        "contact.grid_margin=1.8",
    ] {
        a.push("--set".into());
        a.push(s.into());
    }
    a
}

fn run_cli(cmd: &[&str], out: &std::path::Path) -> serde_json::Value {
    let cache = std::env::temp_dir().join("corrugation-test-cache-passage-cli");
    let mut args: Vec<String> = cmd.iter().map(|s| s.to_string()).collect();
    args.extend(small_args());
    args.extend([
        "--cache".into(),
        cache.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--json".into(),
    ]);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, stdout, stderr) = common::run(&refs);
    assert_eq!(code, 0, "{cmd:?} failed: {stderr}");
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

/// `passage --json` has its documented keys (README) and writes its files; `grow --json` and
/// `predict --json` run end to end on the small model and have their documented keys.
#[test]
fn passage_grow_and_predict_commands_write_their_outputs() {
    let dir = std::env::temp_dir().join(format!("corrugation-test-cli-{}", std::process::id()));
    let p = run_cli(&["passage"], &dir.join("passage"));
    for k in [
        "mean_fn_n",
        "mean_fl_n",
        "fl_band_rms_n",
        "fn_band_rms_n",
        "wear_band_rms",
        "fl_inside_band_rms_n",
        "fn_inside_band_rms_n",
        "wear_inside_band_rms",
        "wear_components",
        "dominant_wavelength_mm",
        "steps",
        "seconds",
    ] {
        assert!(p.get(k).is_some(), "passage --json lacks {k}: {p}");
    }
    // What lies strictly inside the band is part of what the band RMS counts.
    for (inside, band) in [
        ("fl_inside_band_rms_n", "fl_band_rms_n"),
        ("fn_inside_band_rms_n", "fn_band_rms_n"),
        ("wear_inside_band_rms", "wear_band_rms"),
    ] {
        let (a, b) = (p[inside].as_f64().unwrap(), p[band].as_f64().unwrap());
        assert!(a > 0.0 && a <= b, "{inside} {a} vs {band} {b}");
    }
    for f in [
        "forces.csv",
        "wear.csv",
        "rail_point.csv",
        "psd_wear.csv",
        "psd_fl.csv",
        "psd_fn.csv",
        "forces_x.png",
        "psd_wear.svg",
    ] {
        assert!(dir.join("passage").join(f).is_file(), "missing {f}");
    }
    let g = run_cli(&["grow", "--amplitudes-um", "10,80"], &dir.join("grow"));
    for k in [
        "amplitudes_um",
        "limiting_amplitude_um",
        "phase",
        "components",
        "consistency",
    ] {
        assert!(g.get(k).is_some(), "grow --json lacks {k}: {g}");
    }
    assert_eq!(g["phase"].as_array().unwrap().len(), 2);
    for ph in g["phase"].as_array().unwrap() {
        let s = ph.as_str().unwrap();
        assert!(
            ["anti-phase", "in-phase", "indeterminate"].contains(&s),
            "{s}"
        );
    }
    let r = run_cli(
        &["predict", "--amplitudes-um", "10", "--speeds", "100,140"],
        &dir.join("predict"),
    );
    assert!(r.get("sweep_dominant_wavelength_mm").is_some(), "{r}");
    assert!(dir.join("predict/report.html").is_file());
    assert!(dir.join("predict/report.md").is_file());
    assert!(dir.join("predict/sweep/sweep.json").is_file());
    // The growth-rate spectrum beside the trial amplitudes (docs/theory.md §10.6).
    for d in ["grow", "predict/grow"] {
        let csv = std::fs::read_to_string(dir.join(d).join("growth_rate.csv")).unwrap();
        assert!(csv.starts_with(
            "wavelength_mm,frequency_hz,gain_j_per_m2,phase_deg,growth_rate_per_passage"
        ));
        assert_eq!(csv.lines().count(), 242, "header + 241 wavelengths");
    }
    assert!(
        r["growth_rate"]
            .as_str()
            .unwrap()
            .starts_with("Growth-rate spectrum at 140 km/h"),
        "{r}"
    );
    let md = std::fs::read_to_string(dir.join("predict/report.md")).unwrap();
    assert!(md.contains("## Growth-rate spectrum"), "{md}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The static correction of the truncated track modes (`run.residual_flexibility`, default
/// on): the structural residual flexibility of the rail at the contact acts as a series
/// compliance of the contact. With it the passage still holds the static load and the
/// traction within 1 % and its energy balances within 1 % (the residual spring's energy
/// `∫ c F dF` counted); the numbers with and without are printed (F_L / F_N band RMS,
/// dominant wear wavelength) and the correction is checked to be in use (a non-zero spring
/// energy exchange, and the static approach grows by exactly c_n F_N). Measured (this small
/// model, 1.5 kHz, constant compliance): structural residual x 4.2e-10, t 1.1e-9, n 4.2e-10
/// m/N; F_L band RMS 66.5 → 44.4 N, F_N 487.0 → 371.5 N, dominant wear wavelength 74.2 →
/// 73.0 mm, static approach 1.041e-4 → 1.464e-4 m, energy error 0.065 % → 0.075 %.
#[test]
fn residual_flexibility_passage_balances_energy() {
    let mut m = small_model();
    // The rail's correction alone (the wheel's has its own test).
    m.run.wheel_residual_flexibility = false;
    let opts = PassageOptions::default();
    let mut out = Vec::new();
    for on in [false, true] {
        m.run.residual_flexibility = on;
        let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
        assert_eq!(p.engine.residual_flexibility().is_some(), on);
        if let Some(r) = p.engine.residual_flexibility() {
            let [x, t, n] = r.mean_structural_weighted();
            eprintln!(
                "structural residual flexibility (mean) x {x:.3e} t {t:.3e} n {n:.3e} m/N ({} modes)",
                r.modes
            );
        }
        let (rec, s) = run_passage(&p, &m, &opts);
        let e = rec.energy;
        eprintln!(
            "residual {on}: mean F_N {:.1} F_L {:.1} N; band RMS F_L {:.2} F_N {:.2} N; dominant wear λ {:?} mm; static approach {:.4e} m; energy error {:.4} % (spring {:.3e} J, friction {:.3e} J)",
            s.mean_fn_n,
            s.mean_fl_n,
            s.fl_band_rms_n,
            s.fn_band_rms_n,
            s.dominant_wavelength_mm,
            rec.static_approach_m,
            100.0 * e.relative_error(),
            e.residual_spring_energy_change_j,
            e.frictional_work_j
        );
        assert_load_traction_and_energy(&m, &s, &e);
        let (w, cos_a) = (m.vehicle.wheel_load, m.rail.inclination.atan().cos());
        out.push((
            rec.static_approach_m,
            e.residual_spring_energy_change_j,
            p.engine.series_compliance()[2] * w / cos_a,
        ));
    }
    assert_eq!(out[0].1, 0.0);
    assert!(out[1].1 != 0.0, "{out:?}");
    // The static approach grows by exactly the spring's share c_n F_N (F_N = W / cos α): the
    // half-space part of the approach is the same Hertz contact in both runs.
    let (d_approach, cf) = (out[1].0 - out[0].0, out[1].2);
    assert!(cf > 0.0 && (d_approach - cf).abs() < 0.01 * cf, "{out:?}");
}

/// `receptance --json` runs on the small model, writes its files, and its curves behave as a
/// receptance must: finite and positive, the rail's normal receptance at the lowest
/// frequency is stiffness-controlled (phase within 0.1 rad of 0), and the wheel lines of
/// the sweep maps (`wheel_contact_modes_hz`) are wheel eigenfrequencies that include the
/// mode of largest contact participation in each direction.
#[test]
fn receptance_command_and_wheel_lines() {
    let dir = std::env::temp_dir().join(format!("corrugation-test-rec-{}", std::process::id()));
    let r = run_cli(
        &[
            "receptance",
            "--from-hz",
            "5",
            "--to-hz",
            "1500",
            "--step-hz",
            "5",
        ],
        &dir,
    );
    for k in [
        "rail",
        "wheel_longitudinal",
        "wheel_normal",
        "wheel_modes",
        "hertz_compliance_m_per_n",
        "seconds",
    ] {
        assert!(r.get(k).is_some(), "receptance --json lacks {k}: {r}");
    }
    assert_eq!(
        r["rail"].as_array().unwrap().len(),
        2,
        "mid-span and sleeper"
    );
    for f in [
        "receptance.csv",
        "receptance.json",
        "receptance_rail.png",
        "receptance_wheel.svg",
        "force_per_roughness.png",
    ] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let text = std::fs::read_to_string(dir.join("receptance.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 300);
    assert!(rows.iter().flatten().all(|v| v.is_finite()));
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (a, ph) = (col("rail_mid_n_m_per_n"), col("rail_mid_n_phase_rad"));
    assert!(rows.iter().all(|r| r[a] > 0.0));
    assert!(rows[0][ph].abs() < 0.1, "phase at 5 Hz {}", rows[0][ph]);
    let _ = std::fs::remove_dir_all(&dir);

    let m = small_model();
    let p = PreparedModel::new(&m, &cache(), &PassageOptions::default()).expect("modal model");
    let part = p.engine.wheel_contact_participation();
    let lines = p.wheel_contact_modes_hz(0.03);
    assert!(!lines.is_empty());
    assert!(lines.windows(2).all(|w| w[1] > w[0]));
    for d in 0..2 {
        let (i, _) = part
            .iter()
            .max_by(|a, b| a.1[d].total_cmp(&b.1[d]))
            .unwrap();
        let f = p.wheel_frequencies_hz[*i];
        assert!(
            lines.iter().any(|&g| (g - f).abs() <= 0.005 * f),
            "direction {d}: {f} Hz not in {lines:?}"
        );
    }
}

/// The physics check, the part that holds (docs/theory.md §2.4): on the smooth rail the
/// differential wear follows F_L, not F_N — the band-passed wear correlates more strongly
/// with the band-passed F_L than with F_N along the solution zone (measured 0.85 vs 0.40),
/// and the strongest wear component is one of F_L's components within the PSD's wavelength
/// resolution λ²/L of this short (0.4 m) zone (measured 3.9 %, resolution 18 %). (The RPM
/// ranking of the same check does not hold on the default track:
/// validation/frequency_selection.md.)
#[test]
fn smooth_rail_wear_follows_the_longitudinal_force() {
    use corrugation::passage::analysis::{analyse, wear_signal, zone_signal};
    use corrugation::spectral::{correlation_coefficient, resample_linear, Signal};
    let m = small_model();
    let rec = smooth_passage(&m);
    let s = corrugation::passage::analysis::summarise(&rec).unwrap();
    let v = rec.speed_m_per_s;
    let h = &rec.histories;
    let w = analyse(&wear_signal(&rec).unwrap(), v).unwrap().band;
    let fl = analyse(&zone_signal(&rec, &h.longitudinal_n).unwrap(), v)
        .unwrap()
        .band;
    let fnn = analyse(&zone_signal(&rec, &h.normal_n).unwrap(), v)
        .unwrap()
        .band;
    let end = |a: &Signal| a.x_m(a.len() - 1);
    let lo = w.x0_m.max(fl.x0_m).max(fnn.x0_m);
    let hi = end(&w).min(end(&fl)).min(end(&fnn));
    let wb = w.window_x(lo, hi).unwrap();
    let on_wear_grid = |a: &Signal| {
        let xs: Vec<f64> = (0..a.len()).map(|i| a.x_m(i)).collect();
        resample_linear(&xs, &a.values, wb.x0_m, wb.dx_m, wb.len()).unwrap()
    };
    let c_fl = correlation_coefficient(&wb, &on_wear_grid(&fl)).unwrap();
    let c_fn = correlation_coefficient(&wb, &on_wear_grid(&fnn)).unwrap();
    let top = &s.wear_components[0];
    let matched = s
        .fl_components
        .iter()
        .map(|c| (c.wavelength_mm - top.wavelength_mm).abs() / top.wavelength_mm)
        .fold(f64::INFINITY, f64::min);
    println!(
        "corr(wear, F_L) {c_fl:.3}, corr(wear, F_N) {c_fn:.3}; wear {:.2} mm matched by F_L within {:.3} %",
        top.wavelength_mm,
        100.0 * matched
    );
    assert!(c_fl.abs() > c_fn.abs(), "{c_fl} vs {c_fn}");
    assert!(c_fl.abs() > 0.5, "{c_fl}");
    let zone = wb.length_m();
    let res = corrugation::spectral::psd::wavelength_resolution_m(top.wavelength_mm * 1e-3, zone)
        / (top.wavelength_mm * 1e-3);
    assert!(matched < res, "{matched} vs resolution {res}");
}

/// Runs the binary with the small model and plain progress lines every 0.2 s; returns
/// (stdout, stderr) and asserts success.
fn run_plain(cmd: &[&str], out: &std::path::Path) -> (String, String) {
    let cache = std::env::temp_dir().join("corrugation-test-cache-passage-cli");
    let mut args: Vec<String> = cmd.iter().map(|s| s.to_string()).collect();
    args.extend(small_args());
    args.extend([
        "--cache".into(),
        cache.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ]);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(&args)
        .env("CORRUGATION_PROGRESS_SECONDS", "0.2")
        .output()
        .expect("binary runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert!(o.status.success(), "{cmd:?} failed: {stderr}");
    (stdout, stderr)
}

/// The last non-empty lines of `stdout` after the blank line that opens the verdict.
fn verdict_lines(stdout: &str) -> Vec<&str> {
    let lines: Vec<&str> = stdout.lines().collect();
    let start = lines
        .iter()
        .rposition(|l| l.is_empty())
        .expect("blank line");
    lines[start + 1..].to_vec()
}

/// `grow` and `predict` end with the plain-language verdict (one of the four headline forms,
/// then the strongest wear component, its coupled mode and the nearest uncoupled
/// eigenfrequency, then the initiation check against
/// the threshold); the report opens with the same verdict, explains the consistency classes,
/// compares with the wheel modes and names the fastening model as in model files. With
/// stderr not a terminal, every long stage prints plain progress lines (its name, a count
/// `k/n` and the end), never "0/0".
#[test]
fn grow_and_predict_print_a_verdict_and_plain_progress() {
    let tmp = tempfile::Builder::new()
        .prefix("corrugation-test-verdict-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let heads = [
        "No consistent growth on this track at 140 km/h: ",
        "Corrugation grows consistently on this track at 140 km/h ",
        "No corrugation initiates on this track at 140 km/h: ",
    ];
    let (out, err) = run_plain(&["grow", "--amplitudes-um", "10,80"], &dir.join("grow"));
    let v = verdict_lines(&out);
    assert!(heads.iter().any(|h| v[0].starts_with(h)), "{out}");
    assert!(!out.contains("limiting amplitude none"), "{out}");
    if !v[0].starts_with(heads[2]) {
        assert!(v[1].starts_with("Strongest wear component "), "{out}");
        // The coupled mode by the attribution rule, and the uncoupled comparison beside it.
        assert!(
            v[1].contains("coupled wheel–track mode")
                && v[1].contains("; nearest uncoupled eigenfrequency: "),
            "{out}"
        );
    }
    assert!(
        v.last().unwrap().starts_with("Initiation criterion: ")
            && v.last().unwrap().contains("threshold 1 %"),
        "{out}"
    );
    assert!(
        err.contains("trial-amplitude growth (passages: smooth rail + trials) ..."),
        "{err}"
    );
    assert!(
        err.contains("trial-amplitude growth (passages: smooth rail + trials): done (3/3, "),
        "{err}"
    );
    assert!(err.contains("modal bases below 1500 Hz"), "{err}");
    assert!(!err.contains("0/0"), "{err}");
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("grow/grow.json")).unwrap())
            .unwrap();
    assert_eq!(g["verdict"]["lines"][0].as_str(), Some(v[0]));

    let (out, err) = run_plain(
        &["predict", "--amplitudes-um", "10", "--speeds", "100,140"],
        &dir.join("predict"),
    );
    let v = verdict_lines(&out);
    assert!(heads.iter().any(|h| v[0].starts_with(h)), "{out}");
    assert!(err.contains("sweep passages (speeds) ..."), "{err}");
    assert!(
        err.contains("sweep passages (speeds): done (2/2, "),
        "{err}"
    );
    // A stage ends once: one closing line, and no progress line after it.
    assert_eq!(
        err.matches("sweep passages (speeds): done").count(),
        1,
        "{err}"
    );
    assert!(
        err.contains("smooth-rail passage (time steps): done ("),
        "{err}"
    );
    assert!(!err.contains("0/0"), "{err}");
    let md = std::fs::read_to_string(dir.join("predict/report.md")).unwrap();
    let verdict_at = md.find("## Verdict").expect("verdict section");
    assert!(
        verdict_at < md.find("## Model").unwrap(),
        "verdict not first"
    );
    assert!(md.contains(v[0]), "report lacks the verdict");
    assert!(
        md.contains("Fastening model RPM3,"),
        "fastening not printed as RPM3"
    );
    assert!(!md.contains("Rpm3"));
    for s in [
        "Case 1: all three signals consistent",
        "light green",
        "grey = inconsistent",
        "nearest wheel (Hz)",
        "rel. difference wheel",
        "(rel. deviation)",
        "initiation threshold 1 %",
    ] {
        assert!(md.contains(s), "report lacks {s:?}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// The static start on the smooth rail is computed once per engine and shared by the passages
/// at every speed: the contact state at steady rolling does not depend on the speed (a step
/// moves the material by one element whatever Δt). A passage at 120 km/h on an engine that
/// first ran 80 km/h (start computed there) is bit for bit the passage of a fresh engine,
/// whose start is computed at 120 km/h.
#[test]
fn shared_static_start_gives_the_passage_of_a_fresh_engine() {
    let m = small_model();
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let v = |kmh: f64| corrugation::units::kmh_to_ms(kmh);
    let warm = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
    warm.engine.passage(v(80.0), None, &opts, None).unwrap();
    let shared = warm.engine.passage(v(120.0), None, &opts, None).unwrap();
    let fresh = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
    let own = fresh.engine.passage(v(120.0), None, &opts, None).unwrap();
    assert_eq!(shared.steps, own.steps);
    assert_eq!(shared.dt_s, own.dt_s);
    let (a, b) = (&shared.histories, &own.histories);
    assert_eq!(a.normal_n, b.normal_n);
    assert_eq!(a.longitudinal_n, b.longitudinal_n);
    assert_eq!(a.frictional_power_w, b.frictional_power_w);
    assert_eq!(shared.wear_j_per_m, own.wear_j_per_m);
    assert_eq!(shared.static_creepage, own.static_creepage);
}

/// The speed asked for comes back exactly: 60 km/h is 16.666… m/s inside, and the summary of
/// a runner says 60, not 60.00000000000001 (the round trip through m/s).
#[test]
fn a_runner_reports_the_requested_speed_exactly() {
    use corrugation::dynamics::PassageRunner;
    let m = small_model();
    assert_ne!(
        corrugation::units::ms_to_kmh(corrugation::units::kmh_to_ms(60.0)),
        60.0,
        "the round trip this test guards against"
    );
    let p = PreparedModel::new(&m, &cache(), &PassageOptions::default()).expect("modal model");
    let s = p
        .run(corrugation::units::Speed::from_kmh(60.0), None)
        .expect("passage runs");
    assert_eq!(s.speed_kmh, 60.0);
}

/// The start from rest (`run.start = "rest"`, docs/theory.md §7.5): the wheel starts in free
/// rolling under its static vertical load (the first step's F_L is below 1 % of the
/// traction μ_t W: no torque yet), the driving torque and the train's resistance step on
/// `run.rest_start_distance` before the zone (here at the wheel's start, 0.3 m before it).
/// Physical expectation: once the torque has acted over the run-in (about ten settling
/// lengths of the creep force) the zone's mean forces are those of the static start's steady
/// rolling: mean F_N within 0.5 % and mean F_L within 2 % of the static start's (the
/// undamped wheel modes the step excites still ring, so not closer). Conservation: the
/// energy ledger (docs/theory.md §7.8) balances, the torque's work counted from its onset:
/// within 1 % for the static start, within 2 % from rest. Measured (this model): energy
/// error 0.070 % static, 1.03 % from rest, where the start transient's force fluctuations
/// are 18 times larger (F_L band RMS 36.9 → 674 N); that the ledger's error grows with them
/// (the contact's time discretisation) is a presumption, not shown here. Mean F_L 14991 →
/// 15227 N, F_N 100641 → 100651 N.
#[test]
fn start_from_rest_reaches_the_static_starts_mean_forces_and_balances_energy() {
    let mut m = small_model();
    let opts = PassageOptions::default();
    let mut runs = Vec::new();
    for start in [
        corrugation::model::StartKind::Static,
        corrugation::model::StartKind::Rest,
    ] {
        m.run.start = start;
        let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
        let (rec, s) = run_passage(&p, &m, &opts);
        let e = rec.energy;
        eprintln!(
            "{start:?}: first F_L {:.1} N; zone mean F_N {:.2} F_L {:.2} N; band RMS F_L {:.2} F_N {:.2} N; wear {:.4e}; dominant λ {:?} mm; energy error {:.4} % (torque work {:.4e} J)",
            rec.histories.longitudinal_n[0],
            s.mean_fn_n,
            s.mean_fl_n,
            s.fl_band_rms_n,
            s.fn_band_rms_n,
            s.wear_band_rms,
            s.dominant_wavelength_mm,
            100.0 * e.relative_error(),
            e.torque_work_j
        );
        eprintln!("{e:?}");
        let tol = match start {
            corrugation::model::StartKind::Static => 0.01,
            corrugation::model::StartKind::Rest => 0.02,
        };
        assert!(e.relative_error().abs() < tol, "{start:?}: {e:?}");
        runs.push((rec.histories.longitudinal_n[0], s, e));
    }
    let traction = m.contact.traction_coefficient * m.vehicle.wheel_load;
    let (st, rest) = (&runs[0], &runs[1]);
    assert!(
        (st.0 - traction).abs() < 0.01 * traction,
        "static start F_L {}",
        st.0
    );
    assert!(rest.0.abs() < 0.01 * traction, "rest start F_L {}", rest.0);
    assert!(
        (rest.1.mean_fn_n - st.1.mean_fn_n).abs() < 0.005 * st.1.mean_fn_n,
        "mean F_N {} vs {}",
        rest.1.mean_fn_n,
        st.1.mean_fn_n
    );
    assert!(
        (rest.1.mean_fl_n - st.1.mean_fl_n).abs() < 0.02 * st.1.mean_fl_n,
        "mean F_L {} vs {}",
        rest.1.mean_fl_n,
        st.1.mean_fl_n
    );
    // The torque did work from its onset in both runs.
    assert!(rest.2.torque_work_j > 0.0 && st.2.torque_work_j > 0.0);
}

/// The wheel's residual flexibility (`run.wheel_residual_flexibility`, default on) adds to the
/// contact's series compliance: the static approach grows by exactly its normal part times
/// F_N (the half-space part is the same Hertz contact), the passage still holds the static
/// load and the traction within 1 %, and its energy balances within 1 % with the series
/// spring's energy counted.
#[test]
fn wheel_residual_flexibility_adds_to_the_series_compliance_and_balances_energy() {
    let mut m = small_model();
    let opts = PassageOptions::default();
    let mut out = Vec::new();
    for on in [false, true] {
        m.run.wheel_residual_flexibility = on;
        let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
        assert_eq!(p.engine.wheel_residual().is_some(), on);
        let wc = p.engine.wheel_residual().map(|w| {
            eprintln!("wheel residual: {w:?}");
            w.structural_m_per_n
        });
        let (rec, s) = run_passage(&p, &m, &opts);
        let e = rec.energy;
        eprintln!(
            "wheel residual {on}: band RMS F_L {:.2} F_N {:.2} N; dominant λ {:?} mm; static approach {:.4e} m; energy error {:.4} %",
            s.fl_band_rms_n,
            s.fn_band_rms_n,
            s.dominant_wavelength_mm,
            rec.static_approach_m,
            100.0 * e.relative_error()
        );
        assert_load_traction_and_energy(&m, &s, &e);
        let (w, cos_a) = (m.vehicle.wheel_load, m.rail.inclination.atan().cos());
        out.push((rec.static_approach_m, wc.map_or(0.0, |c| c[2] * w / cos_a)));
    }
    let (d_approach, cf) = (out[1].0 - out[0].0, out[1].1);
    assert!(cf > 0.0 && (d_approach - cf).abs() < 0.01 * cf, "{out:?}");
}

/// A recorder whose passages fail over profiles deeper than `limit_m` (peak to trough), as a
/// passage over a deep corrugation fails when the patch outgrows the contact grid.
struct FailsWhenDeep<'a> {
    inner: &'a corrugation::dynamics::passage::PassageEngine,
    limit_m: f64,
}

impl corrugation::dynamics::PassageRecorder for FailsWhenDeep<'_> {
    fn record(
        &self,
        speed: corrugation::units::Speed,
        profile: Option<&corrugation::dynamics::RailProfile>,
    ) -> Result<corrugation::passage::record::PassageRecord, corrugation::passage::PassageError>
    {
        match profile {
            Some(p) if p.peak_to_trough_m() > self.limit_m => {
                Err(corrugation::passage::PassageError::Diverged {
                    t_s: 0.0,
                    x_m: 0.0,
                    what: "a test failure over a deep profile".to_string(),
                })
            }
            _ => self.inner.record(speed, profile),
        }
    }

    fn hertz_b_m(&self) -> f64 {
        self.inner.hertz_b_m()
    }
}

/// A trial passage that fails stops the procedure at its amplitude and keeps the ones below,
/// with the same results as a run that asked for those amplitudes only; the verdict says
/// which amplitude was not evaluated and why.
#[test]
fn a_failed_trial_stops_the_growth_and_keeps_the_smaller_amplitudes() {
    use corrugation::growth::procedure::{trial_growth, ModeLines};
    let m = small_model();
    let opts = PassageOptions::default();
    let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
    let v = m.run.speed();
    let failing = FailsWhenDeep {
        inner: &p.engine,
        limit_m: 60e-6,
    };
    let modes = ModeLines::default();
    let g = trial_growth(&failing, v, &[10.0, 40.0, 80.0], &modes, |_| {}).expect("growth");
    let s = g.stopped.as_ref().expect("the 80 µm trial fails");
    assert_eq!(s.amplitude_um, 80.0);
    assert!(
        s.reason.contains("a test failure over a deep profile"),
        "{}",
        s.reason
    );
    let ran: Vec<f64> = g.amplitudes.iter().map(|a| a.amplitude_um).collect();
    assert_eq!(ran, [10.0, 40.0]);
    let plain = trial_growth(&p.engine, v, &[10.0, 40.0], &modes, |_| {}).expect("growth");
    assert!(plain.stopped.is_none());
    for (a, b) in g.amplitudes.iter().zip(&plain.amplitudes) {
        assert_eq!(a.phase.correlation, b.phase.correlation);
        assert_eq!(a.summary.fl_band_rms_n, b.summary.fl_band_rms_n);
    }
    assert!(p.engine.hertz_b_m() > 0.0);
    let verdict =
        corrugation::growth::verdict::growth_verdict(&g, m.run.speed_kmh, &modes, None, None);
    assert!(
        verdict.lines[1].contains("80 µm") && verdict.lines[1].contains("not evaluated"),
        "{:?}",
        verdict.lines
    );
    // When even the smallest trial fails, no trial is evaluated and the verdict says so
    // (not "no wear component", which the smooth rail had).
    let all_fail = FailsWhenDeep {
        inner: &p.engine,
        limit_m: 1e-6,
    };
    let g = trial_growth(&all_fail, v, &[10.0, 40.0], &modes, |_| {}).expect("growth");
    assert!(g.amplitudes.is_empty());
    assert_eq!(g.stopped.as_ref().map(|s| s.amplitude_um), Some(10.0));
    let verdict =
        corrugation::growth::verdict::growth_verdict(&g, m.run.speed_kmh, &modes, None, None);
    assert_eq!(
        verdict.outcome,
        corrugation::growth::verdict::Outcome::NotEvaluated {
            failed_amplitude_um: 10.0
        }
    );
    assert!(
        verdict.lines[0].starts_with("Growth not evaluated"),
        "{:?}",
        verdict.lines
    );
}

/// The track's damping product beside the contact step (`PassageOptions::overlap`, for a
/// passage that runs alone): the same bits on one thread as on two (the split arithmetic does
/// not depend on whether the second core takes its half), and the passage of the plain step
/// within the tolerances stated for it in docs/log/performance.md §5.11 (the two differ only by
/// the rounding of the split single-precision damping products): mean forces within 1e-6,
/// band RMS within 1e-4, dominant wavelength within 1e-5 (relative).
#[test]
fn damping_product_beside_the_contact_gives_the_same_bits_on_one_and_two_threads() {
    let m = small_model();
    let plain = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let alone = PassageOptions {
        overlap: true,
        ..plain
    };
    let p = PreparedModel::new(&m, &cache(), &plain).expect("modal model");
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| run_passage(&p, &m, &alone))
    };
    let (one, s1) = on(1);
    let (two, _) = on(2);
    let (a, b) = (&one.histories, &two.histories);
    assert_eq!(a.normal_n, b.normal_n);
    assert_eq!(a.longitudinal_n, b.longitudinal_n);
    assert_eq!(one.wear_j_per_m, two.wear_j_per_m);
    let (base, s0) = run_passage(&p, &m, &plain);
    // the split step is taken (its rounding differs from the plain step's)
    assert_ne!(base.histories.longitudinal_n, a.longitudinal_n);
    let rel = |x: f64, y: f64| (x - y).abs() / y.abs();
    assert!(rel(s1.mean_fn_n, s0.mean_fn_n) < 1e-6);
    assert!(rel(s1.mean_fl_n, s0.mean_fl_n) < 1e-6);
    for (x, y, what) in [
        (s1.fl_band_rms_n, s0.fl_band_rms_n, "F_L"),
        (s1.fn_band_rms_n, s0.fn_band_rms_n, "F_N"),
        (s1.wear_band_rms, s0.wear_band_rms, "wear"),
    ] {
        assert!(rel(x, y) < 1e-4, "band RMS of {what}: {x} vs {y}");
    }
    let (w1, w0) = (
        s1.dominant_wavelength_mm.unwrap(),
        s0.dominant_wavelength_mm.unwrap(),
    );
    assert!(rel(w1, w0) < 1e-5, "dominant wavelength {w1} vs {w0} mm");
}

/// The coupled wheel–track modes (frequencies, damping, energy shares, contact amplitudes)
/// are the same bits on one thread as on two: the passage and grow outputs
/// `coupled_modes.*` and `coupled_attribution.json` do not depend on the thread count.
#[test]
fn coupled_modes_give_the_same_bits_on_one_and_two_threads() {
    let m = small_model();
    let p = PreparedModel::new(&m, &cache(), &PassageOptions::default()).expect("modal model");
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| {
                let t = std::time::Instant::now();
                let c = p.coupled_modes(m.run.speed(), &[]).expect("coupled modes");
                eprintln!("coupled modes on {threads} thread(s): {:?}", t.elapsed());
                c
            })
    };
    let (one, two) = (on(1), on(2));
    assert!(!one.modes.is_empty());
    assert_eq!(one, two);
}

/// A rail profile the wheel's contact never meets changes nothing: one whose crest lies
/// beyond the rail the contact passes over (flat where the contact is) gives the smooth
/// rail's summary bit for bit (the contact grid is lengthened only for the heights the
/// contact meets), and one entirely off that rail is refused, naming both ranges.
#[test]
fn a_profile_off_the_wheels_travel_changes_nothing_or_is_refused() {
    use corrugation::dynamics::{DynamicsError, RailProfile};
    let m = small_model();
    let opts = PassageOptions::default();
    let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
    let v = m.run.speed();
    let [_, t1] = p.engine.rail_under_contact_m(v).unwrap();
    let beyond = RailProfile::new(
        vec![t1 - 0.2, t1 + 0.01, t1 + 0.1, t1 + 0.3],
        vec![0.0, 0.0, 200e-6, 0.0],
    )
    .unwrap();
    let summary = |profile: Option<&RailProfile>| {
        let rec = p
            .engine
            .passage(v, profile, &opts, None)
            .expect("passage runs");
        let mut s = corrugation::passage::analysis::summarise(&rec).unwrap();
        s.seconds = 0.0; // wall-clock time
        s
    };
    let (smooth, partly) = (summary(None), summary(Some(&beyond)));
    assert_eq!(
        serde_json::to_string(&partly).unwrap(),
        serde_json::to_string(&smooth).unwrap()
    );
    let off = RailProfile::new(vec![t1 + 0.001, t1 + 0.1], vec![0.0, 100e-6]).unwrap();
    let e = p.engine.passage(v, Some(&off), &opts, None).unwrap_err();
    assert!(
        matches!(
            e,
            DynamicsError::Passage(corrugation::passage::PassageError::ProfileOffTravel { .. })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("entirely off"), "{e}");
}

/// A passage whose progress asks it to stop ([`corrugation::progress::Progress::cancelled`])
/// stops at the next report (every 64 steps) with "cancelled by the caller"; a sweep does not
/// start the speeds left when it is cancelled.
#[test]
fn a_cancelled_progress_stops_the_passage_and_the_sweep() {
    use corrugation::progress::Progress;
    use std::sync::atomic::{AtomicU64, Ordering};
    /// Cancels once `after` units of its stage were reported; counts the reports.
    struct StopAfter {
        after: u64,
        reports: AtomicU64,
        last: AtomicU64,
    }
    impl Progress for StopAfter {
        fn stage(&self, _: &str, _: u64) {}
        fn done(&self, done: u64) {
            self.reports.fetch_add(1, Ordering::Relaxed);
            self.last.store(done, Ordering::Relaxed);
        }
        fn cancelled(&self) -> bool {
            self.last.load(Ordering::Relaxed) >= self.after
        }
    }
    let m = small_model();
    let opts = PassageOptions::default();
    let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
    let stop = StopAfter {
        after: 128,
        reports: AtomicU64::new(0),
        last: AtomicU64::new(0),
    };
    let e = p
        .engine
        .passage(m.run.speed(), None, &opts, Some(&stop))
        .expect_err("cancelled");
    assert!(
        matches!(
            e,
            corrugation::dynamics::DynamicsError::Passage(
                corrugation::passage::PassageError::Cancelled(_)
            )
        ),
        "{e}"
    );
    assert_eq!(e.to_string(), "cancelled by the caller");
    assert_eq!(stop.last.load(Ordering::Relaxed), 128);
    // a sweep cancelled before it starts runs no passage and writes no speed file
    let dir = tempfile::tempdir().expect("temp dir");
    let never = StopAfter {
        after: 0,
        reports: AtomicU64::new(0),
        last: AtomicU64::new(0),
    };
    let r = corrugation::studies::sweep::run_passages(&p, &[100.0, 120.0], dir.path(), "k", &never);
    let Err(corrugation::studies::StudiesError::Passages { failures }) = r else {
        panic!("not refused: {r:?}");
    };
    assert_eq!(failures.len(), 2, "{failures:?}");
    assert!(
        failures[0].ends_with("cancelled by the caller"),
        "{failures:?}"
    );
    assert!(!corrugation::studies::sweep::speed_file(dir.path(), 100.0).exists());
}

//! Size-driving inputs are bounded with an estimate before the work, and bad input is refused
//! early and to the point: the flag or key, its unit and its range. These run the real binary;
//! every refusal comes before any modal or passage work (the explicit one after the small
//! model's few-second set-up).

mod common;

use common::{is_one_line_error, run, SMALL_MODEL};

/// An output path for commands refused before they check `--out` (as root it could be
/// created).
const NO: &str = "/nonexistent/never-written";

/// Runs `args`; asserts a clean one-line error holding each of `must_contain`; returns stderr.
fn refused(args: &[&str], must_contain: &[&str]) -> String {
    let (code, _out, err) = run(args);
    assert_ne!(code, 0, "{args:?} must fail");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert!(is_one_line_error(&err), "one-line error expected: {err}");
    for s in must_contain {
        assert!(err.contains(s), "{args:?}: error `{err}` lacks `{s}`");
    }
    err
}

fn small(cmd: &[&str], extra: &[&str]) -> Vec<String> {
    cmd.iter()
        .chain(SMALL_MODEL.iter())
        .chain(extra.iter())
        .map(|s| s.to_string())
        .collect()
}

fn refused_small(cmd: &[&str], extra: &[&str], must_contain: &[&str]) -> String {
    let args = small(cmd, extra);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    refused(&args, must_contain)
}

/// A corrugation of 1e9 µm (1 km: a height in m read as µm) hung, and 1e15 µm aborted on a
/// 149 GB allocation: the contact grid lengthened for it is refused with its size and memory,
/// naming the flag; a 3 mm one (a likely unit slip) is warned about.
#[test]
fn a_corrugation_beyond_the_contact_grid_bound_is_refused_and_a_deep_one_warned() {
    let tmp = tempfile::tempdir().unwrap();
    for h in ["1e9", "1e15"] {
        let p = tmp.path().join(format!("deep{h}.csv"));
        std::fs::write(&p, format!("x_m,height_um\n0,0\n1,{h}\n2,0\n")).unwrap();
        let t = std::time::Instant::now();
        refused_small(
            &["passage", "--corrugation", p.to_str().unwrap()],
            &["--out", NO],
            &[
                "--corrugation",
                "peak-to-trough",
                "µm",
                "contact grid",
                "GB",
                "at most 48 times",
            ],
        );
        assert!(t.elapsed().as_secs_f64() < 10.0, "{h}: worked first");
    }
    let p = tmp.path().join("mm.csv");
    std::fs::write(&p, "x_m,height_um\n0,0\n1,3000\n2,0\n").unwrap();
    // refused on its --out, under a regular file (root may create any path)
    let under_file = p.join("out");
    let err = refused_small(
        &["passage", "--corrugation", p.to_str().unwrap()],
        &["--out", under_file.to_str().unwrap()],
        &["--out", "cannot write there"],
    );
    assert!(
        err.contains("warning: --corrugation") && err.contains("(not mm or m)"),
        "{err}"
    );
    // the trial amplitudes of grow: 4 mm on a 64 × 64 grid
    refused_small(
        &["grow", "--amplitudes-um", "4000"],
        &[
            "--set",
            "contact.grid_nx=64",
            "--set",
            "contact.grid_ny=64",
            "--out",
            NO,
        ],
        &["--amplitudes-um 4000", "contact grid", "at most 48 times"],
    );
}

/// `explicit.time_step = 1e-10` ran for hours without a word: refused after the set-up with
/// the key and the estimate (steps × cost per DOF sub-step, with its basis).
#[test]
fn an_explicit_passage_beyond_the_time_bound_is_refused_with_its_estimate() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (code, _o, err) = run(&small(
        &["explicit"],
        &[
            "--set",
            "explicit.time_step=1e-10",
            "--out",
            out.to_str().unwrap(),
        ],
    )
    .iter()
    .map(String::as_str)
    .collect::<Vec<_>>());
    assert_ne!(code, 0, "{err}");
    let last = err.trim_end().lines().last().unwrap_or("");
    for s in [
        "explicit.time_step = 1e-10 s",
        "contact steps",
        "per DOF sub-step",
        "beyond the bound of 24 h",
    ] {
        assert!(last.contains(s), "lacks `{s}`: {err}");
    }
}

/// A study of 200 000 speeds ran while a sweep capped at 100 000: one cap for every speed
/// list, and a study's cases × speeds within it too.
#[test]
fn every_speed_list_has_the_one_cap() {
    let tmp = tempfile::tempdir().unwrap();
    let speeds: Vec<String> = (0..100_001)
        .map(|i| format!("{:.3}", 40.0 + 0.004 * i as f64))
        .collect();
    let study = tmp.path().join("many.toml");
    std::fs::write(
        &study,
        format!(
            "model = \"builtin:dutch\"\nspeeds_kmh = [{}]\n[[parameter]]\nkey = \"vehicle.wheel_load\"\nvalues = [1e5]\n",
            speeds.join(", ")
        ),
    )
    .unwrap();
    refused(
        &["study", study.to_str().unwrap(), "--out", NO],
        &["speeds_kmh", "100001 speeds", "at most 100000"],
    );
    let study = tmp.path().join("product.toml");
    std::fs::write(
        &study,
        format!(
            "model = \"builtin:dutch\"\nspeeds_kmh = [{}]\n[[parameter]]\nkey = \"vehicle.wheel_load\"\nvalues = [1e5, 9e4, 8e4]\n",
            speeds[..40_000].join(", ")
        ),
    )
    .unwrap();
    refused(
        &["study", study.to_str().unwrap(), "--out", NO],
        &["speeds_kmh", "120000 passages", "at most 100000"],
    );
    refused(
        &["sweep", "--speeds", "40:500:0.001", "--out", NO],
        &["--speeds", "at most 100000"],
    );
}

/// `study` found an unwritable `--out` only after computing; `--cache` on a regular file
/// cached nothing and said nothing. Both are refused before any work, by every command.
#[test]
fn out_and_cache_are_checked_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    let study = tmp.path().join("s.toml");
    std::fs::write(
        &study,
        "model = \"builtin:dutch\"\n[[parameter]]\nkey = \"vehicle.wheel_load\"\nvalues = [1e5]\n",
    )
    .unwrap();
    let under_file = file.join("out");
    let t = std::time::Instant::now();
    refused(
        &[
            "study",
            study.to_str().unwrap(),
            "--out",
            under_file.to_str().unwrap(),
        ],
        &["--out", "cannot write there"],
    );
    assert!(t.elapsed().as_secs_f64() < 10.0, "study computed first");
    let out = tmp.path().join("out");
    for cmd in [
        &["passage"][..],
        &["modes"],
        &["sweep"],
        &["grow"],
        &["predict"],
        &["initiation"],
        &["receptance"],
        &["coupled-modes"],
        &["study", study.to_str().unwrap()],
    ] {
        let mut args = cmd.to_vec();
        args.extend([
            "--cache",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        refused(&args, &["--cache", "a_file", "not a directory"]);
    }
}

/// A killed run's PNG temp file (`<stem>.tmp<pid>.png`) survived the rerun: the next run into
/// the directory removes the writers' temp files of dead processes, and nothing else.
#[test]
fn a_dead_writers_temp_files_are_removed_from_the_output_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    std::fs::create_dir_all(out.join("sub")).unwrap();
    // above Linux's largest pid (2^22): never a running process
    let dead = ["psd.tmp4194400.png", "forces.csv.tmp.4194401"];
    let kept = [
        "notes.tmp.png",
        "psd.png",
        "my.tmp12x.png",
        "sub/psd.tmp4194400.png",
    ];
    for f in dead.iter().chain(&kept) {
        std::fs::write(out.join(f), "x").unwrap();
    }
    // compliance checks its --out, then fails loading the unknown fastening model
    refused(
        &[
            "compliance",
            "--variants",
            "RPM9",
            "--out",
            out.to_str().unwrap(),
        ],
        &["RPM9"],
    );
    for f in dead {
        assert!(!out.join(f).exists(), "{f} left");
    }
    for f in kept {
        assert!(out.join(f).exists(), "{f} removed");
    }
}

/// Keys that were blamed on something else (the wheel modes, the ballast, the analysis band)
/// are refused by their range, naming the key, the unit and the range.
#[test]
fn keys_blamed_on_something_else_name_themselves() {
    for (set, must) in [
        (
            vec!["vehicle.primary_stiffness=1.0"],
            ["vehicle.primary_stiffness", "1000 to 10000000000 N/m"],
        ),
        (
            vec!["vehicle.primary_stiffness=1e-12"],
            ["vehicle.primary_stiffness", "1000 to 10000000000 N/m"],
        ),
        (
            vec!["fastening.hold=elastic", "fastening.hold_stiffness=1e-12"],
            ["fastening.hold_stiffness", "1e4 to 1e13 N/m"],
        ),
        (
            vec!["run.solution_zone_length=0.01"],
            ["run.solution_zone_length", "0.08 to"],
        ),
    ] {
        let mut args = vec!["model"];
        for s in &set {
            args.extend(["--set", s]);
        }
        refused(&args, &must);
    }
    refused(
        &["compliance", "--elastic", "1e-12", "--out", NO],
        &["--elastic 1e-12", "1e4 to 1e13 N/m"],
    );
    refused_small(
        &["passage", "--nodal-at", "100"],
        &["--out", NO],
        &["--nodal-at 100", "off the track", "0 to 2.4 m"],
    );
}

/// Negative numbers gave clap's "unexpected argument '-1'": now each flag's range check
/// refuses them with the flag, the unit and the range.
#[test]
fn negative_numbers_reach_the_range_checks() {
    for (args, must) in [
        (vec!["modes", "--fmax", "-1"], vec!["--fmax", "Hz"]),
        (
            vec!["initiation", "--speed", "-1"],
            vec!["--speed -1", "km/h"],
        ),
        (vec!["receptance", "--from-hz", "-1"], vec!["--from-hz"]),
        (
            vec!["passage", "--nodal-at", "-1"],
            vec!["--nodal-at -1", "m"],
        ),
        (
            vec!["coupled-modes", "--list-to-hz", "-1"],
            vec!["--list-to-hz -1", "Hz"],
        ),
        (vec!["coupled-modes", "--at", "-1"], vec!["--at -1", "m"]),
        (
            vec!["compliance", "--ahead", "-1"],
            vec!["--ahead", "≥ 0 m"],
        ),
        (
            vec!["grow", "--rate-check", "-1"],
            vec!["--rate-check", "[20, 80] mm"],
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let mut a = args.clone();
        a.extend(["--out", out.to_str().unwrap()]);
        let err = refused(&a, &must);
        assert!(!err.contains("unexpected argument"), "{err}");
    }
}

/// `contact --out` repeated its context; a bad progress interval was warned about once per
/// progress indicator.
#[test]
fn messages_are_not_repeated() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    let out = file.join("x");
    let err = refused(&["contact", "--out", out.to_str().unwrap()], &["--out"]);
    assert_eq!(err.matches(out.to_str().unwrap()).count(), 1, "{err}");
    // receptance: the modes' and the receptances' indicators (small model, a few seconds)
    let cache = tmp.path().join("cache");
    let args = small(
        &["receptance"],
        &[
            "--set",
            "run.fmax=1000",
            "--cache",
            cache.to_str().unwrap(),
            "--out",
            tmp.path().join("r").to_str().unwrap(),
        ],
    );
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(&args)
        .env("CORRUGATION_PROGRESS_SECONDS", "abc")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        err.matches("CORRUGATION_PROGRESS_SECONDS").count(),
        1,
        "{err}"
    );
}

/// `grow --rounds` had no bound (one passage per round).
#[test]
fn growth_rounds_are_bounded() {
    refused(
        &["grow", "--rounds", "1000000", "--out", NO],
        &["--rounds 1000000", "at most 1000"],
    );
}

//! The suite's cases, by class (see the file's opening comment).

use crate::common::{small_model_cache, SMALL_MODEL};
use crate::runner::{Case, Output};
use std::path::Path;

/// Every case of the suite; `scratch` is a directory for the one run made while building them
/// (the model's keys).
pub fn all(scratch: &Path) -> Vec<Case> {
    let mut v = model_keys(scratch);
    v.extend(flags());
    v.extend(input_files());
    v.extend(cache_and_merge());
    v.extend(campaign());
    v
}

/// `cmd` on the small model with its own cache and output in the case's directory, then
/// `rest`.
fn small(cmd: &str, rest: &[&str]) -> Vec<String> {
    let mut a = vec![cmd.to_string()];
    a.extend(SMALL_MODEL.iter().map(|s| s.to_string()));
    a.extend(
        ["--cache", "{dir}/cache", "--out", "{dir}/out"]
            .iter()
            .map(|s| s.to_string()),
    );
    a.extend(rest.iter().map(|s| s.to_string()));
    a
}

/// `cmd` as [`small`] but with the tests' shared cache of the small model's modes
/// ([`small_model_cache`]), for a case refused only once the modes are loaded.
fn small_shared_cache(cmd: &str, rest: &[&str]) -> Vec<String> {
    let cache = small_model_cache().display().to_string();
    small(cmd, rest)
        .into_iter()
        .map(|a| if a == "{dir}/cache" { cache.clone() } else { a })
        .collect()
}

/// `explicit` on the small model with its output in the case's directory (it takes no cache:
/// the explicit path solves no modes), then `rest`.
fn small_explicit(rest: &[&str]) -> Vec<String> {
    let mut a = small("explicit", rest);
    let i = a.iter().position(|s| s == "--cache").expect("--cache");
    a.drain(i..i + 2);
    a
}

fn refused_args(class: &'static str, args: Vec<String>, needles: &[&str]) -> Case {
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    Case::refused(class, &a, needles)
}

/// The model's keys with their kind: from `corrugation model --json` (the default model),
/// plus the keys written only when they differ from their defaults.
fn keys(scratch: &Path) -> Vec<(String, &'static str)> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(["model", "--json"])
        .current_dir(scratch)
        .output()
        .expect("model --json runs");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("model JSON");
    let mut keys = Vec::new();
    for (section, table) in json.as_object().expect("sections") {
        for (key, value) in table.as_object().expect("keys") {
            let kind = match value {
                serde_json::Value::Number(n) if n.is_u64() => "int",
                serde_json::Value::Number(_) => "float",
                serde_json::Value::String(_) => "str",
                serde_json::Value::Bool(_) => "bool",
                serde_json::Value::Array(_) => "list",
                _ => continue,
            };
            keys.push((format!("{section}.{key}"), kind));
        }
    }
    for (k, kind) in [
        ("track.ends", "str"),
        ("track.absorbing_layer_length", "float"),
        ("track.absorbing_layer_rate", "float"),
        ("explicit.time_step", "float"),
        ("wheel.web_shape", "str"),
        ("wheel.web_bend", "float"),
        ("wheel.web_thickness", "float"),
        ("wheel.web_offset", "float"),
        ("wheel.rim_width", "float"),
        ("wheel.rim_thickness", "float"),
        ("wheel.brake_disc", "bool"),
    ] {
        keys.push((k.to_string(), kind));
    }
    keys
}

/// Every model key with values of the wrong kind or far out of any range: refused by
/// `corrugation model` with the key named.
fn model_keys(scratch: &Path) -> Vec<Case> {
    let mut v = Vec::new();
    for (key, kind) in keys(scratch) {
        let values: &[&str] = match kind {
            "float" => &[
                "nan", "inf", "-inf", "1e30", "-1e30", "\"abc\"", "true", "[1.0]",
            ],
            "int" => &[
                "-1",
                "1e30",
                "99999999999",
                "nan",
                "\"abc\"",
                "1.5",
                "{ a = 1 }",
            ],
            "str" => &["1", "\"bogus\"", "true", "\"\""],
            "bool" => &["1", "\"yes\""],
            _ => &["3", "[0, 10, 2]", "[4, 10]", "[100000, 100000, 100000]"],
        };
        for value in values {
            let set = format!("{key}={value}");
            v.push(Case::refused(
                "model key",
                &["model", "--set", &set],
                &[&key],
            ));
        }
    }
    for (set, needle) in [
        ("rail.no_such_key=1", "no_such_key"),
        ("nosection.key=1", "nosection"),
        ("rail=1", "rail"),
        ("rail.density", "rail.density"),
        ("=1", "--set"),
        ("rail.density=1=2", "rail.density"),
        ("rail.density=\"7800", "rail.density"),
    ] {
        v.push(Case::refused(
            "model key",
            &["model", "--set", set],
            &[needle],
        ));
    }
    v
}

/// A flag's bad values: each refused, the flag named.
struct FlagCases {
    cmd: &'static str,
    /// Whether the command reads the model, a cache and an output directory (then it runs on
    /// the small model with all three in the case's directory).
    modelled: bool,
    flag: &'static str,
    values: &'static [&'static str],
    extra: &'static [&'static str],
}

const NON_FINITE: &[&str] = &["nan", "inf", "-inf", "abc", ""];

/// Every numeric and list flag of every command with bad values.
fn flags() -> Vec<Case> {
    let f = |cmd, modelled, flag, values, extra| FlagCases {
        cmd,
        modelled,
        flag,
        values,
        extra,
    };
    let table = [
        f(
            "contact",
            false,
            "--normal-load",
            &["-1", "0", "1e30"][..],
            &[][..],
        ),
        f("contact", false, "--creepage", &["2", "-2", "1e30"], &[]),
        f(
            "contact",
            false,
            "--traction-coefficient",
            &["2", "-2", "1e30"],
            &[],
        ),
        f(
            "contact",
            false,
            "--friction",
            &["-1", "0", "3", "1e30"],
            &[],
        ),
        f(
            "contact",
            false,
            "--steps",
            &["0", "-1", "10001", "1.5", "1e30"],
            &[],
        ),
        f("modes", true, "--fmax", &["-1", "0", "1e-12", "1e30"], &[]),
        f(
            "modes",
            true,
            "--vtu-modes",
            &["-1", "1.5", "1e30"],
            &["--vtu"],
        ),
        f("receptance", true, "--from-hz", &["-1", "1e30"], &[]),
        f("receptance", true, "--to-hz", &["-1", "0", "1e30"], &[]),
        f("receptance", true, "--step-hz", &["-1", "0", "1e-12"], &[]),
        f("receptance", true, "--at", &["-1", "100", "1e30"], &[]),
        f("coupled-modes", true, "--at", &["-1", "100", "1e30"], &[]),
        f("coupled-modes", true, "--list-to-hz", &["-1"], &[]),
        f("passage", true, "--nodal-at", &["-1", "100", "1e30"], &[]),
        f(
            "grow",
            true,
            "--amplitudes-um",
            &["-1", "0", "10,,20", "10,10", "1e9", "1e30"],
            &[],
        ),
        f(
            "grow",
            true,
            "--rounds",
            &["-1", "1.5", "1000000", "1e30"],
            &[],
        ),
        f(
            "grow",
            true,
            "--passages-per-round",
            &["-1", "0", "1.5", "1e30"],
            &[],
        ),
        f(
            "grow",
            true,
            "--rate-check",
            &["-1", "0", "10", "40,40", "1e30"],
            &[],
        ),
        f(
            "predict",
            true,
            "--amplitudes-um",
            &["-1", "0", "10,10", "1e30"],
            &[],
        ),
        f(
            "predict",
            true,
            "--speeds",
            &[
                "0:10:1",
                "60,60",
                "300:60:10",
                "10",
                "1:1000000:1",
                "60:100:0",
                "1e30",
            ],
            &[],
        ),
        f(
            "sweep",
            true,
            "--speeds",
            &["-1", "60,60", "60:60:0", "1:1000000:1", "39", "600", "1e30"],
            &[],
        ),
        f(
            "sweep",
            true,
            "--shard",
            &["3/2", "1/0", "x", "-1/2", "0/0", "1/2/3"],
            &[],
        ),
        f(
            "initiation",
            true,
            "--speed",
            &["-1", "0", "39", "600", "1e30"],
            &[],
        ),
        f(
            "initiation",
            true,
            "--min-relative-wear",
            &["-1", "2", "1e30"],
            &[],
        ),
        f(
            "initiation",
            true,
            "--max-wavelength-deviation",
            &["-1"],
            &[],
        ),
        f(
            "initiation",
            true,
            "--peaks",
            &["0", "-1", "21", "1.5", "1e30"],
            &[],
        ),
        f(
            "initiation",
            true,
            "--variants",
            &["RPM9", "RPM1,RPM1", ","],
            &[],
        ),
        f(
            "compliance",
            false,
            "--elastic",
            &["-1", "0", "1e30"],
            &["--out", "{dir}/out"],
        ),
        f(
            "compliance",
            false,
            "--vertical",
            &["-1", "1e30"],
            &["--out", "{dir}/out"],
        ),
        f(
            "compliance",
            false,
            "--longitudinal",
            &["1e30"],
            &["--out", "{dir}/out"],
        ),
        f(
            "compliance",
            false,
            "--x",
            &["-1", "100", "1e30"],
            &["--out", "{dir}/out"],
        ),
        f(
            "compliance",
            false,
            "--ahead",
            &["-1", "100", "1e30"],
            &["--out", "{dir}/out"],
        ),
        f(
            "compliance",
            false,
            "--variants",
            &["RPM9", "RPM1,RPM1"],
            &["--out", "{dir}/out"],
        ),
        f(
            "cache",
            false,
            "--max-size-gb",
            &["-1"],
            &["--cache", "{dir}/cache"],
        ),
        f(
            "cache",
            false,
            "--max-idle-days",
            &["-1"],
            &["--cache", "{dir}/cache"],
        ),
    ];
    let mut v = Vec::new();
    for t in table {
        // the kind's own bad values, then the non-finite and non-numeric ones for numbers
        let list_of_names = t.flag == "--variants" || t.flag == "--shard";
        let mut values: Vec<&str> = t.values.to_vec();
        if !list_of_names {
            values.extend(NON_FINITE);
        }
        for value in values {
            let mut rest: Vec<&str> = t.extra.to_vec();
            rest.extend([t.flag, value]);
            let args = if t.modelled {
                small(t.cmd, &rest)
            } else {
                std::iter::once(t.cmd)
                    .chain(rest)
                    .map(str::to_string)
                    .collect()
            };
            v.push(refused_args("flag", args, &[t.flag]));
        }
    }
    for (cmd, flag, value) in [("passage", "--engine", "bogus"), ("sweep", "--engine", "")] {
        v.push(refused_args("flag", small(cmd, &[flag, value]), &[flag]));
    }
    v.push(refused_args(
        "flag",
        small_explicit(&["--wheel", "bogus"]),
        &["--wheel"],
    ));
    v
}

/// `study s.toml` refused naming `needle`, with `--out` and `--cache` as given.
fn study_refused(class: &'static str, out: &str, cache: &str, needle: &str) -> Case {
    Case::refused(
        class,
        &["study", "{dir}/s.toml", "--out", out, "--cache", cache],
        &[needle],
    )
}

/// A valid study file of one case (the default model's rail density) at one speed.
const STUDY: &str = "title = \"t\"\nmodel = \"builtin:dutch\"\nspeeds_kmh = [140.0]\ngrowth = false\n\n[[parameter]]\nkey = \"rail.density\"\nvalues = [7800.0]\n";

/// Hostile model files, rail profiles and study files; paths with spaces and non-ASCII.
fn input_files() -> Vec<Case> {
    let mut v = Vec::new();
    let model = |text: &[u8], needle: &str| {
        Case::refused(
            "input file",
            &["model", "--model", "{dir}/m.toml"],
            &[needle],
        )
        .file("m.toml", text.to_vec())
    };
    for (text, needle) in [
        (&b""[..], "m.toml"),
        (b"\xff\xfe\x00garbage\x00", "m.toml"),
        (b"[rail\ndensity = 7800", "m.toml"),
        (b"extends = \"builtin:dutch\"\n[rail]\nfoo = 1\n", "foo"),
        (b"extends = \"builtin:dutch\"\n[nosuch]\nx = 1\n", "nosuch"),
        (
            b"extends = \"builtin:dutch\"\n[rail]\ndensity = 1\ndensity = 2\n",
            "m.toml",
        ),
        (
            b"extends = \"builtin:dutch\"\n[track]\nbays = 99999999999999999999\n",
            "m.toml",
        ),
        (b"extends = \"m.toml\"\n", "extends"),
        (b"extends = \"missing.toml\"\n", "missing.toml"),
        (b"extends = 3\n", "extends"),
        (b"extends = \"builtin:nosuch\"\n", "nosuch"),
        (b"extends = \"builtin:dutch\"\nrail = 3\n", "rail"),
        (
            b"extends = \"builtin:dutch\"\n[rail]\ndensity = \"7800 kg/m3\"\n",
            "rail.density",
        ),
        (
            b"extends = \"builtin:dutch\"\n[track]\nbays = 1000000\n",
            "track.bays",
        ),
    ] {
        v.push(model(text, needle));
    }
    // a cycle of two files and a deep chain that ends in a cycle
    v.push(
        Case::refused(
            "input file",
            &["model", "--model", "{dir}/a.toml"],
            &["extends"],
        )
        .file("a.toml", "extends = \"b.toml\"\n")
        .file("b.toml", "extends = \"a.toml\"\n"),
    );
    let mut deep = Case::refused(
        "input file",
        &["model", "--model", "{dir}/c0.toml"],
        &["extends"],
    );
    for i in 0..40 {
        deep = deep.file(
            &format!("c{i}.toml"),
            format!("extends = \"c{}.toml\"\n", (i + 1) % 40),
        );
    }
    v.push(deep);
    v.push(Case::refused(
        "input file",
        &["model", "--model", "{dir}"],
        &["{dir}"],
    ));
    v.push(Case::refused(
        "input file",
        &["model", "--model", "{dir}/absent.toml"],
        &["absent.toml"],
    ));
    // paths with spaces and non-ASCII letters: valid, they run
    v.push(
        Case::runs(
            "input file",
            &["model", "--model", "{dir}/mödel dir/ü m.toml"],
        )
        .file(
            "mödel dir/ü m.toml",
            "extends = \"builtin:dutch\"\n[rail]\ndensity = 7850.0\n",
        ),
    );
    v.push(
        Case::runs(
            "input file",
            &["contact", "--json", "--out", "{dir}/out/résultat 1"],
        )
        .after(|dir, _| {
            let d = dir.join("out/résultat 1");
            let files = std::fs::read_dir(&d).map_or(0, Iterator::count);
            if files > 0 {
                Ok(())
            } else {
                Err(format!("nothing written into {}", d.display()))
            }
        }),
    );
    // rail profiles: refused before any modes are solved
    for (text, needle) in [
        ("", "c.csv"),
        ("x_m,height_um\n", "c.csv"),
        ("x_m,height_um\n1.0,5\n", "c.csv"),
        ("x_m,height_um\n1.0,nan\n1.1,5\n", "c.csv"),
        ("x_m,height_um\n1.0,abc\n1.1,5\n", "c.csv"),
        ("x_m,height_um\n1.1,5\n1.0,5\n", "c.csv"),
        ("x_m,height_um\n1.0,5\n1.0,6\n", "c.csv"),
        ("x_m;height_um\n1.0;5\n1.1;6\n", "c.csv"),
        ("x_m,height_um\n1.0,5,7\n1.1,6,8\n", "c.csv"),
        ("1.0,5\n1.1,6\n", "c.csv"),
        ("x_m,height_um\n1.0,inf\n1.1,6\n", "c.csv"),
    ] {
        v.push(
            refused_args(
                "input file",
                small("passage", &["--corrugation", "{dir}/c.csv"]),
                &[needle],
            )
            .file("c.csv", text),
        );
    }
    v.push(refused_args(
        "input file",
        small("passage", &["--corrugation", "{dir}/absent.csv"]),
        &["absent.csv"],
    ));
    // study files: refused before any passage runs
    let study = |text: &str, needle: &str| {
        study_refused("input file", "{dir}/out", "{dir}/cache", needle).file("s.toml", text)
    };
    let base = STUDY;
    for (text, needle) in [
        (String::new(), "s.toml"),
        ("title = \"t\"\n".to_string(), "s.toml"),
        (
            base.replace("speeds_kmh", "nosuch = 1\nspeeds_kmh"),
            "nosuch",
        ),
        (base.replace("[140.0]", "[]"), "speeds_kmh"),
        (base.replace("[140.0]", "[140.0, 140.0]"), "140"),
        (base.replace("[140.0]", "[10.0]"), "speeds_kmh"),
        (base.replace("[140.0]", "[\"fast\"]"), "speeds_kmh"),
        (base.replace("builtin:dutch", "absent.toml"), "absent.toml"),
        (base.replace("rail.density", "rail.nosuch"), "rail.nosuch"),
        (base.replace("[7800.0]", "[]"), "values"),
        (base.replace("[7800.0]", "[-1.0]"), "rail.density"),
        (
            base.replace(
                "speeds_kmh",
                "set = [\"rail.youngs_modulus=nan\"]\nspeeds_kmh",
            ),
            "rail.youngs_modulus",
        ),
    ] {
        v.push(study(&text, needle));
    }
    v
}

/// Whether a failed merge left nothing at its `--out` (`dir/m`).
fn no_merge_output(dir: &Path, _: &Output) -> Result<(), String> {
    if dir.join("m").exists() {
        Err("the failed merge left its output directory".into())
    } else {
        Ok(())
    }
}

/// A cache that is not a cache, a file where a directory belongs, merges of what is not a
/// sweep.
fn cache_and_merge() -> Vec<Case> {
    let mut v = Vec::new();
    // a project folder given as the cache: refused, nothing removed
    fn project_intact(dir: &Path, _: &Output) -> Result<(), String> {
        for f in ["proj/notes.txt", "proj/data/run.csv"] {
            if !dir.join(f).is_file() {
                return Err(format!("{f} was removed"));
            }
        }
        Ok(())
    }
    v.push(
        Case::refused(
            "cache",
            &["cache", "--cache", "{dir}/proj", "--max-size-gb", "0"],
            &["--force"],
        )
        .file("proj/notes.txt", "mine")
        .file("proj/data/run.csv", "1,2")
        .after(project_intact),
    );
    v.push(
        Case::runs(
            "cache",
            &[
                "cache",
                "--cache",
                "{dir}/proj",
                "--max-idle-days",
                "0",
                "--force",
            ],
        )
        .file("proj/notes.txt", "mine")
        .file("proj/data/run.csv", "1,2")
        .after(project_intact),
    );
    v.push(
        Case::refused("cache", &["cache", "--cache", "{dir}/f"], &["{dir}/f"]).file("f", "a file"),
    );
    v.push(Case::runs(
        "cache",
        &["cache", "--cache", "{dir}/new cache ü", "--json"],
    ));
    // --out inside the cache
    v.push(Case::refused(
        "cache",
        &["modes", "--cache", "{dir}/c", "--out", "{dir}/c/out"],
        &["--out"],
    ));
    // merges of what is not a sweep
    v.push(
        Case::refused(
            "merge",
            &["merge", "{dir}/a", "{dir}/b", "--out", "{dir}/m"],
            &["{dir}/a"],
        )
        .file("a/notes.txt", "x")
        .file("b/notes.txt", "y"),
    );
    // hostile JSON in a shard: the bad file named, nothing written
    for (file, text) in [
        ("a/sweep.json", "{\"speeds\": ["),
        ("a/sweep.json", "\u{feff}\u{0}"),
        ("a/sweep.json", "[1, 2, 3]"),
    ] {
        v.push(
            Case::refused(
                "merge",
                &["merge", "{dir}/a", "--out", "{dir}/m"],
                &["{dir}/a/sweep.json"],
            )
            .file(file, text)
            .file("a/speeds/run.key", "garbage")
            .after(no_merge_output),
        );
    }
    v.push(Case::refused(
        "merge",
        &["merge", "{dir}/absent", "--out", "{dir}/m"],
        &["absent"],
    ));
    v.push(Case::refused(
        "merge",
        &["merge", "--out", "{dir}/m"],
        &["merge"],
    ));
    v
}

/// The failures of an earlier fault and bad-input campaign, one case each.
fn campaign() -> Vec<Case> {
    let mut v = Vec::new();
    // a profile a billion µm high: refused before any grid is built (it hung, 1e15 aborted)
    for h in ["1e9", "1e15"] {
        v.push(
            refused_args(
                "campaign",
                small("passage", &["--corrugation", "{dir}/c.csv"]),
                &["c.csv"],
            )
            .file("c.csv", format!("x_m,height_um\n1.5,0\n1.52,{h}\n1.54,0\n"))
            .timeout(20.0),
        );
    }
    // an explicit time step of hours of work: refused with its estimate
    v.push(refused_args(
        "campaign",
        small_explicit(&["--set", "explicit.time_step=1e-10"]),
        &["explicit.time_step"],
    ));
    // a study of 200 000 speeds: refused like a sweep of as many
    let speeds: Vec<String> = (0..200_000)
        .map(|i| format!("{:.4}", 60.0 + i as f64 * 1e-3))
        .collect();
    v.push(
        study_refused("campaign", "{dir}/out", "{dir}/cache", "speeds_kmh").file(
            "s.toml",
            STUDY.replace("[140.0]", &format!("[{}]", speeds.join(", "))),
        ),
    );
    // study checks --out and --cache before computing
    v.push(
        study_refused("campaign", "{dir}/f/out", "{dir}/cache", "--out")
            .file("f", "a file")
            .file("s.toml", STUDY)
            .timeout(10.0),
    );
    v.push(
        study_refused("campaign", "{dir}/out", "{dir}/f", "--cache")
            .file("f", "a file")
            .file("s.toml", STUDY)
            .timeout(10.0),
    );
    // keys once blamed on something else, refused naming themselves
    for (set, key) in [
        ("vehicle.primary_stiffness=1.0", "vehicle.primary_stiffness"),
        (
            "vehicle.primary_stiffness=1e-12",
            "vehicle.primary_stiffness",
        ),
        ("run.solution_zone_length=0.01", "run.solution_zone_length"),
    ] {
        v.push(refused_args(
            "campaign",
            small("passage", &["--set", set]),
            &[key],
        ));
    }
    v.push(refused_args(
        "campaign",
        small(
            "passage",
            &[
                "--set",
                "fastening.hold=\"elastic\"",
                "--set",
                "fastening.hold_stiffness=1e-12",
            ],
        ),
        &["fastening.hold_stiffness"],
    ));
    // compliance --elastic values are the flag's, not a model key's
    v.push(Case::refused(
        "campaign",
        &["compliance", "--elastic", "nan", "--out", "{dir}/out"],
        &["--elastic"],
    ));
    // a profile entirely off the wheel's travel
    v.push(
        refused_args(
            "campaign",
            small_shared_cache("passage", &["--corrugation", "{dir}/c.csv"]),
            &["--corrugation", "c.csv", "entirely off"],
        )
        .file("c.csv", "x_m,height_um\n50.0,0\n50.02,20\n50.04,0\n")
        // the modes are loaded (or solved once) before the travel is known
        .timeout(180.0),
    );
    // `merge --out` one of its own shards
    v.push(
        Case::refused(
            "campaign",
            &["merge", "{dir}/a", "--out", "{dir}/a"],
            &["--out"],
        )
        .file("a/notes.txt", "x")
        .after(|dir, _| {
            if dir.join("a/notes.txt").is_file() {
                Ok(())
            } else {
                Err("the shard was touched".into())
            }
        }),
    );
    // a failed merge leaves nothing behind
    v.push(
        Case::refused(
            "campaign",
            &["merge", "{dir}/a", "--out", "{dir}/m"],
            &["{dir}/a"],
        )
        .file("a/notes.txt", "x")
        .after(no_merge_output),
    );
    v.push(Case::refused(
        "campaign",
        &["cache", "--cache", "{dir}/c", "--max-size-gb", "-1"],
        &["--max-size-gb"],
    ));
    v
}

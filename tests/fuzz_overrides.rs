//! A small fuzz test of the model overrides: bad values (zero, negative, tiny, huge,
//! non-finite, wrong type) for the model's numeric keys, run through `mesh --json` on the
//! small model with a time limit each. Whatever the value, the binary must not panic, hang
//! or abort, and must either fail with a one-line error naming a model key or succeed with
//! finite numbers. The cases are drawn by a fixed-seed generator (same cases every run) and
//! kept to about 16 s of CI time.

mod common;

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::SMALL_MODEL;

/// Every numeric key of the model.
const KEYS: [&str; 57] = [
    "track.bays",
    "track.sleeper_spacing",
    "rail.inclination",
    "rail.youngs_modulus",
    "rail.poisson_ratio",
    "rail.density",
    "sleeper.length",
    "sleeper.width",
    "sleeper.height",
    "sleeper.rail_seat",
    "sleeper.youngs_modulus",
    "sleeper.poisson_ratio",
    "sleeper.density",
    "fastening.rows",
    "fastening.columns",
    "fastening.footprint_length",
    "fastening.footprint_width",
    "fastening.strip_width",
    "fastening.pad_thickness",
    "fastening.vertical_stiffness",
    "fastening.vertical_damping",
    "fastening.lateral_stiffness",
    "fastening.lateral_damping",
    "fastening.longitudinal_stiffness",
    "fastening.longitudinal_damping",
    "ballast.vertical_stiffness",
    "ballast.vertical_damping",
    "ballast.lateral_stiffness",
    "ballast.lateral_damping",
    "ballast.longitudinal_stiffness",
    "ballast.longitudinal_damping",
    "wheel.radius",
    "wheel.conicity",
    "wheel.youngs_modulus",
    "wheel.poisson_ratio",
    "wheel.density",
    "wheel.damping_ratio",
    "vehicle.wheel_load",
    "vehicle.primary_stiffness",
    "vehicle.primary_damping",
    "vehicle.gravity",
    "contact.friction",
    "contact.traction_coefficient",
    "contact.rail_crown_radius",
    "contact.grid_nx",
    "contact.grid_ny",
    "contact.grid_margin",
    "mesh.fine_element_length",
    "mesh.section_size",
    "mesh.head_size",
    "mesh.wheel_segments",
    "mesh.wheel_element_size",
    "run.speed_kmh",
    "run.solution_zone_offset",
    "run.fmax",
    "wear.coefficient",
    "explicit.time_step",
];

/// Bad values in TOML syntax.
const VALUES: [&str; 16] = [
    "0",
    "-1",
    "-0.0",
    "1e-12",
    "1e-4",
    "0.499",
    "3",
    "1e12",
    "1e300",
    "nan",
    "inf",
    "-inf",
    "18446744073709551615",
    "\"text\"",
    "[1, 2]",
    "true",
];

/// Cases run (each about 0.1 s on the small model: 150 take about 16 s).
const CASES: usize = 150;

/// Time limit of one case: far above a small-model mesh, far below a hang.
const LIMIT: Duration = Duration::from_secs(30);

/// xorshift64*: a fixed sequence, no dependency.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % n
    }
}

/// Runs the binary with a time limit: (exit code, stdout, stderr); `None` on a hang.
fn run_limited(args: &[&str]) -> Option<(i32, String, String)> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let (mut out, mut err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        out.read_to_string(&mut s).ok();
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        err.read_to_string(&mut s).ok();
        s
    });
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break Some(s);
        }
        if t0.elapsed() > LIMIT {
            child.kill().ok();
            child.wait().ok();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (stdout, stderr) = (reader.join().unwrap(), err_reader.join().unwrap());
    status.map(|s| (s.code().unwrap_or(-1), stdout, stderr))
}

/// All numbers of a JSON value are finite (serde_json cannot hold NaN; checked anyway).
fn all_finite(v: &serde_json::Value) -> bool {
    match v {
        serde_json::Value::Number(n) => n.as_f64().is_some_and(f64::is_finite),
        serde_json::Value::Array(a) => a.iter().all(all_finite),
        serde_json::Value::Object(o) => o.values().all(all_finite),
        _ => true,
    }
}

#[test]
fn bad_overrides_give_a_one_line_error_naming_a_key_or_finite_results() {
    let sections: Vec<String> = KEYS
        .iter()
        .map(|k| format!("{}.", k.split('.').next().unwrap()))
        .collect();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut problems = Vec::new();
    for _ in 0..CASES {
        let set = format!(
            "{}={}",
            KEYS[rng.below(KEYS.len())],
            VALUES[rng.below(VALUES.len())]
        );
        let mut args = vec!["mesh", "--json"];
        args.extend(SMALL_MODEL);
        // The override comes last so that it wins over the small model's.
        args.extend(["--set", &set]);
        let Some((code, out, err)) = run_limited(&args) else {
            problems.push(format!("{set}: no answer within {LIMIT:?} (hang)"));
            continue;
        };
        if code == 101 || err.contains("panicked") || code < 0 {
            problems.push(format!("{set}: panic or abort (code {code}): {err}"));
        } else if code == 0 {
            match serde_json::from_str::<serde_json::Value>(&out) {
                Ok(v) if all_finite(&v) => {}
                _ => problems.push(format!("{set}: exit 0 with non-finite output: {out}")),
            }
        } else if !common::is_one_line_error(&err)
            || !sections.iter().any(|s| err.contains(s.as_str()))
        {
            problems.push(format!("{set}: not a one-line error naming a key: {err}"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

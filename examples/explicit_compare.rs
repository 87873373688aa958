//! Side-by-side comparison of passage output directories (the `passage` / `explicit`
//! commands' `summary.json` and `wear.csv`): the validation table of
//! validation/explicit.md. The first directory is the reference (the explicit path); every
//! other one is compared with it against the pre-registered tolerances of that page.
//!
//! ```sh
//! cargo run --release --example explicit_compare -- DIR_EXPLICIT DIR_REDUCED [DIR ...]
//! ```

use std::path::Path;

/// Pre-registered tolerances (validation/explicit.md).
const TOL_MEAN: f64 = 0.01;
const TOL_DOMINANT: f64 = 0.01;
const TOL_RMS: f64 = 0.10;
const MIN_CORRELATION: f64 = 0.9;

fn summary(dir: &Path) -> serde_json::Value {
    let p = dir.join("summary.json");
    let s = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&s).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn band_wear(dir: &Path) -> Vec<(f64, f64)> {
    let p = dir.join("wear.csv");
    let mut r = csv::Reader::from_path(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    r.records()
        .map(|rec| {
            let rec = rec.expect("csv row");
            (rec[0].parse().unwrap(), rec[2].parse().unwrap())
        })
        .collect()
}

fn num(v: &serde_json::Value, k: &str) -> f64 {
    v[k].as_f64().unwrap_or(f64::NAN)
}

fn peaks(v: &serde_json::Value, k: &str) -> Vec<f64> {
    v[k].as_array()
        .map(|a| {
            a.iter()
                .take(3)
                .filter_map(|c| c["frequency_hz"].as_f64())
                .collect()
        })
        .unwrap_or_default()
}

/// Correlation coefficient and the lag (mm) of the cross-correlation maximum within ±40 mm
/// of two band-passed wear signals on the same bins.
fn correlation(a: &[(f64, f64)], b: &[(f64, f64)]) -> (f64, f64) {
    let n = a.len().min(b.len());
    let dot = |s: isize| -> f64 {
        (0..n as isize)
            .filter_map(|i| {
                let j = i + s;
                (j >= 0 && (j as usize) < n).then(|| a[i as usize].1 * b[j as usize].1)
            })
            .sum()
    };
    let na: f64 = a[..n].iter().map(|x| x.1 * x.1).sum::<f64>().sqrt();
    let nb: f64 = b[..n].iter().map(|x| x.1 * x.1).sum::<f64>().sqrt();
    let dx = if n > 1 { a[1].0 - a[0].0 } else { 1.0 };
    let max_shift = (0.04 / dx).round() as isize;
    let (mut best, mut lag) = (f64::NEG_INFINITY, 0isize);
    for s in -max_shift..=max_shift {
        let c = dot(s);
        if c > best {
            best = c;
            lag = s;
        }
    }
    (dot(0) / (na * nb), lag as f64 * dx * 1e3)
}

fn main() {
    let dirs: Vec<String> = std::env::args().skip(1).collect();
    if dirs.len() < 2 {
        eprintln!("usage: explicit_compare DIR_EXPLICIT DIR_OTHER [DIR ...]");
        std::process::exit(2);
    }
    let refd = Path::new(&dirs[0]);
    let r = summary(refd);
    let rw = band_wear(refd);
    println!("| quantity | {} | {} |", dirs[0], dirs[1..].join(" | "));
    println!("|---|---|{}", "---|".repeat(dirs.len() - 1));
    let others: Vec<(serde_json::Value, Vec<(f64, f64)>)> = dirs[1..]
        .iter()
        .map(|d| (summary(Path::new(d)), band_wear(Path::new(d))))
        .collect();
    let mut misses = Vec::new();
    let rel = |a: f64, b: f64| (a - b) / b;
    for (k, tol, name) in [
        ("mean_fn_n", TOL_MEAN, "mean F_N (N)"),
        ("mean_fl_n", TOL_MEAN, "mean F_L (N)"),
        (
            "dominant_frequency_hz",
            TOL_DOMINANT,
            "dominant wear frequency (Hz)",
        ),
        ("fl_band_rms_n", TOL_RMS, "band RMS F_L (N)"),
        ("fn_band_rms_n", TOL_RMS, "band RMS F_N (N)"),
        ("wear_band_rms", TOL_RMS, "band RMS wear (J/m)"),
    ] {
        let a = num(&r, k);
        let cells: Vec<String> = others
            .iter()
            .enumerate()
            .map(|(i, (o, _))| {
                let b = num(o, k);
                let e = rel(b, a);
                let pass = e.abs() <= tol;
                if !pass {
                    misses.push(format!(
                        "{}: {name} {:+.1} % (tolerance ±{:.0} %)",
                        dirs[i + 1],
                        100.0 * e,
                        100.0 * tol
                    ));
                }
                format!(
                    "{b:.4} ({:+.1} %{})",
                    100.0 * e,
                    if pass { "" } else { ", MISS" }
                )
            })
            .collect();
        println!("| {name} | {a:.4} | {} |", cells.join(" | "));
    }
    for (k, name) in [
        ("wear_components", "top-3 wear peaks (Hz)"),
        ("fl_components", "top-3 F_L peaks (Hz)"),
        ("fn_components", "top-3 F_N peaks (Hz)"),
    ] {
        let f = |v: &serde_json::Value| {
            peaks(v, k)
                .iter()
                .map(|x| format!("{x:.0}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let cells: Vec<String> = others.iter().map(|(o, _)| f(o)).collect();
        println!("| {name} | {} | {} |", f(&r), cells.join(" | "));
    }
    let cells: Vec<String> = others
        .iter()
        .enumerate()
        .map(|(i, (_, w))| {
            let (c, lag) = correlation(&rw, w);
            if c < MIN_CORRELATION {
                misses.push(format!(
                    "{}: band-passed wear correlation {c:.2} (< {MIN_CORRELATION})",
                    dirs[i + 1]
                ));
            }
            format!("{c:.3}, lag {lag:+.1} mm")
        })
        .collect();
    println!(
        "| band-passed wear: correlation, lag of best match | 1 | {} |",
        cells.join(" | ")
    );
    println!();
    if misses.is_empty() {
        println!("All within the pre-registered tolerances.");
    } else {
        println!("Misses:");
        for m in misses {
            println!("- {m}");
        }
    }
}

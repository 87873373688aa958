//! Where the band RMS of passage output directories comes from: the product's 20–80 mm
//! band-pass (docs/theory.md §9.2) has raised-cosine roll-offs *outside* the band (gain 1
//! at 80 mm falling to 0 at 133 mm, and at 20 mm falling to 0 at 18.2 mm), so a strong line
//! just outside the band (for example at 100 mm) still counts in `fl_band_rms_n`. This
//! example splits the band RMS of F_L, F_N and the wear of each directory into
//!
//! - `product`: the product's filter (reproduces `summary.json`'s band RMS);
//! - `inside`: the band with its roll-offs *inside* it ([`BandPass::inside`], the summaries'
//!   `*_inside_band_rms`: gain 0 outside 20–80 mm, 1 on 22.2–57.1 mm), so nothing outside
//!   the band counts;
//! - `below`: the content just below the band (gain 1 on 95–143 mm, 0 outside 80–200 mm),
//!   which the product's low-side roll-off partly passes (gain 0.59 at 97 mm, 0.30 at
//!   107 mm);
//! - `first half`, `second half`: the product's band-passed signal's RMS over the first and
//!   the second half of the solution zone (a start transient shows as a larger first half),
//!   and the same for `inside`.
//!
//! The first directory is the reference; the others get ratios to it. It reads each
//! directory's `forces.csv` (the whole passage) and `wear.csv` (the solution zone, whose
//! ends are taken as the zone's).
//!
//! ```sh
//! cargo run --release --example band_split -- DIR_REF DIR [DIR ...]
//! ```

use corrugation::spectral::{band_pass, BandPass, Signal};
use std::path::Path;

/// Reads columns `cols` (by header name) of a CSV file.
fn columns(path: &Path, cols: &[&str]) -> Vec<Vec<f64>> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let head = r.headers().expect("csv header").clone();
    let idx: Vec<usize> = cols
        .iter()
        .map(|c| {
            head.iter()
                .position(|h| h == *c)
                .unwrap_or_else(|| panic!("{}: no column {c}", path.display()))
        })
        .collect();
    let mut out = vec![Vec::new(); cols.len()];
    for rec in r.records() {
        let rec = rec.expect("csv row");
        for (o, &i) in out.iter_mut().zip(&idx) {
            o.push(rec[i].parse::<f64>().expect("number"));
        }
    }
    out
}

/// The RMS of samples `from..to`.
fn rms(x: &[f64], from: usize, to: usize) -> f64 {
    (x[from..to].iter().map(|v| v * v).sum::<f64>() / (to - from) as f64).sqrt()
}

/// The five figures of one signal along the rail.
fn split(x0: f64, dx: f64, values: &[f64]) -> [f64; 7] {
    let sig = Signal::new(x0, dx, values.to_vec()).expect("signal");
    let filt = |b: BandPass| band_pass(&sig, &b).expect("band pass").values;
    let product = filt(BandPass::default());
    // The summaries' inside-band filter: gain 0 outside 20-80 mm, 1 on 22.2-57.1 mm.
    let inside = filt(BandPass::default().inside().expect("the default band"));
    // 80-200 mm, roll-offs of 2 m^-1 inside it: gain 1 on 95-143 mm, 0 outside 80-200 mm.
    let below = filt(BandPass {
        lambda_min_m: 1.0 / (12.5 - 2.0),
        lambda_max_m: 1.0 / (5.0 + 2.0),
        transition_per_m: 2.0,
    });
    let n = values.len();
    [
        rms(&product, 0, n),
        rms(&inside, 0, n),
        rms(&below, 0, n),
        rms(&product, 0, n / 2),
        rms(&product, n / 2, n),
        rms(&inside, 0, n / 2),
        rms(&inside, n / 2, n),
    ]
}

/// F_L, F_N (N) and the wear (J/m) figures of one directory.
fn directory(dir: &Path) -> [[f64; 7]; 3] {
    let w = columns(&dir.join("wear.csv"), &["x_m", "wf_j_per_m"]);
    let (z0, z1) = (w[0][0], *w[0].last().expect("wear rows"));
    let f = columns(&dir.join("forces.csv"), &["x_m", "fl_n", "fn_n"]);
    let i0 = f[0].partition_point(|&x| x < z0);
    let i1 = f[0].partition_point(|&x| x <= z1);
    let dxf = f[0][i0 + 1] - f[0][i0];
    let dxw = w[0][1] - w[0][0];
    [
        split(f[0][i0], dxf, &f[1][i0..i1]),
        split(f[0][i0], dxf, &f[2][i0..i1]),
        split(w[0][0], dxw, &w[1]),
    ]
}

fn main() {
    let dirs: Vec<String> = std::env::args().skip(1).collect();
    if dirs.is_empty() {
        eprintln!("usage: band_split DIR_REF [DIR ...]");
        std::process::exit(2);
    }
    let figs: Vec<[[f64; 7]; 3]> = dirs.iter().map(|d| directory(Path::new(d))).collect();
    let names = ["F_L (N)", "F_N (N)", "wear (J/m)"];
    let parts = [
        "product's band",
        "inside 20-80 mm",
        "below, 80-200 mm",
        "product's band, first half",
        "product's band, second half",
        "inside, first half",
        "inside, second half",
    ];
    println!("| band RMS | {} |", dirs.join(" | "));
    println!("|---|{}", "---|".repeat(dirs.len()));
    for (q, name) in names.iter().enumerate() {
        for (p, part) in parts.iter().enumerate() {
            let a = figs[0][q][p];
            let cells: Vec<String> = figs
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let b = f[q][p];
                    if i == 0 {
                        format!("{b:.4}")
                    } else {
                        format!("{b:.4} ({:+.1} %)", 100.0 * (b - a) / a)
                    }
                })
                .collect();
            println!("| {name}, {part} | {} |", cells.join(" | "));
        }
    }
}

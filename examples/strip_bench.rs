//! Benchmark of the influence products a local FE contact patch needs (FFT along x, dense
//! blocks across: `contact::influence::strip`) against the half-space's two-dimensional FFT
//! products (`contact::influence::Convolver`), per product, on the default passage grid
//! (32 × 24) and the contact bench's 44 × 32. The kernel is the half-space's in both, so the
//! results are compared too (largest relative difference). The last two columns are the
//! tangential products of the tangential solver's inner loop: on the contact's box only, in
//! single precision (`TangentialInfluence::tangential_box`).
//!
//! Run: `cargo run --release --example strip_bench [repeats]` (default 2,000 products each).

use corrugation::contact::influence::strip::{half_space_kernel, StripConvolver, StripInfluence};
use corrugation::contact::influence::{Convolver, TangentialInfluence};
use std::time::Instant;

#[path = "common/mod.rs"]
mod common;
use common::{cpu_seconds, machine_load};

/// Wall and CPU time per call (µs) of `f` over `reps` calls.
fn time(reps: usize, mut f: impl FnMut()) -> (f64, f64) {
    let (w, c) = (Instant::now(), cpu_seconds());
    for _ in 0..reps {
        f();
    }
    let per = |s: f64| 1e6 * s / reps as f64;
    (per(w.elapsed().as_secs_f64()), per(cpu_seconds() - c))
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

fn main() -> anyhow::Result<()> {
    let reps: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(2000);
    println!(
        "influence products per call (µs wall / µs CPU), {}",
        machine_load()
    );
    println!(
        "{:>8} {:>22} {:>22} {:>22} {:>22} {:>22} {:>10} {:>14} {:>22} {:>22}",
        "grid",
        "half-space normal",
        "strip normal",
        "half-space tangential",
        "strip tangential",
        "strip coupled (3 comp)",
        "max rel",
        "box",
        "half-space box (f32)",
        "strip box (f32)"
    );
    for (nx, ny) in [(32, 24), (44, 32)] {
        let (dx, dy) = (0.45e-3, 0.5e-3);
        let (es, g, nu) = (115e9, 80.8e9, 0.28);
        let mut conv = Convolver::new(nx, ny, dx, dy, es, g, nu);
        let kernel = |comps| half_space_kernel((dx, dy), (es, g, nu), comps);
        let mut sn = StripConvolver::new(nx, ny, 1, kernel(1));
        let mut st = StripConvolver::new(nx, ny, 2, kernel(2));
        let mut s3 = StripConvolver::new(nx, ny, 3, kernel(3));
        let mut si = StripInfluence::new(nx, ny, kernel(3));
        let n = nx * ny;
        // a Hertz-like pressure over the middle of the grid and a traction of the same shape
        let p: Vec<f64> = (0..n)
            .map(|k| {
                let (x, y) = (
                    (k / ny) as f64 / nx as f64 - 0.5,
                    (k % ny) as f64 / ny as f64 - 0.5,
                );
                1e9 * (1.0 - 9.0 * (x * x + y * y)).max(0.0).sqrt()
            })
            .collect();
        let q: Vec<f64> = p.iter().map(|v| 0.3 * v).collect();
        let (mut u1, mut u2) = (vec![0.0; n], vec![0.0; n]);
        let (mut v1, mut v2) = (vec![0.0; n], vec![0.0; n]);
        let (mut w1, mut w2, mut w3) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let hn = time(reps, || conv.normal(&p, &mut u1));
        let sn_t = time(reps, || sn.product(&[&p], &mut [&mut u2], 0));
        let ht = time(reps, || conv.tangential(&p, &q, &mut v1, &mut v2, 0));
        let st_t = time(reps, || st.product(&[&p, &q], &mut [&mut w1, &mut w2], 0));
        let s3_t = time(reps / 4, || {
            s3.product(&[&q, &q, &p], &mut [&mut w1, &mut w2, &mut w3], 0)
        });
        st.product(&[&p, &q], &mut [&mut w1, &mut w2], 0);
        let diff = rel_diff(&u1, &u2)
            .max(rel_diff(&v1, &w1))
            .max(rel_diff(&v2, &w2));
        // the box of the loaded elements
        let loaded = |i: usize, j: usize| p[i * ny + j] > 0.0;
        let rows: Vec<usize> = (0..nx).filter(|&i| (0..ny).any(|j| loaded(i, j))).collect();
        let cols: Vec<usize> = (0..ny).filter(|&j| (0..nx).any(|i| loaded(i, j))).collect();
        let (rb, cb) = (
            (rows[0], rows[rows.len() - 1] + 1),
            (cols[0], cols[cols.len() - 1] + 1),
        );
        let hb = time(reps, || {
            TangentialInfluence::tangential_box(&mut conv, &p, &q, &mut v1, &mut v2, rb, cb)
        });
        let sb = time(reps, || si.tangential_box(&p, &q, &mut w1, &mut w2, rb, cb));
        // both box products on zeroed fields: they write the box's rows only
        for v in [&mut v1, &mut v2, &mut w1, &mut w2] {
            v.fill(0.0);
        }
        TangentialInfluence::tangential_box(&mut conv, &p, &q, &mut v1, &mut v2, rb, cb);
        si.tangential_box(&p, &q, &mut w1, &mut w2, rb, cb);
        let box_diff = rel_diff(&v1, &w1).max(rel_diff(&v2, &w2));
        let f = |(w, c): (f64, f64)| format!("{w:.1} / {c:.1}");
        println!(
            "{:>8} {:>22} {:>22} {:>22} {:>22} {:>22} {:>10.1e} {:>14} {:>22} {:>22}",
            format!("{nx}×{ny}"),
            f(hn),
            f(sn_t),
            f(ht),
            f(st_t),
            f(s3_t),
            diff,
            format!("{}×{}", rb.1 - rb.0, cb.1 - cb.0),
            f(hb),
            format!("{} ({box_diff:.0e})", f(sb))
        );
    }
    Ok(())
}

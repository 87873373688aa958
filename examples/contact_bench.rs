//! Benchmark of the transient rolling contact step (normal + tangential) on grids that resolve
//! the reference contact (100 kN, a × b ≈ 7.2 × 5.4 mm), cold and warm started, and a
//! 0.25 m passage (of the ~2,500 steps per metre) with a varying normal load and a corrugated rail.
//!
//! Run: `cargo run --release --example contact_bench [passage_steps [normal_tol
//! [tangential_tol [forces.csv]]]]` (default 2,500 steps of the passage sequence on the 44 × 32
//! grid of the passage, the solver tolerances of [`TransientConfig::around_hertz`], forces
//! written to `target/contact_bench_forces.csv`).

use corrugation::contact::{
    GridSpec, Longitudinal, NormalInput, StepInputs, TransientConfig, TransientRolling,
    WearAccumulator,
};
use std::time::Instant;

#[path = "common/mod.rs"]
mod common;
use common::cpu_seconds;

/// Roll `steps` steps with constant inputs (two contact lengths ≈ steady) and return the last.
fn roll(
    eng: &mut TransientRolling,
    inp: &StepInputs,
    steps: usize,
) -> anyhow::Result<corrugation::contact::StepResult> {
    let mut r = eng.step(inp)?;
    for _ in 1..steps {
        r = eng.step(inp)?;
    }
    Ok(r)
}

/// Command-line argument `k` parsed, if given.
fn arg<T: std::str::FromStr>(k: usize) -> anyhow::Result<Option<T>>
where
    T::Err: std::error::Error + Send + Sync + 'static,
{
    Ok(std::env::args().nth(k).map(|a| a.parse()).transpose()?)
}

fn main() -> anyhow::Result<()> {
    let passage_steps: usize = arg(1)?.unwrap_or(2500);
    let defaults = TransientConfig::reference();
    let normal_tol = arg(2)?.unwrap_or(defaults.normal_tol);
    let tangential_tol = arg(3)?.unwrap_or(defaults.tangential_tol);
    let out = std::env::args()
        .nth(4)
        .unwrap_or_else(|| "target/contact_bench_forces.csv".into());
    println!("transient rolling step, reference case (R 0.46 / R300, 100 kN, µ 0.4, traction 0.15, 140 km/h)");
    println!(
        "{:>8} {:>8} {:>10} {:>10} {:>11} {:>12} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "grid",
        "dx_mm",
        "cold_ms",
        "warm_ms",
        "warm_cpu_ms",
        "warm_T_ms",
        "N_its",
        "N_prods",
        "T_prods",
        "all_prods",
        "fft_us"
    );
    for &(nx, ny) in &[(25usize, 25usize), (32, 26), (44, 32), (51, 51)] {
        let mut cfg = TransientConfig::reference();
        cfg.grid = GridSpec { nx, ny, ..cfg.grid };
        cfg.normal_tol = normal_tol;
        cfg.tangential_tol = tangential_tol;
        let mut eng = TransientRolling::new(cfg)?;
        // creepage for traction 0.15 (steady), then time steps at that creepage
        let st = roll(
            &mut eng,
            &StepInputs {
                normal: NormalInput::Force(100e3),
                longitudinal: Longitudinal::Force(15e3),
                lateral_creepage: 0.0,
                spin_per_m: 0.0,
                rail_height_m: None,
            },
            2 * nx,
        )?;
        let xi = st.creepage;
        // cold: fresh engine state, first step from rest
        let reps = 5;
        let t0 = Instant::now();
        for _ in 0..reps {
            eng.reset();
            eng.step(&StepInputs::force_creepage(100e3, xi))?;
        }
        let cold = t0.elapsed().as_secs_f64() / reps as f64;
        // warm: steady rolling with a varying load (1 kHz, ±10 %)
        eng.reset();
        roll(&mut eng, &StepInputs::force_creepage(100e3, xi), 2 * nx)?;
        let nsteps = 200;
        let dt = eng.time_step_s();
        let (mut nits, mut tits, mut prods) = (0usize, 0usize, 0usize);
        let t0 = Instant::now();
        let c0 = cpu_seconds();
        for k in 0..nsteps {
            let n =
                100e3 * (1.0 + 0.1 * (2.0 * std::f64::consts::PI * 1000.0 * k as f64 * dt).sin());
            let r = eng.step(&StepInputs::force_creepage(n, xi))?;
            nits += r.normal_iterations;
            tits += r.tangential_iterations;
            prods += r.influence_products;
        }
        let warm = t0.elapsed().as_secs_f64() / nsteps as f64;
        let warm_cpu = (cpu_seconds() - c0) / nsteps as f64;
        // warm with prescribed Fx (creepage solved per step)
        let t0 = Instant::now();
        for k in 0..10 {
            let n =
                100e3 * (1.0 + 0.1 * (2.0 * std::f64::consts::PI * 1000.0 * k as f64 * dt).sin());
            eng.step(&StepInputs {
                normal: NormalInput::Force(n),
                longitudinal: Longitudinal::Force(15e3),
                lateral_creepage: 0.0,
                spin_per_m: 0.0,
                rail_height_m: None,
            })?;
        }
        let warm_t = t0.elapsed().as_secs_f64() / 10.0;
        // cost of one tangential influence product (FFT pair)
        let conv_us = {
            use corrugation::contact::influence::Convolver;
            let g = corrugation::contact::shear_modulus(210e9, 0.3);
            let es = corrugation::contact::combined_modulus(210e9, 0.3);
            let mut c = Convolver::new(nx, ny, cfg.grid.dx(), cfg.grid.dy(), es, g, 0.3);
            let f = vec![1e6; nx * ny];
            let (mut a, mut b) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
            let t0 = Instant::now();
            for _ in 0..200 {
                c.tangential(&f, &f, &mut a, &mut b, 0);
            }
            t0.elapsed().as_secs_f64() / 200.0 * 1e6
        };
        println!(
            "{:>8} {:>8.3} {:>10.3} {:>10.3} {:>11.3} {:>12.3} {:>10.1} {:>10.1} {:>10.1} {:>10.1} {:>10.1}",
            format!("{nx}x{ny}"),
            cfg.grid.dx() * 1e3,
            cold * 1e3,
            warm * 1e3,
            warm_cpu * 1e3,
            warm_t * 1e3,
            nits as f64 / nsteps as f64,
            (prods - tits) as f64 / nsteps as f64,
            tits as f64 / nsteps as f64,
            prods as f64 / nsteps as f64,
            conv_us
        );
    }

    // Passage sequence on the passage's default 44 × 32 grid: approach prescribed, corrugated
    // rail (40 mm, 20 µm peak-to-trough), constant creepage; wear accumulated rail-fixed. The
    // forces of every step are written to `target/contact_bench_forces.csv` (to compare
    // solvers).
    let mut cfg = TransientConfig::reference();
    cfg.normal_tol = normal_tol;
    cfg.tangential_tol = tangential_tol;
    cfg.grid = GridSpec {
        nx: 44,
        ny: 32,
        half_length_x_m: 1.4 * 7.162e-3,
        half_length_y_m: 1.4 * 5.387e-3,
    };
    let mut eng = TransientRolling::new(cfg)?;
    let dx = cfg.grid.dx();
    let st = roll(
        &mut eng,
        &StepInputs {
            normal: NormalInput::Force(100e3),
            longitudinal: Longitudinal::Force(15e3),
            lateral_creepage: 0.0,
            spin_per_m: 0.0,
            rail_height_m: None,
        },
        2 * cfg.grid.nx,
    )?;
    let (xi, delta) = (st.creepage, st.approach_m);
    let nsteps = passage_steps;
    let mut wear = WearAccumulator::new(&eng, -0.05, nsteps + 200);
    let mut rail = vec![0.0; cfg.grid.nx];
    let xs: Vec<f64> = eng.x_m().to_vec();
    let mut forces = Vec::with_capacity(nsteps);
    let t0 = Instant::now();
    let c0 = cpu_seconds();
    let mut fmin = f64::INFINITY;
    let mut fmax = 0.0_f64;
    let (mut np, mut tp, mut ni) = (0usize, 0usize, 0usize);
    for k in 0..nsteps {
        let xc = k as f64 * dx;
        for (r, x) in rail.iter_mut().zip(&xs) {
            *r = 10e-6 * (2.0 * std::f64::consts::PI * (xc + x) / 0.04).sin();
        }
        let res = eng.step(&StepInputs {
            normal: NormalInput::Approach(delta),
            longitudinal: Longitudinal::Creepage(xi),
            lateral_creepage: 0.0,
            spin_per_m: 0.0,
            rail_height_m: Some(&rail),
        })?;
        np += res.influence_products - res.tangential_iterations;
        ni += res.normal_iterations;
        tp += res.tangential_iterations;
        fmin = fmin.min(res.normal_force_n);
        fmax = fmax.max(res.normal_force_n);
        forces.push((res.normal_force_n, res.fx_n, res.frictional_power_w));
        wear.add_step(&eng, xc);
    }
    let el = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - c0;
    println!(
        "passage sequence, 44x32 grid (dx {:.3} mm, tol N {:.0e} T {:.0e}): {} steps in {:.2} s wall, {:.2} s CPU ({:.3} ms/step CPU, {:.1} normal CG its, {:.1} normal + {:.1} tangential FFT pairs/step); F_N {:.1}..{:.1} kN; total frictional work {:.3} J",
        dx * 1e3,
        cfg.normal_tol,
        cfg.tangential_tol,
        nsteps,
        el,
        cpu,
        cpu * 1e3 / nsteps as f64,
        ni as f64 / nsteps as f64,
        np as f64 / nsteps as f64,
        tp as f64 / nsteps as f64,
        fmin / 1e3,
        fmax / 1e3,
        wear.total_j()
    );
    let mut csv = String::from("step,fn_n,fx_n,power_w\n");
    for (k, (f, fx, p)) in forces.iter().enumerate() {
        csv.push_str(&format!("{k},{f:.9e},{fx:.9e},{p:.9e}\n"));
    }
    std::fs::write(&out, csv)?;
    Ok(())
}

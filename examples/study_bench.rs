//! Design-study benchmark and the substructured-basis validation (docs/performance.md §7,
//! validation/substructure.md).
//!
//! ```text
//! cargo run --example study_bench -- study [--basis substructured|full] [--key K] [--values a,b,…] [--speed KMH] [--static-update] [--concurrent N]
//! cargo run --example study_bench -- reduced-check [--key K] [--values a,b,…]
//! cargo run --example study_bench -- validate [--key K] [--value V] [--speed KMH] [--fmax-check HZ] [--ballast-degree D] [--list N] [--residuals N]
//! ```
//!
//! `study`: a one-parameter study of the default model (default: ten railpad vertical
//! stiffnesses 0.4–2.2 GN/m at 140 km/h) through the library's study runner; prints the
//! basis plan, wall and CPU time, the machine's load, a digest of `study.csv` and each
//! substructured case's step times (wall, and the process's CPU time during each step: a
//! step's own with `--concurrent 1`) and the passages' times. `--static-update`: the cases'
//! residual flexibility from the study's reference factorisation updated for the changed
//! springs, instead of a factorisation of each case's own `K`. `--concurrent N`: the study's
//! `concurrent_cases` (default: the study file's default).
//! `reduced-check`: for each value of `study` (default: the ten railpad stiffnesses), the
//! reduced stiffness as the library forms it (by component blocks) against the dense product
//! over all springs' projections `diag(ω̃²) + G diag(k) Gᵀ` formed here, and the reduced
//! eigenproblem's frequencies below f_max from both: largest relative differences.
//! `validate`: for one value, the substructured basis against the full Lanczos basis
//! (frequencies below `--fmax-check`, default 3 kHz) and one passage on each basis (band RMS
//! of F_L, F_N and wear, dominant wavelength). `--residuals N`: for the lowest N modes of
//! both bases, the Rayleigh quotient and the relative residual `‖Kφ − ω²Mφ‖ / ‖Kφ‖` in the
//! full model's assembled K and M, and each substructured mode's best match among the full
//! modes (largest mass-weighted MAC): a substructured mode whose Rayleigh quotient in the
//! full model equals its own ω² is a Ritz pair of the full model, so by Courant–Fischer its
//! rank-th value bounds the full model's rank-th eigenvalue from above.

mod common;

use common::{cpu_seconds, machine_load};

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use corrugation::dynamics::PassageRunner;
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::basis::track_basis;
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::eigen::spmm::sym_spmm;
use corrugation::eigen::substructure::{
    substructured_track_basis, track_components, SubstructureOptions,
};
use corrugation::model::{load_model, ModelSource};
use corrugation::structure::TrackStructure;
use corrugation::studies::speeds::Shard;
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
        Some("reduced-check") => reduced_check(&args, &key),
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
    let concurrent = arg(args, "--concurrent")
        .map(|n| format!("concurrent_cases = {n}\n"))
        .unwrap_or_default();
    let text = format!(
        "title = \"study_bench\"\nmodel = \"builtin:dutch\"\nspeeds_kmh = [{speed:?}]\nbasis = \"{basis}\"\n{concurrent}[[parameter]]\nkey = \"{key}\"\nvalues = [{}]\n",
        values.join(", ")
    );
    let dir = std::env::temp_dir().join(format!("study_bench-{}", std::process::id()));
    let study = Study::parse_str(&text, "study_bench.toml", &dir, "study_bench")?;
    let models = study.case_models()?;
    let cache_dir: PathBuf = default_cache_dir();
    let plan = basis_plan(&study, &models, &ModalCache::new(&cache_dir))?;
    println!(
        "plan: {plan}; {} case(s) at a time after the first",
        study.concurrent_cases
    );
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let runners = CaseRunners::new(&study, &cache_dir)
        .with_static_update(args.iter().any(|a| a == "--static-update"));
    let passages = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let factory = |m: &corrugation::model::Model| -> Result<Box<dyn PassageRunner>, BoxError> {
        Ok(Box::new(Timed {
            inner: runners.prepared(m)?,
            times: passages.clone(),
        }))
    };
    let out = run_study(
        &study,
        &factory,
        None,
        &dir,
        Shard::ALL,
        &corrugation::progress::Silent,
    )?;
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
                "  {}: F_L band {:.9} N, F_N band {:.9} N, wear band/mean {:.9e}, dominant {:?}",
                c.label(),
                row.fl_band_rms_n,
                row.fn_band_rms_n,
                row.relative_wear.unwrap_or(f64::NAN),
                row.wear_peaks.first().map(|p| p.wavelength_mm)
            );
        }
    }
    print_phases(&runners.phases());
    let p = passages.lock().map(|p| p.clone()).unwrap_or_default();
    println!(
        "passages: {}, wall {:.1} s, CPU {:.1} s (summed)",
        p.len(),
        p.iter().map(|x: &[f64; 2]| x[0]).sum::<f64>(),
        p.iter().map(|x| x[1]).sum::<f64>()
    );
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// A passage runner that records each passage's wall and process CPU time (s).
struct Timed<R> {
    inner: R,
    times: std::sync::Arc<std::sync::Mutex<Vec<[f64; 2]>>>,
}

impl<R: PassageRunner> PassageRunner for Timed<R> {
    fn run(
        &self,
        speed: corrugation::units::Speed,
        profile: Option<&corrugation::dynamics::RailProfile>,
    ) -> Result<corrugation::dynamics::PassageSummary, corrugation::passage::PassageError> {
        let (t, c) = (Instant::now(), cpu_seconds());
        let r = self.inner.run(speed, profile);
        if let Ok(mut v) = self.times.lock() {
            v.push([t.elapsed().as_secs_f64(), cpu_seconds() - c]);
        }
        r
    }
}

/// The step times of each substructured case and their sums (wall and process CPU, s).
fn print_phases(phases: &[corrugation::studies::study::CasePhases]) {
    if phases.is_empty() {
        return;
    }
    println!("phases (s): case,structure,components,reduced,expand,classify,engine,of_which_residual | CPU: structure+components,reduced,expand,classify,engine");
    let mut sum = [0.0; 12];
    for (i, p) in phases.iter().enumerate() {
        let v = [
            p.structure_s,
            p.components_s,
            p.basis.reduced_s,
            p.basis.expand_s,
            p.basis.classify_s,
            p.engine_s,
            p.residual_s,
            p.structure_cpu_s,
            p.basis.reduced_cpu_s,
            p.basis.expand_cpu_s,
            p.basis.classify_cpu_s,
            p.engine_cpu_s,
        ];
        sum.iter_mut().zip(&v).for_each(|(s, x)| *s += x);
        let row: Vec<String> = v.iter().map(|x| format!("{x:.2}")).collect();
        println!("  {i},{}", row.join(","));
    }
    let row: Vec<String> = sum.iter().map(|x| format!("{x:.1}")).collect();
    println!("  sum,{}", row.join(","));
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
    if let Some(j) = arg(args, "--ritz-detail") {
        ritz_detail(&track, &comp, fmax, j.parse()?)?;
    }
    if let Some(k) = arg(args, "--residuals") {
        ritz_check(&track, &comp, &full, &sub, k.parse()?)?;
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

/// `y = A x` for a symmetric sparse matrix stored with both triangles.
fn sparse_times(a: faer::sparse::SparseColMatRef<'_, usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = faer::Mat::<f64>::zeros(a.nrows(), 1);
    sym_spmm(
        a,
        faer::MatRef::from_column_major_slice(x, x.len(), 1),
        y.as_mut(),
    );
    y.col(0).iter().copied().collect()
}

/// `A x` for a dense matrix and a vector.
fn dense_times(a: faer::MatRef<'_, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = faer::Mat::<f64>::zeros(a.nrows(), 1);
    faer::linalg::matmul::matmul(
        y.as_mut(),
        faer::Accum::Replace,
        a,
        faer::MatRef::from_column_major_slice(x, x.len(), 1),
        1.0,
        faer::Par::rayon(0),
    );
    y.col(0).iter().copied().collect()
}

/// The lowest `n` modes of both bases in the full model's K and M (see the module doc).
fn ritz_check(
    track: &TrackStructure,
    comp: &corrugation::eigen::substructure::TrackComponents,
    full: &corrugation::eigen::basis::ModalBasis<corrugation::eigen::classify::TrackModeClass>,
    sub: &corrugation::eigen::basis::ModalBasis<corrugation::eigen::classify::TrackModeClass>,
    n: usize,
) -> anyhow::Result<()> {
    let (mats, _) = track.assemble()?;
    let (k, m) = (mats.k.as_ref(), mats.m.as_ref());
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let col = |b: &corrugation::eigen::basis::ModalBasis<_>, j: usize| -> Vec<f64> {
        b.modes.col(j).iter().copied().collect()
    };
    let n = n
        .min(full.frequencies_hz.len())
        .min(sub.frequencies_hz.len());
    let full_m: Vec<(Vec<f64>, Vec<f64>)> = (0..n + 8)
        .filter(|&j| j < full.frequencies_hz.len())
        .map(|j| {
            let p = col(full, j);
            let mp = sparse_times(m, &p);
            (p, mp)
        })
        .collect();
    println!("basis,mode,f_hz,rayleigh_hz,relative_residual,best_full_mode,best_mac,phi_m_phi,rail_mass_share,top_sleeper,top_sleeper_share");
    let (rail_rows, sd) = (comp.rail.vectors.nrows(), comp.sleeper.vectors.nrows());
    for (name, b) in [("full", full), ("substructured", sub)] {
        for j in 0..n {
            let p = col(b, j);
            let kp = sparse_times(k, &p);
            let mp = sparse_times(m, &p);
            let (pkp, pmp) = (dot(&p, &kp), dot(&p, &mp));
            let w2 = (2.0 * std::f64::consts::PI * b.frequencies_hz[j]).powi(2);
            let r: f64 = kp
                .iter()
                .zip(&mp)
                .map(|(a, c)| (a - w2 * c).powi(2))
                .sum::<f64>()
                .sqrt()
                / dot(&kp, &kp).sqrt();
            let rayleigh_hz = (pkp / pmp).sqrt() / (2.0 * std::f64::consts::PI);
            let (best, mac) = full_m
                .iter()
                .enumerate()
                .map(|(i, (q, mq))| {
                    let c = dot(&p, mq);
                    (i, c * c / (pmp * dot(q, mq)))
                })
                .fold((0, 0.0), |a, x| if x.1 > a.1 { x } else { a });
            let share = |r0: usize, len: usize| dot(&p[r0..r0 + len], &mp[r0..r0 + len]) / pmp;
            let (top, top_share) = comp
                .sleeper_offsets
                .iter()
                .enumerate()
                .map(|(i, &o)| (i, share(o, sd)))
                .fold((0, 0.0), |a, x| if x.1 > a.1 { x } else { a });
            println!(
                "{name},{j},{:.6},{rayleigh_hz:.6},{r:.3e},{best},{mac:.6},{pmp:.9},{:.4},{top},{top_share:.4}",
                b.frequencies_hz[j],
                share(0, rail_rows)
            );
        }
    }
    Ok(())
}

/// For the reduced mode `j`: `d = K_red q − Ψᵀ K Ψ q` (zero when the reduced stiffness is the
/// projection of the assembled one); prints its norm against `‖K_red q‖` and its largest
/// entries with the basis vector each belongs to.
fn ritz_detail(
    track: &TrackStructure,
    comp: &corrugation::eigen::substructure::TrackComponents,
    fmax: f64,
    j: usize,
) -> anyhow::Result<()> {
    use corrugation::eigen::substructure::{expand, reduced_modes, reduced_stiffness};
    let k_red = reduced_stiffness(track, comp)?;
    let (f, q) = reduced_modes(&k_red, fmax)?;
    let qj: Vec<f64> = q.col(j).iter().copied().collect();
    let phi = expand(comp, track.dofmap.n_free(), &q);
    let p: Vec<f64> = phi.col(j).iter().copied().collect();
    let (mats, _) = track.assemble()?;
    let kp = sparse_times(mats.k.as_ref(), &p);
    let (rail, sl) = (&comp.rail, &comp.sleeper);
    let (nr, ns, sd) = (rail.vectors.ncols(), sl.vectors.ncols(), sl.vectors.nrows());
    let n = k_red.nrows();
    // g = Ψᵀ K φ, block by block
    let mut g = dense_times(rail.vectors.transpose(), &kp[..rail.vectors.nrows()]);
    for &o in &comp.sleeper_offsets {
        g.extend(dense_times(sl.vectors.transpose(), &kp[o..o + sd]));
    }
    let kq = dense_times(k_red.as_ref(), &qj);
    let d: Vec<f64> = kq.iter().zip(&g).map(|(a, b)| a - b).collect();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let qkq: f64 = qj.iter().zip(&kq).map(|(a, b)| a * b).sum();
    let qg: f64 = qj.iter().zip(&g).map(|(a, b)| a * b).sum();
    let w2 = (2.0 * std::f64::consts::PI * f[j]).powi(2);
    let qq: f64 = qj.iter().map(|x| x * x).sum();
    let res: Vec<f64> = kq.iter().zip(&qj).map(|(a, b)| a - w2 * b).collect();
    let kmax = (0..n).map(|i| k_red[(i, i)].abs()).fold(0.0, f64::max);
    println!(
        "reduced mode {j}: q'q = {qq:.12}, |K_red q - w2 q| = {:.3e}, |K_red q| = {:.3e}, largest diagonal of K_red {kmax:.3e}",
        norm(&res),
        norm(&kq)
    );
    // Rayleigh-Ritz refinement inside the kept subspace: Q' K_red Q and its eigenvalues
    let m = q.ncols();
    let mut kq_all = faer::Mat::<f64>::zeros(n, m);
    faer::linalg::matmul::matmul(
        kq_all.as_mut(),
        faer::Accum::Replace,
        k_red.as_ref(),
        q.as_ref(),
        1.0,
        faer::Par::rayon(0),
    );
    let mut small = faer::Mat::<f64>::zeros(m, m);
    faer::linalg::matmul::matmul(
        small.as_mut(),
        faer::Accum::Replace,
        q.transpose(),
        kq_all.as_ref(),
        1.0,
        faer::Par::rayon(0),
    );
    let mut off: f64 = 0.0;
    for a in 0..m.min(40) {
        for b in 0..m.min(40) {
            if a != b {
                off = off.max(small[(a, b)].abs());
            }
        }
    }
    let small = faer::Mat::from_fn(m, m, |a, b| 0.5 * (small[(a, b)] + small[(b, a)]));
    let ev = small
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let sv = ev.S().column_vector();
    println!("Q'K_red Q: largest off-diagonal among the first 40 modes {off:.3e}; refined frequencies (Hz) of modes 0-11 vs the dense solver's:");
    for a in 0..12.min(m) {
        println!(
            "  {a}: {:.6} vs {:.6}",
            sv[a].max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
            f[a]
        );
    }
    println!(
        "reduced mode {j}: {:.6} Hz; q'K_red q = {qkq:.6e}, q'Psi'K Psi q = {qg:.6e}; |d| = {:.3e} of |K_red q| = {:.3e}",
        f[j],
        norm(&d),
        norm(&kq)
    );
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| d[b].abs().total_cmp(&d[a].abs()));
    println!("vector,what,omega2_tilde,q,d,d_times_q");
    for &i in idx.iter().take(15) {
        let (what, w2) = if i < nr {
            (
                if i < rail.modes {
                    format!("rail mode {i}")
                } else {
                    format!("rail attachment {}", i - rail.modes)
                },
                rail.omega2[i],
            )
        } else {
            let (s, c) = ((i - nr) / ns, (i - nr) % ns);
            (format!("sleeper {s} vector {c}"), sl.omega2[c])
        };
        println!(
            "{i},{what},{w2:.6e},{:.4e},{:.4e},{:.4e}",
            qj[i],
            d[i],
            d[i] * qj[i]
        );
    }
    Ok(())
}

/// `diag(ω̃²) + G diag(k) Gᵀ` with `G` the projections of every spring on the component
/// bases, as one dense product (the reference for [`reduced_check`]).
fn dense_reduced_stiffness(
    track: &TrackStructure,
    comp: &corrugation::eigen::substructure::TrackComponents,
) -> faer::Mat<f64> {
    let (rail_rows, sd) = (comp.rail.vectors.nrows(), comp.sleeper.vectors.nrows());
    let (nr, ns) = (comp.rail.vectors.ncols(), comp.sleeper.vectors.ncols());
    let n = comp.reduced_size();
    let mut g = faer::Mat::<f64>::zeros(n, track.springs.len());
    for (j, s) in track.springs.iter().enumerate() {
        let sides = s
            .side_a
            .iter()
            .copied()
            .chain(s.side_b.iter().map(|&(d, w)| (d, -w)));
        for (dof, w) in sides {
            let Some(f) = track.dofmap.free_index(dof) else {
                continue;
            };
            if f < rail_rows {
                for c in 0..nr {
                    g[(c, j)] += w * comp.rail.vectors[(f, c)];
                }
            } else {
                let i = comp.sleeper_offsets.partition_point(|&o| o <= f) - 1;
                let r = f - comp.sleeper_offsets[i];
                assert!(r < sd, "spring {j} outside the components");
                for c in 0..ns {
                    g[(nr + i * ns + c, j)] += w * comp.sleeper.vectors[(r, c)];
                }
            }
        }
    }
    let gk = faer::Mat::<f64>::from_fn(n, g.ncols(), |i, j| g[(i, j)] * track.springs[j].stiffness);
    let mut k = &gk * g.transpose();
    for (i, w) in comp.reduced_omega2().enumerate() {
        k[(i, i)] += w;
    }
    faer::Mat::from_fn(n, n, |i, j| 0.5 * (k[(i, j)] + k[(j, i)]))
}

/// See the module doc (`reduced-check`).
fn reduced_check(args: &[String], key: &str) -> anyhow::Result<()> {
    use corrugation::eigen::substructure::{reduced_modes, reduced_stiffness};
    let values = arg(args, "--values").unwrap_or_else(|| {
        (0..10)
            .map(|i| format!("{:e}", 0.4e9 + 0.2e9 * i as f64))
            .collect::<Vec<_>>()
            .join(",")
    });
    let cache = ModalCache::new(default_cache_dir());
    let opts = SubstructureOptions::default();
    println!(
        "value,modes,k_red_max_rel_difference,largest_freq_rel_difference,at_hz,blocked_s,dense_s"
    );
    for v in values.split(',') {
        let m = load_model(&ModelSource::Builtin, &[format!("{key}={}", v.trim())])?;
        let fmax = m.run.fmax;
        let track = TrackStructure::build(&m)?;
        let comp = track_components(&m, &track, &cache, fmax, &opts)?;
        let t = Instant::now();
        let kb = reduced_stiffness(&track, &comp)?;
        let tb = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let kd = dense_reduced_stiffness(&track, &comp);
        let td = t.elapsed().as_secs_f64();
        let n = kb.nrows();
        let (mut dk, mut scale) = (0.0f64, 0.0f64);
        for j in 0..n {
            for i in 0..n {
                dk = dk.max((kb[(i, j)] - kd[(i, j)]).abs());
                scale = scale.max(kd[(i, j)].abs());
            }
        }
        let (fb, _) = reduced_modes(&kb, fmax)?;
        let (fd, _) = reduced_modes(&kd, fmax)?;
        anyhow::ensure!(
            fb.len() == fd.len(),
            "{v}: {} vs {} modes",
            fb.len(),
            fd.len()
        );
        let (mut worst, mut at) = (0.0f64, 0.0);
        for (a, b) in fb.iter().zip(&fd) {
            let e = ((a - b) / b).abs();
            if e > worst {
                (worst, at) = (e, *b);
            }
        }
        println!(
            "{v},{},{:.3e},{worst:.3e},{at:.3},{tb:.2},{td:.2}",
            fb.len(),
            dk / scale
        );
    }
    Ok(())
}

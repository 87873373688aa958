//! `corrugation passage`: one reduced-order passage of the wheel over the track
//! (docs/theory.md §7).
//!
//! Outputs in `--out DIR` (default `corrugation-out/passage`), all written atomically:
//! * `forces.csv` — per time step: `t_s, x_m, fn_n, fl_n, flat_n, creepage, approach_m,
//!   contact_length_m, slip_fraction, frictional_power_w` (forces on the wheel; F_L > 0 forward);
//! * `wear.csv` — `x_m, wf_j_per_m, wf_band_j_per_m` in the solution zone (W_f integrated
//!   across the rail head, and its 20–80 mm band-passed part);
//! * `rail_point.csv` — `t_s, ux_m, uy_m, uz_m` of the rail-top node nearest 0.6 m into the
//!   solution zone;
//! * `psd_wear.csv`, `psd_fl.csv`, `psd_fn.csv` — `wavelength_m, frequency_hz, psd` of the
//!   band-passed signals in the solution zone (one-sided, per unit wavenumber);
//! * `summary.json` — the `--json` object;
//! * plots `*.svg` / `*.png` of F_L, F_N and W_f along the rail and their PSDs.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use corrugation::dynamics::analysis::{band_analyses, Analysed};
use corrugation::dynamics::passage::PassageOptions;
use corrugation::dynamics::summary::PassageSummary;
use corrugation::io::{write_atomic, write_csv};
use corrugation::report::plot::{line_plot, line_plot_log_y, Series};

use super::ModelArgs;

/// One passage of the wheel over the track: contact forces, wear along the rail, PSDs.
#[derive(Debug, Args)]
pub struct PassageCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Rail-top profile (CSV with a header: x in m, height in µm), e.g. a corrugation.
    #[arg(long, value_name = "FILE.csv")]
    corrugation: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/passage", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Passage engine: `reduced` (modal, default) or `explicit` (the full explicit FE
    /// path, minutes per passage).
    #[arg(long, value_enum, default_value = "reduced")]
    engine: super::engine::Engine,
    #[command(flatten)]
    reference: super::reference_outputs::ReferenceArgs,
}

impl PassageCmd {
    /// With `--engine explicit`: refuses the flags only the reduced passage reads (the
    /// modal cache, the coupled-mode attribution and the nodal spectrum, which need the
    /// modal bases), instead of ignoring them.
    fn refuse_reduced_only_flags(&self) -> anyhow::Result<()> {
        let r = &self.reference;
        let given = [
            ("--cache", self.cache.is_some()),
            ("--no-coupled", r.no_coupled),
            ("--no-nodal", r.no_nodal),
            ("--nodal-at", !r.nodal_at_m.is_empty()),
        ];
        if let Some((flag, _)) = given.iter().find(|(_, on)| *on) {
            anyhow::bail!(
                "{flag} is for the reduced engine: `passage --engine explicit` writes no coupled-mode or nodal-spectrum files and reads no modal cache"
            );
        }
        Ok(())
    }

    pub fn run(self) -> anyhow::Result<()> {
        if self.engine == super::engine::Engine::Explicit {
            self.refuse_reduced_only_flags()?;
        }
        let m = self.model.load()?;
        self.reference.check(&m)?;
        let profile = match &self.corrugation {
            Some(p) => Some(super::read_profile(p, &m)?),
            None => None,
        };
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        if self.engine == super::engine::Engine::Explicit {
            return super::explicit_cmd::run_explicit(
                &m,
                corrugation::explicit::ExplicitOptions::from_model(&m),
                profile.as_ref(),
                &self.out,
                self.json,
            );
        }
        // a passage that runs alone: the track's damping product on the second core
        let opts = PassageOptions {
            overlap: true,
            ..PassageOptions::default()
        };
        let mut prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        if let (Some(p), Some(path)) = (&profile, &self.corrugation) {
            let travel = prepared.engine.rail_under_contact_m(m.run.speed())?;
            corrugation::dynamics::setup::check_profile_on_travel(p, travel)
                .with_context(|| format!("--corrugation {}", path.display()))?;
        }
        let pb = super::progress::bar("passage (time steps)");
        let rec = prepared
            .engine
            .passage(m.run.speed(), profile.as_ref(), &opts, Some(&pb))
            .context("running the passage")?;
        pb.finish_and_clear();
        let summary = corrugation::dynamics::analysis::summarise(&rec)?;
        write_outputs(&self.out, &rec, &summary, m.mesh.fine_element_length)?;
        if self.json {
            println!("{}", serde_json::to_string_pretty(&summary)?);
        } else {
            print_summary(&summary, &rec, &self.out);
        }
        use super::reference_outputs::{coupled_attribution, nodal_outputs};
        if !self.reference.no_coupled {
            coupled_attribution(&prepared, &summary, &self.out, self.json)?;
        }
        if !self.reference.no_nodal {
            let v = m.run.speed();
            nodal_outputs(
                &mut prepared,
                v,
                profile.as_ref(),
                &self.reference,
                &self.out,
                self.json,
            )?;
        }
        Ok(())
    }
}

///
/// `element_length_m` (m): the node-plane spacing of the rail mesh in the solution zone
/// (`mesh.fine_element_length`), named on the F_N plot, whose fine ripple is the contact
/// passing the node planes.
pub fn write_outputs(
    out: &Path,
    rec: &corrugation::dynamics::record::PassageRecord,
    s: &PassageSummary,
    element_length_m: f64,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let h = &rec.histories;
    write_csv(
        &out.join("forces.csv"),
        &[
            "t_s",
            "x_m",
            "fn_n",
            "fl_n",
            "flat_n",
            "creepage",
            "approach_m",
            "contact_length_m",
            "slip_fraction",
            "frictional_power_w",
        ],
        (0..h.t_s.len()).map(|i| {
            vec![
                h.t_s[i],
                h.x_m[i],
                h.normal_n[i],
                h.longitudinal_n[i],
                h.lateral_n[i],
                h.creepage[i],
                h.approach_m[i],
                h.contact_length_m[i],
                h.slip_fraction[i],
                h.frictional_power_w[i],
            ]
        }),
    )?;
    let v = rec.speed_m_per_s;
    let [w, fl, fnn] = band_analyses(rec)?;
    write_csv(
        &out.join("wear.csv"),
        &["x_m", "wf_j_per_m", "wf_band_j_per_m"],
        (0..rec.wear_x_m.len())
            .map(|i| vec![rec.wear_x_m[i], rec.wear_j_per_m[i], w.band.values[i]]),
    )?;
    if let Some(rp) = &rec.rail_point {
        write_csv(
            &out.join("rail_point.csv"),
            &["t_s", "ux_m", "uy_m", "uz_m"],
            rp.displacement_m
                .iter()
                .zip(&h.t_s)
                .map(|(u, &t)| vec![t, u[0], u[1], u[2]]),
        )?;
    }
    for (name, a) in [
        ("psd_wear.csv", &w),
        ("psd_fl.csv", &fl),
        ("psd_fn.csv", &fnn),
    ] {
        let [l, f, p] = a.psd_columns(v);
        write_csv(
            &out.join(name),
            &["wavelength_m", "frequency_hz", "psd"],
            (0..p.len()).map(|i| vec![l[i], f[i], p[i]]),
        )?;
    }
    write_plots(out, rec, &w, &fl, &fnn, element_length_m)?;
    let json = serde_json::to_string_pretty(s)?;
    write_atomic(&out.join("summary.json"), |f| {
        use std::io::Write;
        f.write_all(json.as_bytes())
    })?;
    Ok(())
}

pub fn print_summary(
    s: &PassageSummary,
    rec: &corrugation::dynamics::record::PassageRecord,
    out: &Path,
) {
    println!(
        "passage at {:.1} km/h: {} steps of {:.3e} s (sub-steps: track {}, wheel {}) in {:.2} s",
        s.speed_kmh, s.steps, rec.dt_s, rec.substeps[0], rec.substeps[1], s.seconds
    );
    println!(
        "  mean F_N {:.0} N, mean F_L {:.0} N (F_L/F_N {:.4}); static creepage {:.3e}",
        s.mean_fn_n,
        s.mean_fl_n,
        s.mean_fl_n / s.mean_fn_n,
        rec.static_creepage
    );
    println!(
        "  band RMS (20-80 mm): F_L {:.1} N, F_N {:.1} N, wear {:.4e} J/m (mean {:.4e} J/m)",
        s.fl_band_rms_n, s.fn_band_rms_n, s.wear_band_rms, s.wear_mean
    );
    for (name, c) in [
        ("wear", &s.wear_components),
        ("F_L", &s.fl_components),
        ("F_N", &s.fn_components),
    ] {
        let list: Vec<String> = c
            .iter()
            .map(|c| format!("{:.1} mm ({:.0} Hz)", c.wavelength_mm, c.frequency_hz))
            .collect();
        println!("  {name} components: {}", list.join(", "));
    }
    let e = &rec.energy;
    println!(
        "  energy: input {:.3} J + spin {:.3} J + convective {:.3} J = stored {:.3} + dampers {:.3} + friction {:.3} + contact {:.3} (error {:.2} %)",
        e.external_work_j,
        e.spin_work_j,
        e.convective_work_j,
        e.stored_change_j,
        e.damper_dissipation_j,
        e.frictional_work_j,
        e.contact_energy_change_j,
        100.0 * e.relative_error()
    );
    println!(
        "  structure: input + contact work {:.3} J = stored + dampers {:.3} J; contact work {:.3} J = -(friction + contact energy) {:.3} J",
        e.external_work_j + e.contact_work_j,
        e.stored_change_j + e.damper_dissipation_j,
        e.contact_work_j,
        -(e.frictional_work_j + e.contact_energy_change_j)
    );
    println!("  outputs in {}", out.display());
}

/// Plots of F_L, F_N and W_f along the rail (solution zone) and their band PSDs (SVG + PNG).
fn write_plots(
    out: &Path,
    rec: &corrugation::dynamics::record::PassageRecord,
    w: &Analysed,
    fl: &Analysed,
    fnn: &Analysed,
    element_length_m: f64,
) -> anyhow::Result<()> {
    write_zone_plots(out, rec, element_length_m)?;
    write_band_plot(out, w, fl, fnn)?;
    line_plot(
        &out.join("wear_x"),
        "Frictional work along the rail",
        "x (m)",
        "W_f (J/m)",
        &[Series::new(
            "W_f",
            rec.wear_x_m.clone(),
            rec.wear_j_per_m.clone(),
        )],
    )?;
    write_psd_plots(out, w, fl, fnn)
}

/// `forces_x` and `normal_force_x`: the raw F_L and F_N in the solution zone.
fn write_zone_plots(
    out: &Path,
    rec: &corrugation::dynamics::record::PassageRecord,
    element_length_m: f64,
) -> anyhow::Result<()> {
    let h = &rec.histories;
    let [z0, z1] = rec.zone_m;
    let idx: Vec<usize> = (0..h.x_m.len())
        .filter(|&i| h.x_m[i] >= z0 && h.x_m[i] <= z1)
        .collect();
    let xs: Vec<f64> = idx.iter().map(|&i| h.x_m[i]).collect();
    line_plot(
        &out.join("forces_x"),
        "Contact forces in the solution zone",
        "x (m)",
        "force on the wheel (N)",
        &[Series::new(
            "F_L",
            xs.clone(),
            idx.iter().map(|&i| h.longitudinal_n[i]).collect(),
        )],
    )?;
    line_plot(
        &out.join("normal_force_x"),
        &format!(
            "Normal force, raw (fine ripple: element passing, {} mm)",
            corrugation::growth::verdict::trim_zeros(&corrugation::growth::verdict::sig(
                corrugation::units::m_to_mm(element_length_m),
                3
            ))
        ),
        "x (m)",
        "F_N (N)",
        &[Series::new(
            "F_N",
            xs,
            idx.iter().map(|&i| h.normal_n[i]).collect(),
        )],
    )?;
    Ok(())
}

/// `band_x`: the band-passed W_f, F_L and F_N along the rail, each divided by its band RMS.
fn write_band_plot(out: &Path, w: &Analysed, fl: &Analysed, fnn: &Analysed) -> anyhow::Result<()> {
    let normalised = |name: &str, a: &Analysed| {
        Series::new(
            name,
            (0..a.band.len()).map(|i| a.band.x_m(i)).collect(),
            a.band
                .values
                .iter()
                .map(|v| v / a.band_rms.max(f64::MIN_POSITIVE))
                .collect(),
        )
    };
    line_plot(
        &out.join("band_x"),
        "Band-passed (20-80 mm) signals along the rail, normalised by their RMS",
        "x (m)",
        "signal / band RMS (-)",
        &[
            normalised("W_f", w),
            normalised("F_L", fl),
            normalised("F_N", fnn),
        ],
    )?;
    Ok(())
}

/// `psd_wear`, `psd_fl`, `psd_fn`: the PSDs of the band-passed signals over wavelengths of
/// 15 to 100 mm.
fn write_psd_plots(out: &Path, w: &Analysed, fl: &Analysed, fnn: &Analysed) -> anyhow::Result<()> {
    let psd_series = |name: &str, a: &Analysed| {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for (k, p) in a.psd.wavenumber_per_m.iter().zip(&a.psd.psd) {
            if *k > 0.0 {
                let l = 1000.0 / k;
                if (15.0..=100.0).contains(&l) {
                    x.push(l);
                    y.push(*p);
                }
            }
        }
        Series::new(name, x, y)
    };
    for (stem, title, unit, a) in [
        (
            "psd_wear",
            "PSD of the band-passed wear",
            "PSD ((J/m)^2 m)",
            w,
        ),
        ("psd_fl", "PSD of the band-passed F_L", "PSD (N^2 m)", fl),
        ("psd_fn", "PSD of the band-passed F_N", "PSD (N^2 m)", fnn),
    ] {
        line_plot_log_y(
            &out.join(stem),
            title,
            "wavelength (mm)",
            unit,
            &[psd_series(stem, a)],
        )?;
    }
    Ok(())
}

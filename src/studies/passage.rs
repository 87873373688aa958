//! The files and plots of one passage (either engine): the force histories, the wear along
//! the rail, the rail point's motion, the band PSDs, the plots of F_L, F_N and W_f along the
//! rail and their PSDs, and `summary.json`; and the passage's summary as text. Written by the
//! `passage` and `explicit` commands.

use std::path::Path;

use crate::io::{write_atomic, write_csv};
use crate::passage::analysis::{band_analyses, Analysed};
use crate::passage::record::PassageRecord;
use crate::passage::summary::PassageSummary;
use crate::report::plot::{line_plot, line_plot_log_y, Series};
use crate::studies::StudiesError;

/// Writes the outputs of one passage into `out` (created if missing), each file atomically:
/// `forces.csv`, `wear.csv`, `rail_point.csv` (when the record has a rail point), the band
/// PSDs `psd_wear.csv`, `psd_fl.csv`, `psd_fn.csv`, the plots and `summary.json` (`s`) last.
///
/// `element_length_m` (m): the node-plane spacing of the rail mesh in the solution zone
/// (`mesh.fine_element_length`), named on the F_N plot, whose fine ripple is the contact
/// passing the node planes.
pub fn write_passage(
    out: &Path,
    rec: &PassageRecord,
    s: &PassageSummary,
    element_length_m: f64,
) -> Result<(), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let h = &rec.histories;
    let path = out.join("forces.csv");
    write_csv(
        &path,
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
            "peak_pressure_pa",
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
                h.peak_pressure_pa[i],
            ]
        }),
    )
    .map_err(StudiesError::io(&path))?;
    let v = rec.speed_m_per_s;
    let [w, fl, fnn] = band_analyses(rec)?;
    let path = out.join("wear.csv");
    write_csv(
        &path,
        &["x_m", "wf_j_per_m", "wf_band_j_per_m"],
        (0..rec.wear_x_m.len())
            .map(|i| vec![rec.wear_x_m[i], rec.wear_j_per_m[i], w.band.values[i]]),
    )
    .map_err(StudiesError::io(&path))?;
    if let Some(rp) = &rec.rail_point {
        let path = out.join("rail_point.csv");
        write_csv(
            &path,
            &["t_s", "ux_m", "uy_m", "uz_m"],
            rp.displacement_m
                .iter()
                .zip(&h.t_s)
                .map(|(u, &t)| vec![t, u[0], u[1], u[2]]),
        )
        .map_err(StudiesError::io(&path))?;
    }
    for (name, a) in [
        ("psd_wear.csv", &w),
        ("psd_fl.csv", &fl),
        ("psd_fn.csv", &fnn),
    ] {
        let [l, f, p] = a.psd_columns(v);
        let path = out.join(name);
        write_csv(
            &path,
            &["wavelength_m", "frequency_hz", "psd"],
            (0..p.len()).map(|i| vec![l[i], f[i], p[i]]),
        )
        .map_err(StudiesError::io(&path))?;
    }
    write_plots(out, rec, &w, &fl, &fnn, element_length_m)?;
    let json = serde_json::to_string_pretty(s).map_err(|source| StudiesError::Json {
        what: "passage summary",
        source,
    })?;
    let path = out.join("summary.json");
    write_atomic(&path, |f| {
        use std::io::Write;
        f.write_all(json.as_bytes())
    })
    .map_err(StudiesError::io(&path))?;
    Ok(())
}

/// The passage's summary as printed lines: steps, mean forces, band RMS, the dominant
/// components and the energy ledger (the CLI prints them; `--json` prints `s` instead).
pub fn summary_lines(s: &PassageSummary, rec: &PassageRecord) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(format!(
        "passage at {:.1} km/h: {} steps of {:.3e} s (sub-steps: track {}, wheel {}) in {:.2} s",
        s.speed_kmh, s.steps, rec.dt_s, rec.substeps[0], rec.substeps[1], s.seconds
    ));
    lines.push(format!(
        "  mean F_N {:.0} N, mean F_L {:.0} N (F_L/F_N {:.4}); static creepage {:.3e}",
        s.mean_fn_n,
        s.mean_fl_n,
        s.mean_fl_n / s.mean_fn_n,
        rec.static_creepage
    ));
    lines.push(format!(
        "  band RMS (20-80 mm): F_L {:.1} N, F_N {:.1} N, wear {:.4e} J/m (mean {:.4e} J/m)",
        s.fl_band_rms_n, s.fn_band_rms_n, s.wear_band_rms, s.wear_mean
    ));
    for (name, c) in [
        ("wear", &s.wear_components),
        ("F_L", &s.fl_components),
        ("F_N", &s.fn_components),
    ] {
        let list: Vec<String> = c
            .iter()
            .map(|c| format!("{:.1} mm ({:.0} Hz)", c.wavelength_mm, c.frequency_hz))
            .collect();
        lines.push(format!("  {name} components: {}", list.join(", ")));
    }
    let e = &rec.energy;
    lines.push(format!(
        "  energy: input {:.3} J + spin {:.3} J + convective {:.3} J = stored {:.3} + dampers {:.3} + friction {:.3} + contact {:.3} (error {:.2} %)",
        e.external_work_j,
        e.spin_work_j,
        e.convective_work_j,
        e.stored_change_j,
        e.damper_dissipation_j,
        e.frictional_work_j,
        e.contact_energy_change_j,
        100.0 * e.relative_error()
    ));
    lines.push(format!(
        "  structure: input + contact work {:.3} J = stored + dampers {:.3} J; contact work {:.3} J = -(friction + contact energy) {:.3} J",
        e.external_work_j + e.contact_work_j,
        e.stored_change_j + e.damper_dissipation_j,
        e.contact_work_j,
        -(e.frictional_work_j + e.contact_energy_change_j)
    ));
    lines
}

/// Plots of F_L, F_N and W_f along the rail (solution zone) and their band PSDs (SVG + PNG).
fn write_plots(
    out: &Path,
    rec: &PassageRecord,
    w: &Analysed,
    fl: &Analysed,
    fnn: &Analysed,
    element_length_m: f64,
) -> Result<(), StudiesError> {
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
    rec: &PassageRecord,
    element_length_m: f64,
) -> Result<(), StudiesError> {
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
            crate::growth::verdict::trim_zeros(&crate::growth::verdict::sig(
                crate::units::m_to_mm(element_length_m),
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
fn write_band_plot(
    out: &Path,
    w: &Analysed,
    fl: &Analysed,
    fnn: &Analysed,
) -> Result<(), StudiesError> {
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
fn write_psd_plots(
    out: &Path,
    w: &Analysed,
    fl: &Analysed,
    fnn: &Analysed,
) -> Result<(), StudiesError> {
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

/// Writes `explicit.json` into `out` (atomically): the explicit passage's figures
/// ([`crate::explicit::passage::ExplicitInfo`]: DOFs, steps, time steps, ω_max, wall and CPU time) and
/// under `energy` the passage's energy ledger (J).
pub fn write_explicit_json(
    out: &Path,
    rec: &crate::explicit::ExplicitRecord,
) -> Result<(), StudiesError> {
    let json = |source| StudiesError::Json {
        what: "explicit.json",
        source,
    };
    let mut v = serde_json::to_value(&rec.info).map_err(json)?;
    v["energy"] = serde_json::to_value(rec.record.energy).map_err(json)?;
    let text = serde_json::to_string_pretty(&v).map_err(json)?;
    let path = out.join("explicit.json");
    write_atomic(&path, |f| {
        use std::io::Write;
        f.write_all(text.as_bytes())
    })
    .map_err(StudiesError::io(&path))
}

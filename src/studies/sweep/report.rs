//! The output files of a sweep: maps, tables, plots, report; `sweep.json` last.

use std::io::Write;
use std::path::Path;

use super::linspace;
use super::{StudiesError, SweepMaps, SweepRecord};
use crate::dynamics::coupled::{seen_by_contact, ModeAttribution};
use crate::report::doc::{sentences, Document};
use crate::report::plot::{heat_map, line_plot, HeatMap, LineStyle, OverlayLine, Series};
use crate::studies::coupled::{attribution_columns, attribution_values};

fn nan_none(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}

/// Writes the assembled outputs. `sweep.json` is the commit marker: it is removed first and
/// written last, so a run killed in between leaves no complete-looking sweep beside missing
/// or stale maps; temp files of killed earlier runs are removed first.
pub(super) fn write_outputs(
    dir: &Path,
    r: &SweepRecord,
    m: &SweepMaps,
) -> Result<(), StudiesError> {
    let io = StudiesError::io;
    for d in [dir.to_path_buf(), dir.join("speeds")] {
        crate::io::remove_stale_temp_files(&d).map_err(io(&d))?;
    }
    let json = dir.join("sweep.json");
    match std::fs::remove_file(&json) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(&json)(e)),
        _ => {}
    }
    write_maps(dir, r, m)?;
    crate::io::write_atomic(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, r).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(io(&json))
}

/// Every output of [`write_outputs`] but `sweep.json`: the tables, the heat maps with the
/// mode lines, the dominant-wavelength and -frequency plots, the report.
fn write_maps(dir: &Path, r: &SweepRecord, m: &SweepMaps) -> Result<(), StudiesError> {
    write_tables(dir, r, m)?;
    let lines = ModeLines::new(r, m);
    draw_heat_maps(dir, m, &lines)?;
    draw_dominant(dir, r, &lines.frequency)?;
    write_report(dir, r)?;
    Ok(())
}

/// `dominant.csv`, the axes and maps as `.npy`, and the two maps as long CSV tables.
fn write_tables(dir: &Path, r: &SweepRecord, m: &SweepMaps) -> Result<(), StudiesError> {
    let io = StudiesError::io;
    let p = dir.join("dominant.csv");
    let mut cols: Vec<String> = [
        "speed_kmh",
        "dominant_wavelength_mm",
        "dominant_frequency_hz",
        "fl_dominant_frequency_hz",
    ]
    .map(String::from)
    .to_vec();
    cols.extend(attribution_columns(""));
    cols.extend(attribution_columns("fl_"));
    let names: Vec<&str> = cols.iter().map(String::as_str).collect();
    let at = |v: &[Option<ModeAttribution>], i: usize| {
        attribution_values(v.get(i).and_then(Option::as_ref))
    };
    crate::io::write_csv(
        &p,
        &names,
        r.speeds_kmh.iter().enumerate().map(|(i, &v)| {
            let mut row = vec![
                v,
                nan_none(r.dominant_wavelength_mm[i]),
                nan_none(r.dominant_frequency_hz[i]),
                nan_none(r.fl_dominant_frequency_hz.get(i).copied().flatten()),
            ];
            row.extend(at(&r.wear_coupled, i));
            row.extend(at(&r.fl_coupled, i));
            row
        }),
    )
    .map_err(io(&p))?;
    let (ns, nl, nf) = (
        m.speeds_kmh.len(),
        m.wavelength_mm.len(),
        m.frequency_hz.len(),
    );
    for (name, shape, data) in [
        ("speeds_kmh.npy", vec![ns], &m.speeds_kmh),
        ("wavelength_mm.npy", vec![nl], &m.wavelength_mm),
        ("frequency_hz.npy", vec![nf], &m.frequency_hz),
        ("map_wear_wavelength.npy", vec![ns, nl], &m.wear_wavelength),
        ("map_fl_wavelength.npy", vec![ns, nl], &m.fl_wavelength),
        ("map_wear_frequency.npy", vec![ns, nf], &m.wear_frequency),
        ("map_fl_frequency.npy", vec![ns, nf], &m.fl_frequency),
    ] {
        let p = dir.join(name);
        crate::io::write_npy(&p, &shape, data).map_err(io(&p))?;
    }
    write_map_csv(
        &dir.join("map_wavelength.csv"),
        ["wavelength_mm", "wear_psd_j2_per_m", "fl_psd_n2_m"],
        &m.speeds_kmh,
        &m.wavelength_mm,
        [&m.wear_wavelength, &m.fl_wavelength],
    )?;
    write_map_csv(
        &dir.join("map_frequency.csv"),
        ["frequency_hz", "wear_psd_j2_per_m2_hz", "fl_psd_n2_per_hz"],
        &m.speeds_kmh,
        &m.frequency_hz,
        [&m.wear_frequency, &m.fl_frequency],
    )
}

/// One map as a long table: a row per (speed, axis value) with the wear and F_L PSDs
/// (`maps` row-major, speeds × axis); `columns` names the axis and the two PSD columns.
fn write_map_csv(
    p: &Path,
    columns: [&str; 3],
    speeds_kmh: &[f64],
    axis: &[f64],
    maps: [&[f64]; 2],
) -> Result<(), StudiesError> {
    let n = axis.len();
    crate::io::write_csv(
        p,
        &["speed_kmh", columns[0], columns[1], columns[2]],
        speeds_kmh.iter().enumerate().flat_map(|(i, &v)| {
            axis.iter()
                .enumerate()
                .map(move |(j, &a)| vec![v, a, maps[0][i * n + j], maps[1][i * n + j]])
        }),
    )
    .map_err(StudiesError::io(p))
}

/// The mode lines drawn over the maps: the track's LC modes solid, the wheel's dashed (at
/// 5 kHz there are about 30 wheel lines), the coupled modes the contact sees in the map's
/// frequency range dotted ([`seen_by_contact`]), as wavelength `V/f` and as frequency
/// against speed.
struct ModeLines {
    wavelength: Vec<OverlayLine>,
    frequency: Vec<OverlayLine>,
}

impl ModeLines {
    fn new(r: &SweepRecord, m: &SweepMaps) -> Self {
        let ns = m.speeds_kmh.len();
        let (v0, v1) = (m.speeds_kmh[0], m.speeds_kmh[ns - 1]);
        let (vlo, vhi) = if v1 > v0 {
            (v0, v1)
        } else {
            (v0 * 0.95, v0 * 1.05)
        };
        let curve_v = linspace(vlo, vhi, 200);
        let band = [m.frequency_hz[0], m.frequency_hz[m.frequency_hz.len() - 1]];
        let labelled: Vec<(String, f64, LineStyle)> = r
            .map
            .frequency_lines_hz
            .iter()
            .map(|&f| (format!("LC {f:.0} Hz"), f, LineStyle::Solid))
            .chain(
                r.map
                    .wheel_lines_hz
                    .iter()
                    .map(|&f| (format!("wheel {f:.0} Hz"), f, LineStyle::Dashed)),
            )
            .chain(seen_by_contact(&r.map.coupled_modes, band).iter().map(|c| {
                (
                    format!("coupled {} {:.0} Hz", c.shares.dominant().0, c.frequency_hz),
                    c.frequency_hz,
                    LineStyle::Dotted,
                )
            }))
            .collect();
        let wavelength = labelled
            .iter()
            .map(|(name, f, style)| OverlayLine {
                name: name.clone(),
                x: curve_v.clone(),
                y: curve_v
                    .iter()
                    .map(|&v| crate::units::m_to_mm(crate::units::kmh_to_ms(v) / f))
                    .collect(),
                style: *style,
            })
            .collect();
        let frequency = labelled
            .iter()
            .map(|(name, f, style)| OverlayLine {
                style: *style,
                ..OverlayLine::horizontal(name.clone(), *f, vlo, vhi)
            })
            .collect();
        Self {
            wavelength,
            frequency,
        }
    }
}

/// The four heat maps (wear and F_L, over wavelength and frequency) with the mode lines. A
/// single speed has no x extent: the map is still drawn, one column wide.
fn draw_heat_maps(dir: &Path, m: &SweepMaps, lines: &ModeLines) -> Result<(), StudiesError> {
    for (stem, title, ylab, y, z, lines, unit) in [
        (
            "map_wear_wavelength",
            "Differential wear PSD: speed × wavelength",
            "wavelength (mm)",
            &m.wavelength_mm,
            &m.wear_wavelength,
            &lines.wavelength,
            "PSD ((J/m)²·m)",
        ),
        (
            "map_fl_wavelength",
            "F_L PSD: speed × wavelength",
            "wavelength (mm)",
            &m.wavelength_mm,
            &m.fl_wavelength,
            &lines.wavelength,
            "PSD (N²·m)",
        ),
        (
            "map_wear_frequency",
            "Differential wear PSD: speed × frequency",
            "frequency (Hz)",
            &m.frequency_hz,
            &m.wear_frequency,
            &lines.frequency,
            "PSD ((J/m)²/Hz)",
        ),
        (
            "map_fl_frequency",
            "F_L PSD: speed × frequency",
            "frequency (Hz)",
            &m.frequency_hz,
            &m.fl_frequency,
            &lines.frequency,
            "PSD (N²/Hz)",
        ),
    ] {
        heat_map(
            &dir.join(stem),
            &HeatMap {
                title,
                x_label: "speed (km/h)",
                y_label: ylab,
                colour_label: unit,
                x: &m.speeds_kmh,
                y,
                z,
                lines,
                log_colour: true,
                line_legend: &[
                    (LineStyle::Solid, "uncoupled rail LC modes"),
                    (LineStyle::Dashed, "uncoupled wheel modes the contact sees"),
                    (LineStyle::Dotted, "coupled wheel–track modes"),
                ],
            },
        )?;
    }
    Ok(())
}

/// The dominant wavelength and frequency against speed; the frequency plot with the mode
/// lines near the dominant frequencies (within 15 % of their range; at most eight, nearest
/// first), so that the curve and its legend stay readable (the maps show all lines). Mode
/// lines first, so the dominant frequency is drawn on top.
fn draw_dominant(dir: &Path, r: &SweepRecord, lines_f: &[OverlayLine]) -> Result<(), StudiesError> {
    let dom_l: Vec<f64> = r
        .dominant_wavelength_mm
        .iter()
        .map(|v| nan_none(*v))
        .collect();
    let dom_f: Vec<f64> = r
        .dominant_frequency_hz
        .iter()
        .map(|v| nan_none(*v))
        .collect();
    line_plot(
        &dir.join("dominant_wavelength"),
        "Dominant wear wavelength vs speed",
        "speed (km/h)",
        "wavelength (mm)",
        &[Series::new(
            "dominant wavelength",
            r.speeds_kmh.clone(),
            dom_l,
        )],
    )?;
    let (flo, fhi) = dom_f
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let dist = |f: f64| {
        if f < flo {
            (flo - f) / flo
        } else if f > fhi {
            (f - fhi) / fhi
        } else {
            0.0
        }
    };
    let mut near: Vec<(&OverlayLine, f64)> = lines_f
        .iter()
        .filter_map(|l| l.y.first().map(|&f| (l, dist(f))))
        .filter(|(_, d)| *d <= 0.15)
        .collect();
    near.sort_by(|a, b| a.1.total_cmp(&b.1));
    near.truncate(8);
    let mut fs: Vec<Series> = near
        .iter()
        .map(|(l, _)| Series::new(l.name.clone(), l.x.clone(), l.y.clone()))
        .collect();
    fs.push(Series::new(
        "dominant frequency",
        r.speeds_kmh.clone(),
        dom_f,
    ));
    line_plot(
        &dir.join("dominant_frequency"),
        "Dominant wear frequency vs speed, with the nearest modes",
        "speed (km/h)",
        "frequency (Hz)",
        &fs,
    )?;
    Ok(())
}

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".into(), |x| format!("{x:.digits$}"))
}

/// The sweep's result in a few plain lines (what `corrugation sweep` prints on stdout and
/// the report opens with): the speeds, the dominant wear wavelength and frequency ranges
/// with the two range ratios, and the coupled mode that selects the wear over each speed
/// range.
pub fn summary_lines(r: &SweepRecord) -> Vec<String> {
    let range = |v: &[Option<f64>]| {
        let xs: Vec<f64> = v.iter().flatten().copied().collect();
        (!xs.is_empty()).then(|| {
            xs.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &x| {
                    (l.min(x), u.max(x))
                })
        })
    };
    let n = r.speeds_kmh.len();
    let mut out = Vec::new();
    let speeds = format!(
        "{} speed(s), {}–{} km/h",
        n,
        r.speeds_kmh[0],
        r.speeds_kmh[n - 1]
    );
    match (
        range(&r.dominant_wavelength_mm),
        range(&r.dominant_frequency_hz),
    ) {
        (Some((l0, l1)), Some((f0, f1))) => out.push(format!(
            "{speeds}: dominant wear wavelength {l0:.1}–{l1:.1} mm, frequency {f0:.0}–{f1:.0} Hz; \
             wavelength range ratio {} against the speed range ratio {:.3}",
            fmt_opt(r.wavelength_range_ratio, 3),
            r.speed_range_ratio
        )),
        _ => out.push(format!(
            "{speeds}: no speed has a wear component in the 20–80 mm band"
        )),
    }
    let without = r
        .dominant_wavelength_mm
        .iter()
        .filter(|x| x.is_none())
        .count();
    if without > 0 && without < n {
        out.push(format!(
            "{without} of {n} speeds have no wear component in the 20–80 mm band"
        ));
    }
    for (i, j, a) in speed_ranges(&r.wear_coupled) {
        out.push(format!(
            "{}–{} km/h: the wear selects the coupled mode at {:.1} Hz (mostly {})",
            r.speeds_kmh[i],
            r.speeds_kmh[j],
            a.mode_frequency_hz,
            a.shares.dominant().0
        ));
    }
    out
}

fn write_report(dir: &Path, r: &SweepRecord) -> Result<(), StudiesError> {
    let mut d = Document::new("Speed sweep: frequency selection");
    d.paragraph(format!("**Summary.** {}", sentences(&summary_lines(r))));
    d.paragraph(format!(
        "{} speeds from {} to {} km/h. Speed range ratio {:.3}; wavelength range ratio of the \
         dominant wear wavelength {}. Frequency selection shows as a wavelength range ratio \
         much smaller than the speed range ratio (docs/theory.md §2.3).",
        r.speeds_kmh.len(),
        r.speeds_kmh[0],
        r.speeds_kmh[r.speeds_kmh.len() - 1],
        r.speed_range_ratio,
        fmt_opt(r.wavelength_range_ratio, 3)
    ));
    if !r.map.frequency_lines_hz.is_empty() {
        let f: Vec<String> = r
            .map
            .frequency_lines_hz
            .iter()
            .map(|f| format!("{f:.1}"))
            .collect();
        d.paragraph(format!(
            "Longitudinal-compression eigenfrequencies drawn on the maps (Hz, `LC`): {}.",
            f.join(", ")
        ));
    }
    if !r.map.wheel_lines_hz.is_empty() {
        let f: Vec<String> = r
            .map
            .wheel_lines_hz
            .iter()
            .map(|f| format!("{f:.1}"))
            .collect();
        d.paragraph(format!(
            "Wheel eigenfrequencies with a large modal displacement at the contact point drawn \
             on the maps (Hz, `wheel`): {}. On the default Dutch track the ridges fall on \
             these, not on the rail's longitudinal-compression modes \
             (validation/frequency_selection.md in the source tree).",
            f.join(", ")
        ));
    }
    coupled_section(&mut d, r);
    d.heading(2, "Maps");
    for (alt, file) in [
        (
            "Differential wear PSD, speed × wavelength",
            "map_wear_wavelength.png",
        ),
        (
            "Differential wear PSD, speed × frequency",
            "map_wear_frequency.png",
        ),
        ("F_L PSD, speed × wavelength", "map_fl_wavelength.png"),
        ("F_L PSD, speed × frequency", "map_fl_frequency.png"),
        ("Dominant wavelength vs speed", "dominant_wavelength.png"),
        ("Dominant frequency vs speed", "dominant_frequency.png"),
    ] {
        d.image(alt, file);
    }
    d.heading(2, "Dominant wear component per speed");
    d.table(
        &["speed (km/h)", "wavelength (mm)", "frequency (Hz)"],
        r.speeds_kmh
            .iter()
            .enumerate()
            .map(|(i, v)| {
                vec![
                    format!("{v}"),
                    fmt_opt(r.dominant_wavelength_mm[i], 2),
                    fmt_opt(r.dominant_frequency_hz[i], 1),
                ]
            })
            .collect(),
    );
    d.write(&dir.join("report"))?;
    Ok(())
}

/// Consecutive speeds whose frequency is attributed to the same coupled mode (same frequency
/// and contact position): `(first index, last index, attribution of the first)`.
fn speed_ranges(a: &[Option<ModeAttribution>]) -> Vec<(usize, usize, &ModeAttribution)> {
    let mut out: Vec<(usize, usize, &ModeAttribution)> = Vec::new();
    for (i, x) in a.iter().enumerate() {
        let Some(x) = x else { continue };
        match out.last_mut() {
            Some((_, last, m))
                if *last + 1 == i
                    && m.mode_frequency_hz == x.mode_frequency_hz
                    && m.position_m == x.position_m =>
            {
                *last = i
            }
            _ => out.push((i, i, x)),
        }
    }
    out
}

/// The tables of which coupled modes select the wear's and F_L's dominant frequency over which
/// speed ranges (nothing without coupled modes).
fn coupled_section(d: &mut Document, r: &SweepRecord) {
    let Some(v) = r.map.coupled_speed_kmh else {
        return;
    };
    d.heading(2, "Coupled wheel–track modes that select");
    d.paragraph(format!(
        "Each speed's strongest wear and F_L component attributed to a coupled wheel–track mode \
         (docs/theory.md §7.10: among the modes within 3 % the one that moves the contact most, \
         else the nearest one the contact moves), with the modes computed once at {v} km/h \
         (the creep terms of the linearised contact depend on the speed; see docs/theory.md \
         §11.2 for how far that moves them). Shares: energy of the mode in the wheel, the rail \
         by family, the support. Per-speed numbers: dominant.csv. Red dotted lines on the maps: \
         the coupled modes the contact sees (contact residue ≥ 3 % of the largest)."
    ));
    for (title, freq, att) in [
        ("Wear", &r.dominant_frequency_hz, &r.wear_coupled),
        ("F_L", &r.fl_dominant_frequency_hz, &r.fl_coupled),
    ] {
        let mut any_distant = false;
        let rows: Vec<Vec<String>> = speed_ranges(att)
            .into_iter()
            .map(|(i, j, a)| {
                let fs: Vec<f64> = (i..=j)
                    .filter_map(|k| freq.get(k).copied().flatten())
                    .collect();
                let (flo, fhi) = fs
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &f| {
                        (l.min(f), u.max(f))
                    });
                let mut shares: Vec<(String, f64)> = crate::dynamics::coupled::ModeShares::labels()
                    .into_iter()
                    .zip(a.shares.values())
                    .filter(|(_, v)| *v >= 0.05)
                    .collect();
                shares.sort_by(|x, y| y.1.total_cmp(&x.1));
                let window = crate::dynamics::coupled::ATTRIBUTION_WINDOW;
                let distant = fs
                    .iter()
                    .any(|f| ((a.mode_frequency_hz - f) / f).abs() > window);
                any_distant |= distant;
                vec![
                    format!("{}–{}", r.speeds_kmh[i], r.speeds_kmh[j]),
                    format!("{flo:.0}–{fhi:.0}"),
                    format!(
                        "{:.1}{}",
                        a.mode_frequency_hz,
                        if distant { " †" } else { "" }
                    ),
                    a.shares.dominant().0,
                    shares
                        .iter()
                        .map(|(l, v)| format!("{l} {:.0} %", 100.0 * v))
                        .collect::<Vec<_>>()
                        .join(", "),
                    format!("{:.2}", 100.0 * a.damping_ratio),
                    crate::growth::verdict::sig(a.rail_x_to_n, 3),
                    format!("{:.3}", a.position_m),
                ]
            })
            .collect();
        if rows.is_empty() {
            continue;
        }
        d.heading(3, format!("{title}: coupled mode by speed range"));
        d.table(
            &[
                "speeds (km/h)",
                "selected (Hz)",
                "coupled mode (Hz)",
                "part",
                "energy shares",
                "ζ (%)",
                "rail x/n at contact",
                "contact at x (m)",
            ],
            rows,
        );
        if any_distant {
            d.paragraph(
                "† No coupled mode lies within 3 % of some of the range's selected frequencies: \
                 the nearest mode the contact sees is shown, and those frequencies are not \
                 explained by a single coupled mode (a forced response between modes, or modes \
                 moved by the speed's creep terms).",
            );
        }
    }
}

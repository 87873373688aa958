//! `corrugation modes`: eigenmodes of the track and the wheel substructures (separately),
//! classified by shape, cached on disk.
//!
//! Outputs in `--out DIR` (default `corrugation-out/modes`):
//! * `modes.csv` — one row per track mode (see [`TRACK_HEADER`]); `family` is the snake_case
//!   name (longitudinal_compression, longitudinal_shear, vertical_bending, lateral_bending,
//!   torsion, sleeper, local, other), `wavelength_m` is empty when undefined (fewer than two
//!   zero crossings), `rail_x_*` and `amp_*` are relative to the RMS rail displacement
//!   (dimensionless), `energy_*` strain-energy shares, `pinned_pinned` 0/1, `rail_family`
//!   the family of the rail's own motion (differs from `family` for `sleeper` modes, whose
//!   rail may e.g. carry a longitudinal-compression motion along with the sleepers);
//! * `wheel_modes.csv` — one row per wheel mode (family rigid, axial, radial, other);
//! * on stdout (and under `wheel_band` with `--json`): the wheel's in-plane (radial and
//!   circumferential rim motion) and out-of-plane (axial) mode frequencies in 0.5–2 kHz (to `--fmax` if lower), so that a
//!   change of the wheel's geometry keys shows where its modes went;
//! * with `--vtu`: `track_mode_NNNN.vtu` and `wheel_mode_NNNN.vtu` for the first
//!   `--vtu-modes` (default 50) modes of each substructure, mesh + point field `displacement`
//!   (mode shape, M-normalised, m/√kg) — ParaView "Warp By Vector".
//!
//! Cache: key = blake3 over the resolved model (serde_json), f_max, the substructure name and
//! the program version ([`CacheKey`]); the classification is stored in the entry's metadata.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::eigen::basis::{track_basis, wheel_basis, ModalBasis};
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::eigen::classify::{
    wheel_band_modes, TrackModeClass, WheelBandModes, WheelModeClass, WHEEL_SUMMARY_BAND_HZ,
};
use corrugation::eigen::RESIDUAL_FLOOR_HZ;
use corrugation::io::{write_vtu, VtuField, VTK_HEXAHEDRON};
use corrugation::mesh::Mesh;
use corrugation::structure::{TrackStructure, WheelStructure};

use super::ModelArgs;

/// Columns of `modes.csv`.
pub const TRACK_HEADER: [&str; 21] = [
    "index",
    "frequency_hz",
    "family",
    "rail_x_head",
    "rail_x_web",
    "rail_x_foot",
    "wavelength_m",
    "energy_rail",
    "energy_sleepers",
    "energy_fastening",
    "energy_ballast",
    "relative_residual",
    "amp_compression",
    "amp_shear",
    "amp_vertical",
    "amp_lateral",
    "amp_torsion",
    "sleeper_kinetic_share",
    "section_fit",
    "pinned_pinned",
    "rail_family",
];

/// Columns of `wheel_modes.csv`.
pub const WHEEL_HEADER: [&str; 9] = [
    "index",
    "frequency_hz",
    "family",
    "rigid",
    "energy_wheel",
    "energy_suspension",
    "rim_radial",
    "rim_axial",
    "rim_circumferential",
];

/// Eigenmodes of the track and the wheel, classified (CSV, optional VTU), cached.
#[derive(Debug, Args)]
pub struct ModesCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Upper frequency (Hz): all modes below it.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = 5000.0,
        value_name = "HZ"
    )]
    fmax: f64,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/modes", value_name = "DIR")]
    out: PathBuf,
    /// Write mode shapes as .vtu files (first --vtu-modes modes of each substructure).
    #[arg(long)]
    vtu: bool,
    /// Number of modes written with --vtu.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = 50,
        value_name = "N"
    )]
    vtu_modes: usize,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

/// Summary of one substructure.
#[derive(Debug, Serialize)]
pub struct SubSummary {
    pub count: usize,
    pub fmax_hz: f64,
    pub sturm_count: usize,
    /// The largest relative residual of the modes above [`RESIDUAL_FLOOR_HZ`] (1 Hz) (a rigid-body
    /// mode's relative residual is its eigenvalue's round-off over the measure's floor, up to
    /// about 1, and says nothing about its accuracy; `eigen` module doc).
    pub max_residual: f64,
    pub seconds: f64,
    pub cached: bool,
    pub families: BTreeMap<String, usize>,
}

/// JSON printed by `modes --json`: the track summary at top level, the wheel under `wheel`.
#[derive(Debug, Serialize)]
pub struct ModesSummary {
    #[serde(flatten)]
    pub track: SubSummary,
    pub wheel: SubSummary,
    /// The wheel's in-plane and out-of-plane modes in 0.5–2 kHz (to `--fmax` if lower).
    pub wheel_band: WheelBandModes,
    pub cache_dir: String,
}

impl ModesCmd {
    /// Runs the command: the track and wheel bases (Lanczos or the cache), the CSV files,
    /// the optional VTU files, the summary.
    pub fn run(self) -> anyhow::Result<()> {
        if !(self.fmax.is_finite() && (100.0..=20000.0).contains(&self.fmax)) {
            anyhow::bail!(
                "--fmax {}: out of range, allowed 100 to 20000 Hz (as run.fmax)",
                self.fmax
            );
        }
        let m = self.model.load()?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let cache_dir = self.cache.clone().unwrap_or_else(default_cache_dir);
        let pb = std::sync::Arc::new(super::progress::bar(&format!(
            "track and wheel modes below {} Hz (Lanczos, or the cache)",
            self.fmax
        )));
        let cache = ModalCache::new(&cache_dir).with_progress(pb.clone());
        let track = TrackStructure::build(&m).context("building the track model")?;
        let wheel = WheelStructure::build(&m).context("building the wheel model")?;
        let tb = track_basis(&m, &track, &cache, self.fmax)?;
        let wb = wheel_basis(&m, &wheel, &cache, self.fmax)?;
        pb.finish_and_clear();
        drop(cache);
        drop(pb);

        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("creating {}", self.out.display()))?;
        write_track_csv(&self.out.join("modes.csv"), &tb)?;
        write_wheel_csv(&self.out.join("wheel_modes.csv"), &wb)?;
        if self.vtu {
            write_mode_vtus(
                &self.out,
                "track",
                &track.mesh,
                &track.dofmap,
                &tb,
                self.vtu_modes,
            )?;
            write_mode_vtus(
                &self.out,
                "wheel",
                &wheel.mesh,
                &wheel.dofmap,
                &wb,
                self.vtu_modes,
            )?;
        }
        let s = ModesSummary {
            track: sub_summary(&tb, tb.classes.iter().map(|c| c.family.name()), self.fmax),
            wheel: sub_summary(&wb, wb.classes.iter().map(|c| c.family.name()), self.fmax),
            wheel_band: wheel_band_modes(
                &wb.frequencies_hz,
                &wb.classes,
                [
                    WHEEL_SUMMARY_BAND_HZ[0],
                    WHEEL_SUMMARY_BAND_HZ[1].min(self.fmax),
                ],
            ),
            cache_dir: cache_dir.display().to_string(),
        };
        if self.json {
            println!("{}", serde_json::to_string_pretty(&s)?);
        } else {
            print_summary(&s, &self.out);
        }
        Ok(())
    }
}

/// The summary of basis `b` below `fmax_hz` whose modes have the family names `families`.
fn sub_summary<'a, C>(
    b: &ModalBasis<C>,
    families: impl Iterator<Item = &'a str>,
    fmax_hz: f64,
) -> SubSummary {
    let mut counts = BTreeMap::new();
    for f in families {
        *counts.entry(f.to_string()).or_insert(0) += 1;
    }
    SubSummary {
        count: b.frequencies_hz.len(),
        fmax_hz,
        sturm_count: b.sturm_count,
        max_residual: b
            .residuals
            .iter()
            .zip(&b.frequencies_hz)
            .filter(|(_, &f)| f >= RESIDUAL_FLOOR_HZ)
            .map(|(&r, _)| r)
            .fold(0.0, f64::max),
        seconds: b.seconds,
        cached: b.cached,
        families: counts,
    }
}

/// `modes.csv`: one row per track mode ([`TRACK_HEADER`]).
fn write_track_csv(path: &Path, tb: &ModalBasis<TrackModeClass>) -> anyhow::Result<()> {
    write_text_csv(
        path,
        &TRACK_HEADER,
        tb.classes.iter().enumerate().map(|(i, c)| {
            let mut r = vec![
                i.to_string(),
                num(tb.frequencies_hz[i]),
                c.family.name().to_string(),
                num(c.rail_x_head),
                num(c.rail_x_web),
                num(c.rail_x_foot),
                c.wavelength_m.map(num).unwrap_or_default(),
                num(c.energy.rail),
                num(c.energy.sleepers),
                num(c.energy.fastening),
                num(c.energy.ballast),
                tb.residuals.get(i).copied().map(num).unwrap_or_default(),
            ];
            r.extend(c.amplitudes.map(num));
            r.extend([
                num(c.sleeper_kinetic_share),
                num(c.section_fit),
                (c.pinned_pinned as u8).to_string(),
                c.rail_family.unwrap_or(c.family).name().to_string(),
            ]);
            r
        }),
    )
}

/// `wheel_modes.csv`: one row per wheel mode ([`WHEEL_HEADER`]).
fn write_wheel_csv(path: &Path, wb: &ModalBasis<WheelModeClass>) -> anyhow::Result<()> {
    write_text_csv(
        path,
        &WHEEL_HEADER,
        wb.classes.iter().enumerate().map(|(i, c)| {
            vec![
                i.to_string(),
                num(wb.frequencies_hz[i]),
                c.family.name().to_string(),
                (c.rigid as u8).to_string(),
                num(c.energy_wheel),
                num(c.energy_suspension),
                num(c.rim_shares[0]),
                num(c.rim_shares[1]),
                num(c.rim_shares[2]),
            ]
        }),
    )
}

fn print_summary(s: &ModesSummary, out: &Path) {
    for (name, b) in [("track", &s.track), ("wheel", &s.wheel)] {
        println!(
            "{name}: {} modes < {} Hz (Sturm count {}), max residual {:.1e} (modes above 1 Hz), {:.2} s{}",
            b.count,
            b.fmax_hz,
            b.sturm_count,
            b.max_residual,
            b.seconds,
            if b.cached { " (cached)" } else { "" }
        );
        for (f, n) in &b.families {
            println!("  {f:<26} {n}");
        }
    }
    let w = &s.wheel_band;
    let list = |v: &[f64]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|f| format!("{f:.0}"))
                .collect::<Vec<_>>()
                .join(", ")
                + " Hz"
        }
    };
    println!(
        "wheel modes {:.0}-{:.0} Hz: in-plane {}; out-of-plane {}",
        w.band_hz[0],
        w.band_hz[1],
        list(&w.in_plane_hz),
        list(&w.out_of_plane_hz),
    );
    println!("written to {}", out.display());
}

/// Writes a CSV of text cells atomically (numbers formatted by the caller).
fn write_text_csv(
    path: &Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<String>>,
) -> anyhow::Result<()> {
    corrugation::io::write_text_csv(path, header, rows)
        .with_context(|| format!("writing {}", path.display()))
}

fn num(x: f64) -> String {
    format!("{x:e}")
}

fn write_mode_vtus<C>(
    dir: &Path,
    name: &str,
    mesh: &Mesh,
    dofmap: &corrugation::fe::assembly::DofMap,
    b: &ModalBasis<C>,
    limit: usize,
) -> anyhow::Result<()> {
    let cells: Vec<(u8, Vec<usize>)> = mesh
        .elements
        .iter()
        .map(|e| (VTK_HEXAHEDRON, e.nodes.to_vec()))
        .collect();
    for j in 0..b.frequencies_hz.len().min(limit) {
        let u = dofmap.expand(&b.modes.col(j).iter().copied().collect::<Vec<f64>>())?;
        let p = dir.join(format!("{name}_mode_{j:04}.vtu"));
        write_vtu(
            &p,
            &mesh.nodes,
            &cells,
            &[VtuField {
                name: "displacement",
                components: 3,
                data: &u,
            }],
            &[],
        )
        .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The printed largest residual leaves out the rigid-body modes below 1 Hz, whose
    /// relative residual is round-off over the measure's floor (0.71 for a 0.84 Hz rotation
    /// of the bare wheelset, where the elastic modes' largest is 3.7e-6).
    #[test]
    fn the_largest_residual_is_the_elastic_modes() {
        let b = ModalBasis::<()> {
            frequencies_hz: vec![0.0, 0.84, 7.5, 610.0],
            modes: faer::Mat::zeros(1, 4),
            residuals: vec![1e-3, 0.71, 2e-6, 3.7e-6],
            sturm_count: 4,
            classes: vec![(); 4],
            cached: false,
            seconds: 0.0,
        };
        let s = sub_summary(
            &b,
            ["rigid", "rigid", "rigid", "radial"].into_iter(),
            5000.0,
        );
        assert_eq!(s.max_residual, 3.7e-6);
        assert_eq!(s.count, 4);
    }
}

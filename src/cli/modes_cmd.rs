//! `corrugation modes`: eigenmodes of the track and the wheel substructures (separately),
//! classified by shape, cached on disk.
//!
//! Outputs in `--out DIR` (default `corrugation-out/modes`): `modes.csv`, `wheel_modes.csv`
//! and with `--vtu` the mode shapes (`corrugation::studies::modes` says what each holds); on
//! stdout (and under `wheel_band` with `--json`) the wheel's in-plane and out-of-plane mode
//! frequencies in 0.5–2 kHz, so that a change of the wheel's geometry keys shows where its
//! modes went.
//!
//! Cache: key = blake3 over the resolved model (serde_json), f_max, the substructure name and
//! the program version ([`CacheKey`]); the classification is stored in the entry's metadata.
//!
//! [`CacheKey`]: corrugation::eigen::cache::CacheKey

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use corrugation::eigen::basis::{track_basis, wheel_basis};
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::structure::{TrackStructure, WheelStructure};
use corrugation::studies::modes::{check_fmax, write_mode_tables, write_mode_vtus, ModesSummary};

use super::ModelArgs;

/// Eigenmodes of the track and the wheel, classified (CSV, optional VTU), cached.
#[derive(Debug, Args)]
pub(crate) struct ModesCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Upper frequency (Hz): all modes below it.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = corrugation::studies::modes::DEFAULT_FMAX_HZ,
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
        default_value_t = corrugation::studies::modes::DEFAULT_VTU_MODES,
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

impl ModesCmd {
    /// Runs the command: the track and wheel bases (Lanczos or the cache), the CSV files,
    /// the optional VTU files, the summary.
    pub fn run(self) -> anyhow::Result<()> {
        check_fmax(self.fmax)?;
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

        write_mode_tables(&self.out, &tb, &wb)?;
        if self.vtu {
            let n = self.vtu_modes;
            write_mode_vtus(&self.out, "track", &track.mesh, &track.dofmap, &tb, n)?;
            write_mode_vtus(&self.out, "wheel", &wheel.mesh, &wheel.dofmap, &wb, n)?;
        }
        let s = ModesSummary::new(&tb, &wb, self.fmax, &cache_dir);
        if self.json {
            println!("{}", serde_json::to_string_pretty(&s)?);
        } else {
            print_summary(&s, &self.out);
        }
        Ok(())
    }
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

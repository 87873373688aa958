//! `corrugation sweep`: passages over a range of speeds (in parallel, resumable, shardable)
//! and the frequency-selection maps. See [`corrugation::studies::sweep`] for the files.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use corrugation::studies::coupled::sweep_reference_speed_kmh;
use corrugation::studies::speeds::{parse_speeds, Shard};
use corrugation::studies::sweep::{map_options, sweep_beside, write_shard_plan, MapOptions};

use super::{engine, ModelArgs};

/// Speed sweep: frequency-selection maps, dominant wavelength and frequency vs speed.
#[derive(Debug, Args)]
pub(crate) struct SweepCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Speeds in km/h: START:STOP:STEP (STOP included only when it falls on the grid) or a
    /// list 60,80,100.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value = corrugation::studies::speeds::DEFAULT_SWEEP_SPEEDS,
        value_name = "SPEEDS"
    )]
    speeds: String,
    /// Run only shard I of N (I = 0 … N−1): every N-th speed starting at the I-th. Join the
    /// shard directories with `corrugation merge`.
    #[arg(allow_hyphen_values = true, long, value_name = "I/N")]
    shard: Option<String>,
    /// Output directory (a rerun into it resumes: finished speeds are not recomputed).
    #[arg(long, default_value = "corrugation-out/sweep", value_name = "DIR")]
    out: PathBuf,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Passage engine: `reduced` (modal, default) or `explicit` (the full explicit FE
    /// path, minutes per passage).
    #[arg(long, value_enum, default_value = "reduced")]
    engine: super::engine::Engine,
}

impl SweepCmd {
    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let all = parse_speeds(&self.speeds)?;
        let shard = match &self.shard {
            Some(s) => Shard::parse(s)?,
            None => Shard::ALL,
        };
        let speeds = shard.select(&all);
        if speeds.is_empty() {
            anyhow::bail!(
                "shard {}/{} of {} speed(s) is empty; use fewer shards",
                shard.index,
                shard.count,
                all.len()
            );
        }
        let model = self.model.load()?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let cache = self.cache.as_deref();
        // One modal model for both the mode lines and the passages.
        let prepared = engine::prepared(&model, cache)?;
        // The coupled modes once, at a speed fixed by the whole sweep (shards agree),
        // computed beside the first passages: they enter only the maps.
        let v_c = sweep_reference_speed_kmh(model.run.speed_kmh, &all);
        let lines = || -> Result<MapOptions, corrugation::studies::BoxError> {
            let t_c = Instant::now();
            let o = map_options(&prepared, v_c)?;
            eprintln!(
                "sweep: coupled wheel–track modes at {v_c} km/h in {:.1} s (beside the passages)",
                t_c.elapsed().as_secs_f64()
            );
            Ok(o)
        };
        let explicit;
        let runner: &dyn corrugation::dynamics::PassageRunner = match self.engine {
            engine::Engine::Reduced => &prepared,
            engine::Engine::Explicit => {
                explicit = engine::runner_for_engine(&model, cache, self.engine)?;
                explicit.as_ref()
            }
        };
        // Resume only into a directory of the same model and program version.
        // (The explicit engine's results are never mixed with the reduced ones.)
        let run_key = format!(
            "{}{}",
            corrugation::model::identity::run_key(&model)?,
            match self.engine {
                engine::Engine::Reduced => "",
                engine::Engine::Explicit => " explicit",
            }
        );
        let pb = super::progress::bar("speed sweep");
        let out = sweep_beside(runner, &speeds, &self.out, lines, &run_key, &pb)?;
        drop(pb);
        // Which shard of which sweep this directory holds: `merge` checks the shards form one.
        write_shard_plan(&self.out, &all, shard)?;
        eprintln!(
            "sweep: {} speed(s), {} computed, {} reused; speed range ratio {:.3}, wavelength range ratio {}; {}",
            speeds.len(),
            out.stats.computed.len(),
            out.stats.reused.len(),
            out.record.speed_range_ratio,
            out.record
                .wavelength_range_ratio
                .map_or("–".into(), |r| format!("{r:.3}")),
            self.out.display()
        );
        if !self.json {
            for line in corrugation::studies::sweep::summary_lines(&out.record) {
                println!("{line}");
            }
        }
        if self.json {
            let mut j = serde_json::to_value(&out.record)?;
            // The coupled modes are in sweep.json; only their count here.
            j["map"]["coupled_modes"] = out.record.map.coupled_modes.len().into();
            j["wall_seconds"] = t0.elapsed().as_secs_f64().into();
            j["computed"] = out.stats.computed.len().into();
            j["reused"] = out.stats.reused.len().into();
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
        Ok(())
    }
}

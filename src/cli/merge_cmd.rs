//! `corrugation merge`: joins the directories of sharded sweeps (`sweep --shard I/N`) into
//! the files and JSON of the unsharded sweep.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use corrugation::studies::sweep::merge;

/// Join shard directories of a sweep into one.
#[derive(Debug, Args)]
pub(crate) struct MergeCmd {
    /// Shard directories (each the --out of one `sweep --shard I/N`).
    #[arg(required = true, value_name = "DIR")]
    dirs: Vec<PathBuf>,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Print the JSON summary of the merged sweep on stdout.
    #[arg(long)]
    json: bool,
}

impl MergeCmd {
    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let (record, _) = merge(&self.dirs, &self.out)?;
        eprintln!(
            "merge: {} shard(s), {} speed(s) → {}",
            self.dirs.len(),
            record.speeds_kmh.len(),
            self.out.display()
        );
        if !self.json {
            for line in corrugation::studies::sweep::summary_lines(&record) {
                println!("{line}");
            }
        }
        if self.json {
            let mut j = serde_json::to_value(&record)?;
            // The coupled modes are in sweep.json; only their count here.
            j["map"]["coupled_modes"] = record.map.coupled_modes.len().into();
            j["wall_seconds"] = t0.elapsed().as_secs_f64().into();
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
        Ok(())
    }
}

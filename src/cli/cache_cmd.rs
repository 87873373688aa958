//! `corrugation cache`: lists the modal cache's entries (size, basis, last use) and, with
//! `--max-size-gb` or `--max-idle-days`, removes the least recently used ones.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::bail;
use clap::Args;

use corrugation::eigen::cache::{default_cache_dir, ModalCache, PrunePolicy};
use corrugation::units::{bytes_to_gb, days_to_s, gb_to_bytes, s_to_days};

/// List the modal cache and remove least recently used entries.
#[derive(Debug, Args)]
pub struct CacheCmd {
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Remove the least recently used entries until the cache holds at most this many GB
    /// (10⁹ bytes); ≥ 0.
    #[arg(long, value_name = "GB", allow_negative_numbers = true)]
    max_size_gb: Option<f64>,
    /// Remove the entries not used for more than this many days; ≥ 0.
    #[arg(long, value_name = "DAYS", allow_negative_numbers = true)]
    max_idle_days: Option<f64>,
    /// Only print what would be removed.
    #[arg(long)]
    dry_run: bool,
    /// Print the entries (and what was removed) as JSON on stdout.
    #[arg(long)]
    json: bool,
}

fn non_negative(flag: &str, v: Option<f64>) -> anyhow::Result<Option<f64>> {
    match v {
        Some(x) if !(x.is_finite() && x >= 0.0) => {
            bail!("{flag} = {x}: allowed range is a finite number ≥ 0")
        }
        _ => Ok(v),
    }
}

impl CacheCmd {
    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        let max_gb = non_negative("--max-size-gb", self.max_size_gb)?;
        let max_days = non_negative("--max-idle-days", self.max_idle_days)?;
        let cache = ModalCache::new(self.cache.clone().unwrap_or_else(default_cache_dir));
        let entries = cache.entries()?;
        let total: u64 = entries.iter().map(|e| e.bytes).sum();
        eprintln!(
            "modal cache {}: {} entries, {:.2} GB",
            cache.dir().display(),
            entries.len(),
            bytes_to_gb(total)
        );
        if !self.json {
            println!("key               GB      DOFs   modes  f_max_Hz  idle_days");
            for e in &entries {
                println!(
                    "{:<16}  {:>6.3}  {:>7}  {:>5}  {:>8.0}  {:>9.2}",
                    &e.key[..e.key.len().min(16)],
                    bytes_to_gb(e.bytes),
                    e.n_dofs,
                    e.n_modes,
                    e.f_max_hz,
                    s_to_days(e.idle_s)
                );
            }
        }
        let report = if max_gb.is_some() || max_days.is_some() {
            let r = cache.prune(PrunePolicy {
                max_bytes: max_gb.map(gb_to_bytes),
                max_idle: max_days.map(|d| Duration::from_secs_f64(days_to_s(d))),
                dry_run: self.dry_run,
            })?;
            eprintln!(
                "{} {} entries ({:.2} GB); {:.2} GB kept",
                if self.dry_run {
                    "would remove"
                } else {
                    "removed"
                },
                r.removed.len(),
                bytes_to_gb(r.freed_bytes),
                bytes_to_gb(r.kept_bytes)
            );
            Some(r)
        } else {
            None
        };
        if self.json {
            let j = serde_json::json!({
                "dir": cache.dir(),
                "total_bytes": total,
                "entries": entries,
                "prune": report,
                "dry_run": self.dry_run,
            });
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
        Ok(())
    }
}

//! `corrugation cache`: lists the modal cache's entries (size, basis, last use) and, with
//! `--max-size-gb` or `--max-idle-days`, removes the least recently used ones.
//!
//! Only the cache's own entries and leftovers are ever listed or removed (the ownership rule
//! of [`corrugation::eigen::cache`]). A directory that does not look like a modal cache — it
//! exists, has no `CACHEDIR.TAG` and holds anything else — is refused (a mistyped `--cache`),
//! unless `--force`; items that are not the cache's are named on stderr and left alone.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::bail;
use clap::Args;

use corrugation::eigen::cache::{default_cache_dir, CacheError, ModalCache, PrunePolicy};
use corrugation::units::{bytes_to_gb, days_to_s, gb_to_bytes, s_to_days};

/// List the modal cache and remove least recently used entries.
#[derive(Debug, Args)]
pub(crate) struct CacheCmd {
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Remove the least recently used entries until the cache holds at most this many GB
    /// (10⁹ bytes); ≥ 0.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_name = "GB",
        allow_negative_numbers = true
    )]
    max_size_gb: Option<f64>,
    /// Remove the entries not used for more than this many days; ≥ 0.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_name = "DAYS",
        allow_negative_numbers = true
    )]
    max_idle_days: Option<f64>,
    /// Only print what would be removed.
    #[arg(long)]
    dry_run: bool,
    /// Print the entries (and what was removed) as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// List and prune a directory that does not look like a modal cache (no CACHEDIR.TAG,
    /// and other things than cache entries in it); even then only cache entries are removed.
    #[arg(long)]
    force: bool,
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
        let survey = match cache.check_is_cache() {
            Ok(s) => s,
            Err(CacheError::NotACache { .. }) if self.force => cache.survey()?,
            Err(e @ CacheError::NotACache { .. }) => bail!(
                "{e}; check --cache, or add --force to list and prune the cache entries in it \
                 anyway (nothing else is ever removed)"
            ),
            Err(e) => return Err(e.into()),
        };
        if !survey.others.is_empty() {
            eprintln!(
                "note: {} item(s) in {} are not cache entries and are left alone: {}",
                survey.others.len(),
                cache.dir().display(),
                corrugation::eigen::cache::quote_names(&survey.others)
            );
        }
        if survey.fe_patches > 0 {
            eprintln!(
                "fe-patches in {}: {} ({:.3} GB; contact.influence = \"fe-patch\", rebuilt when removed by hand)",
                cache.dir().join(corrugation::eigen::cache::FE_PATCH_DIR).display(),
                survey.fe_patches,
                bytes_to_gb(survey.fe_patch_bytes)
            );
        }
        let entries = cache.entries()?;
        let total: u64 = entries.iter().map(|e| e.bytes).sum();
        eprintln!(
            "modal cache {}: {} entries, {:.2} GB",
            cache.dir().display(),
            entries.len(),
            bytes_to_gb(total)
        );
        if !self.json {
            println!("key               GB      DOFs   modes  f_max_Hz  idle_days  valid");
            for e in &entries {
                println!(
                    "{:<16}  {:>6.3}  {:>7}  {:>5}  {:>8.0}  {:>9.2}  {}",
                    &e.key[..e.key.len().min(16)],
                    bytes_to_gb(e.bytes),
                    e.n_dofs,
                    e.n_modes,
                    e.f_max_hz,
                    s_to_days(e.idle_s),
                    if e.intact { "yes" } else { "no (recomputed)" }
                );
            }
        }
        let report = if max_gb.is_some() || max_days.is_some() {
            let r = cache.prune(PrunePolicy {
                max_bytes: max_gb.map(gb_to_bytes),
                // beyond Duration's range (about 5.8e11 years) no entry is that idle
                max_idle: max_days
                    .map(|d| Duration::try_from_secs_f64(days_to_s(d)).unwrap_or(Duration::MAX)),
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
            // A cache written before tags (entries only) gets its tag.
            if !self.dry_run && !survey.tagged {
                if let Err(e) = cache.tag_if_cache() {
                    eprintln!("warning: {e}");
                }
            }
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
                "tagged": survey.tagged,
                "not_entries": survey.others,
            });
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
        Ok(())
    }
}

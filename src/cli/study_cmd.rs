//! `corrugation study FILE.toml`: a design study (parameters varied over a base model), see
//! [`corrugation::studies::study`] for the file format and outputs.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use corrugation::dynamics::prepared::PreparedModel;
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::model::Model;
use corrugation::studies::grow::study_growth;
use corrugation::studies::speeds::Shard;
use corrugation::studies::study::{basis_plan, run_study, CaseRunners, Study};
use corrugation::studies::BoxError;

/// Design study: initiation indicators (and optionally growth) for every case of a study file.
#[derive(Debug, Args)]
pub(crate) struct StudyCmd {
    /// The study file (TOML).
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// Output directory (default: corrugation-out/study-<file stem>); a rerun resumes.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print the cases and their indicators as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Run only shard I of N (I = 0 … N−1): every N-th case from the I-th, saved into --out
    /// without the table and report. After every shard has run into the same --out, a run
    /// without --shard reuses all cases and writes the outputs (a cluster job array).
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
}

impl StudyCmd {
    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let study = Study::load(&self.file)?;
        let shard = match &self.shard {
            Some(s) => Shard::parse(s)?,
            None => Shard::ALL,
        };
        // Every case's model is checked before any engine work.
        let models = study.case_models_of(shard)?;
        for (case, m) in &models {
            super::warn_unit_slips(
                &format!(
                    "{} case {} ({})",
                    self.file.display(),
                    case.index,
                    case.label()
                ),
                m,
            );
        }
        if models.is_empty() {
            anyhow::bail!(
                "--shard {}/{}: no case of the study's {} falls in this shard; use fewer shards",
                shard.index,
                shard.count,
                study.cases().len()
            );
        }
        let cache_dir = self.cache.clone().unwrap_or_else(default_cache_dir);
        let out = self.out.clone().unwrap_or_else(|| {
            let stem = self
                .file
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "study".into());
            PathBuf::from(format!("corrugation-out/study-{stem}"))
        });
        super::check_out_outside_cache(&out, self.cache.as_deref())?;
        super::check_out_dir(&out)?;
        let plan = basis_plan(&study, &models, &ModalCache::new(&cache_dir))?;
        eprintln!("study `{}`: {plan}", study.title);
        let pb = std::sync::Arc::new(super::progress::bar(&format!("study `{}`", study.title)));
        let runners = CaseRunners::new(&study, &cache_dir).with_progress(pb.clone());
        let factory = |m: &Model| -> Result<PreparedModel, BoxError> { runners.prepared(m) };
        let growth = |m: &Model, p: &PreparedModel| study_growth(m, p);
        let o = run_study(&study, &factory, Some(&growth), &out, shard, &*pb)?;
        pb.finish_and_clear();
        eprintln!(
            "study `{}`: {} case(s), {} computed, {} reused → {}",
            study.title,
            o.cases.len(),
            o.computed,
            o.reused,
            out.display()
        );
        if !self.json {
            if shard.is_all() {
                for line in corrugation::studies::study::summary_lines(&o.cases) {
                    println!("{line}");
                }
            } else {
                println!(
                    "shard {}/{}: {} case(s) saved in {}; after every shard, run `corrugation study {} --out {}` there for the table and the report",
                    shard.index,
                    shard.count,
                    o.cases.len(),
                    out.display(),
                    self.file.display(),
                    out.display()
                );
            }
        }
        if self.json {
            let cases: Vec<serde_json::Value> = o
                .cases
                .iter()
                .map(|(c, r)| {
                    serde_json::json!({
                        "case": c.index,
                        "overrides": c.overrides(),
                        "rows": r.rows,
                        "growth": r.growth,
                    })
                })
                .collect();
            let j = serde_json::json!({
                "title": study.title,
                "cases": cases,
                "computed": o.computed,
                "reused": o.reused,
                "seconds": t0.elapsed().as_secs_f64(),
            });
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
        Ok(())
    }
}

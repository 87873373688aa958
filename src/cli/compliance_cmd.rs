//! `corrugation compliance`: the static longitudinal-compliance check
//! ([`corrugation::dynamics::compliance`]) for RPM1–RPM5, rigid and with elastic x-holds.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::dynamics::compliance::{longitudinal_compliance, ComplianceLoad};
use corrugation::model::{load_model, Model, MAX_HOLD_STIFFNESS, MIN_HOLD_STIFFNESS};
use corrugation::structure::TrackStructure;
use corrugation::units::{m_to_um, n_to_kn};

use super::ModelArgs;

/// Static longitudinal compliance of the fastening models: u_x of the rail head, web and foot
/// ahead of a wheel load with a longitudinal force (compliance.csv, compliance.json).
#[derive(Debug, Args)]
pub struct ComplianceCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Fastening models, each applied as --set fastening.model=NAME.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "RPM1,RPM2,RPM3,RPM4,RPM5",
        value_name = "NAMES"
    )]
    variants: Vec<String>,
    /// Elastic longitudinal hold stiffnesses per fastening (N/m): each model is also run with
    /// its x-holds made elastic (fastening.hold = "elastic", hold_directions = ["x"]).
    /// Give --elastic none for rigid holds only.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_delimiter = ',',
        default_value = "1e9",
        value_name = "N_PER_M"
    )]
    elastic: Vec<String>,
    /// Vertical wheel load on the rail (N).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = 100e3,
        value_name = "N"
    )]
    vertical: f64,
    /// Longitudinal force on the rail, along +x (N).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = 15e3,
        value_name = "N"
    )]
    longitudinal: f64,
    /// Load position along the rail (m); default mid-track.
    #[arg(allow_hyphen_values = true, long, value_name = "M")]
    x: Option<f64>,
    /// Distance ahead of the load where u_x is reported (m).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = 0.1,
        value_name = "M"
    )]
    ahead: f64,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/compliance", value_name = "DIR")]
    out: PathBuf,
    /// Print the table as JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// One row of the table (displacements in m).
#[derive(Debug, Serialize)]
struct Row {
    model: String,
    hold: &'static str,
    hold_stiffness_n_per_m: Option<f64>,
    x_load_m: f64,
    x_probe_m: f64,
    head_m: f64,
    web_m: f64,
    foot_m: f64,
    mean_at_load_m: f64,
    vertical_at_load_m: f64,
    head_longitudinal_only_m: f64,
    web_longitudinal_only_m: f64,
    foot_longitudinal_only_m: f64,
}

impl ComplianceCmd {
    /// Runs the command: the arguments, every model variant (all loaded before any solve,
    /// so that a bad name or key stops early), their compliances, the files, the table.
    pub fn run(self) -> anyhow::Result<()> {
        let stiffnesses = self.check_args()?;
        super::check_out_dir(&self.out)?;
        let models = self.models(&stiffnesses)?;
        for (_, _, m) in &models {
            // the library's default load position, mid-track
            let x = self.x.unwrap_or(0.5 * m.track_length());
            super::check_on_track("--x", &[x], m)?;
            super::check_on_track("--x + --ahead", &[x + self.ahead], m)?;
        }
        let load = ComplianceLoad {
            vertical_n: self.vertical,
            longitudinal_n: self.longitudinal,
            x_m: self.x,
            ahead_m: self.ahead,
        };
        let mut rows = Vec::new();
        for (name, k, m) in &models {
            let track = TrackStructure::build(m).with_context(|| format!("building {name}"))?;
            let r = longitudinal_compliance(m, &track, &load)
                .with_context(|| format!("compliance of {name}"))?;
            rows.push(Row {
                model: name.clone(),
                hold: if k.is_some() { "elastic" } else { "rigid" },
                hold_stiffness_n_per_m: *k,
                x_load_m: r.x_load_m,
                x_probe_m: r.x_probe_m,
                head_m: r.head_m,
                web_m: r.web_m,
                foot_m: r.foot_m,
                mean_at_load_m: r.mean_at_load_m,
                vertical_at_load_m: r.vertical_at_load_m,
                head_longitudinal_only_m: r.longitudinal_only_m[0],
                web_longitudinal_only_m: r.longitudinal_only_m[1],
                foot_longitudinal_only_m: r.longitudinal_only_m[2],
            });
        }
        let (csv_path, json) = self.write_files(&load, &rows)?;
        if self.json {
            println!("{json}");
        } else {
            self.print_table(&rows);
            println!("wrote {} and compliance.json", csv_path.display());
        }
        Ok(())
    }

    /// Checks the forces and the distance; returns the elastic hold stiffnesses (N/m).
    fn check_args(&self) -> anyhow::Result<Vec<f64>> {
        for (name, v) in [
            ("--vertical", self.vertical),
            ("--longitudinal", self.longitudinal),
        ] {
            if !v.is_finite() || v.abs() > 1e7 {
                anyhow::bail!("{name} must be a finite force up to 1e7 N (got {v})");
            }
        }
        if self.vertical < 0.0 {
            anyhow::bail!(
                "--vertical {}: out of range, allowed 0 to 1e7 N (the wheel pushes down on the rail)",
                self.vertical
            );
        }
        if !(self.ahead.is_finite() && self.ahead >= 0.0) {
            anyhow::bail!(
                "--ahead must be a finite distance ≥ 0 m (got {})",
                self.ahead
            );
        }
        let mut stiffnesses = Vec::new();
        for s in &self.elastic {
            if s == "none" {
                continue;
            }
            let k: f64 = s
                .parse()
                .with_context(|| format!("--elastic {s}: not a number (N/m) or \"none\""))?;
            if !(k.is_finite() && (MIN_HOLD_STIFFNESS..=MAX_HOLD_STIFFNESS).contains(&k)) {
                anyhow::bail!(
                    "--elastic {s}: out of range, allowed {MIN_HOLD_STIFFNESS:e} to {MAX_HOLD_STIFFNESS:e} N/m per fastening (as fastening.hold_stiffness), or \"none\""
                );
            }
            stiffnesses.push(k);
        }
        let variants: Vec<&str> = self.variants.iter().map(|v| v.trim()).collect();
        corrugation::lists::check_no_repeats("--variants", "", &variants)?;
        let elastic: Vec<&str> = self.elastic.iter().map(|v| v.trim()).collect();
        corrugation::lists::check_no_repeats("--elastic", "", &elastic)?;
        corrugation::lists::check_no_repeats("--elastic", "N/m", &stiffnesses)?;
        Ok(stiffnesses)
    }

    /// Every variant with rigid holds and with each elastic hold stiffness (N/m):
    /// `(fastening model, hold stiffness, model)`.
    fn models(&self, stiffnesses: &[f64]) -> anyhow::Result<Vec<(String, Option<f64>, Model)>> {
        let mut cases = Vec::new();
        for v in &self.variants {
            let mut sets = self.model.set.clone();
            sets.push(format!("fastening.model={v}"));
            cases.push((v.clone(), None, sets.clone()));
            for &k in stiffnesses {
                let mut s = sets.clone();
                s.extend([
                    "fastening.hold=elastic".to_string(),
                    format!("fastening.hold_stiffness={k:e}"),
                    "fastening.hold_directions=[\"x\"]".to_string(),
                ]);
                cases.push((v.clone(), Some(k), s));
            }
        }
        let mut models = Vec::new();
        for (name, k, sets) in &cases {
            let m = load_model(&self.model.source(), sets)
                .with_context(|| format!("the model of --variants {name}"))?;
            super::warn_unit_slips(&format!("--variants {name}"), &m);
            models.push((name.clone(), *k, m));
        }
        Ok(models)
    }

    /// Writes `compliance.csv` and `compliance.json` into `--out` (atomically); returns the CSV's path and
    /// the JSON.
    fn write_files(
        &self,
        load: &ComplianceLoad,
        rows: &[Row],
    ) -> anyhow::Result<(PathBuf, serde_json::Value)> {
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("creating {}", self.out.display()))?;
        let mut csv = String::from("model,hold,hold_stiffness_n_per_m,x_load_m,x_probe_m,head_m,web_m,foot_m,mean_at_load_m,vertical_at_load_m,head_longitudinal_only_m,web_longitudinal_only_m,foot_longitudinal_only_m\n");
        for r in rows {
            let k = r.hold_stiffness_n_per_m.map(|k| format!("{k:e}"));
            writeln!(
                csv,
                "{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                r.model,
                r.hold,
                k.unwrap_or_default(),
                r.x_load_m,
                r.x_probe_m,
                r.head_m,
                r.web_m,
                r.foot_m,
                r.mean_at_load_m,
                r.vertical_at_load_m,
                r.head_longitudinal_only_m,
                r.web_longitudinal_only_m,
                r.foot_longitudinal_only_m
            )?;
        }
        let csv_path = self.out.join("compliance.csv");
        corrugation::io::write_text(&csv_path, &csv)
            .with_context(|| format!("writing {}", csv_path.display()))?;
        let json = serde_json::json!({ "load": load, "rows": rows });
        let json_path = self.out.join("compliance.json");
        corrugation::io::write_text(&json_path, &serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("writing {}", json_path.display()))?;
        Ok((csv_path, json))
    }

    /// The table on stdout (µm).
    fn print_table(&self, rows: &[Row]) {
        println!(
            "u_x {} m ahead of {} kN down + {} kN along x (µm; in brackets the longitudinal force alone; w at the load in µm)",
            self.ahead,
            n_to_kn(self.vertical),
            n_to_kn(self.longitudinal)
        );
        println!(
            "{:<6} {:<8} {:>10} {:>20} {:>20} {:>20} {:>8}",
            "model", "hold", "k (N/m)", "head", "web", "foot", "w"
        );
        for r in rows {
            let k = r
                .hold_stiffness_n_per_m
                .map(|k| format!("{k:.1e}"))
                .unwrap_or_else(|| "rigid".into());
            let pair = |a: f64, b: f64| format!("{:.3} ({:.3})", m_to_um(a), m_to_um(b));
            println!(
                "{:<6} {:<8} {:>10} {:>20} {:>20} {:>20} {:>8.1}",
                r.model,
                r.hold,
                k,
                pair(r.head_m, r.head_longitudinal_only_m),
                pair(r.web_m, r.web_longitudinal_only_m),
                pair(r.foot_m, r.foot_longitudinal_only_m),
                m_to_um(r.vertical_at_load_m)
            );
        }
    }
}

//! The `compliance` command's study: the static longitudinal-compliance check
//! ([`crate::dynamics::compliance`]) for several fastening models, each rigid and with elastic
//! x-holds of given stiffnesses: the arguments checked ([`check_elastic`],
//! [`check_compliance_load`]), the variant models ([`variant_models`]), one row per variant
//! ([`compliance_rows`]) and the files `compliance.csv` and `compliance.json`
//! ([`write_compliance`]).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::dynamics::compliance::{longitudinal_compliance, ComplianceLoad};
use crate::model::{load_model, Model, ModelSource, MAX_HOLD_STIFFNESS, MIN_HOLD_STIFFNESS};
use crate::structure::TrackStructure;
use crate::studies::StudiesError;

/// The default elastic x-hold stiffness of the check (N/m per fastening), beside the rigid
/// hold.
pub const DEFAULT_ELASTIC_N_PER_M: f64 = 1e9;

/// The largest force the check accepts (N), either component.
pub(crate) const MAX_FORCE_N: f64 = 1e7;

/// One row of the table: a fastening model with rigid or elastic x-holds (displacements in m).
#[derive(Debug, Clone, Serialize)]
pub struct ComplianceRow {
    /// The fastening model (`RPM1` … `RPM5`).
    pub model: String,
    /// `rigid` or `elastic`.
    pub hold: &'static str,
    /// The elastic x-hold's stiffness per fastening (N/m); `None` for rigid.
    pub hold_stiffness_n_per_m: Option<f64>,
    /// The load's position along the rail (m).
    pub x_load_m: f64,
    /// Where the displacements are read (m).
    pub x_probe_m: f64,
    /// Longitudinal displacement of the rail head at the probe (m).
    pub head_m: f64,
    /// Of the web (m).
    pub web_m: f64,
    /// Of the foot (m).
    pub foot_m: f64,
    /// Mean longitudinal displacement of the section at the load (m).
    pub mean_at_load_m: f64,
    /// Vertical displacement at the load (m).
    pub vertical_at_load_m: f64,
    /// Head, web and foot under the longitudinal force alone (m).
    pub head_longitudinal_only_m: f64,
    /// See `head_longitudinal_only_m`.
    pub web_longitudinal_only_m: f64,
    /// See `head_longitudinal_only_m`.
    pub foot_longitudinal_only_m: f64,
}

fn argument(flag: &'static str, given: impl ToString, reason: impl ToString) -> StudiesError {
    StudiesError::Argument {
        flag,
        given: given.to_string(),
        reason: reason.to_string(),
    }
}

/// Checks the load's forces (finite, at most `MAX_FORCE_N`, the vertical one pushing down)
/// and the probe's distance ahead (finite, ≥ 0 m).
pub fn check_compliance_load(load: &ComplianceLoad) -> Result<(), StudiesError> {
    for (flag, v) in [
        ("--vertical", load.vertical_n),
        ("--longitudinal", load.longitudinal_n),
    ] {
        if !v.is_finite() || v.abs() > MAX_FORCE_N {
            return Err(argument(
                flag,
                v,
                format!("must be a finite force up to {MAX_FORCE_N:e} N"),
            ));
        }
    }
    if load.vertical_n < 0.0 {
        return Err(argument(
            "--vertical",
            load.vertical_n,
            format!(
                "out of range, allowed 0 to {MAX_FORCE_N:e} N (the wheel pushes down on the rail)"
            ),
        ));
    }
    if !(load.ahead_m.is_finite() && load.ahead_m >= 0.0) {
        return Err(argument(
            "--ahead",
            load.ahead_m,
            "must be a finite distance ≥ 0 m",
        ));
    }
    Ok(())
}

/// The elastic x-hold stiffnesses (N/m per fastening) of the list `elastic` (numbers, or
/// `none` for no elastic variant), each within the range of `fastening.hold_stiffness`; no
/// value twice.
pub fn check_elastic(elastic: &[String]) -> Result<Vec<f64>, StudiesError> {
    let mut stiffnesses = Vec::new();
    for s in elastic.iter().map(|s| s.trim()) {
        if s == "none" {
            continue;
        }
        let k: f64 = s
            .parse()
            .map_err(|_| argument("--elastic", s, "not a number (N/m) or \"none\""))?;
        if !(k.is_finite() && (MIN_HOLD_STIFFNESS..=MAX_HOLD_STIFFNESS).contains(&k)) {
            return Err(argument(
                "--elastic",
                s,
                format!("out of range, allowed {MIN_HOLD_STIFFNESS:e} to {MAX_HOLD_STIFFNESS:e} N/m per fastening (as fastening.hold_stiffness), or \"none\""),
            ));
        }
        stiffnesses.push(k);
    }
    let given: Vec<&str> = elastic.iter().map(|v| v.trim()).collect();
    crate::lists::check_no_repeats("--elastic", "", &given)?;
    crate::lists::check_no_repeats("--elastic", "N/m", &stiffnesses)?;
    Ok(stiffnesses)
}

/// Every fastening model of `variants` with rigid holds and with each elastic x-hold
/// stiffness of `stiffnesses` (N/m): `(fastening model, hold stiffness, model)`, each the
/// model of `source` with `sets` and then the variant's overrides. All are loaded before
/// any is solved, so a bad name or key stops early.
pub fn variant_models(
    source: &ModelSource,
    sets: &[String],
    variants: &[String],
    stiffnesses: &[f64],
) -> Result<Vec<(String, Option<f64>, Model)>, StudiesError> {
    let names: Vec<&str> = variants.iter().map(|v| v.trim()).collect();
    crate::lists::check_no_repeats("--variants", "", &names)?;
    let mut models = Vec::new();
    for v in variants {
        let mut base = sets.to_vec();
        base.push(format!("fastening.model={v}"));
        let mut cases = vec![(None, base.clone())];
        for &k in stiffnesses {
            let mut s = base.clone();
            s.extend([
                "fastening.hold=elastic".to_string(),
                format!("fastening.hold_stiffness={k:e}"),
                "fastening.hold_directions=[\"x\"]".to_string(),
            ]);
            cases.push((Some(k), s));
        }
        for (k, s) in cases {
            let m = load_model(source, &s).map_err(|e| StudiesError::Variant {
                name: v.clone(),
                source: Box::new(e),
            })?;
            models.push((v.clone(), k, m));
        }
    }
    Ok(models)
}

/// One row per variant model ([`variant_models`]) under `load`.
pub fn compliance_rows(
    models: &[(String, Option<f64>, Model)],
    load: &ComplianceLoad,
) -> Result<Vec<ComplianceRow>, StudiesError> {
    let mut rows = Vec::with_capacity(models.len());
    for (name, k, m) in models {
        let variant = |e: Box<dyn std::error::Error + Send + Sync>| StudiesError::Variant {
            name: name.clone(),
            source: e,
        };
        // The library's default load position is mid-track.
        let x = load.x_m.unwrap_or(0.5 * m.track_length());
        m.check_on_track("--x", &[x])?;
        m.check_on_track("--x + --ahead", &[x + load.ahead_m])?;
        let track = TrackStructure::build(m).map_err(|e| variant(Box::new(e)))?;
        let r = longitudinal_compliance(m, &track, load).map_err(|e| variant(Box::new(e)))?;
        rows.push(ComplianceRow {
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
    Ok(rows)
}

/// Writes `compliance.csv` (one line per row, displacements in m) and `compliance.json`
/// (`{"load", "rows"}`) into `out` (created if missing), atomically; returns the CSV's path
/// and the JSON.
pub fn write_compliance(
    out: &Path,
    load: &ComplianceLoad,
    rows: &[ComplianceRow],
) -> Result<(PathBuf, serde_json::Value), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let mut csv = String::from("model,hold,hold_stiffness_n_per_m,x_load_m,x_probe_m,head_m,web_m,foot_m,mean_at_load_m,vertical_at_load_m,head_longitudinal_only_m,web_longitudinal_only_m,foot_longitudinal_only_m\n");
    for r in rows {
        let k = r.hold_stiffness_n_per_m.map(|k| format!("{k:e}"));
        // Writing into a String cannot fail.
        let _ = writeln!(
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
        );
    }
    let csv_path = out.join("compliance.csv");
    crate::io::write_text(&csv_path, &csv).map_err(StudiesError::io(&csv_path))?;
    let json = serde_json::json!({ "load": load, "rows": rows });
    let json_path = out.join("compliance.json");
    let text = serde_json::to_string_pretty(&json).map_err(|source| StudiesError::Json {
        what: "compliance.json",
        source,
    })?;
    crate::io::write_text(&json_path, &text).map_err(StudiesError::io(&json_path))?;
    Ok((csv_path, json))
}

//! Design studies (docs/theory.md §11.5): a TOML study file names a base model and parameters to
//! vary; every case gets the initiation indicators ([`super::initiation`]) and optionally the
//! growth loop (a hook supplied by the caller); the output is one table and plots of the
//! indicators vs the parameters.
//!
//! # Study file
//! ```toml
//! title = "Railpad stiffness × damping"   # optional
//! model = "builtin:dutch"                  # or a model file, relative to the study file
//! set = ["fastening.model=\"RPM3\""]       # optional overrides applied to every case
//! speeds_kmh = [140.0]                     # optional; default: the model's run.speed_kmh
//! combine = "grid"                         # "grid" (full product, default) or "zip"
//! growth = false                           # run the growth loop per case (optional)
//! peaks = 3                                # PSD peaks per signal in the table (optional)
//! basis = "full"                           # track basis: "full" (Lanczos per distinct track,
//!                                          # default) or "substructured" (theory §5.8)
//! # substructure = { cutoff_factor = 1.5, pattern_degree = 3, ballast_pattern_degree = 1 }  # only with "substructured"
//! # concurrent_cases = 2                   # cases run at once after the first, 1 … 4 (default:
//!                                          # 2 substructured, 1 full); results do not change
//!
//! [criterion]                              # optional, see initiation::InitiationCriterion
//! min_relative_wear = 0.01                 # default: each case's wear.initiation_threshold
//! max_wavelength_deviation = 0.03          # default 0.03
//!
//! [[parameter]]
//! key = "fastening.vertical_stiffness"     # a dotted model key, as for --set
//! values = [0.65e9, 1.3e9, 2.6e9]          # any TOML values ...
//!
//! [[parameter]]
//! key = "fastening.vertical_damping"
//! range = { start = 15e3, stop = 75e3, step = 30e3 }   # ... or a numeric range
//! ```
//! A range is `start + k·step`, `k = 0 … ⌊(stop − start)/step + 10⁻⁹⌋` (the stop is included
//! when on the grid, never appended — the same rule as the sweep speeds). With
//! `combine = "grid"` the cases are the Cartesian product of the parameters (the last
//! parameter varies fastest); with `"zip"` the parameters must have equally many values and
//! case `i` takes the `i`-th value of each.
//!
//! Every case's model is the base model with `set` and then the case's `key=value` overrides
//! applied through the model's `--set` machinery ([`crate::model::load_model`]), so a key or
//! value the model does not accept is reported (naming the study file, the case and the key)
//! **before** anything runs. The study file itself is read with unknown keys denied; errors
//! name the file and the dotted key (`parameter[1].range.step`).
//!
//! # Outputs (in the output directory)
//! - `cases/<NNNN>.json` — each finished case (its overrides, model hash and indicators),
//!   written atomically; a rerun reuses the cases whose file matches their overrides, resolved
//!   model (`model_hash`) and speeds (resume), and recomputes the others;
//! - `study.csv` — one row per case and speed: `case`, the parameter values, the indicators
//!   (`super::initiation::indicator_header`) and the growth hook's columns;
//! - `study.md`, `study.html` — the criterion, a readable table and the plots;
//! - `study_<indicator>.{svg,png}` — each indicator vs the first parameter (one curve per
//!   combination of the other parameters and speed); the case index is the abscissa when the
//!   first parameter is not numeric.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[cfg(test)]
use super::StudiesError;
#[cfg(test)]
use std::path::{Path, PathBuf};

use super::initiation::{InitiationCriterion, InitiationRow};

/// The initiation criterion of a study (`[criterion]`): what the file sets, the rest from each
/// case's model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyCriterion {
    /// Minimum `wear_band_rms / wear_mean` (−), range ≥ 0; default (absent): each case's
    /// `wear.initiation_threshold`, so a study that varies that key sees its values.
    #[serde(default)]
    pub min_relative_wear: Option<f64>,
    /// Maximum relative deviation of `F_L`'s dominant wavelength from the wear's (−), ≥ 0;
    /// default [`InitiationCriterion::DEFAULT_MAX_WAVELENGTH_DEVIATION`].
    #[serde(default)]
    pub max_wavelength_deviation: Option<f64>,
}

impl StudyCriterion {
    /// The criterion applied to the case with model `m`.
    pub(crate) fn for_model(&self, m: &crate::model::Model) -> InitiationCriterion {
        let base = InitiationCriterion::from_model(m);
        InitiationCriterion {
            min_relative_wear: self.min_relative_wear.unwrap_or(base.min_relative_wear),
            max_wavelength_deviation: self
                .max_wavelength_deviation
                .unwrap_or(base.max_wavelength_deviation),
        }
    }
}
use crate::eigen::substructure::SubstructureOptions;
use crate::model::{Assignment, ModelSource};

/// The stored result of one case (`cases/<NNNN>.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// The case's overrides (the study's `set`, then the case's own), to detect a changed
    /// study on resume.
    pub overrides: Vec<String>,
    /// blake3 hash of the case's resolved model (serde_json) and the program version: a
    /// changed base model is never taken for a finished case.
    pub model_hash: String,
    /// The indicators, one row per speed.
    pub rows: Vec<InitiationRow>,
    /// The growth hook's results (empty without growth).
    pub growth: BTreeMap<String, f64>,
}

pub mod bases;
mod parse;
mod report;
pub use report::{study_table, summary_lines};
mod run;
pub(crate) mod static_update;

pub use bases::{basis_plan, BasisPlan, CasePhases, CaseRunners, StudyBasis};
pub use run::{run_study, StudyOutcome};

/// Most cases of one study.
pub(crate) const MAX_CASES: usize = 10_000;

/// How the parameters are combined into cases.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Full Cartesian product (last parameter fastest).
    #[default]
    Grid,
    /// Parallel lists of equal length.
    Zip,
}

/// A numeric range `start:stop:step`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// First value.
    pub start: f64,
    /// Last value (included when on the grid).
    pub stop: f64,
    /// Step (> 0).
    pub step: f64,
}

/// One varied parameter: a dotted model key and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Dotted model key (as for `--set`).
    pub key: String,
    /// Its values, in order.
    pub values: Vec<toml::Value>,
}

/// One case: the value of every parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Position in the study (0-based).
    pub index: usize,
    /// `(key, value)` per parameter, in the study's parameter order.
    pub assignments: Vec<(String, toml::Value)>,
}

impl Case {
    /// The case's `key=value` overrides.
    pub fn overrides(&self) -> Vec<String> {
        self.assignments
            .iter()
            .map(|(k, v)| format!("{k}={}", value_text(v)))
            .collect()
    }

    /// A readable label: `key=value, key=value`.
    pub fn label(&self) -> String {
        self.overrides().join(", ")
    }
}

/// A value as TOML text (`1300000000.0`, `"RPM1"`, `[0, 2]`).
pub(crate) fn value_text(v: &toml::Value) -> String {
    v.to_string()
}

/// A parsed, checked study file.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// The study file (for messages).
    pub file: String,
    /// Title (default: the file stem).
    pub title: String,
    /// The base model.
    pub base: ModelSource,
    /// Overrides applied to every case before the case's own: each parsed once from the
    /// file's `key=value` string, beside that string as written (messages and the case files
    /// quote it so).
    pub set: Vec<(Assignment, String)>,
    /// Speeds (km/h); `None` = the model's `run.speed_kmh`.
    pub speeds_kmh: Option<Vec<f64>>,
    /// How parameters combine.
    pub combine: Combine,
    /// Run the growth loop per case.
    pub growth: bool,
    /// PSD peaks per signal in the table.
    pub peaks: usize,
    /// The initiation criterion of the study file's `[criterion]` table.
    pub criterion: StudyCriterion,
    /// The track basis of the cases (default full).
    pub basis: StudyBasis,
    /// Options of the component bases when `basis = "substructured"` (defaults otherwise).
    pub substructure: SubstructureOptions,
    /// Cases run at the same time after the first (`concurrent_cases`, 1 … 4; default 2 with
    /// the substructured basis, whose cases share the first case's component bases and
    /// caches, and 1 with the full basis, whose cases may each run a Lanczos extraction).
    /// The results are the same for every value; wall time falls when one case leaves
    /// cores idle, and peak memory grows with it (about 3.6 GB a case on the default model).
    pub concurrent_cases: usize,
    /// The varied parameters.
    pub parameters: Vec<Parameter>,
}

#[cfg(test)]
mod tests {
    use super::parse::expand_range;
    use super::{InitiationCriterion, ModelSource, Path, PathBuf, Range, StudiesError, Study};
    fn parse(text: &str) -> Result<Study, StudiesError> {
        Study::parse_str(text, "s.toml", Path::new("/studies"), "s")
    }

    #[test]
    fn grid_expansion_is_the_cartesian_product_last_fastest() {
        let s = parse(
            r#"
            model = "builtin:dutch"
            [[parameter]]
            key = "fastening.vertical_stiffness"
            values = [1e9, 2e9]
            [[parameter]]
            key = "fastening.vertical_damping"
            range = { start = 15e3, stop = 75e3, step = 30e3 }
            "#,
        )
        .unwrap();
        assert_eq!(s.base, ModelSource::Builtin);
        let c = s.cases();
        assert_eq!(c.len(), 6);
        let o: Vec<String> = c.iter().map(|c| c.label()).collect();
        assert_eq!(
            o[0],
            "fastening.vertical_stiffness=1000000000.0, fastening.vertical_damping=15000.0"
        );
        assert_eq!(
            o[1],
            "fastening.vertical_stiffness=1000000000.0, fastening.vertical_damping=45000.0"
        );
        assert_eq!(
            o[5],
            "fastening.vertical_stiffness=2000000000.0, fastening.vertical_damping=75000.0"
        );
        assert!(c.iter().enumerate().all(|(i, c)| c.index == i));
    }

    #[test]
    fn zip_pairs_values_and_ranges_follow_the_speed_rule() {
        let s = parse(
            r#"
            model = "base.toml"
            combine = "zip"
            [[parameter]]
            key = "fastening.model"
            values = ["RPM1", "RPM3"]
            [[parameter]]
            key = "track.bays"
            values = [10, 12]
            "#,
        )
        .unwrap();
        assert_eq!(
            s.base,
            ModelSource::File(PathBuf::from("/studies/base.toml"))
        );
        let c = s.cases();
        assert_eq!(c.len(), 2);
        assert_eq!(
            c[1].overrides(),
            vec!["fastening.model=\"RPM3\"", "track.bays=12"]
        );
        let r = |a, b, c| {
            expand_range(&Range {
                start: a,
                stop: b,
                step: c,
            })
            .unwrap()
        };
        assert_eq!(r(0.1, 0.5, 0.1), vec![0.1, 0.2, 0.3, 0.4, 0.5]);
        assert_eq!(r(1.0, 2.5, 1.0), vec![1.0, 2.0]);
    }

    #[test]
    fn errors_name_the_file_and_the_key() {
        let head = "model = \"builtin:dutch\"\n";
        for (body, key) in [
            ("[[parameter]]\nkey = \"a.b\"\nvaluess = [1]\n", "parameter[0].valuess"),
            ("speed = 3\n[[parameter]]\nkey = \"a.b\"\nvalues = [1]\n", "`speed`"),
            ("[[parameter]]\nkey = \"a.b\"\nrange = { start = 1, stop = 0, step = 1 }\n", "parameter[0].range"),
            ("[[parameter]]\nkey = \"a.b\"\nrange = { start = 0, stop = 1, step = -1 }\n", "parameter[0].range"),
            ("[[parameter]]\nkey = \"a.b\"\nrange = { start = 0, stop = 1 }\n", "parameter[0].range"),
            ("[[parameter]]\nkey = \"a.b\"\nvalues = [1]\nrange = { start = 0, stop = 1, step = 1 }\n", "parameter[0]"),
            ("[[parameter]]\nkey = \"a.b\"\nvalues = []\n", "parameter[0].values"),
            ("[[parameter]]\nkey = \"a..b\"\nvalues = [1]\n", "parameter[0].key"),
            ("combine = \"zip\"\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n[[parameter]]\nkey = \"b\"\nvalues = [1, 2]\n", "parameter[1]"),
            ("combine = \"diagonal\"\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n", "combine"),
            ("speeds_kmh = [-1.0]\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n", "speeds_kmh"),
            ("[criterion]\nmin_relative_wear = 0.1\nmax_deviation = 1\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n", "criterion.max_deviation"),
            ("", "parameter"),
        ] {
            let e = parse(&format!("{head}{body}")).unwrap_err().to_string();
            assert!(e.starts_with("s.toml: key `") && e.contains(key), "{body}\n→ {e}");
        }
        let e = parse("model = 3\n").unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("model"), "{e}");
        let e = parse("model = [\n").unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("syntax"), "{e}");
    }

    #[test]
    fn case_models_apply_the_overrides_and_report_bad_keys_before_running() {
        let s = parse(
            r#"
            model = "builtin:dutch"
            set = ["fastening.model=\"RPM1\""]
            [[parameter]]
            key = "fastening.vertical_stiffness"
            values = [1.0e9, 2.0e9]
            "#,
        )
        .unwrap();
        let m = s.case_models().unwrap();
        assert_eq!(m[1].1.fastening.springs.vertical_stiffness, 2.0e9);
        assert_eq!(m[0].1.fastening.model().name(), "RPM1");
        let bad = parse(
            "model = \"builtin:dutch\"\n[[parameter]]\nkey = \"fastening.vertical_stifness\"\nvalues = [1e9]\n",
        )
        .unwrap();
        let e = bad.case_models().unwrap_err().to_string();
        assert!(
            e.contains("s.toml: case 0") && e.contains("vertical_stifness"),
            "{e}"
        );
    }

    /// A case's model, built from its typed assignments, equals the model the command line
    /// builds from the same overrides as text (`--set`); a `set` entry that is not
    /// `key=value` TOML is refused when the study is read, naming `set`.
    #[test]
    fn typed_case_assignments_give_the_command_line_s_model() {
        let s = parse(
            r#"
            model = "builtin:dutch"
            set = ["fastening.model=RPM1", "run.speed_kmh=120"]
            [[parameter]]
            key = "fastening.vertical_stiffness"
            values = [1.3e9, 6.5e8]
            [[parameter]]
            key = "wheel.web_shape"
            values = ["curved", "straight"]
            [[parameter]]
            key = "mesh.sleeper_elements"
            values = [[4, 3, 2]]
            "#,
        )
        .unwrap();
        for (c, m) in s.case_models().unwrap() {
            let text = s.case_overrides(&c);
            let cli = crate::model::load_model(&ModelSource::Builtin, &text).unwrap();
            assert_eq!(m, cli, "{text:?}");
        }
        let text: Vec<&str> = s.set.iter().map(|(_, t)| t.as_str()).collect();
        assert_eq!(text, ["fastening.model=RPM1", "run.speed_kmh=120"]);
        let e = parse("model = \"builtin:dutch\"\nset = [\"track.bays\"]\n[[parameter]]\nkey = \"track.bays\"\nvalues = [4]\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.toml: key `set`") && e.contains("dotted.key=value"),
            "{e}"
        );
    }

    /// Without `min_relative_wear` in `[criterion]`, each case is judged by its own model's
    /// `wear.initiation_threshold` (here a study parameter); a value in the file wins.
    #[test]
    fn the_criterion_defaults_to_each_cases_initiation_threshold() {
        let s = parse(
            r#"
            model = "builtin:dutch"
            set = ["wear.initiation_threshold=0.2"]
            [[parameter]]
            key = "wear.initiation_threshold"
            values = [0.002, 0.05]
            "#,
        )
        .unwrap();
        let m = s.case_models().unwrap();
        let got: Vec<_> = m.iter().map(|(_, m)| s.criterion.for_model(m)).collect();
        assert_eq!(got[0].min_relative_wear, 0.002);
        assert_eq!(got[1].min_relative_wear, 0.05);
        assert_eq!(
            got[1].max_wavelength_deviation,
            InitiationCriterion::DEFAULT_MAX_WAVELENGTH_DEVIATION
        );
        let fixed = parse(
            "model = \"builtin:dutch\"\n[criterion]\nmin_relative_wear = 0.3\n[[parameter]]\nkey = \"wear.initiation_threshold\"\nvalues = [0.002]\n",
        )
        .unwrap();
        let m = fixed.case_models().unwrap();
        assert_eq!(fixed.criterion.for_model(&m[0].1).min_relative_wear, 0.3);
    }
}

//! The modal bases of a study's cases: which track basis a study uses (`basis = "full"` or
//! `"substructured"` in the study file), how many bases it will solve before it starts
//! ([`basis_plan`]), and the case runners that share the wheel basis and, for a
//! substructured study, the track's component bases across cases (docs/theory.md §5.8).

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::{Arc, Mutex};

use serde::{Deserialize, Serialize};

use super::static_update::StaticUpdater;
use super::{Case, Study};
use crate::dynamics::residual::SharedStiffnessAnalysis;
use crate::dynamics::{
    passage::PassageOptions,
    prepared::{PreparedModel, TrackStatic},
};
use crate::eigen::basis::{cache_key, Substructure};
use crate::eigen::cache::{CacheKey, ModalCache};
use crate::eigen::substructure::{
    component_key, passage_track_basis_timed, process_cpu_s, track_components, BasisPhases,
    ReducedShapes, SubstructureOptions, TrackComponents,
};
use crate::model::Model;
use crate::structure::TrackStructure;
use crate::studies::{BoxError, StudiesError};

/// The track basis of a study's cases.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StudyBasis {
    /// Each distinct track (by its cache key) gets its own Lanczos basis (the reference).
    #[default]
    Full,
    /// The track's component bases (rail, one sleeper) are built once per spring layout and
    /// each case solves only the reduced eigenproblem with its spring stiffnesses.
    Substructured,
}

/// How many bases a study will solve and how many it finds in the cache, by kind.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct BasisPlan {
    /// Cases of the study.
    pub cases: usize,
    /// Distinct full track bases to solve by Lanczos (not in the cache).
    pub track_to_solve: usize,
    /// Distinct full track bases found in the cache.
    pub track_cached: usize,
    /// Distinct wheel bases to solve.
    pub wheel_to_solve: usize,
    /// Distinct wheel bases found in the cache.
    pub wheel_cached: usize,
    /// Distinct sets of track component bases (rail + sleeper) to build.
    pub components_to_solve: usize,
    /// Distinct sets of component bases found in the cache.
    pub components_cached: usize,
    /// Reduced (dense) eigenproblems, one per substructured case.
    pub reduced: usize,
}

impl std::fmt::Display for BasisPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} case(s); bases to solve: {} full track ({} cached), {} wheel ({} cached)",
            self.cases,
            self.track_to_solve,
            self.track_cached,
            self.wheel_to_solve,
            self.wheel_cached
        )?;
        if self.components_to_solve + self.components_cached + self.reduced > 0 {
            write!(
                f,
                ", {} track component set(s) ({} cached), {} reduced eigenproblem(s)",
                self.components_to_solve, self.components_cached, self.reduced
            )?;
        }
        Ok(())
    }
}

fn cached(cache: &ModalCache, key: &CacheKey) -> bool {
    cache.has_entry(key)
}

/// The bases the cases of `study` (`models`, from [`Study::case_models`]) need, counted by
/// distinct cache key and split into those to solve and those already in `cache`.
pub fn basis_plan(
    study: &Study,
    models: &[(Case, Model)],
    cache: &ModalCache,
) -> Result<BasisPlan, StudiesError> {
    let key =
        |r: Result<CacheKey, crate::eigen::basis::BasisError>| r.map_err(StudiesError::CacheKey);
    let (mut track, mut wheel, mut comps) = (BTreeSet::new(), BTreeSet::new(), BTreeSet::new());
    let mut plan = BasisPlan {
        cases: models.len(),
        ..BasisPlan::default()
    };
    for (_, m) in models {
        let f = m.run.fmax;
        let w = key(cache_key(m, f, Substructure::Wheel))?;
        if wheel.insert(w.hex()) {
            *if cached(cache, &w) {
                &mut plan.wheel_cached
            } else {
                &mut plan.wheel_to_solve
            } += 1;
        }
        match study.basis {
            StudyBasis::Full => {
                let t = key(cache_key(m, f, Substructure::Track))?;
                if track.insert(t.hex()) {
                    *if cached(cache, &t) {
                        &mut plan.track_cached
                    } else {
                        &mut plan.track_to_solve
                    } += 1;
                }
            }
            StudyBasis::Substructured => {
                plan.reduced += 1;
                let o = &study.substructure;
                let r = key(component_key(m, f, o, "rail-component"))?;
                let s = key(component_key(m, f, o, "sleeper-component"))?;
                if comps.insert(r.hex()) {
                    *if cached(cache, &r) && cached(cache, &s) {
                        &mut plan.components_cached
                    } else {
                        &mut plan.components_to_solve
                    } += 1;
                }
            }
        }
    }
    Ok(plan)
}

/// Builds the passage runner of each case: the full or substructured track basis, the wheel
/// basis from the cache (one per wheel key, so shared by every case that does not touch the
/// wheel), and for a substructured study the component bases kept in memory between cases
/// with the same spring layout.
pub struct CaseRunners {
    cache: ModalCache,
    basis: StudyBasis,
    options: SubstructureOptions,
    components: Mutex<Option<(String, Arc<TrackComponents>)>>,
    shapes: Mutex<Option<(String, Arc<ReducedShapes>)>>,
    statics: Mutex<Option<(String, Arc<StaticUpdater>)>>,
    /// The symbolic analysis of the track's `K` shared by the cases (their `K` differ in
    /// values only when the study changes stiffnesses).
    analysis: SharedStiffnessAnalysis,
    static_update: bool,
    phases: Mutex<Vec<CasePhases>>,
}

/// Wall time (s) of the steps of one substructured case's preparation
/// ([`CaseRunners::prepared`]), in the order the cases were prepared, and the process's CPU
/// time (s, all threads) during the steps: the steps' own only while one case runs at a
/// time (`concurrent_cases = 1`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CasePhases {
    /// Building the case's track structure.
    pub structure_s: f64,
    /// Loading (or building) the component bases and forming their classification
    /// operators ([`ReducedShapes`]); 0 when kept from an earlier case.
    pub components_s: f64,
    /// The substructured basis: reduced eigenproblem, expansion, classification.
    pub basis: BasisPhases,
    /// The passage engine: wheel basis, damping projection, residual flexibilities.
    pub engine_s: f64,
    /// Of `engine_s`, the track's and the wheel's residual flexibilities (with the
    /// reference factorisation of the study's static flexibility, `StaticUpdater`, in the
    /// case that made it).
    pub residual_s: f64,
    /// Process CPU time during the structure and the component bases.
    pub structure_cpu_s: f64,
    /// Process CPU time during the engine's preparation.
    pub engine_cpu_s: f64,
}

impl CaseRunners {
    /// The runners of `study` with the modal cache in `cache_dir`.
    pub fn new(study: &Study, cache_dir: &Path) -> Self {
        Self {
            cache: ModalCache::new(cache_dir),
            basis: study.basis,
            options: study.substructure,
            components: Mutex::new(None),
            shapes: Mutex::new(None),
            statics: Mutex::new(None),
            analysis: SharedStiffnessAnalysis::default(),
            static_update: false,
            phases: Mutex::new(Vec::new()),
        }
    }

    /// The runners with the modal cache reporting to `progress` (the stages of the bases a
    /// case computes: "track modes below … Hz (Lanczos)", the component bases, …).
    pub fn with_progress(
        mut self,
        progress: std::sync::Arc<dyn crate::progress::Progress + Send>,
    ) -> Self {
        self.cache = self.cache.with_progress(progress);
        self
    }

    /// Whether a substructured study's cases get the track's static flexibility at the
    /// contact by updating one reference factorisation (`StaticUpdater`) or each from a
    /// factorisation of its own `K` (`false`, the default: on the default track a railpad
    /// stiffness changes several thousand springs, and solving them once costs about as much
    /// as ten cases' own factorisations, docs/log/performance.md §7.1).
    pub fn with_static_update(mut self, on: bool) -> Self {
        self.static_update = on;
        self
    }

    /// The step times of the substructured cases prepared so far.
    pub fn phases(&self) -> Vec<CasePhases> {
        self.phases.lock().map(|p| p.clone()).unwrap_or_default()
    }

    fn components(
        &self,
        m: &Model,
        track: &TrackStructure,
    ) -> Result<Arc<TrackComponents>, BoxError> {
        let key = component_key(m, m.run.fmax, &self.options, "rail-component")?.hex();
        memoised(&self.components, key, "component memo", || {
            Ok(track_components(
                m,
                track,
                &self.cache,
                m.run.fmax,
                &self.options,
            )?)
        })
    }

    /// The classification operators and passage rows of the component set of `track`
    /// ([`ReducedShapes`]), formed by the first case of a component set.
    fn shapes(
        &self,
        m: &Model,
        track: &TrackStructure,
        comp: &TrackComponents,
    ) -> Result<Arc<ReducedShapes>, BoxError> {
        let key = component_key(m, m.run.fmax, &self.options, "rail-component")?.hex();
        memoised(&self.shapes, key, "classification-operator memo", || {
            Ok(ReducedShapes::new(track, comp)?)
        })
    }

    /// The reference factorisation for the cases with the spring layout of `track`
    /// ([`StaticUpdater`]): `track` becomes the reference when there is none for its
    /// component key.
    fn statics(&self, m: &Model, track: &TrackStructure) -> Result<Arc<StaticUpdater>, BoxError> {
        let key = component_key(m, m.run.fmax, &self.options, "rail-component")?.hex();
        memoised(&self.statics, key, "static-flexibility memo", || {
            Ok(StaticUpdater::new(track)?)
        })
    }

    /// The prepared model (engine and bases) of one case.
    pub fn prepared(&self, m: &Model) -> Result<PreparedModel, BoxError> {
        let opts = PassageOptions::default();
        match self.basis {
            StudyBasis::Full => Ok(PreparedModel::new(m, &self.cache, &opts)?),
            StudyBasis::Substructured => {
                let (t, c0) = (std::time::Instant::now(), process_cpu_s());
                let track = TrackStructure::build(m)?;
                let structure_s = t.elapsed().as_secs_f64();
                let comp = self.components(m, &track)?;
                let shapes = self.shapes(m, &track, &comp)?;
                let components_s = t.elapsed().as_secs_f64() - structure_s;
                let c1 = process_cpu_s();
                let (tb, basis) = passage_track_basis_timed(&track, &comp, &shapes, m.run.fmax)?;
                let (t1, c2) = (std::time::Instant::now(), process_cpu_s());
                let t_ref = std::time::Instant::now();
                let statics = if m.run.residual_flexibility && self.static_update {
                    Some(self.statics(m, &track)?)
                } else {
                    None
                };
                let reference_s = t_ref.elapsed().as_secs_f64();
                let case_static = statics.as_ref().map(|u| u.for_track(&track));
                let stat = match &case_static {
                    Some(c) => TrackStatic::Given(c),
                    None => TrackStatic::FactoriseShared(&self.analysis),
                };
                let p = PreparedModel::with_track_basis_static(
                    m,
                    &track,
                    tb,
                    &self.cache,
                    stat,
                    &opts,
                )?;
                let phase = CasePhases {
                    structure_s,
                    components_s,
                    basis,
                    engine_s: t1.elapsed().as_secs_f64(),
                    residual_s: p.residual_seconds + reference_s,
                    structure_cpu_s: c1 - c0,
                    engine_cpu_s: process_cpu_s() - c2,
                };
                if let Ok(mut v) = self.phases.lock() {
                    v.push(phase);
                }
                Ok(p)
            }
        }
    }
}

/// The value memoised in `memo` under `key`, or `build()`'s, which then replaces the memo (a
/// memo holds one key: a study's cases share one component set). `what` names the memo in
/// the error when an earlier panic poisoned it.
fn memoised<T>(
    memo: &Mutex<Option<(String, Arc<T>)>>,
    key: String,
    what: &str,
    build: impl FnOnce() -> Result<T, BoxError>,
) -> Result<Arc<T>, BoxError> {
    let mut memo = memo
        .lock()
        .map_err(|_| format!("{what} poisoned by an earlier panic"))?;
    if let Some((k, v)) = memo.as_ref() {
        if *k == key {
            return Ok(v.clone());
        }
    }
    *memo = None;
    let v = Arc::new(build()?);
    *memo = Some((key, v.clone()));
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::{basis_plan, ModalCache, Path, Study, StudyBasis, SubstructureOptions};
    fn study(basis: &str) -> Study {
        let text = format!(
            "model = \"builtin:dutch\"\nbasis = \"{basis}\"\n[[parameter]]\nkey = \"fastening.vertical_stiffness\"\nvalues = [0.6e9, 1.3e9]\n[[parameter]]\nkey = \"fastening.vertical_damping\"\nvalues = [15e3, 45e3]\n"
        );
        Study::parse_str(&text, "s.toml", Path::new("/studies"), "s").unwrap()
    }

    /// A 2 × 2 railpad stiffness × damping study against an empty cache: the full basis
    /// solves one track basis per stiffness (the damping is not in the key) and one wheel
    /// basis in all; the substructured basis one component set and a reduced eigenproblem
    /// per case.
    #[test]
    fn the_plan_counts_distinct_bases_per_kind() {
        let dir = std::env::temp_dir().join(format!("plan-test-{}", std::process::id()));
        let cache = ModalCache::new(&dir);
        let s = study("full");
        let p = basis_plan(&s, &s.case_models().unwrap(), &cache).unwrap();
        assert_eq!(
            (p.cases, p.track_to_solve, p.track_cached, p.wheel_to_solve),
            (4, 2, 0, 1)
        );
        assert_eq!((p.components_to_solve, p.reduced), (0, 0));
        let s = study("substructured");
        let p = basis_plan(&s, &s.case_models().unwrap(), &cache).unwrap();
        assert_eq!(
            (
                p.track_to_solve,
                p.wheel_to_solve,
                p.components_to_solve,
                p.reduced
            ),
            (0, 1, 1, 4)
        );
        assert!(p.to_string().contains("1 track component set(s)"), "{p}");
    }

    /// `substructure` options only with the substructured basis, and in range.
    #[test]
    fn substructure_options_are_checked() {
        let base = "model = \"builtin:dutch\"\n[[parameter]]\nkey = \"fastening.vertical_stiffness\"\nvalues = [1e9]\n";
        let parse = |extra: &str| {
            Study::parse_str(
                &format!("{extra}\n{base}"),
                "s.toml",
                Path::new("/studies"),
                "s",
            )
        };
        let e = parse("substructure = { cutoff_factor = 2.0, sleeper_cutoff_factor = 1.0, pattern_degree = 3 }")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("substructure") && e.contains("substructured"),
            "{e}"
        );
        let e = parse("basis = \"substructured\"\nsubstructure = { cutoff_factor = 9.0, sleeper_cutoff_factor = 1.0, pattern_degree = 3 }")
            .unwrap_err()
            .to_string();
        assert!(e.contains("cutoff_factor") && e.contains("1 to 4"), "{e}");
        let s = parse("basis = \"substructured\"").unwrap();
        assert_eq!(s.basis, StudyBasis::Substructured);
        assert_eq!(s.substructure, SubstructureOptions::default());
    }
}

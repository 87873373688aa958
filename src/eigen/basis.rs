//! A classified modal basis of one substructure, loaded from the modal cache or computed
//! (shift-invert Lanczos), classified and stored: the one place where "modes are extracted
//! once and reused" is implemented. Used by `corrugation modes` and by the passage engine.
//!
//! The cache key ([`cache_key`]) hashes only what determines the modes: the structural
//! sections of the model (track, rail, sleeper, fastening, ballast, wheel, vehicle, mesh, and
//! the solution zone, which places the fine mesh), f_max, the substructure name and the
//! program version. Speed, contact, wear and explicit settings do not change the modes, so a
//! speed sweep reuses one entry. No key holds a damper (railpads, ballast, elastic holds,
//! primary suspension): dampers enter C only, so a damping study reuses the modes. The
//! track's key leaves out the wheel, the vehicle and the wheel's mesh keys (the track is
//! built without them), so a study of wheel or suspension parameters reuses the track's
//! modes, the expensive ones; the wheel's key holds only the wheel, the vehicle and the
//! wheel's mesh keys, so a fastening, ballast or rail study shares one wheel basis.

use std::time::Instant;

use faer::Mat;
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::cache::{CacheKey, CacheLookup, CacheMeta, ModalCache};
use super::classify::{
    classify_wheel_modes, ClassifyError, TrackClassifier, TrackModeClass, WheelModeClass,
};
use super::{solve, EigenError, EigenOptions};
use crate::fe::assembly::FeMatrices;
use crate::model::identity::{model_identity, IdentityScope};
use crate::model::Model;
use crate::progress::{Counter, Progress};
use crate::structure::{StructureError, TrackStructure, WheelStructure};

/// Errors of [`track_basis`] / [`wheel_basis`].
#[derive(Debug, thiserror::Error)]
pub enum BasisError {
    /// The eigensolver failed.
    #[error("eigenmodes of the {substructure}: {source}")]
    Eigen {
        /// The substructure whose eigenproblem failed.
        substructure: Substructure,
        /// The solver error (says what to change).
        source: EigenError,
    },
    /// Building or assembling the substructure failed.
    #[error(transparent)]
    Structure(#[from] StructureError),
    /// A mode could not be classified.
    #[error(transparent)]
    Classify(#[from] ClassifyError),
    /// The model or the mode classes could not be (de)serialised as JSON (cache key, cache
    /// record).
    #[error("modal cache key or record: {0}")]
    Json(#[from] serde_json::Error),
}

/// A modal basis with its classification.
#[derive(Clone, Debug)]
pub struct ModalBasis<C> {
    /// Natural frequencies (Hz), ascending.
    pub frequencies_hz: Vec<f64>,
    /// Mass-normalised mode shapes over the free DOFs (n × m; unit m/√kg).
    pub modes: Mat<f64>,
    /// Relative residuals ‖Kφ − ω²Mφ‖/‖Kφ‖ per mode.
    pub residuals: Vec<f64>,
    /// Eigenvalues below f_max by the Sturm count.
    pub sturm_count: usize,
    /// Classification per mode.
    pub classes: Vec<C>,
    /// True when loaded from the cache.
    pub cached: bool,
    /// Wall time to load or compute (s).
    pub seconds: f64,
}

/// Revision of the structural model's physics (how a model becomes K, M, C). Bump it when a
/// change alters the matrices of an unchanged model file, so that no stale cache entry is
/// reused (the program version alone does not change between development commits).
/// 2: journal-node weights of the primary suspension balanced about the axle axis.
pub(crate) const PHYSICS_REVISION: u64 = 2;

/// The substructure a modal basis belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Substructure {
    /// The track (rails, fastenings, sleepers, ballast).
    Track,
    /// The wheel with the sprung mass on its primary suspension.
    Wheel,
}

impl Substructure {
    /// Its name in cache keys and messages: `"track"` or `"wheel"`.
    pub fn name(self) -> &'static str {
        match self {
            Substructure::Track => "track",
            Substructure::Wheel => "wheel",
        }
    }

    /// The part of the model its K and M read.
    pub fn scope(self) -> IdentityScope {
        match self {
            Substructure::Track => IdentityScope::Track,
            Substructure::Wheel => IdentityScope::Wheel,
        }
    }
}

impl std::fmt::Display for Substructure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The cache key of one substructure's modal basis (see the module doc for what it covers):
/// the model's identity in the substructure's scope ([`Substructure::scope`]), f_max (Hz),
/// the substructure's name and `PHYSICS_REVISION`. Compute it once per model and pass it
/// on ([`track_basis_keyed`], [`wheel_basis_keyed`], the residual flexibilities).
pub fn cache_key(
    m: &Model,
    fmax_hz: f64,
    substructure: Substructure,
) -> Result<CacheKey, BasisError> {
    let bytes = model_identity(m, substructure.scope())?;
    let key = CacheKey::new()
        .u64("physics_revision", PHYSICS_REVISION)
        .bytes("model", &bytes)
        .f64("f_max_hz", fmax_hz)
        .str("substructure", substructure.name());
    Ok(match substructure {
        Substructure::Track => section_mesh_keyed(key, m)?,
        Substructure::Wheel => key,
    })
}

/// `key` with the model's rail section mesh added
/// ([`crate::structure::track::section_mesh_bytes`]): a track's basis is keyed by the mesh it
/// was computed on, so a change of the section mesher never reads a basis of a former mesh.
pub(crate) fn section_mesh_keyed(key: CacheKey, m: &Model) -> Result<CacheKey, BasisError> {
    Ok(key.bytes(
        "rail_section_mesh",
        &crate::structure::track::section_mesh_bytes(m)?,
    ))
}

fn column(modes: &Mat<f64>, j: usize) -> Vec<f64> {
    (0..modes.nrows()).map(|i| modes[(i, j)]).collect()
}

/// Classifies mode shapes (columns of `modes`, frequencies in Hz) in chunks: one pass over
/// the elements per chunk (element stiffnesses are rebuilt per pass), bounded memory for the
/// expanded mode shapes; chunks in parallel (rayon keeps their order). 256 modes: the default
/// track to 5 kHz rebuilds them 3 times, not 12 as with 64, and a chunk's expanded shapes
/// take about 330 MB (3 n_nodes f64 per mode).
pub(crate) fn classify_in_chunks<C: Send>(
    modes: &Mat<f64>,
    frequencies_hz: &[f64],
    progress: &dyn Progress,
    classify: impl Fn(&[&[f64]], &[f64]) -> Result<Vec<C>, BasisError> + Sync,
) -> Result<Vec<C>, BasisError> {
    const CHUNK: usize = 256;
    let nm = frequencies_hz.len();
    let counter = Counter::within(progress);
    let per_chunk: Vec<Vec<C>> = {
        use rayon::prelude::*;
        (0..nm)
            .step_by(CHUNK)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|c0| {
                let c1 = (c0 + CHUNK).min(nm);
                let cols: Vec<Vec<f64>> = (c0..c1).map(|j| column(modes, j)).collect();
                let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
                let out = classify(&refs, &frequencies_hz[c0..c1]);
                counter.add((c1 - c0) as u64);
                out
            })
            .collect::<Result<_, _>>()?
    };
    Ok(per_chunk.into_iter().flatten().collect())
}

/// Loads a basis from the cache or solves, classifies and stores it.
fn basis<C: Serialize + DeserializeOwned + Send>(
    cache: &ModalCache,
    key: &CacheKey,
    name: Substructure,
    fmax: f64,
    mats: impl FnOnce() -> Result<FeMatrices, BasisError>,
    classify: impl Fn(&[&[f64]], &[f64]) -> Result<Vec<C>, BasisError> + Sync,
) -> Result<ModalBasis<C>, BasisError> {
    let t = Instant::now();
    match cache.load(key) {
        CacheLookup::Hit(c) => {
            match serde_json::from_value::<Vec<C>>(c.meta.classification.clone()) {
                Ok(classes) if classes.len() == c.frequencies_hz.len() => {
                    return Ok(ModalBasis {
                        frequencies_hz: c.frequencies_hz,
                        residuals: c.meta.relative_residuals.clone(),
                        sturm_count: c.meta.sturm_count,
                        modes: c.modes,
                        classes,
                        cached: true,
                        seconds: t.elapsed().as_secs_f64(),
                    });
                }
                _ => cache.progress().warn(&format!(
                    "modal cache: {name} entry has an incomplete classification; recomputing"
                )),
            }
        }
        CacheLookup::Corrupt(r) => cache.progress().warn(&format!(
            "modal cache: {name} entry corrupt ({}); recomputing",
            crate::progress::error_chain(&r)
        )),
        CacheLookup::Miss => {}
    }
    // Only K and M enter the solve: the dampers' matrix goes, and the mass is kept without
    // the stored zeros of the pattern it shares with K (a lumped mass fills only its
    // diagonal; the 34-bay strip-held track: 480 MB each). The factorisations' pattern is
    // K's with either mass, so the modes are the same to the bit.
    let FeMatrices { k, m, .. } = mats()?;
    let m = {
        // moved in here so that the full mass is freed at the block's end, not kept shadowed
        let full = m;
        super::lanczos::drop_stored_zeros(full.as_ref())
    };
    let progress = cache.progress();
    progress.stage(&format!("{name} modes below {fmax} Hz (Lanczos)"), 0);
    let sol = solve(
        k.as_ref(),
        m.as_ref(),
        &EigenOptions::new(fmax),
        Some(progress),
    )
    .map_err(|source| BasisError::Eigen {
        substructure: name,
        source,
    })?;
    progress.finish();
    progress.stage(
        &format!("classifying {name} modes"),
        sol.frequencies_hz.len() as u64,
    );
    let classes = classify_in_chunks(&sol.modes, &sol.frequencies_hz, progress, classify)?;
    progress.finish();
    let value = serde_json::to_value(&classes).map_err(BasisError::Json)?;
    let meta = CacheMeta::from_solution(&sol, 0.0, fmax, value.clone());
    if let Err(e) = cache.store(key, &sol.frequencies_hz, &sol.modes, meta) {
        progress.warn(&format!(
            "could not store the {name} modes in the cache: {e}"
        ));
    }
    // serde_json (without its `float_roundtrip` feature) may parse a printed f64 one ulp off.
    // Use the values exactly as a cache hit will read them back from meta.json (print, then
    // parse), so that a fresh run and a cached run give identical results.
    let reparse = |v: &serde_json::Value| -> Result<String, BasisError> {
        serde_json::to_string(v).map_err(BasisError::Json)
    };
    let classes: Vec<C> = serde_json::from_str(&reparse(&value)?).map_err(BasisError::Json)?;
    let residuals: Vec<f64> = serde_json::from_str(&reparse(
        &serde_json::to_value(&sol.relative_residuals).map_err(BasisError::Json)?,
    )?)
    .map_err(BasisError::Json)?;
    Ok(ModalBasis {
        frequencies_hz: sol.frequencies_hz,
        residuals,
        sturm_count: sol.sturm_count,
        modes: sol.modes,
        classes,
        cached: false,
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// The track's classified modes below `fmax_hz` (cached under [`cache_key`] of `m`).
pub fn track_basis(
    m: &Model,
    track: &TrackStructure,
    cache: &ModalCache,
    fmax_hz: f64,
) -> Result<ModalBasis<TrackModeClass>, BasisError> {
    let key = cache_key(m, fmax_hz, Substructure::Track)?;
    track_basis_keyed(&key, track, cache, fmax_hz)
}

/// [`track_basis`] under a key already computed (`cache_key(m, fmax_hz, Substructure::Track)`).
pub fn track_basis_keyed(
    key: &CacheKey,
    track: &TrackStructure,
    cache: &ModalCache,
    fmax_hz: f64,
) -> Result<ModalBasis<TrackModeClass>, BasisError> {
    let classifier = TrackClassifier::new(track)?;
    basis(
        cache,
        key,
        Substructure::Track,
        fmax_hz,
        || Ok(track.assemble()?.0),
        |u, _| Ok(classifier.classify_many(track, u)?),
    )
}

/// The wheel's classified modes below `fmax_hz` (cached under [`cache_key`] of `m`),
/// rigid-body modes included.
pub fn wheel_basis(
    m: &Model,
    wheel: &WheelStructure,
    cache: &ModalCache,
    fmax_hz: f64,
) -> Result<ModalBasis<WheelModeClass>, BasisError> {
    let key = cache_key(m, fmax_hz, Substructure::Wheel)?;
    wheel_basis_keyed(&key, wheel, cache, fmax_hz)
}

/// [`wheel_basis`] under a key already computed (`cache_key(m, fmax_hz, Substructure::Wheel)`).
pub fn wheel_basis_keyed(
    key: &CacheKey,
    wheel: &WheelStructure,
    cache: &ModalCache,
    fmax_hz: f64,
) -> Result<ModalBasis<WheelModeClass>, BasisError> {
    basis(
        cache,
        key,
        Substructure::Wheel,
        fmax_hz,
        || Ok(wheel.assemble()?.0),
        |u, f| Ok(classify_wheel_modes(wheel, u, f)?),
    )
}

#[cfg(test)]
mod key_tests {
    use super::{cache_key, section_mesh_keyed, Model, Substructure};
    use crate::eigen::cache::CacheKey;

    #[test]
    fn a_track_key_follows_its_rail_section_mesh() {
        // The same model twice gives the same key; another section mesh (here a finer one)
        // another key, through the mesh itself; the wheel's key does not carry the rail's.
        let m = model(&[]);
        let plain = CacheKey::new().str("substructure", "track");
        let keyed = |m: &Model| section_mesh_keyed(plain.clone(), m).unwrap().hex();
        assert_eq!(keyed(&m), keyed(&model(&[])));
        assert_ne!(keyed(&m), plain.hex());
        let bytes = |m: &Model| crate::structure::track::section_mesh_bytes(m).unwrap();
        let mut finer = model(&[]);
        finer.mesh.section_size = 0.01;
        finer.mesh.head_size = 0.01;
        assert!(bytes(&m) != bytes(&finer), "a finer section, another mesh");
        assert_ne!(keyed(&m), keyed(&finer));
        let w = |m: &Model| cache_key(m, 2000.0, Substructure::Wheel).unwrap().hex();
        assert_eq!(w(&m), w(&finer));
    }
    use crate::model::{load_model, ModelSource};
    use crate::structure::track::TrackStructure;

    fn model(extra: &[&str]) -> Model {
        let mut sets: Vec<String> = [
            "track.bays=2",
            "mesh.element_length=0.1",
            "mesh.fine_element_length=0.1",
            "mesh.section_size=0.04",
            "mesh.head_size=0.02",
            "run.solution_zone_offset=0.1",
            "run.solution_zone_length=0.2",
        ]
        .map(String::from)
        .to_vec();
        sets.extend(extra.iter().map(|s| s.to_string()));
        load_model(&ModelSource::Builtin, &sets).unwrap()
    }

    const TRACK_5KHZ: &str = "02ee7d027310faa50bb1c98fa9c2195a9a69dd0a847d6b5db92efa7777f3011c";
    const WHEEL_5KHZ: &str = "d64f584be6144d9f52b158545295c5d05de966c3c038bc390bad0a66d442fbf1";

    fn key(m: &Model, sub: &str) -> String {
        let sub = match sub {
            "track" => Substructure::Track,
            _ => Substructure::Wheel,
        };
        cache_key(m, 2000.0, sub).unwrap().hex()
    }

    /// Regression guard: the default model's cache keys at 5 kHz, the names of the modal
    /// cache's entries for it. The wheel's is the one the string-named substructures gave; the
    /// track's changed once on 2026-11-30, when it began to carry the rail section mesh.
    #[test]
    fn the_default_model_s_cache_keys_are_unchanged() {
        let m = Model::default_model();
        let hex = |s| cache_key(&m, 5000.0, s).unwrap().hex();
        assert_eq!(hex(Substructure::Track), TRACK_5KHZ);
        assert_eq!(hex(Substructure::Wheel), WHEEL_5KHZ);
    }

    /// The track's key ignores the wheel, the vehicle and the wheel mesh — and the track's
    /// assembled K, M, C are indeed bit-identical when those change; it changes with a track
    /// parameter. The wheel's key changes with the wheel; neither changes with the wheel's
    /// damping ratio (applied after the modes).
    #[test]
    fn track_key_ignores_exactly_what_the_track_does_not_read() {
        let base = model(&[]);
        let wheelish = model(&[
            "wheel.density=9000",
            "wheel.youngs_modulus=2e11",
            "vehicle.wheel_load=80e3",
            "mesh.wheel_segments=24",
            "mesh.wheel_element_size=0.05",
        ]);
        assert_eq!(key(&base, "track"), key(&wheelish, "track"));
        assert_ne!(key(&base, "wheel"), key(&wheelish, "wheel"));
        let damped = model(&["wheel.damping_ratio=0.001"]);
        assert_eq!(key(&base, "track"), key(&damped, "track"));
        assert_eq!(key(&base, "wheel"), key(&damped, "wheel"));
        let stiffer = model(&["rail.youngs_modulus=2.2e11"]);
        assert_ne!(key(&base, "track"), key(&stiffer, "track"));

        let (a, _) = TrackStructure::build(&base).unwrap().assemble().unwrap();
        let (b, _) = TrackStructure::build(&wheelish)
            .unwrap()
            .assemble()
            .unwrap();
        for (x, y) in [(&a.k, &b.k), (&a.m, &b.m), (&a.c, &b.c)] {
            assert_eq!(x.col_ptr(), y.col_ptr());
            assert_eq!(x.row_idx(), y.row_idx());
            assert_eq!(x.val(), y.val());
        }
    }

    /// The dampers (railpads, ballast, primary suspension) enter only C: no key changes with
    /// them, and the track's K and M are bit-identical. The wheel's key ignores every track
    /// parameter (a fastening or rail study shares one wheel basis) but not the wheel's.
    #[test]
    fn keys_ignore_the_dampers_and_the_wheel_key_ignores_the_track() {
        let base = model(&[]);
        let damped = model(&[
            "fastening.vertical_damping=5e4",
            "fastening.longitudinal_damping=1e4",
            "ballast.vertical_damping=8e4",
            "vehicle.primary_damping=2e3",
        ]);
        for sub in ["track", "wheel"] {
            assert_eq!(key(&base, sub), key(&damped, sub), "{sub}");
        }
        let (a, _) = TrackStructure::build(&base).unwrap().assemble().unwrap();
        let (b, _) = TrackStructure::build(&damped).unwrap().assemble().unwrap();
        assert_eq!(a.k.val(), b.k.val());
        assert_eq!(a.m.val(), b.m.val());
        assert_ne!(a.c.val(), b.c.val());
        let tracky = model(&[
            "fastening.model=RPM1",
            "fastening.vertical_stiffness=3e8",
            "rail.youngs_modulus=2.2e11",
            "track.bays=3",
        ]);
        assert_eq!(key(&base, "wheel"), key(&tracky, "wheel"));
        assert_ne!(key(&base, "track"), key(&tracky, "track"));
        assert_ne!(
            key(&base, "wheel"),
            key(&model(&["wheel.radius=0.45"]), "wheel")
        );
    }

    /// Elastic holds: the stiffness is in the track key, the damping is not (it enters only C);
    /// a rigid preset keeps the key it had before elastic holds existed (no new keys written).
    #[test]
    fn hold_stiffness_enters_the_key_and_hold_damping_does_not() {
        let rigid = model(&[]);
        let json = serde_json::to_value(&rigid.fastening).unwrap();
        assert!(json.get("hold").is_none() && json.get("hold_stiffness").is_none());
        let el = |k: &str, c: &str| {
            model(&[
                "fastening.hold=\"elastic\"",
                &format!("fastening.hold_stiffness={k}"),
                &format!("fastening.hold_damping={c}"),
            ])
        };
        assert_ne!(key(&rigid, "track"), key(&el("1e9", "0"), "track"));
        assert_ne!(key(&el("1e9", "0"), "track"), key(&el("3e9", "0"), "track"));
        assert_eq!(
            key(&el("1e9", "0"), "track"),
            key(&el("1e9", "5e4"), "track")
        );
        let custom = |k: &str, c: &str| {
            model(&[
                "fastening.model=custom",
                &format!(
                    "fastening.custom.x={{ elastic = \"columns\", indices = [1], stiffness = {k}, damping = {c} }}"
                ),
                "fastening.custom.y={ rigid = \"rows\", indices = [0, 3] }",
                "fastening.custom.z={ rigid = \"none\" }",
            ])
        };
        assert_ne!(
            key(&custom("1e9", "0"), "track"),
            key(&custom("2e9", "0"), "track")
        );
        assert_eq!(
            key(&custom("1e9", "0"), "track"),
            key(&custom("1e9", "7e3"), "track")
        );
    }
}

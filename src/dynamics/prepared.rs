//! The prepared reduced-order model: a passage engine with its classified modal bases (from
//! the modal cache or given), built once and run for any number of passages; the
//! [`super::PassageRunner`] the studies use (docs/theory.md §7).

use super::passage::{PassageEngine, PassageOptions, TrackInput, WheelInput};
use super::{DynamicsError, RailProfile};
use crate::eigen::basis::{
    cache_key, track_basis_keyed, wheel_basis_keyed, ModalBasis, Substructure,
};
use crate::eigen::cache::{CacheKey, ModalCache};
use crate::eigen::classify::{TrackModeClass, WheelModeClass};
use crate::fe::assembly::FeMatrices;
use crate::model::Model;
use crate::structure::{TrackStructure, WheelStructure};
use faer::sparse::SparseColMat;

/// Where the track's static flexibility at the contact (for its residual flexibility,
/// [`super::residual`]) comes from.
pub enum TrackStatic<'a> {
    /// The residual flexibility cached with the track entry of this key (computed from a
    /// factorisation of `K` and stored when absent).
    Cached(&'a crate::eigen::cache::CacheKey),
    /// A factorisation of the track's `K`, not cached.
    Factorise,
    /// A factorisation of the track's `K` reusing the symbolic analysis shared by the
    /// models of a study (same pattern of `K`), not cached.
    FactoriseShared(&'a super::residual::SharedStiffnessAnalysis),
    /// Given (e.g. a reference factorisation updated for changed spring stiffnesses); it
    /// must be the static flexibility of this track's `K`.
    Given(&'a (dyn super::residual::StaticFlexibility + Sync)),
}

/// Wall times (s) of the phases of a [`PreparedModel`]'s preparation. The track's side (mesh,
/// basis, damping) runs beside the wheel's (mesh, basis, assembly, Rayleigh frequencies), and
/// the track's residual flexibility beside the wheel's, so phases overlap: `total` is the
/// wall time of the whole. A phase that did not run is 0.
#[derive(Clone, Debug, Default)]
pub struct PreparationTimes {
    /// Building the track's mesh and structure (0 when the track was given).
    pub track_mesh: f64,
    /// Loading (or computing) the track's modal basis (0 when the basis was given).
    pub track_basis: f64,
    /// Assembling the track's damping matrix.
    pub track_damping: f64,
    /// Building the wheel's mesh and structure.
    pub wheel_mesh: f64,
    /// Loading (or computing) the wheel's modal basis.
    pub wheel_basis: f64,
    /// Assembling the wheel's stiffness, mass and damping.
    pub wheel_assembly: f64,
    /// The wheel modes' Rayleigh frequencies.
    pub wheel_rayleigh: f64,
    /// The passage engine: the modal systems (damping projections), the contact lines'
    /// modal rows, the loads.
    pub engine: f64,
    /// The track's residual flexibility (from the cache, or a factorisation of `K`).
    pub track_residual: f64,
    /// The wheel's residual flexibility.
    pub wheel_residual: f64,
    /// The whole preparation.
    pub total: f64,
}

/// Runs `f`, adding its wall time (s) to `into`.
fn timed<T>(into: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = std::time::Instant::now();
    let out = f();
    *into += t.elapsed().as_secs_f64();
    out
}

/// The engine of a model with its classified bases, built once and reused for any number of
/// passages (speeds, rail profiles).
pub struct PreparedModel {
    /// The engine.
    pub engine: PassageEngine,
    /// Track modes: frequencies (Hz) and classification.
    pub track_frequencies_hz: Vec<f64>,
    /// Track mode classes.
    pub track_classes: Vec<crate::eigen::classify::TrackModeClass>,
    /// Wheel modes: frequencies (Hz).
    pub wheel_frequencies_hz: Vec<f64>,
    /// Seconds spent on the modal bases (0 when both came from the cache… plus loading).
    pub modal_seconds: f64,
    /// True when both bases came from the cache.
    pub cached: bool,
    /// Wall time (s) of the track's and the wheel's residual flexibilities (0 when the
    /// model asks for neither).
    pub residual_seconds: f64,
    /// Wall times (s) of the preparation's phases.
    pub times: PreparationTimes,
}

/// The wheel's side of the preparation: structure, basis, matrices, Rayleigh frequencies.
struct WheelSide {
    /// The wheel basis's cache key (the wheel's residual flexibility is cached beside it).
    key: CacheKey,
    wheel: WheelStructure,
    basis: ModalBasis<WheelModeClass>,
    mats: FeMatrices,
    hz: Vec<f64>,
}

impl WheelSide {
    fn prepare(
        model: &Model,
        cache: &ModalCache,
        times: &mut PreparationTimes,
    ) -> Result<Self, DynamicsError> {
        let key = cache_key(model, model.run.fmax, Substructure::Wheel)?;
        let wheel = timed(&mut times.wheel_mesh, || WheelStructure::build(model))?;
        let basis = timed(&mut times.wheel_basis, || {
            wheel_basis_keyed(&key, &wheel, cache, model.run.fmax)
        })?;
        let (mats, _) = timed(&mut times.wheel_assembly, || wheel.assemble())?;
        // The wheel floats: its rigid modes' frequencies from the Rayleigh quotient, which is
        // 0 to round-off where the eigen-solver's eigenvalue may not be.
        let hz = timed(&mut times.wheel_rayleigh, || {
            super::reduced::rayleigh_frequencies_hz(mats.k.as_ref(), &basis.modes)
        });
        Ok(WheelSide {
            key,
            wheel,
            basis,
            mats,
            hz,
        })
    }
}

/// The track's side of the preparation and the wheel's, ready for the engine.
struct Parts<'a> {
    track: &'a TrackStructure,
    basis: ModalBasis<TrackModeClass>,
    damping: SparseColMat<usize, f64>,
    wheel: WheelSide,
    times: PreparationTimes,
}

impl PreparedModel {
    /// Builds the track and wheel, loads or computes their modes below `model.run.fmax`
    /// (cached in `cache`), assembles the damping, and builds the engine. The wheel's side is
    /// prepared first, then the track's: one progress stage at a time, each with its own name
    /// and count (prepared side by side, the two eigen-solves' stages interleaved on the one
    /// progress of `cache`, and the track's long solve went unreported). The wheel's solve is
    /// the small one (about 20 s cold on the default model, 0.2 s from the cache).
    pub fn new(
        model: &Model,
        cache: &ModalCache,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let t = std::time::Instant::now();
        let fmax = model.run.fmax;
        let key = cache_key(model, fmax, Substructure::Track)?;
        let (mut tt, mut tw) = (PreparationTimes::default(), PreparationTimes::default());
        let wheel = WheelSide::prepare(model, cache, &mut tw)?;
        let track = timed(&mut tt.track_mesh, || TrackStructure::build(model))?;
        let basis = timed(&mut tt.track_basis, || {
            track_basis_keyed(&key, &track, cache, fmax)
        })?;
        let damping = timed(&mut tt.track_damping, || track.assemble_damping())?;
        let parts = Parts {
            track: &track,
            basis,
            damping,
            wheel,
            times: PreparationTimes {
                track_mesh: tt.track_mesh,
                track_basis: tt.track_basis,
                track_damping: tt.track_damping,
                ..tw
            },
        };
        Self::finish(model, parts, cache, TrackStatic::Cached(&key), opts, t)
    }

    /// As [`Self::new`] with the track's modal basis given (e.g. a substructured one,
    /// [`crate::eigen::substructure`]); the wheel's basis comes from `cache`. The residual
    /// flexibility (when the model asks for it) is cached with the track entry of
    /// `residual_key`, or computed without caching when `None`.
    pub fn with_track_basis(
        model: &Model,
        track: &TrackStructure,
        tb: ModalBasis<TrackModeClass>,
        cache: &ModalCache,
        residual_key: Option<&crate::eigen::cache::CacheKey>,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let stat = match residual_key {
            Some(k) => TrackStatic::Cached(k),
            None => TrackStatic::Factorise,
        };
        Self::with_track_basis_static(model, track, tb, cache, stat, opts)
    }

    /// As [`Self::with_track_basis`], with the source of the track's static flexibility at
    /// the contact given.
    pub fn with_track_basis_static(
        model: &Model,
        track: &TrackStructure,
        tb: ModalBasis<TrackModeClass>,
        cache: &ModalCache,
        stat: TrackStatic<'_>,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let t = std::time::Instant::now();
        let (mut tt, mut tw) = (PreparationTimes::default(), PreparationTimes::default());
        let (damping, wheel) = rayon::join(
            || timed(&mut tt.track_damping, || track.assemble_damping()),
            || WheelSide::prepare(model, cache, &mut tw),
        );
        let parts = Parts {
            track,
            basis: tb,
            damping: damping?,
            wheel: wheel?,
            times: PreparationTimes {
                track_damping: tt.track_damping,
                ..tw
            },
        };
        Self::finish(model, parts, cache, stat, opts, t)
    }

    /// Builds the engine from the prepared parts and sets the residual flexibilities the
    /// model asks for (the track's and the wheel's concurrently). `t` is the preparation's
    /// start.
    fn finish(
        model: &Model,
        parts: Parts<'_>,
        cache: &ModalCache,
        stat: TrackStatic<'_>,
        opts: &PassageOptions,
        t: std::time::Instant,
    ) -> Result<Self, DynamicsError> {
        let Parts {
            track,
            basis: tb,
            damping,
            wheel: w,
            mut times,
        } = parts;
        // the fe-patch (if the model asks for it), kept with the modes
        super::fe_patch::use_cache_dir(cache.dir());
        super::setup::prepare_fe_patch(model, Some(cache.progress()))?;
        let mut engine = timed(&mut times.engine, || {
            PassageEngine::new(
                model,
                TrackInput {
                    structure: track,
                    frequencies_hz: &tb.frequencies_hz,
                    modes: &tb.modes,
                    damping: damping.as_ref(),
                },
                WheelInput {
                    structure: &w.wheel,
                    frequencies_hz: &w.hz,
                    modes: &w.basis.modes,
                    matrices: &w.mats,
                },
                opts,
            )
        })?;
        let t_residual = std::time::Instant::now();
        let (r, wr) = {
            let (tr, twr) = (&mut times.track_residual, &mut times.wheel_residual);
            let e = &engine;
            rayon::join(
                || timed(tr, || track_residual(model, e, track, cache, stat)),
                || timed(twr, || wheel_residual(model, e, &w, cache)),
            )
        };
        if let Some(r) = r? {
            engine.set_residual_flexibility(Some(r))?;
        }
        if let Some(wr) = wr? {
            engine.set_wheel_residual(Some(wr))?;
        }
        times.total = t.elapsed().as_secs_f64();
        Ok(PreparedModel {
            residual_seconds: t_residual.elapsed().as_secs_f64(),
            engine,
            modal_seconds: tb.seconds + w.basis.seconds,
            cached: tb.cached && w.basis.cached,
            track_frequencies_hz: tb.frequencies_hz,
            track_classes: tb.classes,
            wheel_frequencies_hz: w.hz,
            times,
        })
    }

    /// Frequencies (Hz) of the track's longitudinal-compression modes.
    pub fn longitudinal_compression_hz(&self) -> Vec<f64> {
        use crate::eigen::classify::TrackFamily;
        self.track_frequencies_hz
            .iter()
            .zip(&self.track_classes)
            .filter(|(_, c)| c.family == TrackFamily::LongitudinalCompression)
            .map(|(&f, _)| f)
            .collect()
    }

    /// Frequencies (Hz) of the wheel modes the contact sees strongly: elastic wheel modes
    /// whose squared mass-normalised displacement at the wheel's contact point, in the rolling
    /// (x) or the normal (n) direction, is at least `share` (−, e.g. 0.1) of the largest one
    /// in that direction ([`PassageEngine::wheel_contact_participation`]). These are the poles
    /// of the wheel's contact receptance with the largest residues. Modes within 0.5 % of
    /// the previous one kept (the pairs of an axisymmetric wheel) give one frequency.
    pub fn wheel_contact_modes_hz(&self, share: f64) -> Vec<f64> {
        let p = self.engine.wheel_contact_participation();
        let max = |d: usize| p.iter().map(|(_, r)| r[d]).fold(0.0, f64::max);
        let (mx, mn) = (max(0), max(1));
        let mut out: Vec<f64> = Vec::new();
        for &(i, r) in &p {
            if (mx > 0.0 && r[0] >= share * mx) || (mn > 0.0 && r[1] >= share * mn) {
                let f = self.wheel_frequencies_hz[i];
                // A pair of modes (sine and cosine about the contact) is one line.
                if out.last().is_none_or(|&g| f > g * 1.005) {
                    out.push(f);
                }
            }
        }
        out
    }

    /// Frequencies (Hz) of the track's vertical-bending modes.
    pub fn vertical_bending_hz(&self) -> Vec<f64> {
        use crate::eigen::classify::TrackFamily;
        self.track_frequencies_hz
            .iter()
            .zip(&self.track_classes)
            .filter(|(_, c)| c.family == TrackFamily::VerticalBending)
            .map(|(&f, _)| f)
            .collect()
    }
}

/// The track's residual flexibility when the model asks for it, from `stat`; the track's
/// `K` is assembled only when it is to be factorised.
fn track_residual(
    model: &Model,
    engine: &PassageEngine,
    track: &TrackStructure,
    cache: &ModalCache,
    stat: TrackStatic<'_>,
) -> Result<Option<super::residual::ResidualFlexibility>, DynamicsError> {
    use super::residual::{cached_residual, LineModes, ResidualFlexibility, StiffnessFactor};
    if !model.run.residual_flexibility {
        return Ok(None);
    }
    let lm = LineModes {
        line: &engine.rail_line,
        frame: &engine.frame,
        omega2: &engine.track_sys.omega2,
    };
    let travel = engine.travel_m();
    let stiffness =
        || -> Result<SparseColMat<usize, f64>, DynamicsError> { Ok(track.assemble()?.0.k) };
    let r = match stat {
        TrackStatic::Cached(key) => {
            cached_residual(cache, key, track, &stiffness, lm, engine.hertz_b_m, travel)?.0
        }
        TrackStatic::Factorise => ResidualFlexibility::compute(
            track,
            &StiffnessFactor::new(stiffness()?.as_ref())?,
            lm,
            travel,
        )?,
        TrackStatic::FactoriseShared(a) => {
            ResidualFlexibility::compute(track, &a.factor(stiffness()?.as_ref())?, lm, travel)?
        }
        TrackStatic::Given(f) => ResidualFlexibility::compute(track, f, lm, travel)?,
    };
    Ok(Some(r))
}

/// The wheel's residual flexibility when the model asks for it, cached with the wheel's
/// basis.
fn wheel_residual(
    model: &Model,
    engine: &PassageEngine,
    w: &WheelSide,
    cache: &ModalCache,
) -> Result<Option<super::wheel_residual::WheelResidual>, DynamicsError> {
    use super::wheel_residual::{WheelModes, WheelResidual};
    if !model.run.wheel_residual_flexibility {
        return Ok(None);
    }
    let wm = WheelModes {
        wheel: &w.wheel,
        k: w.mats.k.as_ref(),
        m: w.mats.m.as_ref(),
        modes: &w.basis.modes,
        omega2: &engine.wheel_system().omega2,
        frame: &engine.frame,
        half_width_m: engine.hertz_b_m,
    };
    Ok(Some(WheelResidual::cached(cache, &w.key, wm)?.0))
}

impl super::PassageRunner for PreparedModel {
    fn run(
        &self,
        speed: crate::units::Speed,
        profile: Option<&RailProfile>,
    ) -> Result<super::PassageSummary, super::PassageError> {
        let opts = PassageOptions {
            energy: false,
            rail_point_offset_m: None,
            overlap: false,
        };
        let rec = self
            .engine
            .passage(speed.m_per_s(), profile, &opts, None)
            .map_err(DynamicsError::into_passage)?;
        super::analysis::summarise_at(&rec, speed)
    }
}

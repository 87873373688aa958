//! The prepared reduced-order model: a passage engine with its classified modal bases (from
//! the modal cache or given), built once and run for any number of passages; the
//! [`super::PassageRunner`] the studies use (docs/theory.md §7).

use super::passage::{PassageEngine, PassageOptions, TrackInput, WheelInput};
use super::{DynamicsError, RailProfile};
use crate::model::Model;
use crate::structure::{TrackStructure, WheelStructure};

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
    Given(&'a dyn super::residual::StaticFlexibility),
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
}

impl PreparedModel {
    /// Builds the track and wheel, loads or computes their modes below `model.run.fmax`
    /// (cached in `cache`), assembles the damping, and builds the engine.
    pub fn new(
        model: &Model,
        cache: &crate::eigen::cache::ModalCache,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        let track = TrackStructure::build(model)?;
        let fmax = model.run.fmax;
        let tb = crate::eigen::basis::track_basis(model, &track, cache, fmax)?;
        let key = crate::eigen::basis::cache_key(model, fmax, "track")?;
        Self::with_track_basis(model, &track, tb, cache, Some(&key), opts)
    }

    /// As [`Self::new`] with the track's modal basis given (e.g. a substructured one,
    /// [`crate::eigen::substructure`]); the wheel's basis comes from `cache`. The residual
    /// flexibility (when the model asks for it) is cached with the track entry of
    /// `residual_key`, or computed without caching when `None`.
    pub fn with_track_basis(
        model: &Model,
        track: &TrackStructure,
        tb: crate::eigen::basis::ModalBasis<crate::eigen::classify::TrackModeClass>,
        cache: &crate::eigen::cache::ModalCache,
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
        tb: crate::eigen::basis::ModalBasis<crate::eigen::classify::TrackModeClass>,
        cache: &crate::eigen::cache::ModalCache,
        stat: TrackStatic<'_>,
        opts: &PassageOptions,
    ) -> Result<Self, DynamicsError> {
        use crate::eigen::basis::wheel_basis;

        let wheel = WheelStructure::build(model)?;
        let fmax = model.run.fmax;
        let wb = wheel_basis(model, &wheel, cache, fmax)?;
        let (tm, _) = track.assemble()?;
        let (wm, _) = wheel.assemble()?;
        // The wheel floats: its rigid modes' frequencies from the Rayleigh quotient, which is
        // 0 to round-off where the eigen-solver's eigenvalue may not be.
        let wheel_hz = super::reduced::rayleigh_frequencies_hz(wm.k.as_ref(), &wb.modes);
        let mut engine = PassageEngine::new(
            model,
            TrackInput {
                structure: track,
                frequencies_hz: &tb.frequencies_hz,
                modes: &tb.modes,
                damping: tm.c.as_ref(),
            },
            WheelInput {
                structure: &wheel,
                frequencies_hz: &wheel_hz,
                modes: &wb.modes,
                matrices: &wm,
            },
            opts,
        )?;
        let t_residual = std::time::Instant::now();
        if model.run.residual_flexibility {
            let lm = super::residual::LineModes {
                line: &engine.rail_line,
                frame: &engine.frame,
                omega2: &engine.track_sys.omega2,
            };
            let travel = engine.travel_m();
            let r = match stat {
                TrackStatic::Cached(key) => {
                    let k = tm.k.as_ref();
                    super::residual::cached_residual(
                        cache,
                        key,
                        track,
                        k,
                        lm,
                        engine.hertz_b_m,
                        travel,
                    )?
                    .0
                }
                TrackStatic::Factorise => super::residual::ResidualFlexibility::compute(
                    track,
                    &super::residual::StiffnessFactor::new(tm.k.as_ref())?,
                    lm,
                    travel,
                )?,
                TrackStatic::FactoriseShared(a) => super::residual::ResidualFlexibility::compute(
                    track,
                    &a.factor(tm.k.as_ref())?,
                    lm,
                    travel,
                )?,
                TrackStatic::Given(f) => {
                    super::residual::ResidualFlexibility::compute(track, f, lm, travel)?
                }
            };
            engine.set_residual_flexibility(Some(r))?;
        }
        if model.run.wheel_residual_flexibility {
            let w =
                super::wheel_residual::WheelResidual::compute(super::wheel_residual::WheelModes {
                    wheel: &wheel,
                    k: wm.k.as_ref(),
                    m: wm.m.as_ref(),
                    modes: &wb.modes,
                    omega2: &engine.wheel_system().omega2,
                    frame: &engine.frame,
                    half_width_m: engine.hertz_b_m,
                })?;
            engine.set_wheel_residual(Some(w))?;
        }
        Ok(PreparedModel {
            residual_seconds: t_residual.elapsed().as_secs_f64(),
            engine,
            modal_seconds: tb.seconds + wb.seconds,
            cached: tb.cached && wb.cached,
            track_frequencies_hz: tb.frequencies_hz,
            track_classes: tb.classes,
            wheel_frequencies_hz: wheel_hz,
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

impl super::PassageRunner for PreparedModel {
    fn prepared(&self) -> Option<&PreparedModel> {
        Some(self)
    }

    fn run(
        &self,
        speed: crate::units::Speed,
        profile: Option<&RailProfile>,
    ) -> Result<super::PassageSummary, DynamicsError> {
        let opts = PassageOptions {
            energy: false,
            rail_point_offset_m: None,
        };
        let rec = self.engine.passage(speed.m_per_s(), profile, &opts, None)?;
        super::analysis::summarise_at(&rec, speed)
    }
}

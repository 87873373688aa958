//! The model file: every parameter of the wheel–track model, with its unit.
//!
//! A model is a TOML file (see `models/dutch-base.toml`, which documents every key with its
//! unit). Files are parsed with `deny_unknown_fields`: a misspelt key is an error that names
//! the file and the dotted key, never a silently ignored value. A file may start with
//! `extends = "other.toml"` (a path relative to the file) or `extends = "builtin:dutch"` (the
//! embedded Dutch base model): the base is read first and the file's tables are merged over it,
//! key by key. Command-line overrides `--set dotted.key=value` (TOML value syntax; a bare word
//! is taken as a string) are merged last. The merged table is then deserialised and
//! [validated](Model::validate): every numeric parameter is checked against a stated range.
//!
//! Units are SI everywhere, except `run.speed_kmh` (km/h), converted in [`crate::units`].
//!
//! The fastening models RPM1–RPM5 (docs/theory.md §3.2) are *data*: each is a [`HoldPattern`] — which
//! rail-foot regions are held rigidly, in which direction — and any other pattern can be given
//! with `fastening.model = "custom"` and a `[fastening.custom]` table.

mod fastening;
mod holds;
pub mod identity;
mod load;
pub(crate) mod plausibility;
pub mod test_problems;
mod validate;

pub use fastening::{
    Axis, DirectionHold, ElasticHolds, Fastening, FasteningModel, HoldPattern, Holds, Preset,
    RigidRegion, MAX_HOLD_STIFFNESS, MIN_HOLD_STIFFNESS, PRESET_NAMES,
};
pub(crate) use load::BUILTIN_DUTCH;
pub use load::{
    apply_assignment, load_model, load_model_assigned, load_model_shown, load_model_str,
    Assignment, ModelSource,
};
pub use validate::{FMAX_HZ, MAX_GRID_WORK, MAX_WHEEL_LOAD_N, SPEED_KMH, SPEED_KMH_WHY};

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

use crate::fe::material::IsotropicElastic;
use crate::mesh::wheel::{BrakeDisc, WheelParams};

/// Errors while reading or checking a model file. Each names the file and the key.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A position along the rail (an argument `what`, e.g. `--at`) off the model's track.
    #[error("{what} {x_m}: off the track: a position in m along the rail, 0 to {length_m} m (the track's length, track.bays × track.sleeper_spacing)")]
    OffTrack {
        /// What the position is (the flag or key that gave it).
        what: String,
        /// The position (m).
        x_m: f64,
        /// The track's length (m).
        length_m: f64,
    },
    /// The file could not be read.
    #[error("{file}: cannot read model file: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// TOML syntax error.
    #[error("{file}: TOML syntax error: {message}")]
    Syntax {
        /// The file.
        file: String,
        /// The parser's message (with line and column).
        message: String,
    },
    /// A key is unknown, missing, or of the wrong type.
    #[error("{file}: key `{key}`: {message}")]
    Key {
        /// The file (with the files it extends).
        file: String,
        /// The dotted key.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A value outside its allowed range.
    #[error("{file}: key `{key}` = {value}: out of range, allowed {allowed}")]
    OutOfRange {
        /// The file (with the files it extends).
        file: String,
        /// The dotted key.
        key: String,
        /// The value given.
        value: String,
        /// The allowed range, with unit.
        allowed: String,
    },
    /// A `--set key=value` override that cannot be applied.
    #[error("--set {arg}: {message}")]
    Override {
        /// The argument as given.
        arg: String,
        /// What is wrong.
        message: String,
    },
    /// `extends` chains that loop or go too deep.
    #[error("{file}: `extends` chain too deep or circular (more than 8 levels)")]
    ExtendsLoop {
        /// The file.
        file: String,
    },
}

/// The complete model. Field docs state units; `models/dutch-base.toml` gives the defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// Track layout.
    pub track: Track,
    /// Rail geometry and material.
    pub rail: Rail,
    /// Half sleeper.
    pub sleeper: Sleeper,
    /// Rail fastening (railpad springs and rigid holds).
    pub fastening: Fastening,
    /// Ballast under each half sleeper.
    pub ballast: Ballast,
    /// Wheel geometry and material.
    pub wheel: Wheel,
    /// Vehicle: static load and primary suspension.
    pub vehicle: Vehicle,
    /// Wheel–rail contact parameters.
    pub contact: Contact,
    /// Mesh sizes.
    pub mesh: MeshParams,
    /// Run parameters of a passage.
    pub run: Run,
    /// Wear law (docs/theory.md §6.6).
    pub wear: Wear,
    /// The full explicit FE path (docs/theory.md §8); optional section.
    #[serde(default)]
    pub explicit: Explicit,
}

/// Wear law: W_f = k Σ τ·s·Δt (docs/theory.md §6.6).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wear {
    /// Wear coefficient k (m³/J), greater than 0 and at most 1e-6: worn volume per joule of
    /// frictional work. A single passage
    /// judges relative (differential) wear, which k scales and never shapes; the iterative
    /// growth uses it for the worn depth per passage. Default 1e-13 (Archard K ≈ 1e-4, mild
    /// wear, H ≈ 3 GPa, µ = 0.4: k = K/(µH)).
    pub coefficient: f64,
    /// Initiation threshold (−): the smooth rail initiates corrugation only when the RMS of
    /// its 20–80 mm band-passed differential wear is at least this fraction of the mean wear
    /// (and F_L follows the wear; docs/theory.md §11.4). Default 0.01, range 0 to 1. A
    /// stated choice, not a published value.
    #[serde(default = "default_initiation_threshold")]
    pub initiation_threshold: f64,
}

/// Default of [`Wear::initiation_threshold`] (−).
pub const DEFAULT_INITIATION_THRESHOLD: f64 = 0.01;

fn default_initiation_threshold() -> f64 {
    DEFAULT_INITIATION_THRESHOLD
}

/// The full explicit FE path (used to confirm the reduced model's frequency selection): a
/// central-difference integration of the same track and wheel FE models as the reduced
/// passage, untruncated (docs/theory.md §8).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Explicit {
    /// Safety factor on the computed critical time step `(2/ω_max)(√(1+ξ²) − ξ)` (−), in
    /// [0.1, 1]; default 0.9. ω_max is estimated by Lanczos on `M^{-½}KM^{-½}` (a lower
    /// estimate of the true value), so the factor keeps a margin.
    #[serde(default = "default_explicit_safety")]
    pub safety: f64,
    /// A time step for the track and the wheel (s, 1e-10 to 1e-4), instead of the computed
    /// one; when the explicit model is built it is refused above `safety` × the computed
    /// critical step of either substructure. Default: none (computed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_step: Option<f64>,
    /// How the contact force is applied to the rail's node planes: `"patch"` (default, the
    /// static Hertz patch's parabolic line load through the shape functions of every plane
    /// under it) or `"node"` (the two planes around the contact point, linear
    /// interpolation; the mesh then indents locally under a node line, docs/theory.md §8.6).
    #[serde(default)]
    pub load_spread: LoadSpread,
    /// What the contact sees of the mesh's local compliance under the moving load:
    /// `"constant"` (default: on the rail its element-scale variation with the load's
    /// position is removed, the mean kept, as the reduced passage's constant residual
    /// flexibility; on the rotating wheel its variation with the contact's material angle is
    /// removed, the value at θ = 0, the fixed wheel's contact, kept) or `"mesh"` (the mesh's
    /// own, position dependent; docs/theory.md §8.6, §8.7).
    #[serde(default)]
    pub local_compliance: ExplicitLocalCompliance,
    /// The wheel treatment of the explicit path (docs/theory.md §8.7): `"fixed"` (default,
    /// the wheel as the reduced model has it, not rotating) or `"rotating"` (its elastic
    /// motion in a frame spinning at V/R, with the Coriolis and spin-softening terms).
    #[serde(default)]
    pub wheel: ExplicitWheel,
}

/// The explicit path's treatment of the mesh's local compliance (docs/theory.md §8.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExplicitLocalCompliance {
    /// The element-scale variation removed (series compliance −Δg(x) on the rail, and
    /// −(g(φ) − g(0)) on the rotating wheel).
    #[default]
    Constant,
    /// The mesh's own position-dependent local compliance.
    Mesh,
}

/// How the explicit path applies the contact force to the rail (docs/theory.md §8.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LoadSpread {
    /// Over the static Hertz patch along the rail (parabolic line load).
    #[default]
    Patch,
    /// On the two node planes around the contact point (linear interpolation).
    Node,
}

/// The wheel treatment of the explicit path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExplicitWheel {
    /// Not rotating: the contact point is fixed on the wheel (as in the reduced model).
    #[default]
    Fixed,
    /// Rotating at `Ω = V/R`: the wheel's elastic motion in the spinning frame, the contact
    /// point moving around the tread.
    Rotating,
}

impl ExplicitWheel {
    /// The key's value as written in a model file (`"fixed"`, `"rotating"`).
    pub fn as_str(self) -> &'static str {
        match self {
            ExplicitWheel::Fixed => "fixed",
            ExplicitWheel::Rotating => "rotating",
        }
    }
}

fn default_explicit_safety() -> f64 {
    0.9
}

impl Default for Explicit {
    fn default() -> Self {
        Self {
            safety: default_explicit_safety(),
            time_step: None,
            load_spread: LoadSpread::Patch,
            local_compliance: ExplicitLocalCompliance::Constant,
            wheel: ExplicitWheel::Fixed,
        }
    }
}

/// Track layout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Track {
    /// Number of sleeper bays (−), 2 to 400; the track is `bays × sleeper_spacing` long.
    /// Default model: 16.
    pub bays: usize,
    /// Sleeper spacing, centre to centre (m), 0.2 to 2; default model 0.6.
    pub sleeper_spacing: f64,
    /// Boundary condition at both rail ends (docs/theory.md §3.7): `"free"` (default; the
    /// ends reflect every wave) or `"absorbing"` (viscous dashpots on the end faces matched to
    /// the rail's wave impedances, so that waves leave the model). Enters the damping only:
    /// the modes, and their cache, do not depend on it.
    #[serde(default, skip_serializing_if = "RailEnds::is_free")]
    pub ends: RailEnds,
    /// With `ends = "absorbing"`: length of the absorbing layer at each rail end (m), 0 to 10,
    /// default [`DEFAULT_ABSORBING_LAYER_M`]; 0 = the end-face dashpots alone. The layers must
    /// lie outside the wheel's travel.
    #[serde(
        default = "default_absorbing_layer",
        skip_serializing_if = "is_default_absorbing_layer"
    )]
    pub absorbing_layer_length: f64,
    /// With `ends = "absorbing"`: the layer's largest damping rate α_max (1/s), 0 to 1e6,
    /// default [`DEFAULT_ABSORBING_LAYER_RATE`]: grounded dashpots in y and z of `α(d) m_i` on
    /// every rail node of mass `m_i` in the layer, `α(d) = α_max (1 − d/L)²` at distance `d`
    /// from the end face.
    #[serde(
        default = "default_absorbing_layer_rate",
        skip_serializing_if = "is_default_absorbing_layer_rate"
    )]
    pub absorbing_layer_rate: f64,
}

/// Default `track.absorbing_layer_length` (m): about one vertical bending wavelength of the
/// UIC54 rail at 300 Hz, the band's lower edge (docs/theory.md §3.7).
pub const DEFAULT_ABSORBING_LAYER_M: f64 = 2.4;
/// Default `track.absorbing_layer_rate` (1/s): with the default length, a quadratic ramp to
/// it reflects at most 0.3 % of a vertical bending wave's energy over 0.3–3 kHz on a
/// Euler–Bernoulli rail (docs/theory.md §3.7).
pub const DEFAULT_ABSORBING_LAYER_RATE: f64 = 1.0e4;

fn default_absorbing_layer() -> f64 {
    DEFAULT_ABSORBING_LAYER_M
}
fn is_default_absorbing_layer(x: &f64) -> bool {
    *x == DEFAULT_ABSORBING_LAYER_M
}
fn default_absorbing_layer_rate() -> f64 {
    DEFAULT_ABSORBING_LAYER_RATE
}
fn is_default_absorbing_layer_rate(x: &f64) -> bool {
    *x == DEFAULT_ABSORBING_LAYER_RATE
}

/// Boundary condition at the rail's two end faces (docs/theory.md §3.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RailEnds {
    /// Traction-free end faces: every wave reflects.
    #[default]
    Free,
    /// Dashpots to the ground at every end-face node, per tributary area `A_i`: normal (x)
    /// `ρ c_b A_i` with the bar speed `c_b = √(E/ρ)`, tangential (y, z) `ρ c_s A_i` with the
    /// shear speed `c_s = √(G/ρ)`: the impedances of the rail's longitudinal wave and the
    /// high-frequency limit of its bending waves.
    Absorbing,
}

impl RailEnds {
    /// Whether the ends are free (the default, left out when a model is written).
    pub(crate) fn is_free(&self) -> bool {
        *self == RailEnds::Free
    }

    /// The model-file name: `free`, `absorbing`.
    pub fn name(self) -> &'static str {
        match self {
            RailEnds::Free => "free",
            RailEnds::Absorbing => "absorbing",
        }
    }
}

/// Rail.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rail {
    /// Cross-section profile (the only one accepted: `"uic54"`, the embedded, checked 54E1
    /// half profile; a file naming another is refused).
    pub profile: String,
    /// Rail cant as tan(angle) (−), 0 to 0.1: 0.025 = 1/40; 0 = upright.
    pub inclination: f64,
    /// Young's modulus (Pa), 1e9 to 1e13 (`YOUNGS_MODULUS_PA`).
    pub youngs_modulus: f64,
    /// Poisson's ratio (−), 0 to 0.45 (`POISSON_RATIO`).
    pub poisson_ratio: f64,
    /// Density (kg/m³), 1000 to 20000 (`DENSITY_KG_M3`).
    pub density: f64,
}

/// Half monoblock sleeper as a solid block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sleeper {
    /// Length across the track (m), 0.3 to 5.
    pub length: f64,
    /// Width along the rail (m), 0.05 to `track.sleeper_spacing`.
    pub width: f64,
    /// Height (m), 0.05 to 1.
    pub height: f64,
    /// Distance from the sleeper's track-centre end to the rail centre line (m).
    pub rail_seat: f64,
    /// Young's modulus (Pa), 1e9 to 1e13 (`YOUNGS_MODULUS_PA`).
    pub youngs_modulus: f64,
    /// Poisson's ratio (−), 0 to 0.45 (`POISSON_RATIO`).
    pub poisson_ratio: f64,
    /// Density (kg/m³), 1000 to 20000 (`DENSITY_KG_M3`).
    pub density: f64,
}

/// A spring–damper in each direction (x longitudinal, y lateral, z vertical), as the
/// fastening's railpad and the ballast have: written as six flat keys of their tables.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringDampers {
    /// Vertical stiffness (N/m).
    pub vertical_stiffness: f64,
    /// Vertical damping (N·s/m).
    pub vertical_damping: f64,
    /// Lateral stiffness (N/m).
    pub lateral_stiffness: f64,
    /// Lateral damping (N·s/m).
    pub lateral_damping: f64,
    /// Longitudinal stiffness (N/m).
    pub longitudinal_stiffness: f64,
    /// Longitudinal damping (N·s/m).
    pub longitudinal_damping: f64,
}

/// Ballast under each half sleeper, spread over its bottom face by area (the `[ballast]`
/// table).
pub type Ballast = SpringDampers;

impl SpringDampers {
    /// Stiffness in x, y, z (N/m).
    pub fn stiffness(&self) -> [f64; 3] {
        [
            self.longitudinal_stiffness,
            self.lateral_stiffness,
            self.vertical_stiffness,
        ]
    }
    /// Damping in x, y, z (N·s/m).
    pub fn damping(&self) -> [f64; 3] {
        [
            self.longitudinal_damping,
            self.lateral_damping,
            self.vertical_damping,
        ]
    }
}

/// Wheel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wheel {
    /// Nominal rolling radius (m), 0.2 to 0.8; default model 0.46. The rim's inner radius
    /// stays at 0.39 m unless `rim_thickness` is set, so without it the radius must be at
    /// least 0.42 m (a rim of `MIN_RIM_THICKNESS_M`); with it, at least 0.23 m.
    pub radius: f64,
    /// Tread conicity (−): 0.025 = 1/40; 0 to 0.1.
    pub conicity: f64,
    /// Young's modulus (Pa), 1e9 to 1e13 (`YOUNGS_MODULUS_PA`).
    pub youngs_modulus: f64,
    /// Poisson's ratio (−), 0 to 0.45 (`POISSON_RATIO`).
    pub poisson_ratio: f64,
    /// Density (kg/m³), 1000 to 20000 (`DENSITY_KG_M3`).
    pub density: f64,
    /// Modal damping ratio of the wheel's elastic modes (−), added to the diagonal of the
    /// wheel's projected damping as `2 ζ ω_i` (1/s); default 0, as in the reference (no
    /// damping in the steel). Measured railway wheels have ζ ≈ 1e-4–1e-3 for most modes.
    #[serde(default)]
    pub damping_ratio: f64,
    /// Shape of the web (docs/theory.md §3.5): `"straight"` (default, a flat disc) or
    /// `"curved"` (its mid-plane moves axially by `web_bend` from the hub to the rim along a
    /// half cosine, meeting both at right angles, as an S-shaped web).
    #[serde(default, skip_serializing_if = "WebShape::is_straight")]
    pub web_shape: WebShape,
    /// With `web_shape = "curved"`: axial shift of the web's mid-plane from the hub to the rim
    /// (m, + towards the field side), −0.1 to 0.1 and not 0, the web's faces at the rim at
    /// least `WEB_RIM_CLEARANCE_M` inside the rim's faces; default
    /// `DEFAULT_WEB_BEND_M`. Refused with a straight web.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub web_bend: Option<f64>,
    /// Axial thickness of the web (m), 0.01 to 0.1 and at most the rim width less twice
    /// `WEB_RIM_CLEARANCE_M`; default [`DEFAULT_WEB_THICKNESS_M`] (30 mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub web_thickness: Option<f64>,
    /// Axial position of the web's mid-plane at the hub, from the rolling-circle plane (m, +
    /// towards the field side); default [`DEFAULT_WEB_OFFSET_M`] (30 mm towards the track
    /// centre). The web's faces must lie within the hub (y −0.12 to 0.065 m) and, at the hub
    /// and at the rim, at least `WEB_RIM_CLEARANCE_M` inside the rim's faces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub web_offset: Option<f64>,
    /// Axial width of the rim (m), 0.11 to 0.2; default [`DEFAULT_RIM_WIDTH_M`] (135 mm). The
    /// rim's back face stays 70 mm from the rolling circle (y = −0.07 m); the width moves
    /// its field-side face.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rim_width: Option<f64>,
    /// Radial thickness of the rim, from the tread's rolling circle to its inner radius (m),
    /// `MIN_RIM_THICKNESS_M` (0.03) to `radius − 0.2` (the web at least
    /// `MIN_WEB_HEIGHT_M` high above the 0.15 m hub). Default: the rim's inner radius stays
    /// at [`DEFAULT_RIM_INNER_RADIUS_M`] (0.39 m), 0.07 m on the default 0.46 m wheel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rim_thickness: Option<f64>,
    /// Whether the axle carries the brake disc (a solid steel ring r 0.095–0.32 m, y −0.42 to
    /// −0.36 m, about 137 kg); default true. `false` leaves the bare wheel and axle.
    #[serde(default = "default_true", skip_serializing_if = "is_true")]
    pub brake_disc: bool,
}

/// Shape of the wheel's web (`wheel.web_shape`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WebShape {
    /// A flat disc between hub and rim.
    #[default]
    Straight,
    /// Mid-plane shifted axially by `wheel.web_bend` from the hub to the rim (half cosine).
    Curved,
}

impl WebShape {
    /// Whether the web is straight (the default, left out when a model is written).
    pub(crate) fn is_straight(&self) -> bool {
        *self == WebShape::Straight
    }
}

fn is_true(b: &bool) -> bool {
    *b
}

/// Default `wheel.web_thickness` (m).
pub const DEFAULT_WEB_THICKNESS_M: f64 = 0.030;
/// Default `wheel.web_offset` (m).
pub const DEFAULT_WEB_OFFSET_M: f64 = -0.030;
/// Default `wheel.web_bend` of a curved web (m).
pub(crate) const DEFAULT_WEB_BEND_M: f64 = 0.030;
/// Default `wheel.rim_width` (m).
pub const DEFAULT_RIM_WIDTH_M: f64 = 0.135;
/// The rim's inner radius when `wheel.rim_thickness` is not given (m).
pub const DEFAULT_RIM_INNER_RADIUS_M: f64 = 0.39;
/// Smallest `wheel.rim_thickness` (m): the tread's fine contact zone reaches 30 mm deep.
pub(crate) const MIN_RIM_THICKNESS_M: f64 = 0.03;
/// Smallest radial height of the web, rim inner radius less hub radius (m).
pub(crate) const MIN_WEB_HEIGHT_M: f64 = 0.05;
/// Least axial distance from the web's faces to the rim's faces (m), at the hub and at the
/// rim: the rim's cells beside the web keep a width.
pub(crate) const WEB_RIM_CLEARANCE_M: f64 = 0.005;

impl Wheel {
    /// The web's faces at the hub (m, wheel frame y): `web_offset ∓ web_thickness/2`, or the
    /// default wheel's −0.045 and −0.015 m when neither key is given.
    pub fn web_y_m(&self) -> [f64; 2] {
        if self.web_thickness.is_none() && self.web_offset.is_none() {
            return WheelParams::default().web_y_m;
        }
        let t = self.web_thickness.unwrap_or(DEFAULT_WEB_THICKNESS_M);
        let c = self.web_offset.unwrap_or(DEFAULT_WEB_OFFSET_M);
        [c - 0.5 * t, c + 0.5 * t]
    }

    /// The web's axial bend from hub to rim (m): 0 for a straight web.
    pub fn web_bend_m(&self) -> f64 {
        match self.web_shape {
            WebShape::Straight => 0.0,
            WebShape::Curved => self.web_bend.unwrap_or(DEFAULT_WEB_BEND_M),
        }
    }

    /// The rim's faces (m, wheel frame y): the back face at −0.07 m, the front face
    /// `rim_width` from it (the default wheel's 0.065 m when not given).
    pub fn rim_y_m(&self) -> [f64; 2] {
        let d = WheelParams::default();
        match self.rim_width {
            None => [d.rim_y_start_m, d.rim_y_end_m],
            Some(w) => [d.rim_y_start_m, d.rim_y_start_m + w],
        }
    }

    /// The rim's inner radius (m): `radius − rim_thickness`, or
    /// [`DEFAULT_RIM_INNER_RADIUS_M`] when the thickness is not given.
    pub fn rim_inner_radius_m(&self) -> f64 {
        match self.rim_thickness {
            None => DEFAULT_RIM_INNER_RADIUS_M,
            Some(t) => self.radius - t,
        }
    }

    /// The axle's brake disc, if the wheel has one.
    pub fn brake_disc(&self) -> Option<BrakeDisc> {
        if self.brake_disc {
            WheelParams::default().brake_disc
        } else {
            None
        }
    }
}

/// Vehicle above the wheel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vehicle {
    /// Static vertical wheel load (N), greater than 0 and at most [`MAX_WHEEL_LOAD_N`];
    /// default model 100e3. The sprung mass is (load / g − unsprung mass).
    pub wheel_load: f64,
    /// Primary suspension stiffness per wheel (N/m), `MIN_PRIMARY_STIFFNESS` (1e3) to 1e10;
    /// default model 1.15e6.
    pub primary_stiffness: f64,
    /// Primary suspension damping per wheel (N·s/m), 0 to 1e9; default model 2.5e3.
    pub primary_damping: f64,
    /// Gravitational acceleration (m/s²), 9 to 10.5 (the sprung mass is load / gravity).
    pub gravity: f64,
}

/// Wheel–rail contact.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    /// Coulomb friction coefficient (−), greater than 0 and at most 2.
    pub friction: f64,
    /// Traction coefficient: mean F_L / F_N, set by the driving torque (−), 0 to
    /// `friction`; default model 0.15.
    pub traction_coefficient: f64,
    /// Lateral radius of the rail head crown (m), 0.05 to 10; default model 0.3 (R300).
    pub rail_crown_radius: f64,
    /// Contact-patch grid elements along the rolling direction (−). The passage's time step
    /// is one grid element over the speed, Δt = Δx / V. 8 to 256, and
    /// `grid_nx² · grid_ny` at most [`MAX_GRID_WORK`] (the passage's work grows so).
    pub grid_nx: usize,
    /// Contact-patch grid elements across the rail (−), 4 to 256; default model 24.
    pub grid_ny: usize,
    /// Grid half-lengths over the static Hertz semi-axes (−), 1.05 to 3 (default model
    /// 1.4): the grid covers
    /// `grid_margin · a` by `grid_margin · b`; larger when the normal load varies strongly.
    /// Over a corrugated rail the passage lengthens it along x at the same element size
    /// (`passage::setup::grid_for_profile`); a passage whose contact patch still reaches the
    /// grid's edge is rerun on a grid widened along that edge (`passage::setup::widen_grid`,
    /// docs/theory.md §6.8).
    pub grid_margin: f64,
    /// The influence coefficients the contact is solved with: `"half-space"` (default) or
    /// `"fe-patch"` (see [`ContactInfluence`]).
    #[serde(default, skip_serializing_if = "ContactInfluence::is_half_space")]
    pub influence: ContactInfluence,
}

/// The influence coefficients of the contact grid (`contact.influence`, docs/theory.md §6.9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactInfluence {
    /// Kalker's two quasi-identical elastic half-spaces (Boussinesq–Cerruti), the FE model
    /// entering only through the contact's load rows and the series compliance.
    #[default]
    HalfSpace,
    /// The local FE contact patch: the rail head's (the model's UIC54 section) and the
    /// tread's (the model's rim) influence coefficients condensed from refined FE submodels
    /// on the contact grid, each less its global twin's compliance (what the global model
    /// already carries at the contact), summed. Built once per contact grid (default model:
    /// about 70 s and 8.4 GB peak on two cores) and cached beside the modes. The
    /// normal–tangential couplings of the two different bodies are left out, as for
    /// quasi-identical bodies. The reduced engine and the `contact` command only: the
    /// explicit engine refuses it.
    FePatch,
}

impl ContactInfluence {
    /// Whether it is the half-space (the default, left out when a model is written).
    pub(crate) fn is_half_space(&self) -> bool {
        *self == ContactInfluence::HalfSpace
    }
}

/// Mass matrix kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassKind {
    /// Diagonal (lumped) mass.
    Lumped,
    /// Consistent mass.
    Consistent,
}

/// Mesh sizes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshParams {
    /// Element length along the rail outside the fine zone (m), greater than 0 and at most a
    /// quarter of the sleeper spacing; default model 0.04.
    pub element_length: f64,
    /// Element length along the rail in and around the solution zone (m), greater than 0 and
    /// at most `element_length`; default model 0.01.
    pub fine_element_length: f64,
    /// Target element size in the rail foot and web (m), 0.002 to 0.05; default model 0.02.
    pub section_size: f64,
    /// Target element size near the running surface (m), 0.001 to `section_size`; default
    /// model 0.01.
    pub head_size: f64,
    /// Hexahedra of a sleeper along x, y, z (−), 1 to 64 each; default model [4, 10, 2].
    pub sleeper_elements: [usize; 3],
    /// Circumferential divisions of the wheel away from the contact (−), 12 to 720; default
    /// model 36.
    pub wheel_segments: usize,
    /// Largest element size of the wheel, axially and radially (m), 0.005 to 0.1 (default
    /// model 0.06); half of it at the contact zone of the tread.
    pub wheel_element_size: f64,
    /// Lumped or consistent mass.
    pub mass: MassKind,
    /// Where the rail's node planes sit in the fine zone: `"graded"` (default) or
    /// `"lattice"` (see [`NodePlanes`]).
    #[serde(default, skip_serializing_if = "NodePlanes::is_graded")]
    pub node_planes: NodePlanes,
}

/// Where the rail's node planes sit in the fine zone (`mesh.node_planes`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NodePlanes {
    /// Graded through every hold breakpoint (strip edges, footprint ends): inside the fine
    /// zone the spacing is at most `mesh.fine_element_length` and shrinks between breakpoints
    /// that are not a whole number of elements apart, so it varies with the sleeper period.
    #[default]
    Graded,
    /// Every node plane of the fine zone on one lattice, `x = k · mesh.fine_element_length`
    /// (the zone's ends moved out to the lattice): a uniform spacing. Hold breakpoints inside
    /// the zone that are off the lattice are not node planes; a held strip or footprint then
    /// holds the lattice planes inside it (its held length differs by up to one element), and a
    /// hold on node lines off the lattice is refused. For testing whether a result depends on
    /// the spacing's variation along the rail (a mesh artefact).
    Lattice,
}

impl NodePlanes {
    /// Whether the planes are graded (the default, left out when a model is written).
    pub(crate) fn is_graded(&self) -> bool {
        *self == NodePlanes::Graded
    }
}

/// Run parameters of a passage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Run {
    /// Train speed (km/h; converted to m/s by [`Run::speed`]), 40 to 500 ([`SPEED_KMH`]);
    /// default model 140. Not below 40 km/h: the passage's time step is the contact step
    /// `Δx/V` (one contact-grid element over the speed), and its explicit coupling of the
    /// contact force and the structures is stable only while that step is short against the
    /// stiffest motion coupled through the contact; below about 30 km/h on the default model
    /// the normal force grows step by step until the contact patch leaves the contact grid
    /// (a wider grid, `contact.grid_margin`, does not help).
    pub speed_kmh: f64,
    /// Distance from the wheel's start to the solution zone (m), 0 to 10; default model 0.3.
    pub solution_zone_offset: f64,
    /// Length of the solution zone (m), at least 0.08 (the longest wavelength of the wear
    /// analysis band, 20–80 mm, which the zone's record must hold), the zone fitting on the
    /// track with its offset; default model 1.
    pub solution_zone_length: f64,
    /// Highest natural frequency kept in the modal bases of the passage (Hz), 100 to 20000;
    /// default model 5000.
    pub fmax: f64,
    /// Static correction of the truncated track modes at the contact: the structural
    /// residual flexibility of the rail ([`crate::dynamics::residual`]) in series with the
    /// contact (default true; `false` = modal flexibility only).
    #[serde(default = "default_true")]
    pub residual_flexibility: bool,
    /// How the residual flexibility varies along the rail: `"mean"` (default: one constant,
    /// its length-weighted mean along the travel; the element-to-element variation of a
    /// graded mesh is an artefact) or `"consistent"` (position dependent: the flexibility of
    /// the load as the passage spreads it over the two node planes around the contact, which
    /// dips between planes as the full FE model's own local compliance does; for comparing
    /// with the explicit path, docs/theory.md §8.6).
    #[serde(default)]
    pub residual_variation: ResidualVariation,
    /// Static correction of the truncated wheel modes at the contact: the wheel's residual
    /// flexibility (free wheel, inertia relief; [`crate::dynamics::wheel_residual`]) in series
    /// with the contact, added to the rail's (default true: a truncated basis is too stiff at
    /// the contact; `false` = the wheel's modal flexibility only).
    #[serde(default = "default_true")]
    pub wheel_residual_flexibility: bool,
    /// How a passage starts (docs/theory.md §7.5): `"static"` (default: steady rolling at
    /// the static load, traction included, from a static solve) or `"rest"` (the wheel
    /// placed on the rail under its static vertical load in free rolling, no traction; the
    /// driving torque and the train's resistance come on as a step `run.rest_start_distance`
    /// before the solution zone).
    #[serde(default)]
    pub start: StartKind,
    /// With `start = "rest"`: distance before the solution zone at which the driving torque
    /// comes on (m), default `DEFAULT_REST_START_DISTANCE_M`, greater than 0 and at most the
    /// run-in (the distance from the wheel's start to the zone, `run.solution_zone_offset`
    /// when the track is long enough).
    #[serde(default = "default_rest_start_distance")]
    pub rest_start_distance: f64,
    /// How the reduced passage forms the creepages from the structures' motion at the
    /// contact (docs/theory.md §7.3): `"velocity"` (default: the relative velocity at the
    /// step's end, `t_{n+1}`, divided by the speed) or `"increment"` (the relative
    /// displacement increment over the contact step of the same material points divided by
    /// `V Δt_c`, the slip Kalker's transient step integrates; the explicit path's). Reduced
    /// engine only.
    #[serde(default)]
    pub creepage: CreepageKind,
}

/// How the reduced passage forms the creepages from the structures' motion (docs/theory.md
/// §7.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CreepageKind {
    /// The relative velocity of wheel and rail at the contact at the step's end, `t_{n+1}`
    /// (the integrator's predicted velocity), divided by the speed.
    #[default]
    Velocity,
    /// The relative displacement increment of the wheel's and the rail's contact points over
    /// the contact step (both read with the rows of the step's end position), divided by
    /// `V Δt_c`.
    Increment,
}

/// How a passage starts (docs/theory.md §7.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StartKind {
    /// Steady rolling at the static load, traction included (a static solve).
    #[default]
    Static,
    /// Free rolling under the static vertical load; the driving torque steps on before the
    /// solution zone, as an explicit FE run starts from rest.
    Rest,
}

/// Default of `run.rest_start_distance` (m): the reference study's explicit run starts its
/// wheel from a static equilibrium 0.3 m before the solution zone (docs/theory.md §2.5,
/// §3.6); 0.3 m is also about eight times the distance in which the creep force reaches the
/// traction after a torque step at 140 km/h (35 mm measured; `m_eff V²/κ`, docs/theory.md
/// §7.5), so the mean traction is established in the zone while the elastic modes the step
/// excites still ring.
pub(crate) const DEFAULT_REST_START_DISTANCE_M: f64 = 0.3;

fn default_rest_start_distance() -> f64 {
    DEFAULT_REST_START_DISTANCE_M
}

/// How the residual flexibility of the truncated track modes varies along the rail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ResidualVariation {
    /// One constant: the length-weighted mean of the structural residual along the travel.
    #[default]
    Mean,
    /// The consistent quadratic form of the load at the contact position (position
    /// dependent, mesh dependent).
    Consistent,
}

fn default_true() -> bool {
    true
}

impl Run {
    /// Speed (m/s).
    pub fn speed(&self) -> f64 {
        crate::units::kmh_to_ms(self.speed_kmh)
    }

    /// The speed as given in the model (`speed_kmh` carried exactly; see
    /// [`crate::units::Speed`]).
    pub fn requested_speed(&self) -> crate::units::Speed {
        crate::units::Speed::from_kmh(self.speed_kmh)
    }
}

impl Model {
    /// Refuses a position of `xs` (m along the rail, given as `what`) off the track: each must
    /// be finite and within 0 to [`Model::track_length`].
    pub fn check_on_track(&self, what: &str, xs: &[f64]) -> Result<(), ModelError> {
        let length_m = self.track_length();
        match xs
            .iter()
            .find(|x| !(x.is_finite() && (0.0..=length_m).contains(*x)))
        {
            Some(&x_m) => Err(ModelError::OffTrack {
                what: what.to_string(),
                x_m,
                length_m,
            }),
            None => Ok(()),
        }
    }

    /// The embedded default model (Dutch track, RPM3).
    pub fn default_model() -> Model {
        load_model_str(BUILTIN_DUTCH, "builtin:dutch", &[]).expect("embedded model is valid")
    }

    /// Track length `bays × sleeper_spacing` (m).
    pub fn track_length(&self) -> f64 {
        self.track.bays as f64 * self.track.sleeper_spacing
    }

    /// Rail steel.
    pub fn rail_material(&self) -> IsotropicElastic {
        IsotropicElastic {
            youngs_modulus: self.rail.youngs_modulus,
            poisson_ratio: self.rail.poisson_ratio,
            density: self.rail.density,
        }
    }

    /// Sleeper concrete.
    pub fn sleeper_material(&self) -> IsotropicElastic {
        IsotropicElastic {
            youngs_modulus: self.sleeper.youngs_modulus,
            poisson_ratio: self.sleeper.poisson_ratio,
            density: self.sleeper.density,
        }
    }

    /// Wheel steel.
    pub fn wheel_material(&self) -> IsotropicElastic {
        IsotropicElastic {
            youngs_modulus: self.wheel.youngs_modulus,
            poisson_ratio: self.wheel.poisson_ratio,
            density: self.wheel.density,
        }
    }
}

#[cfg(test)]
mod tests;

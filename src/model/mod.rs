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

mod holds;
mod load;

pub use load::{apply_override, load_model, load_model_str, ModelSource, BUILTIN_DUTCH};

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

use crate::fe::material::IsotropicElastic;

/// Errors while reading or checking a model file. Each names the file and the key.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
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
    /// Wear coefficient k (m³/J): worn volume per joule of frictional work. A single passage
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
    /// A time step for the track and the wheel (s), instead of the computed one; it is
    /// checked against the computed stable limit when the explicit model is built, and a
    /// larger value is an error. Default: none (computed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_step: Option<f64>,
    /// How the contact force is applied to the rail's node planes: `"patch"` (default, the
    /// static Hertz patch's parabolic line load through the shape functions of every plane
    /// under it) or `"node"` (the two planes around the contact point, linear
    /// interpolation; the mesh then indents locally under a node line, docs/theory.md §8.6).
    #[serde(default)]
    pub load_spread: LoadSpread,
    /// What the contact sees of the mesh's local compliance under the moving load:
    /// `"constant"` (default: its element-scale variation with the load's position is
    /// removed, the mean kept, as the reduced passage's constant residual flexibility) or
    /// `"mesh"` (the mesh's own, position dependent; docs/theory.md §8.6).
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
    /// The element-scale variation removed (series compliance −Δg(x)).
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
    /// Number of sleeper bays (−); the track is `bays × sleeper_spacing` long.
    pub bays: usize,
    /// Sleeper spacing, centre to centre (m).
    pub sleeper_spacing: f64,
}

/// Rail.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rail {
    /// Cross-section profile: `"uic54"` (the embedded 54E1 half profile).
    pub profile: String,
    /// Rail cant as tan(angle) (−): 0.025 = 1/40; 0 = upright.
    pub inclination: f64,
    /// Young's modulus (Pa), 1e9 to 1e13 ([`YOUNGS_MODULUS_PA`]).
    pub youngs_modulus: f64,
    /// Poisson's ratio (−), 0 to 0.45 ([`POISSON_RATIO`]).
    pub poisson_ratio: f64,
    /// Density (kg/m³), 1000 to 20000 ([`DENSITY_KG_M3`]).
    pub density: f64,
    /// Stiffness-proportional (Rayleigh β) structural damping of the steel (s); 0 in the
    /// reference, where all damping sits in the discrete dampers. Only 0 is accepted: steel
    /// damping is not modelled yet (a non-zero value is an error, not silently ignored).
    pub structural_damping: f64,
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
    /// Young's modulus (Pa), 1e9 to 1e13 ([`YOUNGS_MODULUS_PA`]).
    pub youngs_modulus: f64,
    /// Poisson's ratio (−), 0 to 0.45 ([`POISSON_RATIO`]).
    pub poisson_ratio: f64,
    /// Density (kg/m³), 1000 to 20000 ([`DENSITY_KG_M3`]).
    pub density: f64,
}

/// Named fastening models of docs/theory.md §3.2, or a custom hold pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FasteningModel {
    /// V-3-4: railpad springs; longitudinally rigid at all three columns; laterally at four rows.
    #[serde(rename = "RPM1")]
    Rpm1,
    /// V-∞-4: railpad springs; longitudinally rigid at every rail-foot node (continuous).
    #[serde(rename = "RPM2")]
    Rpm2,
    /// V-1-4: railpad springs; longitudinally rigid at the middle column only (degraded).
    #[serde(rename = "RPM3")]
    Rpm3,
    /// ∞-1-4: vertically rigid everywhere (no vertical bending); longitudinally the middle column.
    #[serde(rename = "RPM4")]
    Rpm4,
    /// ∞-∞-4: vertically and longitudinally rigid everywhere (longitudinal shear alone).
    #[serde(rename = "RPM5")]
    Rpm5,
    /// The pattern in `[fastening.custom]`.
    #[serde(rename = "custom")]
    Custom,
}

impl std::fmt::Display for FasteningModel {
    /// The name used in model files: `RPM1` … `RPM5`, `custom`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FasteningModel::Rpm1 => "RPM1",
            FasteningModel::Rpm2 => "RPM2",
            FasteningModel::Rpm3 => "RPM3",
            FasteningModel::Rpm4 => "RPM4",
            FasteningModel::Rpm5 => "RPM5",
            FasteningModel::Custom => "custom",
        })
    }
}

impl FasteningModel {
    /// Name as in the model file.
    pub fn name(self) -> &'static str {
        match self {
            FasteningModel::Rpm1 => "RPM1",
            FasteningModel::Rpm2 => "RPM2",
            FasteningModel::Rpm3 => "RPM3",
            FasteningModel::Rpm4 => "RPM4",
            FasteningModel::Rpm5 => "RPM5",
            FasteningModel::Custom => "custom",
        }
    }
}

/// A rail-foot region held in one direction: rigidly (`rigid = "…"`) or by grounded springs
/// (`elastic = "…"`). Columns, rows and the continuous region have a physical size, so what
/// they hold converges under mesh refinement; `grid_points` does not (docs/theory.md §3.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RigidRegion {
    /// Not held (only the railpad springs act).
    None,
    /// The listed columns: strips of width `strip_width` along x, across the whole foot.
    Columns,
    /// The listed rows: strips of width `strip_width` across y, over the footprint length.
    Rows,
    /// Every node of the rail-foot underside, along the whole rail.
    Continuous,
    /// One rail-foot node per railpad grid point (the `rows × columns` cell centres, where the
    /// railpad springs sit; the mesh gets a node there). A node-like hold: its stiffness grows
    /// without bound under mesh refinement (docs/theory.md §3.3), so results depend on the mesh.
    GridPoints,
}

/// The hold of one direction: `{ rigid = "columns", indices = [1] }` fixes the region's DOFs;
/// `{ elastic = "columns", indices = [1], stiffness = 1e9, damping = 0.0 }` instead ties them to
/// the ground by spring-dampers whose stiffness (N/m) and damping (N·s/m) *per fastening* are
/// spread over the region's nodes by tributary area (evenly over the grid points for
/// `grid_points`; per bay of one sleeper spacing for `continuous`). Give one of `rigid` and
/// `elastic`; an absent `rigid` means `"none"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionHold {
    /// The region held rigidly (`"none"` when the direction is held elastically or not at all).
    #[serde(default = "region_none")]
    pub rigid: RigidRegion,
    /// The region held by springs; absent for a rigid hold.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elastic: Option<RigidRegion>,
    /// Column or row indices (0-based; columns counted along +x, rows along +y) for
    /// `columns`/`rows`; empty otherwise.
    #[serde(default)]
    pub indices: Vec<usize>,
    /// Elastic hold: stiffness per fastening (N/m), greater than 0 and at most
    /// [`MAX_HOLD_STIFFNESS`]; shared equally by the listed columns/rows or grid points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Elastic hold: damping per fastening (N·s/m), 0 to 1e12; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

fn region_none() -> RigidRegion {
    RigidRegion::None
}

/// Largest stiffness per fastening of an elastic hold (N/m): far above any railpad, so that
/// "k → ∞" can be approached, yet small enough to keep K well conditioned.
pub const MAX_HOLD_STIFFNESS: f64 = 1e13;

impl DirectionHold {
    fn none() -> Self {
        Self::rigid(RigidRegion::None, vec![])
    }
    fn continuous() -> Self {
        Self::rigid(RigidRegion::Continuous, vec![])
    }
    fn columns(indices: Vec<usize>) -> Self {
        Self::rigid(RigidRegion::Columns, indices)
    }
    fn rows(indices: Vec<usize>) -> Self {
        Self::rigid(RigidRegion::Rows, indices)
    }
    fn rigid(region: RigidRegion, indices: Vec<usize>) -> Self {
        DirectionHold {
            rigid: region,
            elastic: None,
            indices,
            stiffness: None,
            damping: None,
        }
    }

    /// The held region, rigid or elastic.
    pub fn region(&self) -> RigidRegion {
        self.elastic.unwrap_or(self.rigid)
    }

    /// Stiffness (N/m) and damping (N·s/m) per fastening of an elastic hold; `None` for a
    /// rigid hold or none.
    pub fn elastic_stiffness_damping(&self) -> Option<(f64, f64)> {
        match self.elastic {
            Some(r) if r != RigidRegion::None => {
                Some((self.stiffness.unwrap_or(0.0), self.damping.unwrap_or(0.0)))
            }
            _ => None,
        }
    }

    /// The same region held elastically with `k` (N/m) and `c` (N·s/m) per fastening; a
    /// direction not held stays so.
    fn made_elastic(&self, k: f64, c: f64) -> Self {
        if self.rigid == RigidRegion::None {
            return self.clone();
        }
        DirectionHold {
            rigid: RigidRegion::None,
            elastic: Some(self.rigid),
            indices: self.indices.clone(),
            stiffness: Some(k),
            damping: Some(c),
        }
    }
}

/// How the rail foot is held, per direction: the general description of which the RPM models
/// are instances. Railpad springs act in a direction whenever its stiffness or damping is
/// non-zero, whatever the hold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldPattern {
    /// Longitudinal (x).
    pub x: DirectionHold,
    /// Lateral (y).
    pub y: DirectionHold,
    /// Vertical (z).
    pub z: DirectionHold,
}

impl HoldPattern {
    /// The pattern of a named model for a `rows × columns` fastening grid (docs/theory.md §3.2):
    /// the first number of the Li et al. code (V-3-4) is the vertical hold (V = springs,
    /// ∞ = rigid everywhere), the second the longitudinal one (number of rigid columns, ∞ =
    /// continuous), the third the lateral one (number of rigid rows). `None` for `custom`.
    pub fn preset(model: FasteningModel, rows: usize, columns: usize) -> Option<HoldPattern> {
        let all_rows = DirectionHold::rows((0..rows).collect());
        let middle = DirectionHold::columns(vec![columns / 2]);
        let all_columns = DirectionHold::columns((0..columns).collect());
        let (x, z) = match model {
            FasteningModel::Rpm1 => (all_columns, DirectionHold::none()),
            FasteningModel::Rpm2 => (DirectionHold::continuous(), DirectionHold::none()),
            FasteningModel::Rpm3 => (middle, DirectionHold::none()),
            FasteningModel::Rpm4 => (middle, DirectionHold::continuous()),
            FasteningModel::Rpm5 => (DirectionHold::continuous(), DirectionHold::continuous()),
            FasteningModel::Custom => return None,
        };
        Some(HoldPattern { x, y: all_rows, z })
    }
}

/// Rail fastening: railpad springs on a `rows × columns` grid and rigid holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fastening {
    /// RPM1–RPM5 or custom.
    pub model: FasteningModel,
    /// The hold pattern when `model = "custom"` (must be absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub custom: Option<HoldPattern>,
    /// Spring rows across the track (−).
    pub rows: usize,
    /// Spring columns along the rail (−).
    pub columns: usize,
    /// Footprint length along the rail (m).
    pub footprint_length: f64,
    /// Footprint width across the track (m).
    pub footprint_width: f64,
    /// Width of a rigidly held column strip (along x) or row strip (along y) (m).
    pub strip_width: f64,
    /// Gap between the rail-foot underside and the sleeper top (m).
    pub pad_thickness: f64,
    /// Vertical stiffness per fastening (N/m), spread evenly over the grid.
    pub vertical_stiffness: f64,
    /// Vertical damping per fastening (N·s/m).
    pub vertical_damping: f64,
    /// Lateral stiffness per fastening (N/m).
    pub lateral_stiffness: f64,
    /// Lateral damping per fastening (N·s/m).
    pub lateral_damping: f64,
    /// Longitudinal stiffness per fastening (N/m).
    pub longitudinal_stiffness: f64,
    /// Longitudinal damping per fastening (N·s/m).
    pub longitudinal_damping: f64,
    /// How the regions of a preset (RPM1–RPM5) are held: `"rigid"` (default, the models as
    /// published) or `"elastic"`: every rigidly held region of the directions in
    /// `hold_directions` becomes grounded springs of `hold_stiffness` and `hold_damping` per
    /// fastening. Not allowed with `model = "custom"` (give `elastic` regions there).
    #[serde(default, skip_serializing_if = "HoldKind::is_rigid")]
    pub hold: HoldKind,
    /// Stiffness per fastening of the elastic holds of a preset (N/m), greater than 0 and at
    /// most [`MAX_HOLD_STIFFNESS`]; required with `hold = "elastic"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_stiffness: Option<f64>,
    /// Damping per fastening of the elastic holds of a preset (N·s/m), 0 to 1e12; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_damping: Option<f64>,
    /// Directions whose preset holds become elastic with `hold = "elastic"`, e.g. `["x"]`;
    /// default all three.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_directions: Option<Vec<Axis>>,
}

/// Rigid or elastic holds of a preset fastening model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HoldKind {
    /// Held DOFs are fixed (the published models).
    #[default]
    Rigid,
    /// Held regions are tied to the ground by spring-dampers.
    Elastic,
}

impl HoldKind {
    fn is_rigid(&self) -> bool {
        *self == HoldKind::Rigid
    }
}

/// A global direction, as named in the model file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// Longitudinal.
    X,
    /// Lateral.
    Y,
    /// Vertical.
    Z,
}

impl Axis {
    /// DOF offset within a node (0, 1, 2).
    pub fn index(self) -> usize {
        self as usize
    }
}

impl Fastening {
    /// The hold pattern in force: the preset of the named model (its holds made elastic when
    /// `hold = "elastic"`), or the custom one.
    pub fn hold_pattern(&self) -> HoldPattern {
        match HoldPattern::preset(self.model, self.rows, self.columns) {
            Some(mut p) => {
                if self.hold == HoldKind::Elastic {
                    let k = self.hold_stiffness.unwrap_or(0.0);
                    let c = self.hold_damping.unwrap_or(0.0);
                    let dirs = self
                        .hold_directions
                        .clone()
                        .unwrap_or_else(|| vec![Axis::X, Axis::Y, Axis::Z]);
                    for a in dirs {
                        let h = match a {
                            Axis::X => &mut p.x,
                            Axis::Y => &mut p.y,
                            Axis::Z => &mut p.z,
                        };
                        *h = h.made_elastic(k, c);
                    }
                }
                p
            }
            None => self
                .custom
                .clone()
                .expect("validated: custom model has a pattern"),
        }
    }

    /// Stiffness per fastening in x, y, z (N/m).
    pub fn stiffness(&self) -> [f64; 3] {
        [
            self.longitudinal_stiffness,
            self.lateral_stiffness,
            self.vertical_stiffness,
        ]
    }

    /// Damping per fastening in x, y, z (N·s/m).
    pub fn damping(&self) -> [f64; 3] {
        [
            self.longitudinal_damping,
            self.lateral_damping,
            self.vertical_damping,
        ]
    }
}

/// Ballast under each half sleeper (spread over its bottom face by area).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ballast {
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

impl Ballast {
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
    /// Nominal rolling radius (m).
    pub radius: f64,
    /// Tread conicity (−): 0.025 = 1/40; 0 to 0.1.
    pub conicity: f64,
    /// Young's modulus (Pa), 1e9 to 1e13 ([`YOUNGS_MODULUS_PA`]).
    pub youngs_modulus: f64,
    /// Poisson's ratio (−), 0 to 0.45 ([`POISSON_RATIO`]).
    pub poisson_ratio: f64,
    /// Density (kg/m³), 1000 to 20000 ([`DENSITY_KG_M3`]).
    pub density: f64,
    /// Modal damping ratio of the wheel's elastic modes (−), added to the diagonal of the
    /// wheel's projected damping as `2 ζ ω_i` (1/s); default 0, as in the reference (no
    /// damping in the steel). Measured railway wheels have ζ ≈ 1e-4–1e-3 for most modes.
    #[serde(default)]
    pub damping_ratio: f64,
}

/// Vehicle above the wheel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vehicle {
    /// Static vertical wheel load (N); the sprung mass is (load / g − unsprung mass).
    pub wheel_load: f64,
    /// Primary suspension stiffness per wheel (N/m).
    pub primary_stiffness: f64,
    /// Primary suspension damping per wheel (N·s/m).
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
    /// Traction coefficient: mean F_L / F_N, set by the driving torque (−).
    pub traction_coefficient: f64,
    /// Lateral radius of the rail head crown (m).
    pub rail_crown_radius: f64,
    /// Contact-patch grid elements along the rolling direction (−). The passage's time step
    /// is one grid element over the speed, Δt = Δx / V. 8 to 256, and
    /// `grid_nx² · grid_ny` at most [`MAX_GRID_WORK`] (the passage's work grows so).
    pub grid_nx: usize,
    /// Contact-patch grid elements across the rail (−).
    pub grid_ny: usize,
    /// Grid half-lengths over the static Hertz semi-axes (−): the grid covers
    /// `grid_margin · a` by `grid_margin · b`; larger when the normal load varies strongly.
    /// Over a corrugated rail the passage lengthens it along x at the same element size
    /// (`dynamics::passage::grid_for_profile`).
    pub grid_margin: f64,
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
    /// Element length along the rail outside the fine zone (m).
    pub element_length: f64,
    /// Element length along the rail in and around the solution zone (m).
    pub fine_element_length: f64,
    /// Target element size in the rail foot and web (m).
    pub section_size: f64,
    /// Target element size near the running surface (m).
    pub head_size: f64,
    /// Hexahedra of a sleeper along x, y, z (−).
    pub sleeper_elements: [usize; 3],
    /// Circumferential divisions of the wheel away from the contact (−).
    pub wheel_segments: usize,
    /// Largest element size of the wheel, axially and radially (m); half of it at the
    /// contact zone of the tread.
    pub wheel_element_size: f64,
    /// Lumped or consistent mass.
    pub mass: MassKind,
}

/// Run parameters of a passage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Run {
    /// Train speed (km/h; converted to m/s by [`Run::speed`]).
    pub speed_kmh: f64,
    /// Distance from the wheel's start to the solution zone (m).
    pub solution_zone_offset: f64,
    /// Length of the solution zone (m).
    pub solution_zone_length: f64,
    /// Highest natural frequency kept in the modal bases of the passage (Hz).
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
}

impl Model {
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

    /// Checks every value against its allowed range; `file` names the source in the error.
    pub fn validate(&self, file: &str) -> Result<(), ModelError> {
        let mut c = Checker { file };
        let t = &self.track;
        c.int("track.bays", t.bays, 2, 400)?;
        c.range("track.sleeper_spacing", t.sleeper_spacing, 0.2, 2.0, "m")?;
        let r = &self.rail;
        if r.profile != "uic54" {
            return Err(ModelError::OutOfRange {
                file: file.into(),
                key: "rail.profile".into(),
                value: format!("{:?}", r.profile),
                allowed: "\"uic54\"".into(),
            });
        }
        c.range(
            "rail.inclination",
            r.inclination,
            0.0,
            0.1,
            "(tan of cant angle)",
        )?;
        c.elastic("rail", r.youngs_modulus, r.poisson_ratio, r.density)?;
        // Only 0 is supported: the reduced model (and the explicit path) has no steel damping
        // yet, and a value that is accepted but ignored would mislead. The range says so.
        c.range(
            "rail.structural_damping",
            r.structural_damping,
            0.0,
            0.0,
            "s (Rayleigh beta; steel damping is not modelled yet: all damping sits in the discrete dampers, as in the reference)",
        )?;
        let s = &self.sleeper;
        c.range("sleeper.length", s.length, 0.3, 5.0, "m")?;
        c.range(
            "sleeper.width",
            s.width,
            0.05,
            t.sleeper_spacing,
            "m (at most the sleeper spacing)",
        )?;
        c.range("sleeper.height", s.height, 0.05, 1.0, "m")?;
        c.range(
            "sleeper.rail_seat",
            s.rail_seat,
            0.1,
            s.length - 0.1,
            "m (inside the sleeper)",
        )?;
        c.elastic("sleeper", s.youngs_modulus, s.poisson_ratio, s.density)?;
        let f = &self.fastening;
        c.int("fastening.rows", f.rows, 1, 16)?;
        c.int("fastening.columns", f.columns, 1, 16)?;
        c.pos(
            "fastening.footprint_length",
            f.footprint_length,
            s.width,
            "m (within the sleeper width)",
        )?;
        c.pos(
            "fastening.footprint_width",
            f.footprint_width,
            0.14,
            "m (within the 0.14 m rail foot)",
        )?;
        let max_strip =
            (f.footprint_length / f.columns as f64).min(f.footprint_width / f.rows as f64);
        c.pos(
            "fastening.strip_width",
            f.strip_width,
            max_strip,
            "m (at most one grid cell)",
        )?;
        c.range("fastening.pad_thickness", f.pad_thickness, 0.0, 0.05, "m")?;
        c.spring_damper("fastening", f.stiffness(), f.damping())?;
        f.validate_holds(file)?;
        // The rail floats on the railpads where no rigid hold acts: a direction without a hold
        // needs a railpad spring, else the rail is a free body in it.
        let pattern = self.fastening.hold_pattern();
        for (h, key, k) in [
            (
                &pattern.x,
                "fastening.longitudinal_stiffness",
                f.longitudinal_stiffness,
            ),
            (
                &pattern.y,
                "fastening.lateral_stiffness",
                f.lateral_stiffness,
            ),
            (
                &pattern.z,
                "fastening.vertical_stiffness",
                f.vertical_stiffness,
            ),
        ] {
            if h.region() == RigidRegion::None {
                c.pos(
                    key,
                    k,
                    1e12,
                    "N/m (> 0: this direction has no rigid hold in the fastening model, so the railpad springs alone support the rail)",
                )?;
            }
        }
        let b = &self.ballast;
        c.spring_damper("ballast", b.stiffness(), b.damping())?;
        // Sleepers float on the ballast: they need a spring in every direction.
        for (k, v) in [
            ("vertical_stiffness", b.vertical_stiffness),
            ("lateral_stiffness", b.lateral_stiffness),
            ("longitudinal_stiffness", b.longitudinal_stiffness),
        ] {
            c.pos(
                &format!("ballast.{k}"),
                v,
                1e12,
                "N/m (> 0: a sleeper needs support in every direction)",
            )?;
        }
        let w = &self.wheel;
        c.range("wheel.radius", w.radius, 0.2, 0.8, "m")?;
        // The wheel mesh needs |c| < 0.2 (the tread must stay above the rim); treads are 1/40
        // to 1/20, so the model stops well inside.
        c.range("wheel.conicity", w.conicity, 0.0, 0.1, "(-)")?;
        c.elastic("wheel", w.youngs_modulus, w.poisson_ratio, w.density)?;
        c.range("wheel.damping_ratio", w.damping_ratio, 0.0, 0.1, "(-)")?;
        let v = &self.vehicle;
        c.pos("vehicle.wheel_load", v.wheel_load, MAX_WHEEL_LOAD_N, "N")?;
        c.pos(
            "vehicle.primary_stiffness",
            v.primary_stiffness,
            1e10,
            "N/m",
        )?;
        c.range(
            "vehicle.primary_damping",
            v.primary_damping,
            0.0,
            1e9,
            "N s/m",
        )?;
        // The sprung mass is wheel_load / gravity: near 0 it runs away (0 gives an infinite
        // mass). Earth's surface: 9.78 to 9.83.
        c.range("vehicle.gravity", v.gravity, 9.0, 10.5, "m/s^2")?;
        let k = &self.contact;
        c.pos(
            "contact.friction",
            k.friction,
            2.0,
            "(-) (> 0: the driving torque is transmitted by friction)",
        )?;
        c.range(
            "contact.traction_coefficient",
            k.traction_coefficient,
            0.0,
            k.friction,
            "(-) (below contact.friction)",
        )?;
        c.range(
            "contact.rail_crown_radius",
            k.rail_crown_radius,
            0.05,
            10.0,
            "m",
        )?;
        c.int("contact.grid_nx", k.grid_nx, 8, 256)?;
        c.int("contact.grid_ny", k.grid_ny, 4, 256)?;
        // A passage's contact work grows as grid_nx² · grid_ny (grid_nx cells per step and
        // steps of one cell): refuse grids far beyond the default's time.
        let work = k.grid_nx * k.grid_nx * k.grid_ny;
        if work > MAX_GRID_WORK {
            return c.fail(
                "contact.grid_nx",
                format!("{} (with contact.grid_ny = {})", k.grid_nx, k.grid_ny),
                format!(
                    "grid_nx^2 * grid_ny at most {MAX_GRID_WORK} (here {work}: {:.0} times the 32 x 24 default's passage time; e.g. 64 x 64 is {:.1} times)",
                    work as f64 / (32.0 * 32.0 * 24.0),
                    64.0 * 64.0 * 64.0 / (32.0 * 32.0 * 24.0)
                ),
            );
        }
        c.range("contact.grid_margin", k.grid_margin, 1.05, 3.0, "(-)")?;
        let m = &self.mesh;
        c.pos(
            "mesh.element_length",
            m.element_length,
            t.sleeper_spacing / 4.0,
            "m (at most a quarter of the sleeper spacing)",
        )?;
        c.pos(
            "mesh.fine_element_length",
            m.fine_element_length,
            m.element_length,
            "m (at most mesh.element_length)",
        )?;
        c.range("mesh.section_size", m.section_size, 0.002, 0.05, "m")?;
        c.range(
            "mesh.head_size",
            m.head_size,
            0.001,
            m.section_size,
            "m (at most mesh.section_size)",
        )?;
        for (i, n) in m.sleeper_elements.iter().enumerate() {
            c.int(&format!("mesh.sleeper_elements[{i}]"), *n, 1, 64)?;
        }
        c.int("mesh.wheel_segments", m.wheel_segments, 12, 720)?;
        c.range(
            "mesh.wheel_element_size",
            m.wheel_element_size,
            0.005,
            0.1,
            "m",
        )?;
        let run = &self.run;
        c.range(
            "run.speed_kmh",
            run.speed_kmh,
            SPEED_KMH[0],
            SPEED_KMH[1],
            "km/h",
        )?;
        c.range(
            "run.solution_zone_offset",
            run.solution_zone_offset,
            0.0,
            10.0,
            "m",
        )?;
        c.range("run.fmax", run.fmax, 100.0, 20000.0, "Hz")?;
        c.pos("wear.coefficient", self.wear.coefficient, 1e-6, "m^3/J")?;
        c.range(
            "wear.initiation_threshold",
            self.wear.initiation_threshold,
            0.0,
            1.0,
            "-",
        )?;
        c.range("explicit.safety", self.explicit.safety, 0.1, 1.0, "-")?;
        if let Some(dt) = self.explicit.time_step {
            // The stable limit depends on the assembled matrices and is checked when the
            // explicit model is built; here only a physical range.
            c.range("explicit.time_step", dt, 1e-10, 1e-4, "s")?;
        }
        let room = self.track_length() - run.solution_zone_offset;
        c.pos(
            "run.solution_zone_length",
            run.solution_zone_length,
            room,
            "m (zone must fit on the track)",
        )?;
        Ok(())
    }
}

/// Allowed train speed (km/h), of `run.speed_kmh` and of every speed a sweep, study or
/// initiation table runs: the model is not meant beyond 500 km/h.
pub const SPEED_KMH: [f64; 2] = [1.0, 500.0];

/// Largest static wheel load (N): 50 t per wheel, beyond any railway axle load.
pub const MAX_WHEEL_LOAD_N: f64 = 500e3;

/// Largest `contact.grid_nx² · contact.grid_ny`: 12 times the default 32 × 24 grid's passage
/// time (64 × 64 takes 10.7 times; 256 × 256 would take 680 times, hours in place of minutes).
pub const MAX_GRID_WORK: usize = 12 * 32 * 32 * 24;

/// Allowed Young's modulus of the rail, sleeper and wheel (Pa): the solids a track is made of
/// (steel 2.1e11, concrete 3.8e10, polymers from 1e9). Far outside it the modal bases and the
/// contact grid go out of scale (e.g. E = 1e-12 Pa puts thousands of modes below `run.fmax`).
pub const YOUNGS_MODULUS_PA: [f64; 2] = [1e9, 1e13];

/// Allowed Poisson's ratio of the rail, sleeper and wheel (−). Above 0.45 a solid is nearly
/// incompressible: its dilatational wave speed, hence the explicit time step, runs away and
/// the linear hexahedra lock.
pub const POISSON_RATIO: [f64; 2] = [0.0, 0.45];

/// Allowed density of the rail, sleeper and wheel (kg/m³): steel 7800, concrete 2500.
pub const DENSITY_KG_M3: [f64; 2] = [1000.0, 20000.0];

struct Checker<'a> {
    file: &'a str,
}

impl Checker<'_> {
    fn fail(&self, key: &str, value: String, allowed: String) -> Result<(), ModelError> {
        Err(ModelError::OutOfRange {
            file: self.file.into(),
            key: key.into(),
            value,
            allowed,
        })
    }
    /// lo ≤ v ≤ hi, finite.
    fn range(&mut self, key: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), ModelError> {
        if !(v.is_finite() && v >= lo && v <= hi) {
            return self.fail(key, v.to_string(), format!("{lo} to {hi} {unit}"));
        }
        Ok(())
    }
    /// 0 < v ≤ hi, finite.
    fn pos(&mut self, key: &str, v: f64, hi: f64, unit: &str) -> Result<(), ModelError> {
        if !(v.is_finite() && v > 0.0 && v <= hi) {
            return self.fail(
                key,
                v.to_string(),
                format!("greater than 0 and at most {hi} {unit}"),
            );
        }
        Ok(())
    }
    /// Stiffness (N/m) and damping (N·s/m) in x, y, z under `prefix`: each 0 to 1e12.
    fn spring_damper(&mut self, prefix: &str, k: [f64; 3], c: [f64; 3]) -> Result<(), ModelError> {
        for (d, name) in ["longitudinal", "lateral", "vertical"].iter().enumerate() {
            self.range(
                &format!("{prefix}.{name}_stiffness"),
                k[d],
                0.0,
                1e12,
                "N/m",
            )?;
            self.range(
                &format!("{prefix}.{name}_damping"),
                c[d],
                0.0,
                1e12,
                "N s/m",
            )?;
        }
        Ok(())
    }

    fn int(&mut self, key: &str, v: usize, lo: usize, hi: usize) -> Result<(), ModelError> {
        if v < lo || v > hi {
            return self.fail(key, v.to_string(), format!("{lo} to {hi}"));
        }
        Ok(())
    }
    /// Young's modulus, Poisson's ratio and density of a solid part in their physical ranges
    /// ([`YOUNGS_MODULUS_PA`], [`POISSON_RATIO`], [`DENSITY_KG_M3`]).
    fn elastic(&mut self, part: &str, e: f64, nu: f64, rho: f64) -> Result<(), ModelError> {
        let [e_lo, e_hi] = YOUNGS_MODULUS_PA;
        self.range(
            &format!("{part}.youngs_modulus"),
            e,
            e_lo,
            e_hi,
            "Pa (solids of a track: steel 2.1e11, concrete 3.8e10)",
        )?;
        let [nu_lo, nu_hi] = POISSON_RATIO;
        self.range(
            &format!("{part}.poisson_ratio"),
            nu,
            nu_lo,
            nu_hi,
            "(-) (nearly incompressible material is not supported)",
        )?;
        let [rho_lo, rho_hi] = DENSITY_KG_M3;
        self.range(
            &format!("{part}.density"),
            rho,
            rho_lo,
            rho_hi,
            "kg/m^3 (steel 7800, concrete 2500)",
        )
    }
}

#[cfg(test)]
mod tests;

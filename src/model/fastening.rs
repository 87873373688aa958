//! The fastening: railpad spring–dampers over a footprint grid and the hold pattern of the
//! rail foot — the presets RPM1–RPM5 (docs/theory.md §3.2) or a custom pattern.

use super::{Deserialize, Serialize, SpringDampers};

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
        f.write_str(self.name())
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

/// The names of the published fastening models, in order (the default list of the commands
/// that compare them).
pub const PRESET_NAMES: [&str; 5] = ["RPM1", "RPM2", "RPM3", "RPM4", "RPM5"];

/// The published fastening models RPM1–RPM5 (docs/theory.md §3.2): a [`FasteningModel`]
/// that is not `custom`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preset {
    /// V-3-4.
    Rpm1,
    /// V-∞-4.
    Rpm2,
    /// V-1-4.
    Rpm3,
    /// ∞-1-4.
    Rpm4,
    /// ∞-∞-4.
    Rpm5,
}

impl Preset {
    /// The model-file name of the preset.
    pub fn model(self) -> FasteningModel {
        match self {
            Preset::Rpm1 => FasteningModel::Rpm1,
            Preset::Rpm2 => FasteningModel::Rpm2,
            Preset::Rpm3 => FasteningModel::Rpm3,
            Preset::Rpm4 => FasteningModel::Rpm4,
            Preset::Rpm5 => FasteningModel::Rpm5,
        }
    }
}

impl FasteningModel {
    /// The preset of this name (`None` for `custom`).
    pub fn preset(self) -> Option<Preset> {
        match self {
            FasteningModel::Rpm1 => Some(Preset::Rpm1),
            FasteningModel::Rpm2 => Some(Preset::Rpm2),
            FasteningModel::Rpm3 => Some(Preset::Rpm3),
            FasteningModel::Rpm4 => Some(Preset::Rpm4),
            FasteningModel::Rpm5 => Some(Preset::Rpm5),
            FasteningModel::Custom => None,
        }
    }
}

/// The elastic variant of a preset: every region the preset holds rigidly in one of
/// `directions` is tied to the ground by spring-dampers instead.
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticHolds {
    /// Stiffness per fastening (N/m), [`MIN_HOLD_STIFFNESS`] to [`MAX_HOLD_STIFFNESS`].
    pub stiffness: f64,
    /// Damping per fastening (N·s/m), 0 to 1e12; `None` (not given) is 0.
    pub damping: Option<f64>,
    /// The directions made elastic, each held by the preset; `None` (not given) is all three.
    pub directions: Option<Vec<Axis>>,
}

impl ElasticHolds {
    /// The damping per fastening (N·s/m).
    pub(crate) fn damping_n_s_per_m(&self) -> f64 {
        self.damping.unwrap_or(0.0)
    }

    /// The directions made elastic.
    pub fn directions(&self) -> Vec<Axis> {
        self.directions
            .clone()
            .unwrap_or_else(|| vec![Axis::X, Axis::Y, Axis::Z])
    }
}

/// How the rail foot is held: a preset (rigid as published, or elastic), or a custom pattern.
// One per model, read once: the custom pattern's size costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Holds {
    /// One of RPM1–RPM5; `elastic` = `None` holds its regions rigidly.
    Preset {
        /// The preset.
        preset: Preset,
        /// Its elastic variant (`fastening.hold = "elastic"`).
        elastic: Option<ElasticHolds>,
    },
    /// The pattern of `[fastening.custom]` (`fastening.model = "custom"`).
    Custom(HoldPattern),
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

impl RigidRegion {
    /// Whether the region can be held on node lines (`node_lines = true`): columns and rows.
    pub(crate) fn has_node_lines(self) -> bool {
        matches!(self, RigidRegion::Columns | RigidRegion::Rows)
    }
}

/// The hold of one direction: `{ rigid = "columns", indices = [1] }` fixes the region's DOFs;
/// `{ elastic = "columns", indices = [1], stiffness = 1e9, damping = 0.0 }` instead ties them to
/// the ground by spring-dampers whose stiffness (N/m) and damping (N·s/m) *per fastening* are
/// spread over the region's nodes by tributary area (evenly over the grid points for
/// `grid_points`; per bay of one sleeper spacing for `continuous`). Columns and rows can
/// instead be held on *node lines* (`node_lines = true`, docs/theory.md §3.3): the rail-foot
/// nodes on the node plane through each listed column's centre (across the whole foot), or on
/// the foot node line through each listed row's centre (over the footprint length), with no
/// width; an elastic node-line hold takes its stiffness and damping *per held line*:
/// `{ elastic = "columns", indices = [1], node_lines = true, line_stiffness = 3e8,
/// line_damping = 0.0 }`, each line's spread over its nodes by tributary length. Give one of
/// `rigid` and `elastic`; an absent `rigid` means `"none"`.
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
    /// Elastic hold: stiffness per fastening (N/m), [`MIN_HOLD_STIFFNESS`] to
    /// [`MAX_HOLD_STIFFNESS`]; shared equally by the listed columns/rows or grid points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Elastic hold: damping per fastening (N·s/m), 0 to 1e12; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Columns or rows only: hold their node lines (the foot nodes on the node plane through
    /// each column centre, or on the foot node line through each row centre within the
    /// footprint; the mesh gets that plane or line) instead of strips of `strip_width`. A
    /// hold of zero width, as the reference study's: mesh dependent (docs/theory.md §3.3).
    /// Default false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub node_lines: bool,
    /// Elastic hold on node lines (`node_lines = true`) only: stiffness of each held
    /// line (N/m per line; a fastening holding n lines holds with n times it),
    /// [`MIN_HOLD_STIFFNESS`] to [`MAX_HOLD_STIFFNESS`], spread over the line's nodes by
    /// tributary length. Required with an elastic node-line hold; no default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line_stiffness: Option<f64>,
    /// Elastic hold on node lines only: damping of each held line (N·s/m per line), 0 to
    /// 1e12, spread as `line_stiffness`; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line_damping: Option<f64>,
}

fn region_none() -> RigidRegion {
    RigidRegion::None
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// Smallest stiffness per fastening of an elastic hold (N/m): 100 times below the softest
/// fastening clip (1e6 N/m); a hold far softer leaves the rail, where the hold alone holds it
/// in a direction (no railpad spring there), nearly free: at 1 N/m the track gets a rigid-body
/// mode.
pub const MIN_HOLD_STIFFNESS: f64 = 1e4;

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
            node_lines: false,
            line_stiffness: None,
            line_damping: None,
        }
    }

    /// The held region, rigid or elastic.
    pub fn region(&self) -> RigidRegion {
        self.elastic.unwrap_or(self.rigid)
    }

    /// Whether the hold acts on node lines (`node_lines = true` on columns or rows).
    pub fn on_node_lines(&self) -> bool {
        self.node_lines && self.region().has_node_lines()
    }

    /// Stiffness (N/m) and damping (N·s/m) of an elastic hold: per fastening, or per held
    /// line on node lines ([`Self::on_node_lines`]); `None` for a rigid hold or none.
    pub fn elastic_stiffness_damping(&self) -> Option<(f64, f64)> {
        match self.elastic {
            Some(_) if self.on_node_lines() => Some((
                self.line_stiffness.unwrap_or(0.0),
                self.line_damping.unwrap_or(0.0),
            )),
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
            node_lines: self.node_lines,
            line_stiffness: None,
            line_damping: None,
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
    pub fn preset(preset: Preset, rows: usize, columns: usize) -> HoldPattern {
        let all_rows = DirectionHold::rows((0..rows).collect());
        let middle = DirectionHold::columns(vec![columns / 2]);
        let all_columns = DirectionHold::columns((0..columns).collect());
        let (x, z) = match preset {
            Preset::Rpm1 => (all_columns, DirectionHold::none()),
            Preset::Rpm2 => (DirectionHold::continuous(), DirectionHold::none()),
            Preset::Rpm3 => (middle, DirectionHold::none()),
            Preset::Rpm4 => (middle, DirectionHold::continuous()),
            Preset::Rpm5 => (DirectionHold::continuous(), DirectionHold::continuous()),
        };
        HoldPattern { x, y: all_rows, z }
    }
}

/// Rail fastening: railpad springs on a `rows × columns` grid and the holds of the rail foot.
/// Read from and written as the `[fastening]` table (keys `model`, `custom`, `hold`,
/// `hold_stiffness`, `hold_damping`, `hold_directions` for the holds); a table whose holds
/// contradict each other is refused when it is read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "FasteningFile", into = "FasteningFile")]
pub struct Fastening {
    /// How the rail foot is held (`model`, `custom`, `hold`, … in the file).
    pub holds: Holds,
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
    /// The railpad's stiffness (N/m) and damping (N·s/m) per fastening, spread evenly over
    /// the spring grid.
    pub springs: SpringDampers,
}

impl TryFrom<FasteningFile> for Fastening {
    type Error = String;

    /// The holds' keys must agree: `custom` exactly with `model = "custom"`, `hold =
    /// "elastic"` only with a preset and with `hold_stiffness`, the other hold keys only with
    /// it. (Value ranges are checked by [`super::Model::validate`].)
    fn try_from(f: FasteningFile) -> Result<Self, String> {
        let holds = match (f.model.preset(), f.custom.clone()) {
            (None, None) => {
                return Err("fastening.custom: fastening.model = \"custom\" needs a [fastening.custom] table with x, y, z holds".into())
            }
            (Some(_), Some(_)) => {
                return Err(format!(
                    "fastening.custom: only allowed with fastening.model = \"custom\" (model is {})",
                    f.model.name()
                ))
            }
            (None, Some(p)) => {
                if f.hold == HoldKind::Elastic {
                    return Err("fastening.hold: \"elastic\" applies to the presets RPM1–RPM5; with model = \"custom\" give elastic regions in [fastening.custom], e.g. x = { elastic = \"columns\", indices = [1], stiffness = 1e9 }".into());
                }
                Holds::Custom(p)
            }
            (Some(preset), None) => Holds::Preset {
                preset,
                elastic: elastic_holds(&f)?,
            },
        };
        if matches!(
            holds,
            Holds::Custom(_) | Holds::Preset { elastic: None, .. }
        ) {
            for (key, given) in [
                ("fastening.hold_stiffness", f.hold_stiffness.is_some()),
                ("fastening.hold_damping", f.hold_damping.is_some()),
                ("fastening.hold_directions", f.hold_directions.is_some()),
            ] {
                if given {
                    return Err(format!(
                        "{key}: only allowed with fastening.hold = \"elastic\""
                    ));
                }
            }
        }
        Ok(Fastening {
            holds,
            rows: f.rows,
            columns: f.columns,
            footprint_length: f.footprint_length,
            footprint_width: f.footprint_width,
            strip_width: f.strip_width,
            pad_thickness: f.pad_thickness,
            springs: SpringDampers {
                vertical_stiffness: f.vertical_stiffness,
                vertical_damping: f.vertical_damping,
                lateral_stiffness: f.lateral_stiffness,
                lateral_damping: f.lateral_damping,
                longitudinal_stiffness: f.longitudinal_stiffness,
                longitudinal_damping: f.longitudinal_damping,
            },
        })
    }
}

/// The elastic variant of a preset's table (`None` for `hold = "rigid"`).
fn elastic_holds(f: &FasteningFile) -> Result<Option<ElasticHolds>, String> {
    if f.hold == HoldKind::Rigid {
        return Ok(None);
    }
    let Some(stiffness) = f.hold_stiffness else {
        return Err("fastening.hold_stiffness: fastening.hold = \"elastic\" needs hold_stiffness (N/m per fastening)".into());
    };
    Ok(Some(ElasticHolds {
        stiffness,
        damping: f.hold_damping,
        directions: f.hold_directions.clone(),
    }))
}

impl From<Fastening> for FasteningFile {
    fn from(f: Fastening) -> Self {
        let (model, custom, hold, hold_stiffness, hold_damping, hold_directions) = match f.holds {
            Holds::Custom(p) => (
                FasteningModel::Custom,
                Some(p),
                HoldKind::Rigid,
                None,
                None,
                None,
            ),
            Holds::Preset {
                preset,
                elastic: None,
            } => (preset.model(), None, HoldKind::Rigid, None, None, None),
            Holds::Preset {
                preset,
                elastic: Some(e),
            } => (
                preset.model(),
                None,
                HoldKind::Elastic,
                Some(e.stiffness),
                e.damping,
                e.directions,
            ),
        };
        FasteningFile {
            model,
            custom,
            rows: f.rows,
            columns: f.columns,
            footprint_length: f.footprint_length,
            footprint_width: f.footprint_width,
            strip_width: f.strip_width,
            pad_thickness: f.pad_thickness,
            vertical_stiffness: f.springs.vertical_stiffness,
            vertical_damping: f.springs.vertical_damping,
            lateral_stiffness: f.springs.lateral_stiffness,
            lateral_damping: f.springs.lateral_damping,
            longitudinal_stiffness: f.springs.longitudinal_stiffness,
            longitudinal_damping: f.springs.longitudinal_damping,
            hold,
            hold_stiffness,
            hold_damping,
            hold_directions,
        }
    }
}

/// What the track's stiffness and mass read of a fastening: its `[fastening]` table as a model
/// file writes it, without a damper (no `*_damping` key, none in the custom holds). The
/// identity of the track's modes ([`super::identity`]) is built from it, so a damping study
/// reuses the modes.
#[derive(Serialize)]
pub(crate) struct FasteningStiffness {
    model: FasteningModel,
    #[serde(skip_serializing_if = "Option::is_none")]
    custom: Option<HoldPatternStiffness>,
    rows: usize,
    columns: usize,
    footprint_length: f64,
    footprint_width: f64,
    strip_width: f64,
    pad_thickness: f64,
    vertical_stiffness: f64,
    lateral_stiffness: f64,
    longitudinal_stiffness: f64,
    #[serde(skip_serializing_if = "HoldKind::is_rigid")]
    hold: HoldKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    hold_stiffness: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hold_directions: Option<Vec<Axis>>,
}

/// A custom hold pattern without its dampers (see [`FasteningStiffness`]).
#[derive(Serialize)]
struct HoldPatternStiffness {
    x: DirectionHoldStiffness,
    y: DirectionHoldStiffness,
    z: DirectionHoldStiffness,
}

/// One direction's hold without its dampers (see [`FasteningStiffness`]).
#[derive(Serialize)]
struct DirectionHoldStiffness {
    rigid: RigidRegion,
    #[serde(skip_serializing_if = "Option::is_none")]
    elastic: Option<RigidRegion>,
    indices: Vec<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stiffness: Option<f64>,
    #[serde(skip_serializing_if = "is_false")]
    node_lines: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    line_stiffness: Option<f64>,
}

impl From<DirectionHold> for DirectionHoldStiffness {
    fn from(h: DirectionHold) -> Self {
        // Every field named, so that a new one does not compile until it is placed.
        let DirectionHold {
            rigid,
            elastic,
            indices,
            stiffness,
            damping: _,
            node_lines,
            line_stiffness,
            line_damping: _,
        } = h;
        DirectionHoldStiffness {
            rigid,
            elastic,
            indices,
            stiffness,
            node_lines,
            line_stiffness,
        }
    }
}

/// A fastening's layout: [`FasteningStiffness`] without the railpads' and the holds'
/// stiffness (a node line's own `line_stiffness` stays), what the track's component bases
/// read ([`super::identity::IdentityScope::Components`]).
#[derive(Serialize)]
pub(crate) struct FasteningLayout {
    model: FasteningModel,
    #[serde(skip_serializing_if = "Option::is_none")]
    custom: Option<HoldPatternLayout>,
    rows: usize,
    columns: usize,
    footprint_length: f64,
    footprint_width: f64,
    strip_width: f64,
    pad_thickness: f64,
    #[serde(skip_serializing_if = "HoldKind::is_rigid")]
    hold: HoldKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    hold_directions: Option<Vec<Axis>>,
}

/// A custom hold pattern's layout (see [`FasteningLayout`]).
#[derive(Serialize)]
struct HoldPatternLayout {
    x: DirectionHoldLayout,
    y: DirectionHoldLayout,
    z: DirectionHoldLayout,
}

/// One direction's hold layout (see [`FasteningLayout`]).
#[derive(Serialize)]
struct DirectionHoldLayout {
    rigid: RigidRegion,
    #[serde(skip_serializing_if = "Option::is_none")]
    elastic: Option<RigidRegion>,
    indices: Vec<usize>,
    #[serde(skip_serializing_if = "is_false")]
    node_lines: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    line_stiffness: Option<f64>,
}

impl From<DirectionHoldStiffness> for DirectionHoldLayout {
    fn from(h: DirectionHoldStiffness) -> Self {
        DirectionHoldLayout {
            rigid: h.rigid,
            elastic: h.elastic,
            indices: h.indices,
            node_lines: h.node_lines,
            line_stiffness: h.line_stiffness,
        }
    }
}

impl Fastening {
    /// The fastening's layout ([`FasteningLayout`]).
    pub(crate) fn layout_view(&self) -> FasteningLayout {
        let s = self.stiffness_view();
        FasteningLayout {
            model: s.model,
            custom: s.custom.map(|p| HoldPatternLayout {
                x: p.x.into(),
                y: p.y.into(),
                z: p.z.into(),
            }),
            rows: s.rows,
            columns: s.columns,
            footprint_length: s.footprint_length,
            footprint_width: s.footprint_width,
            strip_width: s.strip_width,
            pad_thickness: s.pad_thickness,
            hold: s.hold,
            hold_directions: s.hold_directions,
        }
    }

    /// The fastening as the track's stiffness and mass read it ([`FasteningStiffness`]).
    pub(crate) fn stiffness_view(&self) -> FasteningStiffness {
        // Every field named, so that a new one does not compile until it is placed.
        let FasteningFile {
            model,
            custom,
            rows,
            columns,
            footprint_length,
            footprint_width,
            strip_width,
            pad_thickness,
            vertical_stiffness,
            vertical_damping: _,
            lateral_stiffness,
            lateral_damping: _,
            longitudinal_stiffness,
            longitudinal_damping: _,
            hold,
            hold_stiffness,
            hold_damping: _,
            hold_directions,
        } = FasteningFile::from(self.clone());
        FasteningStiffness {
            model,
            custom: custom.map(|p| HoldPatternStiffness {
                x: p.x.into(),
                y: p.y.into(),
                z: p.z.into(),
            }),
            rows,
            columns,
            footprint_length,
            footprint_width,
            strip_width,
            pad_thickness,
            vertical_stiffness,
            lateral_stiffness,
            longitudinal_stiffness,
            hold,
            hold_stiffness,
            hold_directions,
        }
    }
}

/// The `[fastening]` table as written in a model file; [`Fastening`] is its checked form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FasteningFile {
    /// RPM1–RPM5 or custom.
    model: FasteningModel,
    /// The hold pattern when `model = "custom"` (must be absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    custom: Option<HoldPattern>,
    /// Spring rows across the track (−).
    rows: usize,
    /// Spring columns along the rail (−).
    columns: usize,
    /// Footprint length along the rail (m).
    footprint_length: f64,
    /// Footprint width across the track (m).
    footprint_width: f64,
    /// Width of a rigidly held column strip (along x) or row strip (along y) (m).
    strip_width: f64,
    /// Gap between the rail-foot underside and the sleeper top (m).
    pad_thickness: f64,
    /// Vertical stiffness per fastening (N/m), spread evenly over the grid.
    vertical_stiffness: f64,
    /// Vertical damping per fastening (N·s/m).
    vertical_damping: f64,
    /// Lateral stiffness per fastening (N/m).
    lateral_stiffness: f64,
    /// Lateral damping per fastening (N·s/m).
    lateral_damping: f64,
    /// Longitudinal stiffness per fastening (N/m).
    longitudinal_stiffness: f64,
    /// Longitudinal damping per fastening (N·s/m).
    longitudinal_damping: f64,
    /// How the regions of a preset (RPM1–RPM5) are held: `"rigid"` (default, the models as
    /// published) or `"elastic"`: every rigidly held region of the directions in
    /// `hold_directions` becomes grounded springs of `hold_stiffness` and `hold_damping` per
    /// fastening. Not allowed with `model = "custom"` (give `elastic` regions there).
    #[serde(default, skip_serializing_if = "HoldKind::is_rigid")]
    hold: HoldKind,
    /// Stiffness per fastening of the elastic holds of a preset (N/m), [`MIN_HOLD_STIFFNESS`]
    /// to [`MAX_HOLD_STIFFNESS`]; required with `hold = "elastic"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hold_stiffness: Option<f64>,
    /// Damping per fastening of the elastic holds of a preset (N·s/m), 0 to 1e12; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hold_damping: Option<f64>,
    /// Directions whose preset holds become elastic with `hold = "elastic"`, e.g. `["x"]`;
    /// default all three.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hold_directions: Option<Vec<Axis>>,
}

/// Rigid or elastic holds of a preset fastening model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum HoldKind {
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
    /// The model-file name of the fastening (`RPM1` … `RPM5`, `custom`).
    pub fn model(&self) -> FasteningModel {
        match &self.holds {
            Holds::Preset { preset, .. } => preset.model(),
            Holds::Custom(_) => FasteningModel::Custom,
        }
    }

    /// The hold pattern in force: the preset (its holds made elastic in the elastic variant),
    /// or the custom one.
    pub fn hold_pattern(&self) -> HoldPattern {
        match &self.holds {
            Holds::Custom(p) => p.clone(),
            Holds::Preset { preset, elastic } => {
                let mut p = HoldPattern::preset(*preset, self.rows, self.columns);
                if let Some(e) = elastic {
                    for a in &e.directions() {
                        let h = match a {
                            Axis::X => &mut p.x,
                            Axis::Y => &mut p.y,
                            Axis::Z => &mut p.z,
                        };
                        *h = h.made_elastic(e.stiffness, e.damping_n_s_per_m());
                    }
                }
                p
            }
        }
    }
}

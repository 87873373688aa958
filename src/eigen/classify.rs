//! Classification of track and wheel eigenmodes by their shape, in quantities a railway
//! engineer knows.
//!
//! **Track modes.** Per rail node plane (cross-section at x) the mode shape is reduced to
//! *section resultants* (area-weighted means over the section nodes, nodal weight = ¼ of the
//! area of every adjacent section quad):
//!
//! * `x_head`, `x_web`, `x_foot`: mean u_x (m) of the head, web and foot nodes. The split is by
//!   height z above the foot underside (section node coordinates): head above
//!   `WEB_TOP_Z_M`, foot below `WEB_BOTTOM_Z_M`, web in between. The limits are the
//!   ends of the straight (8 mm half-thickness) web of the UIC54 profile
//!   (`data/uic54-half-profile.csv`: z = 38.5 mm where the R16 foot fillet ends, z = 97.1 mm
//!   where the R22 head fillet starts), so the fillets count to foot and head. With the 1:40
//!   inclination the node heights move by < 1 mm; this is ignored.
//! * `w`, `v`: vertical and lateral displacement of the section centroid (area-weighted
//!   mean of u_z, u_y, m);
//! * `θ`: section rotation about x (rad), the least-squares rigid rotation
//!   `θ = Σ a [(y−y_c) u_z − (z−z_c) u_y] / Σ a [(y−y_c)² + (z−z_c)²]`.
//!
//! From these, five amplitudes (RMS over the planes, m) compete:
//!
//! | family | amplitude |
//! |---|---|
//! | `longitudinal_compression` | section-mean u_x (head, web, foot in phase) |
//! | `longitudinal_shear` | `½ max(0, |x_head − x_foot| − |w′| (z̄_head − z̄_foot))` (signed like x_head − x_foot): the head–foot x difference beyond what the plane-section rotation of vertical bending can explain (Euler–Bernoulli kinematics, `u_x = −w′ (z − z_c)`, gives exactly `|w′| (z̄_head − z̄_foot)`) |
//! | `vertical_bending` | w |
//! | `lateral_bending` | v |
//! | `torsion` | θ · r_p, with r_p = √(I_p / A) the polar radius of gyration of the section |
//!
//! The largest one gives the family, unless (in this order) the sleepers carry more than
//! `SLEEPER_KINETIC_SHARE` of the kinetic energy (`sleeper`), the section-resultant field
//! (group means of u_x, centroid translation + rotation θ in y–z) reproduces less than
//! `LOCAL_FIT_MIN` of the rail's displacement norm (`local`: the cross-section deforms —
//! web breathing, foot flapping), or the largest amplitude holds less than
//! `OTHER_DOMINANCE` of the sum of squares (`other`: strongly coupled).
//!
//! Because the sleeper test comes first, a `sleeper` mode says nothing about the rail; its
//! `rail_family` field holds the family the rail's own motion gets from the remaining rules
//! (so a rail longitudinal-compression motion carried along by moving sleepers can be found;
//! whether it matters is told by the sleeper kinetic share and the rail's energy share).
//!
//! The *wavelength* (m) of the dominant quantity along x is found from its zero crossings
//! (linear interpolation between planes; the planes may be graded):
//! `λ = 2 (x_last − x_first)/(n − 1)` for n ≥ 2 crossings; for fewer crossings it is not
//! defined (`None`). A mode is flagged *pinned-pinned* when it is vertical bending, its
//! wavelength is within ±`PINNED_PINNED_WAVELENGTH_TOL` of twice the mean sleeper spacing,
//! and the RMS of w interpolated at the sleeper centres is below
//! `PINNED_PINNED_NODE_RATIO` × the RMS of w over the planes (nodes at the supports).
//! (Pinned-pinned resonance: Knothe & Grassie, Vehicle Syst. Dyn. 22 (1993) 209–262; Grassie
//! et al., J. Mech. Eng. Sci. 24 (1982) 77–90.)
//!
//! *Energy shares*: element strain energy of rail and sleepers, spring energy of fastening
//! and ballast springs, each divided by their sum (shares sum to 1; all zero for a
//! rigid-body mode whose strain energy is zero).
//!
//! **Wheel modes.** Strain-energy share of the wheel (elements) vs the primary suspension
//! (spring); `rigid` when the wheel's own share is below ½ or f < `RIGID_BODY_HZ`; elastic
//! modes are `axial` (umbrella / axial rim motion u_y dominant on the rim nodes), `radial`
//! (radial rim motion dominant) or `other` (e.g. circumferential), by the share of the squared
//! rim displacements (rim = nodes with radius ≥ the rim inner radius) above ½.
//!
//! All shape measures are independent of the mode's scaling.

use serde::{Deserialize, Serialize};

use crate::fe::assembly::strain_energy_per_part_many;
use crate::fe::hex8;
use crate::mesh::Part;
use crate::structure::track::SpringKind;
use crate::structure::TrackStructure;

mod wheel;
pub(crate) use wheel::classify_wheel_modes;
pub use wheel::{
    classify_wheel_mode, wheel_band_modes, WheelBandModes, WheelFamily, WheelModeClass,
    WHEEL_SUMMARY_BAND_HZ,
};

/// Height (m above the foot underside) of the top of the straight UIC54 web (start of the
/// R22 head fillet); section nodes above it are *head*.
pub(crate) const WEB_TOP_Z_M: f64 = 0.0971;
/// Height (m) of the bottom of the straight UIC54 web (end of the R16 foot fillet); section
/// nodes below it are *foot*.
pub(crate) const WEB_BOTTOM_Z_M: f64 = 0.0385;
/// Kinetic-energy share of the sleepers above which a mode is `sleeper` (majority of the
/// moving mass is in the sleepers: sleeper bounce/rocking on the ballast).
pub(crate) const SLEEPER_KINETIC_SHARE: f64 = 0.5;
/// Minimum fraction of the rail displacement norm reproduced by the section resultants;
/// below it the cross-section itself deforms and the mode is `local`.
pub(crate) const LOCAL_FIT_MIN: f64 = 0.5;
/// Minimum share (of the sum of squared amplitudes) of the largest amplitude; below it the
/// mode is `other` (no family dominates; 5 candidates, so ≥ 0.2 always).
pub(crate) const OTHER_DOMINANCE: f64 = 0.4;
/// Relative tolerance of the pinned-pinned wavelength against 2 × sleeper spacing.
pub(crate) const PINNED_PINNED_WAVELENGTH_TOL: f64 = 0.25;
/// Max RMS of w at the sleeper centres relative to the RMS of w over the planes for a
/// pinned-pinned mode (a sine has ratio 1 for random sampling and 0 at its nodes).
pub(crate) const PINNED_PINNED_NODE_RATIO: f64 = 0.35;
/// Below this frequency (Hz) a wheel mode counts as rigid-body.
pub(crate) const RIGID_BODY_HZ: f64 = 1.0;

/// Errors of the classification.
#[derive(Debug, thiserror::Error)]
pub enum ClassifyError {
    /// A displacement vector of the wrong length.
    #[error("mode shape has {got} values, the structure has {expected} (free or full DOFs): pass a mode of this structure")]
    Length {
        /// expected length
        expected: usize,
        /// given length
        got: usize,
    },
    /// A different number of frequencies than of mode shapes.
    #[error("{modes} mode shapes but {frequencies} frequencies: pass one frequency per mode")]
    Count {
        /// number of mode shapes
        modes: usize,
        /// number of frequencies
        frequencies: usize,
    },
    /// The mode shape contains NaN or infinite values.
    #[error("mode shape contains non-finite values")]
    NonFinite,
    /// The rail has fewer than two node planes or no meshed section.
    #[error(
        "classification: the rail needs at least two node planes and a meshed section \
         ({planes} planes, {section_nodes} section nodes)"
    )]
    TooFewPlanes {
        /// Node planes of the rail.
        planes: usize,
        /// Nodes of the rail's cross-section mesh.
        section_nodes: usize,
    },
    /// A part of the rail section (head, web or foot) has no nodes.
    #[error(
        "classification: the rail section has no nodes in its {part}: the section mesh is too \
         coarse (reduce mesh.section_size)"
    )]
    EmptySectionPart {
        /// "head", "web" or "foot".
        part: &'static str,
    },
    /// Element energy evaluation failed.
    #[error(transparent)]
    Fe(#[from] crate::fe::FeError),
}

/// Family of a track mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackFamily {
    /// Head, web and foot move together along x.
    LongitudinalCompression,
    /// Head and foot move opposite along x (beyond bending rotation).
    LongitudinalShear,
    /// Vertical bending of the rail (incl. pinned-pinned).
    VerticalBending,
    /// Lateral bending of the rail.
    LateralBending,
    /// Torsion of the rail about x.
    Torsion,
    /// Sleeper motion dominates (kinetic energy).
    Sleeper,
    /// Cross-section deformation (web, foot) dominates.
    Local,
    /// No single family dominates.
    Other,
}

impl TrackFamily {
    /// All families, in output order.
    pub const ALL: [TrackFamily; 8] = [
        TrackFamily::LongitudinalCompression,
        TrackFamily::LongitudinalShear,
        TrackFamily::VerticalBending,
        TrackFamily::LateralBending,
        TrackFamily::Torsion,
        TrackFamily::Sleeper,
        TrackFamily::Local,
        TrackFamily::Other,
    ];

    /// snake_case name (as serde).
    pub fn name(self) -> &'static str {
        match self {
            TrackFamily::LongitudinalCompression => "longitudinal_compression",
            TrackFamily::LongitudinalShear => "longitudinal_shear",
            TrackFamily::VerticalBending => "vertical_bending",
            TrackFamily::LateralBending => "lateral_bending",
            TrackFamily::Torsion => "torsion",
            TrackFamily::Sleeper => "sleeper",
            TrackFamily::Local => "local",
            TrackFamily::Other => "other",
        }
    }

    /// Numeric code for CSV output: the index in [`TrackFamily::ALL`].
    pub fn code(self) -> usize {
        TrackFamily::ALL
            .iter()
            .position(|&f| f == self)
            .unwrap_or(0)
    }
}

/// Strain-energy shares of a track mode (dimensionless, sum 1, or all 0 if no strain energy).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TrackEnergyShares {
    /// Rail elements.
    pub rail: f64,
    /// Sleeper elements.
    pub sleepers: f64,
    /// Fastening springs (railpads and elastic holds).
    pub fastening: f64,
    /// Ballast springs.
    pub ballast: f64,
}

impl TrackEnergyShares {
    /// The shares of the strain energies `[rail, sleepers, fastening, ballast]` (J); all zero
    /// when their sum is not positive.
    pub(crate) fn from_energies(parts: [f64; 4]) -> Self {
        let tot: f64 = parts.iter().sum();
        if tot > 0.0 {
            TrackEnergyShares {
                rail: parts[0] / tot,
                sleepers: parts[1] / tot,
                fastening: parts[2] / tot,
                ballast: parts[3] / tot,
            }
        } else {
            TrackEnergyShares::default()
        }
    }
}

/// Section resultants of one node plane (units of the mode shape: m for a displacement).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct SectionMotion {
    /// x of the plane (m).
    pub x_m: f64,
    /// Mean u_x of the head nodes.
    pub x_head: f64,
    /// Mean u_x of the web nodes.
    pub x_web: f64,
    /// Mean u_x of the foot nodes.
    pub x_foot: f64,
    /// Area-weighted mean u_x of the section.
    pub x_mean: f64,
    /// Centroid lateral displacement (area-weighted mean u_y).
    pub v: f64,
    /// Centroid vertical displacement (area-weighted mean u_z).
    pub w: f64,
    /// Rotation about x (rad per unit of the mode scale).
    pub theta: f64,
}

/// Number of section sums per node plane ([`TrackClassifier::section_sum_terms`]).
pub(crate) const SECTION_SUMS: usize = 6;

/// Quadratic measures of a mode's shape that `TrackClassifier::classify_measured` reads.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShapeNorms {
    /// The rail's `Σ a l |u|²` (`TrackClassifier::rail_norm_weights`; m³ times the
    /// displacement unit squared).
    pub rail: f64,
    /// `Σ m |u|²` over the sleepers' nodes (kg times the displacement unit squared).
    pub sleeper_mass: f64,
    /// `Σ m |u|²` over all nodes (same unit).
    pub total_mass: f64,
}

impl ShapeNorms {
    /// The sleepers' share of `Σ m |u|²` (0 when there is no motion).
    pub fn sleeper_kinetic_share(&self) -> f64 {
        if self.total_mass > 0.0 {
            self.sleeper_mass / self.total_mass
        } else {
            0.0
        }
    }
}

/// Classification of one track mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackModeClass {
    /// Family.
    pub family: TrackFamily,
    /// RMS over planes of x_head, relative to the RMS nodal displacement magnitude of the rail
    /// (dimensionless).
    pub rail_x_head: f64,
    /// Same for x_web.
    pub rail_x_web: f64,
    /// Same for x_foot.
    pub rail_x_foot: f64,
    /// Amplitudes (relative as above) [compression, shear, vertical, lateral, torsion].
    pub amplitudes: [f64; 5],
    /// Dominant wavelength along the rail (m) of the dominant quantity; `None` with fewer
    /// than two zero crossings.
    pub wavelength_m: Option<f64>,
    /// Strain-energy shares.
    pub energy: TrackEnergyShares,
    /// Kinetic-energy share of the sleepers (lumped nodal masses).
    pub sleeper_kinetic_share: f64,
    /// Fraction of the rail displacement norm reproduced by the section resultants.
    pub section_fit: f64,
    /// Pinned-pinned-like vertical bending.
    pub pinned_pinned: bool,
    /// Family of the rail's own motion: the same rules without the sleeper test. It equals
    /// `family` unless the sleeper override applied; for a `sleeper` mode it tells what the
    /// rail does meanwhile (e.g. a longitudinal-compression rail motion carried along by
    /// moving sleepers). `None` when a cache entry does not record it (it is then
    /// read as `family`).
    #[serde(default)]
    pub rail_family: Option<TrackFamily>,
}

/// Precomputed data to classify the modes of one [`TrackStructure`].
#[derive(Debug, Clone)]
pub struct TrackClassifier {
    planes_x_m: Vec<f64>,
    /// Global node of (plane, section node).
    plane_nodes: Vec<Vec<usize>>,
    /// Section node area weights (m²).
    area: Vec<f64>,
    /// Group of each section node: 0 head, 1 web, 2 foot.
    group: Vec<u8>,
    /// Section coordinates relative to the centroid (m).
    dy: Vec<f64>,
    dz: Vec<f64>,
    group_area: [f64; 3],
    /// Mean height of head and foot groups (m).
    z_head_m: f64,
    z_foot_m: f64,
    /// Σ a (dy² + dz²) (m⁴) and r_p (m).
    polar_m4: f64,
    r_polar_m: f64,
    /// Tributary length of each plane (m).
    plane_len: Vec<f64>,
    /// Lumped nodal mass (kg) and whether the node is in a sleeper.
    node_mass: Vec<f64>,
    is_sleeper: Vec<bool>,
    sleepers_x_m: Vec<f64>,
    spacing_m: f64,
}

fn tributary(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let a = if i > 0 { x[i] - x[i - 1] } else { 0.0 };
            let b = if i + 1 < n { x[i + 1] - x[i] } else { 0.0 };
            0.5 * (a + b)
        })
        .collect()
}

fn rms(v: impl Iterator<Item = f64>, w: &[f64]) -> f64 {
    let (mut s, mut t) = (0.0, 0.0);
    for (x, &wi) in v.zip(w) {
        s += wi * x * x;
        t += wi;
    }
    if t > 0.0 {
        (s / t).sqrt()
    } else {
        0.0
    }
}

/// Wavelength (m) of a signal `q(x)` sampled at increasing `x` from its zero crossings:
/// `2 (x_last − x_first)/(n − 1)` for n ≥ 2 crossings, else `None`. Samples with
/// |q| ≤ 1e-6 max |q| are skipped (no spurious crossings from round-off near nodes).
pub(crate) fn wavelength_from_crossings(x_m: &[f64], q: &[f64]) -> Option<f64> {
    let qmax = q.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    if qmax == 0.0 || !qmax.is_finite() {
        return None;
    }
    let eps = 1e-6 * qmax;
    let mut last: Option<usize> = None;
    let mut crossings = Vec::new();
    for i in 0..q.len().min(x_m.len()) {
        if q[i].abs() <= eps {
            continue;
        }
        if let Some(j) = last {
            if q[j].signum() != q[i].signum() {
                // linear interpolation between the two significant samples
                let t = q[j] / (q[j] - q[i]);
                crossings.push(x_m[j] + t * (x_m[i] - x_m[j]));
            }
        }
        last = Some(i);
    }
    if crossings.len() < 2 {
        return None;
    }
    let n = crossings.len();
    Some(2.0 * (crossings[n - 1] - crossings[0]) / (n - 1) as f64)
}

impl TrackClassifier {
    /// Precomputes section weights, groups, nodal masses of a track structure.
    pub fn new(track: &TrackStructure) -> Result<Self, ClassifyError> {
        let rail = &track.rail;
        let sec = &rail.section;
        let ns = sec.nodes.len();
        if rail.n_planes() < 2 || ns == 0 {
            return Err(ClassifyError::TooFewPlanes {
                planes: rail.n_planes(),
                section_nodes: ns,
            });
        }
        let mut area = vec![0.0; ns];
        for (q, quad) in sec.quads.iter().enumerate() {
            let a = sec.quad_area(q).abs();
            for &j in quad {
                area[j] += 0.25 * a;
            }
        }
        let atot: f64 = area.iter().sum();
        let yc = area
            .iter()
            .zip(&sec.nodes)
            .map(|(a, p)| a * p[0])
            .sum::<f64>()
            / atot;
        let zc = area
            .iter()
            .zip(&sec.nodes)
            .map(|(a, p)| a * p[1])
            .sum::<f64>()
            / atot;
        let group: Vec<u8> = sec
            .nodes
            .iter()
            .map(|p| {
                if p[1] > WEB_TOP_Z_M {
                    0
                } else if p[1] < WEB_BOTTOM_Z_M {
                    2
                } else {
                    1
                }
            })
            .collect();
        let mut group_area = [0.0; 3];
        let mut gz = [0.0; 3];
        for j in 0..ns {
            group_area[group[j] as usize] += area[j];
            gz[group[j] as usize] += area[j] * sec.nodes[j][1];
        }
        if let Some(g) = group_area.iter().position(|&a| a <= 0.0) {
            return Err(ClassifyError::EmptySectionPart {
                part: ["head", "web", "foot"][g],
            });
        }
        let dy: Vec<f64> = sec.nodes.iter().map(|p| p[0] - yc).collect();
        let dz: Vec<f64> = sec.nodes.iter().map(|p| p[1] - zc).collect();
        let polar_m4: f64 = (0..ns)
            .map(|j| area[j] * (dy[j] * dy[j] + dz[j] * dz[j]))
            .sum();
        let plane_nodes = (0..rail.n_planes())
            .map(|i| (0..ns).map(|j| rail.node(i, j)).collect())
            .collect();
        let mut node_mass = vec![0.0; track.mesh.nodes.len()];
        let mut is_sleeper = vec![false; track.mesh.nodes.len()];
        for el in &track.mesh.elements {
            let c = el.nodes.map(|n| track.mesh.nodes[n]);
            let lm = hex8::lumped_mass(&c, &track.materials[el.material])?;
            for (a, &n) in el.nodes.iter().enumerate() {
                node_mass[n] += lm[a];
                if el.part == Part::Sleeper {
                    is_sleeper[n] = true;
                }
            }
        }
        let sl = &track.layout.sleepers;
        let spacing_m = if sl.len() >= 2 {
            (sl[sl.len() - 1] - sl[0]) / (sl.len() - 1) as f64
        } else {
            0.0
        };
        Ok(Self {
            plane_len: tributary(&rail.planes_x_m),
            planes_x_m: rail.planes_x_m.clone(),
            plane_nodes,
            area,
            group,
            dy,
            dz,
            group_area,
            z_head_m: gz[0] / group_area[0],
            z_foot_m: gz[2] / group_area[2],
            polar_m4,
            r_polar_m: (polar_m4 / atot).sqrt(),
            node_mass,
            is_sleeper,
            sleepers_x_m: sl.clone(),
            spacing_m,
        })
    }

    /// Number of mesh nodes of the structure this classifier was built for.
    pub fn n_nodes(&self) -> usize {
        self.node_mass.len()
    }

    /// Polar radius of gyration r_p = √(I_p/A) of the section about its centroid (m).
    pub fn polar_radius_m(&self) -> f64 {
        self.r_polar_m
    }

    /// Section resultants per node plane of a full displacement vector (length 3 n_nodes).
    pub fn section_motion(&self, u_full: &[f64]) -> Result<Vec<SectionMotion>, ClassifyError> {
        self.check_full(u_full)?;
        Ok(self
            .plane_nodes
            .iter()
            .enumerate()
            .map(|(p, nodes)| {
                let mut sums = [0.0; SECTION_SUMS];
                for (j, &n) in nodes.iter().enumerate() {
                    let a = self.area[j];
                    let u = &u_full[3 * n..3 * n + 3];
                    sums[self.group[j] as usize] += a * u[0];
                    sums[3] += a * u[1];
                    sums[4] += a * u[2];
                    sums[5] += a * (self.dy[j] * u[2] - self.dz[j] * u[1]);
                }
                self.section_motion_from_sums(p, &sums)
            })
            .collect())
    }

    /// The section sums of node plane `p`'s displacement that [`Self::section_motion`]
    /// forms, as linear functionals of the full displacement vector: `(global DOF, sum,
    /// coefficient)` with the sums `Σ a u_x` over the head, the web and the foot nodes,
    /// `Σ a u_y`, `Σ a u_z` and `Σ a (dy u_z − dz u_y)` (indices 0–5; a in m², dy, dz in m).
    pub(crate) fn section_sum_terms(&self, p: usize) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::with_capacity(5 * self.area.len());
        for (j, &n) in self.plane_nodes[p].iter().enumerate() {
            let a = self.area[j];
            t.push((3 * n, self.group[j] as usize, a));
            t.push((3 * n + 1, 3, a));
            t.push((3 * n + 1, 5, -a * self.dz[j]));
            t.push((3 * n + 2, 4, a));
            t.push((3 * n + 2, 5, a * self.dy[j]));
        }
        t
    }

    /// Number of rail node planes.
    pub fn n_planes(&self) -> usize {
        self.plane_nodes.len()
    }

    /// The motion of node plane `p` from its section sums ([`Self::section_sum_terms`]).
    pub(crate) fn section_motion_from_sums(
        &self,
        p: usize,
        s: &[f64; SECTION_SUMS],
    ) -> SectionMotion {
        let atot: f64 = self.group_area.iter().sum();
        SectionMotion {
            x_m: self.planes_x_m[p],
            x_head: s[0] / self.group_area[0],
            x_web: s[1] / self.group_area[1],
            x_foot: s[2] / self.group_area[2],
            x_mean: (s[0] + s[1] + s[2]) / atot,
            v: s[3] / atot,
            w: s[4] / atot,
            theta: s[5] / self.polar_m4,
        }
    }

    /// The weight of every rail DOF in the rail's squared norm that [`Self::classify_shape`]
    /// reads (`Σ a l |u|²`: section node area a, m², times the plane's tributary length l,
    /// m): `(global DOF, weight)`.
    pub(crate) fn rail_norm_weights(&self) -> Vec<(usize, f64)> {
        let mut w = Vec::with_capacity(3 * self.plane_nodes.len() * self.area.len());
        for (nodes, &l) in self.plane_nodes.iter().zip(&self.plane_len) {
            for (j, &n) in nodes.iter().enumerate() {
                for d in 0..3 {
                    w.push((3 * n + d, self.area[j] * l));
                }
            }
        }
        w
    }

    /// Lumped mass of every mesh node (kg) and whether it is a sleeper node: the weights of
    /// the sleepers' kinetic share.
    pub(crate) fn node_masses(&self) -> (&[f64], &[bool]) {
        (&self.node_mass, &self.is_sleeper)
    }

    fn check_full(&self, u_full: &[f64]) -> Result<(), ClassifyError> {
        if u_full.len() != 3 * self.node_mass.len() {
            return Err(ClassifyError::Length {
                expected: 3 * self.node_mass.len(),
                got: u_full.len(),
            });
        }
        if u_full.iter().any(|v| !v.is_finite()) {
            return Err(ClassifyError::NonFinite);
        }
        Ok(())
    }

    /// Classifies a mode given as a free-DOF vector of `track` (the structure the classifier
    /// was built from); energies included.
    pub fn classify(
        &self,
        track: &TrackStructure,
        u_free: &[f64],
    ) -> Result<TrackModeClass, ClassifyError> {
        Ok(self.classify_many(track, &[u_free])?.remove(0))
    }

    /// [`Self::classify`] of several modes at once (one pass over the elements for the
    /// strain energies of all of them).
    pub(crate) fn classify_many(
        &self,
        track: &TrackStructure,
        u_free: &[&[f64]],
    ) -> Result<Vec<TrackModeClass>, ClassifyError> {
        let full = expand_all(track, u_free)?;
        let refs: Vec<&[f64]> = full.iter().map(|u| u.as_slice()).collect();
        let energies = strain_energy_per_part_many(&track.mesh, &track.materials, &refs)?;
        let solid: Vec<[f64; 2]> = energies
            .iter()
            .map(|e| [e.get(Part::Rail), e.get(Part::Sleeper)])
            .collect();
        self.classify_full_with_solid_energy(track, &full, &solid)
    }

    /// [`Self::classify_many`] with the strain energies of the rail and the sleeper elements
    /// given per mode (`[rail, sleepers]`, J for the mode's amplitude), e.g. from a
    /// substructured basis's component coordinates; the springs' energies are computed.
    pub(crate) fn classify_many_with_solid_energy(
        &self,
        track: &TrackStructure,
        u_free: &[&[f64]],
        solid: &[[f64; 2]],
    ) -> Result<Vec<TrackModeClass>, ClassifyError> {
        let full = expand_all(track, u_free)?;
        if solid.len() != u_free.len() {
            return Err(ClassifyError::Count {
                modes: u_free.len(),
                frequencies: solid.len(),
            });
        }
        self.classify_full_with_solid_energy(track, &full, solid)
    }

    fn classify_full_with_solid_energy(
        &self,
        track: &TrackStructure,
        full: &[Vec<f64>],
        solid: &[[f64; 2]],
    ) -> Result<Vec<TrackModeClass>, ClassifyError> {
        let mut out = Vec::with_capacity(full.len());
        for (u, e) in full.iter().zip(solid) {
            let (mut ef, mut eb) = (0.0, 0.0);
            for (s, k) in track.springs.iter().zip(&track.spring_kinds) {
                match k {
                    // An elastic hold is part of the fastening.
                    SpringKind::Fastening | SpringKind::Hold => ef += s.energy(u),
                    SpringKind::Ballast => eb += s.energy(u),
                    // damping only: no strain energy
                    SpringKind::EndDashpot => {}
                }
            }
            let energy = TrackEnergyShares::from_energies([e[0], e[1], ef, eb]);
            out.push(self.classify_shape(u, energy)?);
        }
        Ok(out)
    }

    /// Classifies by shape only, from a full displacement vector, with given energy shares
    /// (used by [`Self::classify`]; handy for synthetic fields).
    ///
    /// Phases: the sleepers' kinetic share, the rail's RMS displacement and the fit of the
    /// section resultants (`Self::rail_fit`), the five resultant series along the rail
    /// (`Self::motion_series`), the family of the largest one, its wavelength and the
    /// pinned–pinned test (`Self::is_pinned_pinned`).
    pub(crate) fn classify_shape(
        &self,
        u_full: &[f64],
        energy: TrackEnergyShares,
    ) -> Result<TrackModeClass, ClassifyError> {
        let sm = self.section_motion(u_full)?;
        let sleeper_kinetic_share = self.sleeper_kinetic_share(u_full);
        let (rail_rms, section_fit) = self.rail_fit(u_full, &sm);
        Ok(self.classify_motion(&sm, sleeper_kinetic_share, rail_rms, section_fit, energy))
    }

    /// Classifies from measures of a mode's shape: the section motions `sm` of every node
    /// plane, the sleepers' kinetic share ([`ShapeNorms::sleeper_kinetic_share`]), and the
    /// rail's squared norm `Σ a l |u|²` ([`Self::rail_norm_weights`], m³ times the unit of
    /// the displacements squared), from which the rail's RMS displacement and the section
    /// fit follow: the squared norm of the rigid-section fit's residual is
    /// `Σ a l |u|² − Σ_p l_p (2 X_p − Y_p)` with `X_p = Σ a u·fit` and `Y_p = Σ a |fit|²`,
    /// both quadratic in the plane's section motion. Used for modes given by their
    /// component coordinates, whose section motions and norms are products of small matrices.
    pub(crate) fn classify_measured(
        &self,
        sm: &[SectionMotion],
        norms: ShapeNorms,
        energy: TrackEnergyShares,
    ) -> TrackModeClass {
        let (rail_rms, section_fit) = self.rail_fit_from_motion(norms.rail, sm);
        self.classify_motion(
            sm,
            norms.sleeper_kinetic_share(),
            rail_rms,
            section_fit,
            energy,
        )
    }

    /// [`Self::rail_fit`] from the rail's squared norm and the section motions.
    fn rail_fit_from_motion(&self, norm: f64, sm: &[SectionMotion]) -> (f64, f64) {
        let ns = self.area.len();
        let (mut sa, mut sdy, mut sdz, mut sr2) = ([0.0; 3], 0.0, 0.0, 0.0);
        for j in 0..ns {
            let a = self.area[j];
            sa[self.group[j] as usize] += a;
            sdy += a * self.dy[j];
            sdz += a * self.dz[j];
            sr2 += a * (self.dy[j] * self.dy[j] + self.dz[j] * self.dz[j]);
        }
        let atot: f64 = self.group_area.iter().sum();
        let sat: f64 = sa.iter().sum();
        let mut explained = 0.0;
        for (s, &l) in sm.iter().zip(&self.plane_len) {
            let gx = [s.x_head, s.x_web, s.x_foot];
            // X: Σ a u·fit = Σ_g gx_g Σ_g a u_x + v Σ a u_y + w Σ a u_z + θ Σ a (dy u_z − dz u_y)
            let x: f64 = (0..3)
                .map(|g| gx[g] * gx[g] * self.group_area[g])
                .sum::<f64>()
                + atot * (s.v * s.v + s.w * s.w)
                + s.theta * s.theta * self.polar_m4;
            // Y: Σ a [gx² + (v − θ dz)² + (w + θ dy)²]
            let y: f64 = (0..3).map(|g| gx[g] * gx[g] * sa[g]).sum::<f64>()
                + sat * (s.v * s.v + s.w * s.w)
                + 2.0 * s.theta * (s.w * sdy - s.v * sdz)
                + s.theta * s.theta * sr2;
            explained += l * (2.0 * x - y);
        }
        let resid = norm - explained;
        let ltot: f64 = self.plane_len.iter().sum();
        let rail_rms = if ltot > 0.0 {
            (norm.max(0.0) / (ltot * atot)).sqrt()
        } else {
            0.0
        };
        let section_fit = if norm > 0.0 { 1.0 - resid / norm } else { 0.0 };
        (rail_rms, section_fit)
    }

    /// The family and the rest of a mode's class from its shape measures.
    fn classify_motion(
        &self,
        sm: &[SectionMotion],
        sleeper_kinetic_share: f64,
        rail_rms: f64,
        section_fit: f64,
        energy: TrackEnergyShares,
    ) -> TrackModeClass {
        let wl = &self.plane_len;
        let series = self.motion_series(sm);
        let scale = if rail_rms > 0.0 { 1.0 / rail_rms } else { 0.0 };
        let mut amplitudes = [0.0; 5];
        for (a, s) in amplitudes.iter_mut().zip(&series) {
            *a = rms(s.iter().copied(), wl) * scale;
        }
        let (imax, amax) =
            amplitudes
                .iter()
                .enumerate()
                .fold((0, -1.0), |b, (i, &a)| if a > b.1 { (i, a) } else { b });
        let sumsq: f64 = amplitudes.iter().map(|a| a * a).sum();
        let rail_family = if section_fit < LOCAL_FIT_MIN {
            TrackFamily::Local
        } else if sumsq <= 0.0 || amax * amax < OTHER_DOMINANCE * sumsq {
            TrackFamily::Other
        } else {
            [
                TrackFamily::LongitudinalCompression,
                TrackFamily::LongitudinalShear,
                TrackFamily::VerticalBending,
                TrackFamily::LateralBending,
                TrackFamily::Torsion,
            ][imax]
        };
        let family = if sleeper_kinetic_share > SLEEPER_KINETIC_SHARE {
            TrackFamily::Sleeper
        } else {
            rail_family
        };
        let wavelength_m = wavelength_from_crossings(&self.planes_x_m, &series[imax]);
        let pinned_pinned = family == TrackFamily::VerticalBending
            && self.spacing_m > 0.0
            && wavelength_m.is_some_and(|l| {
                (l - 2.0 * self.spacing_m).abs()
                    <= PINNED_PINNED_WAVELENGTH_TOL * 2.0 * self.spacing_m
            })
            && self.is_pinned_pinned(&series[2]);
        TrackModeClass {
            family,
            rail_x_head: rms(sm.iter().map(|s| s.x_head), wl) * scale,
            rail_x_web: rms(sm.iter().map(|s| s.x_web), wl) * scale,
            rail_x_foot: rms(sm.iter().map(|s| s.x_foot), wl) * scale,
            amplitudes,
            wavelength_m,
            energy,
            sleeper_kinetic_share,
            section_fit,
            pinned_pinned,
            rail_family: Some(rail_family),
        }
    }

    /// The sleepers' share of Σ m|u|² over all nodes of `u_full` (0 if there is no motion).
    fn sleeper_kinetic_share(&self, u_full: &[f64]) -> f64 {
        let (mut ks, mut kt) = (0.0, 0.0);
        for (n, &m) in self.node_mass.iter().enumerate() {
            let u2 = u_full[3 * n].powi(2) + u_full[3 * n + 1].powi(2) + u_full[3 * n + 2].powi(2);
            kt += m * u2;
            if self.is_sleeper[n] {
                ks += m * u2;
            }
        }
        if kt > 0.0 {
            ks / kt
        } else {
            0.0
        }
    }

    /// The rail's RMS displacement (unit of `u_full`, area- and length-weighted)
    /// and the fraction of its squared norm that the section resultants `sm` explain (the
    /// section fit, 1 for a rigid-section motion).
    fn rail_fit(&self, u_full: &[f64], sm: &[SectionMotion]) -> (f64, f64) {
        let wl = &self.plane_len;
        let (mut norm, mut resid) = (0.0, 0.0);
        for (i, nodes) in self.plane_nodes.iter().enumerate() {
            let s = &sm[i];
            let gx = [s.x_head, s.x_web, s.x_foot];
            for (j, &n) in nodes.iter().enumerate() {
                let wa = self.area[j] * wl[i];
                let u = &u_full[3 * n..3 * n + 3];
                let fit = [
                    gx[self.group[j] as usize],
                    s.v - s.theta * self.dz[j],
                    s.w + s.theta * self.dy[j],
                ];
                norm += wa * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
                resid += wa
                    * ((u[0] - fit[0]).powi(2) + (u[1] - fit[1]).powi(2) + (u[2] - fit[2]).powi(2));
            }
        }
        let ltot: f64 = wl.iter().sum();
        let rail_rms = if ltot > 0.0 {
            (norm / (ltot * self.group_area.iter().sum::<f64>())).sqrt()
        } else {
            0.0
        };
        let section_fit = if norm > 0.0 { 1.0 - resid / norm } else { 0.0 };
        (rail_rms, section_fit)
    }

    /// The five motion series along the rail, one value per node plane (unit of the
    /// displacements): mean
    /// longitudinal displacement (compression), half the head–foot difference beyond the
    /// bending rotation w'·(z_head − z_foot) (shear), vertical w, lateral v, and the twist
    /// θ times the polar radius (torsion). w' by (non-uniform) central differences.
    fn motion_series(&self, sm: &[SectionMotion]) -> [Vec<f64>; 5] {
        let np = sm.len();
        let x = &self.planes_x_m;
        let dw: Vec<f64> = (0..np)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(np - 1));
                (sm[b].w - sm[a].w) / (x[b] - x[a])
            })
            .collect();
        let dzhf = self.z_head_m - self.z_foot_m;
        [
            sm.iter().map(|s| s.x_mean).collect(),
            sm.iter()
                .zip(&dw)
                .map(|(s, d)| {
                    let diff = s.x_head - s.x_foot;
                    0.5 * diff.signum() * (diff.abs() - (d * dzhf).abs()).max(0.0)
                })
                .collect(),
            sm.iter().map(|s| s.w).collect(),
            sm.iter().map(|s| s.v).collect(),
            sm.iter().map(|s| s.theta * self.r_polar_m).collect(),
        ]
    }

    /// Whether the vertical motion `w` (one value per node plane) has nodes at the
    /// sleepers: its RMS there below `PINNED_PINNED_NODE_RATIO` of its RMS along the rail.
    fn is_pinned_pinned(&self, w: &[f64]) -> bool {
        let (x, wl) = (&self.planes_x_m, &self.plane_len);
        let at: Vec<f64> = self
            .sleepers_x_m
            .iter()
            .map(|&xs| interp(x, w, xs))
            .collect();
        let r_s = (at.iter().map(|a| a * a).sum::<f64>() / at.len().max(1) as f64).sqrt();
        r_s < PINNED_PINNED_NODE_RATIO * rms(w.iter().copied(), wl)
    }
}

/// Free-DOF vectors of `track` expanded to all DOFs (constrained DOFs zero).
fn expand_all(track: &TrackStructure, u_free: &[&[f64]]) -> Result<Vec<Vec<f64>>, ClassifyError> {
    let n_free = track.dofmap.n_free();
    u_free
        .iter()
        .map(|u| {
            if u.len() != n_free {
                return Err(ClassifyError::Length {
                    expected: n_free,
                    got: u.len(),
                });
            }
            Ok(track.dofmap.expand(u)?)
        })
        .collect()
}

/// Linear interpolation of samples (x increasing), clamped at the ends.
fn interp(x: &[f64], y: &[f64], at: f64) -> f64 {
    let n = x.len();
    if at <= x[0] {
        return y[0];
    }
    if at >= x[n - 1] {
        return y[n - 1];
    }
    let i = x.partition_point(|&v| v <= at).clamp(1, n - 1) - 1;
    let t = (at - x[i]) / (x[i + 1] - x[i]);
    y[i] + t * (y[i + 1] - y[i])
}

#[cfg(test)]
mod tests;

//! Geometry and meshes of the wheel–track model.
//!
//! A [`Mesh`] is a set of nodes (global coordinates, m) and 8-node hexahedra tagged with the
//! [`Part`] they belong to. Springs, dampers and constraints are not geometry: they are added
//! by the track builder in [`crate::fe`].
//!
//! Hexahedron node order (the usual one, as in VTK_HEXAHEDRON): nodes 0–3 counter-clockwise
//! on the face ζ = −1 seen from ζ = +1, nodes 4–7 above them on ζ = +1; natural coordinates
//! of node i are ξ = (−1, 1, 1, −1, −1, 1, 1, −1)\[i\], η = (−1, −1, 1, 1, −1, −1, 1, 1)\[i\],
//! ζ = (−1, −1, −1, −1, 1, 1, 1, 1)\[i\]. Every element has a positive Jacobian determinant.

use serde::Serialize;

pub mod grading;
pub mod profile;
pub mod rail;
pub mod section;
pub mod sleeper;
pub mod wheel;

/// The physical part an element or node belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// The rail (UIC54 solid).
    Rail,
    /// A half sleeper (concrete solid block).
    Sleeper,
    /// The wheel (rim, web, hub) and the half axle.
    Wheel,
}

impl Part {
    /// All parts, in output order.
    pub const ALL: [Part; 3] = [Part::Rail, Part::Sleeper, Part::Wheel];

    /// Lower-case name used in CSV/JSON/VTU output.
    pub fn name(self) -> &'static str {
        match self {
            Part::Rail => "rail",
            Part::Sleeper => "sleeper",
            Part::Wheel => "wheel",
        }
    }
}

/// An 8-node trilinear hexahedron (node order: see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hex8 {
    /// Global node indices.
    pub nodes: [usize; 8],
    /// Index into the material table of the owning model.
    pub material: usize,
    /// Which part it belongs to.
    pub part: Part,
}

/// Nodes (m) and hexahedral elements.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Node coordinates `[x, y, z]` in m.
    pub nodes: Vec<[f64; 3]>,
    /// Elements.
    pub elements: Vec<Hex8>,
}

impl Mesh {
    /// Appends another mesh, renumbering its nodes; returns the offset added to its node indices.
    pub fn append(&mut self, other: &Mesh) -> usize {
        let offset = self.nodes.len();
        self.nodes.extend_from_slice(&other.nodes);
        self.elements.extend(other.elements.iter().map(|e| Hex8 {
            nodes: e.nodes.map(|n| n + offset),
            ..*e
        }));
        offset
    }
}

/// Errors of the mesh generators: each variant says which input to change.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    /// A parameter is out of its valid range.
    #[error("mesh parameter `{name}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name (as in the params struct).
        name: &'static str,
        /// The offending value (SI units).
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// A line of a profile CSV could not be read.
    #[error("profile CSV line {line}: {reason}")]
    ProfileParse {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A required node position lies outside the meshed interval.
    #[error(
        "required node position {x} m lies outside [{lo}, {hi}] m: remove it or widen the range"
    )]
    BreakpointOutside {
        /// The position (m).
        x: f64,
        /// Lower end of the interval (m).
        lo: f64,
        /// Upper end of the interval (m).
        hi: f64,
    },
    /// The grading could not satisfy the neighbour size ratio.
    #[error("grading did not reach neighbour ratio <= {max_ratio} after {iterations} passes: loosen the ratio or move breakpoints apart")]
    GradingNotConverged {
        /// The requested maximum neighbour size ratio.
        max_ratio: f64,
        /// Passes made.
        iterations: usize,
    },
    /// The mesh would have more nodes than allowed (refused before allocating them).
    #[error("the mesh would have {nodes} nodes ({layers} layers of {per_layer}), more than {limit}: use larger elements")]
    TooLarge {
        /// Nodes of the mesh.
        nodes: usize,
        /// Node layers (circumferential, along the rail).
        layers: usize,
        /// Nodes per layer.
        per_layer: usize,
        /// The limit.
        limit: usize,
    },
    /// The generated mesh has an invalid element (a bug or an extreme parameter set).
    #[error("generated mesh is invalid: {reason}; try a smaller element size")]
    InvalidElement {
        /// What is wrong (element index, Jacobian, ...).
        reason: String,
    },
}

/// Natural coordinates (ξ, η, ζ) of the 8 hexahedron nodes (see the module docs).
pub(crate) const HEX8_NATURAL: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Jacobian determinant (m³ per unit natural volume) of the trilinear map of a hexahedron with
/// corner coordinates `x` (m) at the natural point `p = (ξ, η, ζ)`.
pub(crate) fn hex8_jacobian_det(x: &[[f64; 3]; 8], p: [f64; 3]) -> f64 {
    let mut j = [[0.0; 3]; 3]; // j[a][b] = d x_a / d ξ_b
    for (n, nat) in HEX8_NATURAL.iter().enumerate() {
        let f = [
            1.0 + nat[0] * p[0],
            1.0 + nat[1] * p[1],
            1.0 + nat[2] * p[2],
        ];
        let d = [
            0.125 * nat[0] * f[1] * f[2],
            0.125 * nat[1] * f[0] * f[2],
            0.125 * nat[2] * f[0] * f[1],
        ];
        for a in 0..3 {
            for b in 0..3 {
                j[a][b] += x[n][a] * d[b];
            }
        }
    }
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// Volume (m³) of a trilinear hexahedron: 2×2×2 Gauss rule, exact because det J is of degree
/// ≤ 2 in each natural coordinate.
pub(crate) fn hex8_volume(x: &[[f64; 3]; 8]) -> f64 {
    let g = 1.0 / 3f64.sqrt();
    let mut v = 0.0;
    for a in [-g, g] {
        for b in [-g, g] {
            for c in [-g, g] {
                v += hex8_jacobian_det(x, [a, b, c]);
            }
        }
    }
    v
}

impl Mesh {
    /// Corner coordinates (m) of element `e`.
    pub(crate) fn element_coords(&self, e: usize) -> [[f64; 3]; 8] {
        self.elements[e].nodes.map(|n| self.nodes[n])
    }

    /// Smallest Jacobian determinant over the 8 corners of element `e` (positive for a valid
    /// element).
    pub(crate) fn min_corner_jacobian(&self, e: usize) -> f64 {
        let x = self.element_coords(e);
        HEX8_NATURAL
            .iter()
            .map(|&p| hex8_jacobian_det(&x, p))
            .fold(f64::INFINITY, f64::min)
    }

    /// Total volume (m³) of the elements of `part`.
    pub fn part_volume(&self, part: Part) -> f64 {
        (0..self.elements.len())
            .filter(|&e| self.elements[e].part == part)
            .map(|e| hex8_volume(&self.element_coords(e)))
            .sum()
    }

    /// Checks that every element has a positive Jacobian at all 8 corners; returns the smallest
    /// corner Jacobian (m³) over the mesh.
    pub fn check_jacobians(&self) -> Result<f64, MeshError> {
        let mut min = f64::INFINITY;
        for e in 0..self.elements.len() {
            let j = self.min_corner_jacobian(e);
            if j.is_nan() || j <= 0.0 {
                return Err(MeshError::InvalidElement {
                    reason: format!("element {e} has corner Jacobian {j:e}"),
                });
            }
            min = min.min(j);
        }
        Ok(min)
    }
}

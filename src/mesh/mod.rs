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

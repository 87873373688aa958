//! Extrusion of a rail cross-section along x into 8-node hexahedra.
//!
//! The section ([`SectionMesh`], (y, z) in m) is copied to every node plane x_i (from
//! [`crate::mesh::grading::grade`] or any strictly increasing list) and each section quad
//! (a, b, c, d) between planes i and i + 1 becomes the hexahedron
//! (a_i, b_i, c_i, d_i, a_{i+1}, b_{i+1}, c_{i+1}, d_{i+1}): natural coordinates (ξ, η) are
//! those of the quad and ζ runs along +x, so det J = (Δx/2) · det J_quad > 0 for a
//! counter-clockwise quad. The extruded rail is a prism: its volume is exactly
//! (section area) × (length) and the point location reduces to a 2D bilinear inversion in the
//! section plus a linear map in x.
//!
//! Numbering: global node of (plane i, section node j) = offset + i · n_section_nodes + j;
//! element of (interval i, section quad q) = element_offset + i · n_section_quads + q.

use super::section::{SectionLocator, SectionMesh};
use super::{Hex8, Mesh, MeshError, Part};

/// Map from (plane, section node) to global nodes of an extruded rail, and point location.
#[derive(Debug, Clone, PartialEq)]
pub struct RailTopology {
    /// x of the node planes (m), strictly increasing.
    pub planes_x_m: Vec<f64>,
    /// The extruded cross-section.
    pub section: SectionMesh,
    /// Added to every node index (set by [`Self::shifted`] after `Mesh::append`).
    pub node_offset: usize,
    /// Added to every element index.
    pub element_offset: usize,
    /// Bucket grid over the section for [`Self::locate`].
    pub locator: SectionLocator,
}

/// A point located in the rail: its element and natural coordinates (ξ, η, ζ) ∈ [−1, 1]³.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RailPoint {
    /// Global element index.
    pub element: usize,
    /// Natural coordinates in that element (node order of [`Hex8`]).
    pub natural: [f64; 3],
}

impl RailTopology {
    /// Number of node planes.
    pub fn n_planes(&self) -> usize {
        self.planes_x_m.len()
    }

    /// Nodes per plane.
    pub fn n_section_nodes(&self) -> usize {
        self.section.nodes.len()
    }

    /// Global node of section node `j` in plane `plane`.
    pub fn node(&self, plane: usize, j: usize) -> usize {
        self.node_offset + plane * self.section.nodes.len() + j
    }

    /// Global element of section quad `q` between planes `interval` and `interval + 1`.
    pub fn element(&self, interval: usize, q: usize) -> usize {
        self.element_offset + interval * self.section.quads.len() + q
    }

    /// Foot-underside nodes of a plane, ordered along the foot (see
    /// [`SectionMesh::foot_underside_s_m`] for their positions).
    pub fn foot_underside_nodes(&self, plane: usize) -> Vec<usize> {
        self.section
            .foot_underside
            .iter()
            .map(|&j| self.node(plane, j))
            .collect()
    }

    /// Running-surface (head top) nodes of a plane, ordered by y.
    pub fn running_surface_nodes(&self, plane: usize) -> Vec<usize> {
        self.section
            .running_surface
            .iter()
            .map(|&j| self.node(plane, j))
            .collect()
    }

    /// The same topology with node and element indices shifted (after appending the rail
    /// mesh to a larger mesh with `Mesh::append`, pass the returned node offset and the
    /// element count before appending).
    pub fn shifted(&self, node_offset: usize, element_offset: usize) -> Self {
        RailTopology {
            node_offset,
            element_offset,
            ..self.clone()
        }
    }

    /// The element containing the point (x, y, z) (m) and its natural coordinates; `None`
    /// outside the rail. Cost: a binary search in x and a bucket search in the section.
    pub fn locate(&self, x: f64, y: f64, z: f64) -> Option<RailPoint> {
        let px = &self.planes_x_m;
        if !(x >= px[0] && x <= px[px.len() - 1]) {
            return None;
        }
        // Interval i with px[i] <= x <= px[i+1].
        let i = px.partition_point(|&v| v <= x).clamp(1, px.len() - 1) - 1;
        let zeta = 2.0 * (x - px[i]) / (px[i + 1] - px[i]) - 1.0;
        let (q, nat) = self.locator.locate(&self.section, y, z)?;
        Some(RailPoint {
            element: self.element(i, q),
            natural: [nat[0], nat[1], zeta],
        })
    }
}

/// Extrudes `section` through the node planes `planes_x_m` (m, strictly increasing, at least
/// two) into hexahedra of [`Part::Rail`] with material index `material`.
pub fn extrude_rail(
    section: &SectionMesh,
    planes_x_m: &[f64],
    material: usize,
) -> Result<(Mesh, RailTopology), MeshError> {
    if planes_x_m.len() < 2 {
        return Err(MeshError::InvalidParameter {
            name: "planes_x_m",
            value: planes_x_m.len() as f64,
            reason: "need at least two node planes",
        });
    }
    for w in planes_x_m.windows(2) {
        if !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]) {
            return Err(MeshError::InvalidParameter {
                name: "planes_x_m",
                value: w[1],
                reason: "node planes must be finite and strictly increasing",
            });
        }
    }
    section.check_quads()?;
    let ns = section.nodes.len();
    let nq = section.quads.len();
    let np = planes_x_m.len();
    let mut mesh = Mesh {
        nodes: Vec::with_capacity(ns * np),
        elements: Vec::with_capacity(nq * (np - 1)),
    };
    for &x in planes_x_m {
        mesh.nodes
            .extend(section.nodes.iter().map(|&[y, z]| [x, y, z]));
    }
    for i in 0..np - 1 {
        let (o0, o1) = (i * ns, (i + 1) * ns);
        for q in &section.quads {
            mesh.elements.push(Hex8 {
                nodes: [
                    o0 + q[0],
                    o0 + q[1],
                    o0 + q[2],
                    o0 + q[3],
                    o1 + q[0],
                    o1 + q[1],
                    o1 + q[2],
                    o1 + q[3],
                ],
                material,
                part: Part::Rail,
            });
        }
    }
    let topo = RailTopology {
        planes_x_m: planes_x_m.to_vec(),
        section: section.clone(),
        node_offset: 0,
        element_offset: 0,
        locator: SectionLocator::new(section),
    };
    Ok((mesh, topo))
}

#[cfg(test)]
mod tests {
    use super::{extrude_rail, Mesh, Part, RailTopology, SectionMesh};
    use crate::mesh::grading::{grade, FineZone, GradingSpec};
    use crate::mesh::section::SectionParams;
    use crate::mesh::HEX8_NATURAL;

    fn rail() -> (Mesh, RailTopology, f64) {
        let section = SectionMesh::uic54(&SectionParams {
            size_m: 0.008,
            running_surface_size_m: 0.004,
            inclination_rad: (1.0f64 / 40.0).atan(),
            ..Default::default()
        })
        .unwrap();
        let mut spec = GradingSpec::new(0.0, 1.2, 0.05);
        spec.zones.push(FineZone {
            start_m: 0.5,
            end_m: 0.7,
            size_m: 0.01,
        });
        spec.breakpoints_m = vec![0.215, 0.385];
        let planes = grade(&spec).unwrap();
        let (m, t) = extrude_rail(&section, &planes, 0).unwrap();
        (m, t, 1.2)
    }

    #[test]
    fn volume_mass_and_jacobians() {
        let (m, t, len) = rail();
        let area = t.section.properties().area_m2;
        let vol = m.part_volume(Part::Rail);
        // Prism: V = A L exactly (up to rounding).
        assert!(
            (vol / (area * len) - 1.0).abs() < 1e-12,
            "{vol} vs {}",
            area * len
        );
        assert!(m.check_jacobians().unwrap() > 0.0);
        // Mass per metre. EN 13674-1 gives 54.77 kg/m for A = 6977 mm², i.e. ρ = 7850 kg/m³.
        let m7850 = vol / len * 7850.0;
        let m7800 = vol / len * 7800.0;
        eprintln!(
            "rail: {} nodes, {} hex; mass {m7800:.2} kg/m at 7800 ({:+.2} % vs 54.77), {m7850:.2} kg/m at 7850 ({:+.2} %)",
            m.nodes.len(),
            m.elements.len(),
            (m7800 / 54.77 - 1.0) * 100.0,
            (m7850 / 54.77 - 1.0) * 100.0
        );
        assert!((m7850 / 54.77 - 1.0).abs() < 0.01);
        // With the model's 7800 kg/m³: 0.64 % of the deficit is the density difference.
        assert!((m7800 / 54.77 - 1.0).abs() < 0.011);
        assert!((m7800 / (6977e-6 * 7800.0) - 1.0).abs() < 0.005);
    }

    #[test]
    fn topology_maps_planes_and_surfaces() {
        let (m, t, _) = rail();
        assert_eq!(m.nodes.len(), t.n_planes() * t.n_section_nodes());
        let p = 7;
        for (k, &n) in t.foot_underside_nodes(p).iter().enumerate() {
            assert_eq!(m.nodes[n][0], t.planes_x_m[p]);
            assert_eq!(n, t.node(p, t.section.foot_underside[k]));
        }
        let rs = t.running_surface_nodes(p);
        assert!(rs.windows(2).all(|w| m.nodes[w[1]][1] > m.nodes[w[0]][1]));
        let shifted = t.shifted(100, 10);
        assert_eq!(shifted.node(p, 3), t.node(p, 3) + 100);
        assert_eq!(shifted.element(2, 3), t.element(2, 3) + 10);
    }

    #[test]
    fn locate_reproduces_points() {
        let (m, t, _) = rail();
        for &(x, y, z) in &[
            (0.6001, -0.003, 0.157),
            (0.0, 0.0, 0.0005),
            (1.2, 0.03, 0.01),
            (0.2151, -0.004, 0.08),
        ] {
            let rp = t.locate(x, y, z).expect("inside");
            let xe = m.element_coords(rp.element);
            // Trilinear interpolation of the element's corners at the natural point.
            let mut p = [0.0; 3];
            for (k, nat) in HEX8_NATURAL.iter().enumerate() {
                let w = (0..3)
                    .map(|d| 0.5 * (1.0 + nat[d] * rp.natural[d]))
                    .product::<f64>();
                for d in 0..3 {
                    p[d] += w * xe[k][d];
                }
            }
            assert!(
                (p[0] - x).abs() < 1e-12 && (p[1] - y).abs() < 1e-12 && (p[2] - z).abs() < 1e-12
            );
        }
        assert!(t.locate(1.3, 0.0, 0.1).is_none());
        assert!(t.locate(0.5, 0.05, 0.1).is_none());
    }

    #[test]
    fn bad_planes_are_errors() {
        let s = SectionMesh::uic54(&SectionParams::default()).unwrap();
        assert!(extrude_rail(&s, &[0.0], 0).is_err());
        assert!(extrude_rail(&s, &[0.0, 0.1, 0.1], 0).is_err());
        assert!(extrude_rail(&s, &[0.0, f64::NAN], 0).is_err());
    }
}

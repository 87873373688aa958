//! The rail's ends: free, or absorbing (docs/theory.md §3.7).
//!
//! A finite track with free rail ends reflects every wave that reaches an end, so the
//! solution zone sees the whole rail's standing waves; the reference study's track has
//! non-reflecting ends. An absorbing end here has two parts, both pure damping (no stiffness:
//! the modes and their cache do not change, the reduced passage keeps the full `ΦᵀCΦ`):
//!
//! - **Face dashpots** (`face_dashpots`): the viscous boundary of Lysmer and Kuhlemeyer
//!   (1969). Every node `i` of an end face is tied to the ground, with the consistent nodal
//!   area `A_i = ∫ N_i dA` (`nodal_areas`), by `ρ c_b A_i` in x (normal; `c_b = √(E/ρ)`, the
//!   rail's longitudinal bar wave) and `ρ c_s A_i` in y and z (`c_s = √(G/ρ)`). A plane
//!   longitudinal wave leaving the face has normal traction `σ = ρ c_b v`, what the dashpots
//!   apply. For bending waves they give the high-frequency limits of a Timoshenko beam's
//!   impedances only, and reflect a large part at a few hundred Hz.
//! - **An absorbing layer** (`layer_dashpots`): over the last `L` metres of the rail,
//!   grounded dashpots in y and z of `α(d) m_i` on every node of lumped mass `m_i`,
//!   `α(d) = α_max (1 − d/L)²` at distance `d` from the face. It takes out the bending waves'
//!   energy; the longitudinal wave passes it to the face.
//!
//! Assumptions: small displacements, a straight prismatic rail (the same section mesh on every
//! node plane), the layer outside the wheel's travel. The measured reflections are in
//! validation/reference_regime.md; [`reflection`] computes them.
//!
//! References: J. Lysmer, R. L. Kuhlemeyer, "Finite dynamic model for infinite media",
//! J. Eng. Mech. Div. ASCE 95 (1969) 859–877; J.-F. Semblat, L. Lenti, A. Gandomzadeh, "A
//! simple multi-directional absorbing layer method to simulate elastic wave propagation in
//! unbounded domains", Int. J. Numer. Meth. Engng 85 (2011) 1543–1563.

use crate::fe::material::IsotropicElastic;
use crate::fe::spring::{Direction, Spring};
use crate::mesh::rail::RailTopology;
use crate::mesh::section::SectionMesh;

pub mod reflection;

/// Consistent nodal areas of a section mesh, `A_i = ∫ N_i dA` over its bilinear quads (m²),
/// by 2 × 2 Gauss points (exact for bilinear shape functions on a bilinear map). They sum to
/// the section's area, and `Σ A_i y_i`, `Σ A_i z_i` to its first moments.
pub(crate) fn nodal_areas(section: &SectionMesh) -> Vec<f64> {
    let mut a = vec![0.0; section.nodes.len()];
    let g = 1.0 / 3f64.sqrt();
    for quad in &section.quads {
        let p = quad.map(|n| section.nodes[n]);
        for (xi, eta) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
            let n = [
                0.25 * (1.0 - xi) * (1.0 - eta),
                0.25 * (1.0 + xi) * (1.0 - eta),
                0.25 * (1.0 + xi) * (1.0 + eta),
                0.25 * (1.0 - xi) * (1.0 + eta),
            ];
            let dxi = [
                -0.25 * (1.0 - eta),
                0.25 * (1.0 - eta),
                0.25 * (1.0 + eta),
                -0.25 * (1.0 + eta),
            ];
            let deta = [
                -0.25 * (1.0 - xi),
                -0.25 * (1.0 + xi),
                0.25 * (1.0 + xi),
                0.25 * (1.0 - xi),
            ];
            let (mut j11, mut j12, mut j21, mut j22) = (0.0, 0.0, 0.0, 0.0);
            for k in 0..4 {
                j11 += dxi[k] * p[k][0];
                j12 += dxi[k] * p[k][1];
                j21 += deta[k] * p[k][0];
                j22 += deta[k] * p[k][1];
            }
            let det = (j11 * j22 - j12 * j21).abs();
            for k in 0..4 {
                a[quad[k]] += n[k] * det;
            }
        }
    }
    a
}

/// Dashpot constants of an absorbing end per unit area (N·s/m³): `[ρ c_b, ρ c_s, ρ c_s]` for
/// x (normal), y, z.
pub(crate) fn impedances_per_area(material: &IsotropicElastic) -> [f64; 3] {
    let (e, nu, rho) = (
        material.youngs_modulus,
        material.poisson_ratio,
        material.density,
    );
    let g = e / (2.0 * (1.0 + nu));
    let (cb, cs) = ((e / rho).sqrt(), (g / rho).sqrt());
    [rho * cb, rho * cs, rho * cs]
}

/// The dashpots (node to ground, damping only) of an absorbing end face at node `plane` of
/// `rail`, for the rail's `material`.
pub(crate) fn face_dashpots(
    rail: &RailTopology,
    plane: usize,
    material: &IsotropicElastic,
) -> Vec<Spring> {
    let areas = nodal_areas(&rail.section);
    let z = impedances_per_area(material);
    let mut out = Vec::with_capacity(3 * areas.len());
    for (j, &a) in areas.iter().enumerate() {
        let node = rail.node(plane, j);
        for d in Direction::ALL {
            out.push(Spring::node_to_ground(node, d, 0.0, z[d.index()] * a));
        }
    }
    out
}

/// The absorbing layer of one end (docs/theory.md §3.7): grounded dashpots in y and z on every
/// rail node within `length_m` (m) of the end face at `x_end` (m), `c_i = α(d) m_i` with the
/// node's lumped mass `m_i = ρ A_i ℓ_p` (section area `A_i`, tributary length `ℓ_p` of its
/// plane) and `α(d) = rate (1 − d/length)²` (1/s) at distance `d` from the face. Transverse
/// only, so that the rail's longitudinal wave, which the face dashpots absorb, passes it.
pub(crate) fn layer_dashpots(
    rail: &RailTopology,
    material: &IsotropicElastic,
    x_end: f64,
    length_m: f64,
    rate_per_s: f64,
) -> Vec<Spring> {
    let mut out = Vec::new();
    if !(length_m > 0.0 && rate_per_s > 0.0) {
        return out;
    }
    let areas = nodal_areas(&rail.section);
    let xs = &rail.planes_x_m;
    for (p, &x) in xs.iter().enumerate() {
        let d = (x - x_end).abs();
        if d >= length_m {
            continue;
        }
        let lo = if p > 0 { 0.5 * (x - xs[p - 1]) } else { 0.0 };
        let hi = if p + 1 < xs.len() {
            0.5 * (xs[p + 1] - x)
        } else {
            0.0
        };
        let s = 1.0 - d / length_m;
        let alpha = rate_per_s * s * s;
        for (j, &a) in areas.iter().enumerate() {
            let c = alpha * material.density * a * (lo + hi);
            let node = rail.node(p, j);
            for dir in [Direction::Y, Direction::Z] {
                out.push(Spring::node_to_ground(node, dir, 0.0, c));
            }
        }
    }
    out
}

/// The absorbing ends of `rail` (both end faces' dashpots and both layers) for the rail's
/// `material`, a layer of `layer_m` (m) and rate `rate_per_s` (1/s) at each end.
pub(crate) fn end_dashpots(
    rail: &RailTopology,
    material: &IsotropicElastic,
    layer_m: f64,
    rate_per_s: f64,
) -> Vec<Spring> {
    let last = rail.n_planes().saturating_sub(1);
    let xs = &rail.planes_x_m;
    let mut out = face_dashpots(rail, 0, material);
    out.extend(face_dashpots(rail, last, material));
    out.extend(layer_dashpots(rail, material, xs[0], layer_m, rate_per_s));
    out.extend(layer_dashpots(
        rail, material, xs[last], layer_m, rate_per_s,
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::{impedances_per_area, nodal_areas, IsotropicElastic};
    use crate::mesh::section::{SectionMesh, SectionParams};

    fn section() -> SectionMesh {
        SectionMesh::uic54(&SectionParams::default()).unwrap()
    }

    /// The nodal areas integrate 1, y and z exactly: they give the area and the centroid of
    /// the section's own polygon, computed independently by the shoelace formula of its quads.
    #[test]
    fn nodal_areas_give_the_area_and_the_centroid() {
        let s = section();
        let a = nodal_areas(&s);
        let area: f64 = (0..s.quads.len()).map(|q| s.quad_area(q)).sum();
        assert!((a.iter().sum::<f64>() - area).abs() < 1e-12 * area);
        let props = s.properties();
        let zc: f64 = a.iter().zip(&s.nodes).map(|(ai, p)| ai * p[1]).sum::<f64>() / area;
        assert!(
            (zc - props.centroid_z_m).abs() < 1e-9,
            "{zc} vs {}",
            props.centroid_z_m
        );
        // UIC54 (54E1): 69.77 cm² (the mesh's polygon is within 1 %)
        assert!((area / 69.77e-4 - 1.0).abs() < 0.01, "{area}");
    }

    /// The default track with absorbing ends: the face dashpots sum to `ρ c_b A` (x) and
    /// `ρ c_s A` (y, z) per end, and the layer's y dashpots to `ρ A α_max L / 3` per end, the
    /// integral of `α_max (1 − d/L)²` over the layer (closed forms; the layer's sum by the
    /// node planes' trapezoid rule within 1 %). The free track has none.
    #[test]
    fn the_absorbing_track_carries_the_closed_form_dashpots() {
        use crate::fe::spring::Direction;
        use crate::structure::track::{SpringKind, TrackStructure};
        let load = |set: &[&str]| {
            let o: Vec<String> = set.iter().map(|s| s.to_string()).collect();
            crate::model::load_model(&crate::model::ModelSource::Builtin, &o).unwrap()
        };
        let free = TrackStructure::build(&load(&[])).unwrap();
        assert!(!free.spring_kinds.contains(&SpringKind::EndDashpot));
        let m = load(&["track.ends=\"absorbing\""]);
        let t = TrackStructure::build(&m).unwrap();
        let area: f64 = nodal_areas(&t.rail.section).iter().sum();
        let z = impedances_per_area(&m.rail_material());
        // damping per direction summed over every end dashpot (faces and layers)
        let mut sum = [0.0; 3];
        for (s, k) in t.springs.iter().zip(&t.spring_kinds) {
            if *k == SpringKind::EndDashpot {
                assert_eq!(s.stiffness, 0.0);
                sum[s.side_a[0].0 % 3] += s.damping;
            }
        }
        // x: the faces alone
        let x = Direction::X.index();
        assert!((sum[x] / (2.0 * z[x] * area) - 1.0).abs() < 1e-9, "{sum:?}");
        // y and z: the faces plus the layers
        let (l, a) = (m.track.absorbing_layer_length, m.track.absorbing_layer_rate);
        let layer = 2.0 * m.rail.density * area * a * l / 3.0;
        for d in [Direction::Y.index(), Direction::Z.index()] {
            let got = sum[d] - 2.0 * z[d] * area;
            assert!((got / layer - 1.0).abs() < 0.01, "{d}: {got} vs {layer}");
        }
    }

    /// Steel: ρ c_b = √(E ρ) and ρ c_s = √(G ρ).
    #[test]
    fn impedances_are_the_bar_and_shear_impedances() {
        let z = impedances_per_area(&IsotropicElastic::STEEL);
        let (e, rho) = (210e9_f64, 7800.0_f64);
        assert!((z[0] - (e * rho).sqrt()).abs() < 1e-6 * z[0]);
        let g = e / 2.6;
        assert!((z[1] - (g * rho).sqrt()).abs() < 1e-6 * z[1]);
        assert_eq!(z[1], z[2]);
    }
}

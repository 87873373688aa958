//! `mesh.node_planes = "lattice"` against its definition: every node plane of the fine zone on
//! `x = k·e`, uniformly spaced, the graded mesh's breakpoints outside the zone kept, the
//! neighbour ratio of the grading held across the zone's ends; holds off the lattice refused
//! by name. The graded mesh of the same model is checked to have the variation the lattice
//! removes (plane spacing shorter than `e` over the footprints, with the sleeper period).

use super::track::TrackStructure;
use super::StructureError;
use crate::model::test_problems::small_model;
use crate::model::Model;

/// The small model (4 bays) with the default model's 10 mm fine zone and 40 mm elements.
fn fine(extra: &[&str]) -> Model {
    let sets: Vec<&str> = ["mesh.element_length=0.04", "mesh.fine_element_length=0.01"]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
    small_model(&sets).unwrap()
}

/// The spacings of the node planes that lie in `[a, b]`.
fn spacings_in(planes: &[f64], [a, b]: [f64; 2]) -> Vec<f64> {
    planes
        .windows(2)
        .filter(|w| w[0] >= a - 1e-12 && w[1] <= b + 1e-12)
        .map(|w| w[1] - w[0])
        .collect()
}

#[test]
fn lattice_planes_are_uniform_in_the_fine_zone_and_graded_outside() {
    let e = 0.01;
    let graded = TrackStructure::build(&fine(&["fastening.model=RPM3"])).unwrap();
    let lattice =
        TrackStructure::build(&fine(&["fastening.model=RPM3", "mesh.node_planes=lattice"]))
            .unwrap();
    let zone = graded.layout.fine_zone;
    // The graded mesh varies: the footprint ends (±85 mm about each sleeper) are not a
    // whole number of 10 mm elements from the strip edges, so the planes there are closer.
    let g = spacings_in(&graded.rail.planes_x_m, zone);
    let shortest = g.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(shortest < 0.95 * e, "graded: shortest spacing {shortest}");
    // The lattice: every plane in the zone is a multiple of e, every spacing e.
    let p = &lattice.rail.planes_x_m;
    for &x in p.iter().filter(|&&x| x >= zone[0] && x <= zone[1]) {
        assert!(
            ((x / e).round() * e - x).abs() < 1e-12,
            "plane {x} off the lattice"
        );
    }
    for s in spacings_in(p, zone) {
        assert!((s - e).abs() < 1e-12, "lattice spacing {s}");
    }
    // Outside the zone the breakpoints of the graded mesh are kept (the strip edges about
    // the first sleeper, at 0.3 m), and the grading's ratio holds everywhere.
    for x in [0.29, 0.31] {
        assert!(p.iter().any(|&q| (q - x).abs() < 1e-12), "breakpoint {x}");
    }
    for w in p.windows(3) {
        let (ea, eb) = (w[1] - w[0], w[2] - w[1]);
        assert!(
            ea.max(eb) <= 1.25 * ea.min(eb) * (1.0 + 1e-9),
            "ratio at {}",
            w[1]
        );
    }
    // The rail ends stay.
    assert_eq!(p[0], 0.0);
    assert!((p[p.len() - 1] - lattice.layout.length).abs() < 1e-12);
}

#[test]
fn lattice_refuses_node_line_holds_off_the_lattice() {
    // RPM1's outer columns on node lines sit 56.7 mm from the sleeper: off the 10 mm lattice.
    let m = fine(&[
        "fastening.model=custom",
        "fastening.custom.x={ rigid = \"columns\", indices = [0, 1, 2], node_lines = true }",
        "fastening.custom.y={ rigid = \"rows\", indices = [0, 1, 2, 3] }",
        "fastening.custom.z={ rigid = \"none\" }",
        "mesh.node_planes=lattice",
    ]);
    match TrackStructure::build(&m) {
        Err(e @ StructureError::HoldMissesNodes { .. }) => {
            assert!(e.to_string().contains("mesh.node_planes"), "{e}")
        }
        Err(e) => panic!("wrong error: {e}"),
        Ok(_) => panic!("a node-line hold off the lattice was accepted"),
    }
    // The middle column (on the sleeper centre, on the lattice) is accepted.
    let m = fine(&[
        "fastening.model=custom",
        "fastening.custom.x={ rigid = \"columns\", indices = [1], node_lines = true }",
        "fastening.custom.y={ rigid = \"rows\", indices = [0, 1, 2, 3] }",
        "fastening.custom.z={ rigid = \"none\" }",
        "mesh.node_planes=lattice",
    ]);
    TrackStructure::build(&m).unwrap();
}

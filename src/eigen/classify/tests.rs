//! Classification of synthetic displacement fields of known shape on the real rail mesh.

use super::*;
use crate::model::{load_model, ModelSource};
use crate::structure::TrackStructure;

fn small_track() -> TrackStructure {
    let o: Vec<String> = [
        "track.bays=4",
        "mesh.element_length=0.04",
        "mesh.fine_element_length=0.04",
        "mesh.section_size=0.03",
        "mesh.head_size=0.015",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    TrackStructure::build(&load_model(&ModelSource::Builtin, &o).unwrap()).unwrap()
}

/// Full displacement vector with `f(x, y, z) -> [ux, uy, uz]` on the rail nodes, 0 elsewhere.
fn rail_field(t: &TrackStructure, f: impl Fn(f64, f64, f64) -> [f64; 3]) -> Vec<f64> {
    let mut u = vec![0.0; 3 * t.mesh.nodes.len()];
    for i in 0..t.rail.n_planes() {
        for j in 0..t.rail.n_section_nodes() {
            let n = t.rail.node(i, j);
            let [x, y, z] = t.mesh.nodes[n];
            u[3 * n..3 * n + 3].copy_from_slice(&f(x, y, z));
        }
    }
    u
}

fn max_spacing(t: &TrackStructure) -> f64 {
    t.rail
        .planes_x_m
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(0.0, f64::max)
}

#[test]
fn uniform_axial_field_is_longitudinal_compression() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let r = c
        .classify_shape(
            &rail_field(&t, |_, _, _| [1.0, 0.0, 0.0]),
            Default::default(),
        )
        .unwrap();
    assert_eq!(r.family, TrackFamily::LongitudinalCompression);
    // Uniform unit field: every group mean is 1 = the rail RMS.
    for v in [r.rail_x_head, r.rail_x_web, r.rail_x_foot] {
        assert!((v - 1.0).abs() < 1e-12, "{r:?}");
    }
    assert!((r.section_fit - 1.0).abs() < 1e-12);
    assert_eq!(r.wavelength_m, None);
}

#[test]
fn head_foot_opposite_is_longitudinal_shear() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let u = rail_field(&t, |_, _, z| {
        let ux = if z > WEB_TOP_Z_M {
            1.0
        } else if z < WEB_BOTTOM_Z_M {
            -1.0
        } else {
            0.0
        };
        [ux, 0.0, 0.0]
    });
    let r = c.classify_shape(&u, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::LongitudinalShear, "{r:?}");
    assert!(r.rail_x_web < 1e-12);
}

#[test]
fn vertical_sine_is_vertical_bending_with_its_wavelength() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let h = max_spacing(&t);
    for lambda in [0.3, 0.5, 0.8] {
        let u = rail_field(&t, |x, _, _| {
            [0.0, 0.0, (2.0 * std::f64::consts::PI * x / lambda).sin()]
        });
        let r = c.classify_shape(&u, Default::default()).unwrap();
        assert_eq!(r.family, TrackFamily::VerticalBending);
        let l = r.wavelength_m.unwrap();
        assert!(
            (l - lambda).abs() < h,
            "λ {lambda} → {l} (plane spacing {h})"
        );
        eprintln!(
            "lambda {lambda} m -> {l} m, error {:.2e} m",
            (l - lambda).abs()
        );
    }
}

#[test]
fn bending_with_plane_section_rotation_is_not_shear() {
    // Euler–Bernoulli kinematics: u_z = sin(kx), u_x = −k cos(kx) (z − z_c) (large rotation
    // relative to w at this short wavelength: k (z_h − z_f)/2 ≈ 0.9).
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let zc = t.section_properties.centroid_z_m;
    let k = 2.0 * std::f64::consts::PI / 0.3;
    let u = rail_field(&t, |x, _, z| {
        [-k * (k * x).cos() * (z - zc), 0.0, (k * x).sin()]
    });
    let r = c.classify_shape(&u, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::VerticalBending, "{r:?}");
}

#[test]
fn pinned_pinned_flag_needs_nodes_at_the_sleepers() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let s = t.layout.sleepers[1] - t.layout.sleepers[0];
    let x0 = t.layout.sleepers[0];
    let k = std::f64::consts::PI / s;
    let at_nodes = rail_field(&t, |x, _, _| [0.0, 0.0, (k * (x - x0)).sin()]);
    let r = c.classify_shape(&at_nodes, Default::default()).unwrap();
    assert!(r.pinned_pinned, "{r:?}");
    let at_antinodes = rail_field(&t, |x, _, _| [0.0, 0.0, (k * (x - x0)).cos()]);
    let r = c.classify_shape(&at_antinodes, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::VerticalBending);
    assert!(!r.pinned_pinned, "{r:?}");
}

#[test]
fn lateral_torsion_sleeper_fields() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let lat = rail_field(&t, |_, _, _| [0.0, 1.0, 0.0]);
    assert_eq!(
        c.classify_shape(&lat, Default::default()).unwrap().family,
        TrackFamily::LateralBending
    );
    let zc = t.section_properties.centroid_z_m;
    let tor = rail_field(&t, |_, y, z| [0.0, -(z - zc), y]);
    let r = c.classify_shape(&tor, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::Torsion, "{r:?}");
    // Only the sleepers move: all kinetic energy in the sleepers.
    let mut sl = vec![0.0; 3 * t.mesh.nodes.len()];
    for s in 0..sl.len() / 3 {
        if s >= t.rail.n_planes() * t.rail.n_section_nodes() {
            sl[3 * s + 2] = 1.0;
        }
    }
    let r = c.classify_shape(&sl, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::Sleeper);
    assert!((r.sleeper_kinetic_share - 1.0).abs() < 1e-12);
}

#[test]
fn section_deformation_is_local_and_bad_input_is_an_error() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    // Foot flapping: u_z ∝ |y| on the foot only (foot tips up, centre still) – not a
    // rigid section motion.
    let u = rail_field(&t, |_, y, z| {
        [
            0.0,
            0.0,
            if z < WEB_BOTTOM_Z_M {
                y.abs() - 0.05
            } else {
                0.0
            },
        ]
    });
    let r = c.classify_shape(&u, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::Local, "{r:?}");
    assert!(matches!(
        c.classify_shape(&[0.0; 3], Default::default()),
        Err(ClassifyError::Length { .. })
    ));
    let mut nan = vec![0.0; 3 * t.mesh.nodes.len()];
    nan[0] = f64::NAN;
    assert!(matches!(
        c.classify_shape(&nan, Default::default()),
        Err(ClassifyError::NonFinite)
    ));
}

#[test]
fn wavelength_on_a_graded_grid() {
    // Graded samples of sin(2πx/0.25) on [0, 1]: crossings at multiples of 0.125.
    let x: Vec<f64> = (0..=200).map(|i| (i as f64 / 200.0).powf(1.3)).collect();
    let q: Vec<f64> = x
        .iter()
        .map(|&x| (2.0 * std::f64::consts::PI * x / 0.25).sin())
        .collect();
    let l = wavelength_from_crossings(&x, &q).unwrap();
    assert!((l - 0.25).abs() < 1e-3, "{l}");
    assert_eq!(wavelength_from_crossings(&x, &vec![0.0; x.len()]), None);
}

//! Classification of synthetic displacement fields of known shape on the real rail mesh.

use super::{
    classify_wheel_mode, classify_wheel_modes, wavelength_from_crossings, ClassifyError,
    TrackClassifier, TrackFamily, TrackModeClass, WheelFamily, SLEEPER_KINETIC_SHARE,
    WEB_BOTTOM_Z_M, WEB_TOP_Z_M,
};
use crate::model::{load_model, ModelSource};
use crate::structure::{TrackStructure, WheelStructure};

fn small_track() -> TrackStructure {
    TrackStructure::build(
        &crate::model::test_problems::small_model_with_elements(0.04, &[]).unwrap(),
    )
    .unwrap()
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

/// Small custom-held track (4 bays, coarse mesh) with the given `fastening.custom` table.
fn custom_track(custom: &str) -> TrackStructure {
    let o: Vec<String> = [
        "track.bays=4",
        "mesh.element_length=0.05",
        "mesh.fine_element_length=0.05",
        "mesh.section_size=0.03",
        "mesh.head_size=0.015",
        "fastening.model=\"custom\"",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([format!("fastening.custom={custom}")])
    .collect();
    TrackStructure::build(&load_model(&ModelSource::Builtin, &o).unwrap()).unwrap()
}

fn solve_and_classify(t: &TrackStructure, f_max: f64) -> (Vec<f64>, Vec<TrackModeClass>) {
    let (mats, _) = t.assemble().unwrap();
    let sol = crate::eigen::solve(
        mats.k.as_ref(),
        mats.m.as_ref(),
        &crate::eigen::EigenOptions::new(f_max),
        None,
    )
    .unwrap();
    let c = TrackClassifier::new(t).unwrap();
    let classes = (0..sol.frequencies_hz.len())
        .map(|j| {
            let u: Vec<f64> = (0..sol.modes.nrows()).map(|i| sol.modes[(i, j)]).collect();
            c.classify(t, &u).unwrap()
        })
        .collect();
    (sol.frequencies_hz, classes)
}

/// Bar-like rail: the whole foot underside held in y and z, x free (pads have no
/// longitudinal stiffness): the rail is a free–free bar along x. Its longitudinal modes are at
/// f_n = n c / (2L), c = √(E/ρ) (1D bar; the 3D section adds a small Love (lateral inertia)
/// correction, ν² n² π² r_p²/L² ≈ 1e-4 here). Those modes must classify as
/// longitudinal_compression, the n = 2 one with wavelength L.
/// Run: `cargo test --release --lib classify::tests::bar_like -- --ignored` (~10 s in dev).
#[test]
#[ignore = "eigen solve of a 4-bay rail (~10 s)"]
fn bar_like_rail_longitudinal_modes_are_compression() {
    let t = custom_track(
        "{x={rigid=\"none\",indices=[]},y={rigid=\"continuous\",indices=[]},z={rigid=\"continuous\",indices=[]}}",
    );
    let (f, cl) = solve_and_classify(&t, 2400.0);
    let m = &t.materials[crate::structure::track::RAIL_MATERIAL];
    let c = (m.youngs_modulus / m.density).sqrt();
    let l = t.layout.length;
    for n in [1.0, 2.0] {
        let f_n = n * c / (2.0 * l);
        let (j, fj) = f
            .iter()
            .enumerate()
            .filter(|(j, _)| cl[*j].family == TrackFamily::LongitudinalCompression)
            .map(|(j, &x)| (j, x))
            .min_by(|a, b| (a.1 - f_n).abs().total_cmp(&(b.1 - f_n).abs()))
            .expect("a longitudinal_compression mode");
        eprintln!(
            "n = {n}: closed form {f_n:.1} Hz, FE {fj:.1} Hz ({:+.3} %), {:?}",
            100.0 * (fj / f_n - 1.0),
            cl[j]
        );
        assert!(
            (fj / f_n - 1.0).abs() < 0.02,
            "n = {n}: {fj} Hz vs {f_n} Hz"
        );
        if n == 2.0 {
            let lam = cl[j].wavelength_m.unwrap();
            assert!((lam - l).abs() < 0.05 * l, "λ {lam} vs L {l}");
        }
    }
}

/// Rail on rigid point supports every sleeper spacing (z and x held at the middle fastening
/// column, lateral pads only): the pinned-pinned mode — vertical bending with nodes at the
/// supports, wavelength 2 × spacing — must be found and flagged. Closed form bound: the
/// simply supported Euler–Bernoulli span, f = (π/s)² √(EI/ρA) / 2π (≈ 1.31 kHz for UIC54,
/// s = 0.6 m); shear and rotary inertia lower it (docs/theory.md §3.6: about 1.0–1.1 kHz), the
/// coarse fully integrated hex8 mesh raises it.
/// Run: `cargo test --release --lib classify::tests::pinned -- --ignored` (~10 s in dev).
#[test]
#[ignore = "eigen solve of a 4-bay rail (~10 s)"]
fn pinned_pinned_mode_on_rigid_point_supports() {
    let t = custom_track(
        "{x={rigid=\"columns\",indices=[1]},y={rigid=\"none\",indices=[]},z={rigid=\"columns\",indices=[1]}}",
    );
    let (f, cl) = solve_and_classify(&t, 1500.0);
    let m = &t.materials[crate::structure::track::RAIL_MATERIAL];
    let sp = t.section_properties;
    let s = t.layout.sleepers[1] - t.layout.sleepers[0];
    let k = std::f64::consts::PI / s;
    let f_euler =
        k * k * (m.youngs_modulus * sp.i_vertical_bending_m4 / (m.density * sp.area_m2)).sqrt()
            / (2.0 * std::f64::consts::PI);
    for (fi, c) in f.iter().zip(&cl) {
        eprintln!(
            "{fi:8.1} Hz {:?} λ {:?} pp {}",
            c.family, c.wavelength_m, c.pinned_pinned
        );
    }
    let pp: Vec<f64> = f
        .iter()
        .zip(&cl)
        .filter(|(_, c)| c.pinned_pinned)
        .map(|(&x, _)| x)
        .collect();
    eprintln!("pinned-pinned modes {pp:?} Hz, Euler span {f_euler:.0} Hz");
    assert!(!pp.is_empty(), "no pinned-pinned mode below 1.5 kHz");
    // Measured: one flagged mode at 1298.3 Hz vs 1296.6 Hz (Euler span). Shear and rotary
    // inertia would lower it ~15 %, but this coarse hex8 mesh (0.05 m, fully integrated, stiff
    // in bending) and the supports acting on the foot (x held there too) raise it; the band
    // checks the mode is the first-pass-band top of a 0.6 m span, not a mode of another span.
    assert!(
        pp.iter().all(|&x| x > 0.75 * f_euler && x < 1.15 * f_euler),
        "{pp:?} vs {f_euler}"
    );
}

fn small_wheel() -> WheelStructure {
    let o: Vec<String> = ["mesh.wheel_segments=16", "mesh.wheel_element_size=0.05"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    WheelStructure::build(&load_model(&ModelSource::Builtin, &o).unwrap()).unwrap()
}

/// Free vector of `f(x, y, z)` on the wheel nodes (sprung node still).
fn wheel_field(w: &WheelStructure, f: impl Fn(f64, f64, f64) -> [f64; 3]) -> Vec<f64> {
    let mut u = vec![0.0; 3 * w.mesh.nodes.len()];
    for (n, p) in w.mesh.nodes.iter().enumerate() {
        if n != w.sprung_node {
            u[3 * n..3 * n + 3].copy_from_slice(&f(p[0], p[1], p[2]));
        }
    }
    w.dofmap.restrict(&u).unwrap()
}

#[test]
fn wheel_fields_of_known_shape() {
    let w = small_wheel();
    // Rigid translation along x: no strain energy anywhere (conservation: a rigid motion of
    // a solid stores none; the suspension acts in z only).
    let r = classify_wheel_mode(&w, &wheel_field(&w, |_, _, _| [1.0, 0.0, 0.0]), 0.0).unwrap();
    assert_eq!(r.family, WheelFamily::Rigid);
    assert!(r.rigid);
    // Umbrella: u_y = (r/R)², axial everywhere, elastic.
    let rr = w.params.radius_m;
    let um = wheel_field(&w, |x, _, z| [0.0, (x * x + z * z) / (rr * rr), 0.0]);
    let r = classify_wheel_mode(&w, &um, 500.0).unwrap();
    assert_eq!(r.family, WheelFamily::Axial, "{r:?}");
    assert!(r.energy_wheel > 0.99 && (r.rim_shares[1] - 1.0).abs() < 1e-12);
    // Uniform radial expansion u = ε (x, 0, z): radial, elastic.
    let ex = wheel_field(&w, |x, _, z| [1e-3 * x, 0.0, 1e-3 * z]);
    let r = classify_wheel_mode(&w, &ex, 500.0).unwrap();
    assert_eq!(r.family, WheelFamily::Radial, "{r:?}");
    assert!((r.rim_shares[0] - 1.0).abs() < 1e-12);
    assert!(matches!(
        classify_wheel_mode(&w, &[1.0], 1.0),
        Err(ClassifyError::Length { .. })
    ));
    // The batch (one element pass for all modes) gives each mode's own classification.
    let batch = classify_wheel_modes(&w, &[&um, &ex], &[500.0, 500.0]).unwrap();
    for (b, one) in batch
        .iter()
        .zip([classify_wheel_mode(&w, &um, 500.0).unwrap(), r])
    {
        assert_eq!((b.family, b.rigid), (one.family, one.rigid));
        assert!((b.energy_wheel - one.energy_wheel).abs() < 1e-12);
        assert!((b.energy_suspension - one.energy_suspension).abs() < 1e-12);
        assert_eq!(b.rim_shares, one.rim_shares);
    }
    assert!(matches!(
        classify_wheel_modes(&w, &[&um, &ex], &[500.0]),
        Err(ClassifyError::Count { .. })
    ));
}

/// A sleeper-dominated mode (sleepers carry most of the kinetic energy) during which the rail
/// moves as a bar along x: `family` is `sleeper` (the override), and `rail_family` reports
/// the rail's longitudinal compression, so such modes are not lost to the LC count.
#[test]
fn sleeper_mode_keeps_the_rail_family() {
    let t = small_track();
    let c = TrackClassifier::new(&t).unwrap();
    let n_rail = t.rail.n_planes() * t.rail.n_section_nodes();
    let l = t.rail.planes_x_m[t.rail.n_planes() - 1];
    // Rail: u_x = 0.1 sin(2π x / l) (in phase over the section); sleepers: u_x = 1.
    let mut u = rail_field(&t, |x, _, _| {
        [0.1 * (2.0 * std::f64::consts::PI * x / l).sin(), 0.0, 0.0]
    });
    for s in n_rail..t.mesh.nodes.len() {
        u[3 * s] = 1.0;
    }
    let r = c.classify_shape(&u, Default::default()).unwrap();
    assert!(r.sleeper_kinetic_share > SLEEPER_KINETIC_SHARE, "{r:?}");
    assert_eq!(r.family, TrackFamily::Sleeper);
    assert_eq!(
        r.rail_family,
        Some(TrackFamily::LongitudinalCompression),
        "{r:?}"
    );
    // Without the sleepers moving the same rail field is LC itself.
    for s in n_rail..t.mesh.nodes.len() {
        u[3 * s] = 0.0;
    }
    let r = c.classify_shape(&u, Default::default()).unwrap();
    assert_eq!(r.family, TrackFamily::LongitudinalCompression);
    assert_eq!(r.rail_family, Some(r.family));
}

//! The wheel substructure against rigid-body kinematics and the static load.

use corrugation::fe::assembly::apply_full_stiffness;
use corrugation::model::Model;
use corrugation::structure::WheelStructure;

fn relative_force(w: &WheelStructure, u: &[f64]) -> f64 {
    let f = apply_full_stiffness(&w.mesh, &w.materials, &w.springs, u).unwrap();
    // Only free DOFs count (held DOFs carry reactions by definition).
    (0..f.len())
        .filter(|&d| !w.dofmap.is_constrained(d))
        .map(|d| f[d].abs())
        .fold(0.0, f64::max)
}

#[test]
fn rigid_body_motions_are_stress_free_and_the_suspension_carries_the_static_load() {
    let m = Model::default_model();
    let w = WheelStructure::build(&m).unwrap();
    let n = w.mesh.nodes.len();
    // Scale: a unit vertical displacement of the whole wheel without the sprung mass stretches
    // the primary suspension: force = k_primary.
    let mut uz = vec![0.0; 3 * n];
    for i in 0..n {
        if i != w.sprung_node {
            uz[3 * i + 2] = 1.0;
        }
    }
    let f = apply_full_stiffness(&w.mesh, &w.materials, &w.springs, &uz).unwrap();
    let on_sprung = f[3 * w.sprung_node + 2];
    assert!((on_sprung + m.vehicle.primary_stiffness).abs() < 1e-6 * m.vehicle.primary_stiffness);
    let energy: f64 = w.springs.iter().map(|s| s.energy(&uz)).sum();
    assert!(
        (energy - 0.5 * m.vehicle.primary_stiffness).abs() < 1e-9 * m.vehicle.primary_stiffness
    );

    // Rigid-body motions the constraints leave free: K u = 0 (relative to element forces of a
    // unit strain-like field, 1e-9 of the steel stiffness scale).
    let scale = m.wheel.youngs_modulus * 0.05; // N per m of a typical element
    let mut ux = vec![0.0; 3 * n];
    for i in 0..n {
        ux[3 * i] = 1.0;
    }
    assert!(relative_force(&w, &ux) < 1e-9 * scale, "x translation");
    // Vertical translation of everything, sprung mass included.
    let mut uz_all = uz.clone();
    uz_all[3 * w.sprung_node + 2] = 1.0;
    assert!(relative_force(&w, &uz_all) < 1e-9 * scale, "z translation");
    // Small rotation about the axle (y axis): u = θ × r = (θ z, 0, −θ x); the sprung mass node
    // sits on the axle line at x = 0, so it does not move vertically.
    let mut rot = vec![0.0; 3 * n];
    for (i, p) in w.mesh.nodes.iter().enumerate() {
        if i != w.sprung_node {
            rot[3 * i] = p[2];
            rot[3 * i + 2] = -p[0];
        }
    }
    assert!(
        relative_force(&w, &rot) < 1e-9 * scale,
        "rotation about the axle"
    );
    // Held: lateral DOFs of the symmetry plane and x, y of the sprung mass.
    for node in w.topology.symmetry_plane_nodes() {
        assert!(w.dofmap.is_constrained(3 * node + 1));
    }
    assert!(
        w.dofmap.is_constrained(3 * w.sprung_node)
            && !w.dofmap.is_constrained(3 * w.sprung_node + 2)
    );

    // Static load: (sprung + unsprung) g = wheel_load.
    let total = (w.sprung_mass + w.unsprung_mass) * m.vehicle.gravity;
    assert!((total - m.vehicle.wheel_load).abs() < 1e-9 * m.vehicle.wheel_load);
    // Half wheelset within the 600–900 kg of docs/theory.md §3.6.
    assert!(
        w.unsprung_mass > 600.0 && w.unsprung_mass < 900.0,
        "{}",
        w.unsprung_mass
    );
}

#[test]
fn a_wheel_load_below_the_wheel_weight_is_a_clear_error() {
    let m = corrugation::model::load_model(
        &corrugation::model::ModelSource::Builtin,
        &["vehicle.wheel_load=1000".to_string()],
    )
    .unwrap();
    let e = WheelStructure::build(&m).unwrap_err().to_string();
    assert!(e.contains("vehicle.wheel_load"), "{e}");
}

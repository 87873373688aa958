//! The wheel substructure against rigid-body kinematics and the static load.

mod common;

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

/// The wheel's elastic flexibility at the contact (the passage's inertia relief: one LDLᵀ of
/// K held at statically determinate DOFs) against an independent direct solve of the free
/// wheel without supports: for the balanced load `Pb` (rigid part removed),
/// `f(σ) = bᵀ(K + σM)⁻¹Pb = Σ_{elastic} (φᵀb)²/(ω² + σ) = G − σS + O(σ²)`, so
/// `2f(σ) − f(2σ) = G + O(σ²)`; with σ = 10 rad²/s², below the lowest elastic ω² (the
/// primary bounce, ≈ 1.7e3), G to 1e-4 in x, t and n (the shifted solve's round-off, its
/// condition number ω_max²/σ, limits it to about 1e-5). And the residual of the kept modes
/// below 1.5 kHz is above 10 % of the Hertz compliance (a truncated basis is too stiff at the
/// contact).
#[test]
fn wheel_residual_flexibility_matches_an_independent_shifted_solve() {
    use corrugation::dynamics::reduced::{ContactFrame, WheelContact};
    use corrugation::dynamics::wheel_residual::{WheelModes, WheelResidual};
    let o: Vec<String> = common::SMALL_MODEL
        .chunks(2)
        .map(|c| c[1].to_string())
        .chain(["run.fmax=1500".to_string()])
        .collect();
    let m = corrugation::model::load_model(&corrugation::model::ModelSource::Builtin, &o).unwrap();
    let w = WheelStructure::build(&m).unwrap();
    let (mats, _) = w.assemble().unwrap();
    let cache = corrugation::eigen::cache::ModalCache::new(
        std::env::temp_dir().join("corrugation-test-cache-wheel-residual"),
    );
    let basis = corrugation::eigen::basis::wheel_basis(&m, &w, &cache, m.run.fmax).unwrap();
    let hz = corrugation::dynamics::reduced::rayleigh_frequencies_hz(mats.k.as_ref(), &basis.modes);
    let omega2: Vec<f64> = hz
        .iter()
        .map(|&f| {
            if f < corrugation::dynamics::passage::RIGID_HZ {
                0.0
            } else {
                (2.0 * std::f64::consts::PI * f).powi(2)
            }
        })
        .collect();
    let frame = ContactFrame::for_inclination(m.rail.inclination);
    let b_m = 5.4e-3;
    let r = WheelResidual::compute(WheelModes {
        wheel: &w,
        k: mats.k.as_ref(),
        m: mats.m.as_ref(),
        modes: &basis.modes,
        omega2: &omega2,
        frame: &frame,
        half_width_m: b_m,
    })
    .unwrap();
    eprintln!("{} wheel modes: {r:?}", omega2.len());
    assert_eq!(r.rigid_modes, 3);
    // The independent solve.
    let n = w.dofmap.n_free();
    let nodes = WheelContact::ring_nodes(&w, w.topology.contact_angle_index(), b_m);
    let sys = corrugation::eigen::factor::ShiftedSystem::new(
        mats.k.as_ref(),
        mats.m.as_ref(),
        corrugation::eigen::FillOrdering::Auto,
        faer::Par::Seq,
    )
    .unwrap();
    let mut rhs = faer::Mat::<f64>::zeros(n, 3);
    let mut loads = Vec::new();
    for d in 0..3 {
        let mut force = [0.0; 3];
        force[d] = 1.0;
        let mut b = vec![0.0; n];
        corrugation::dynamics::reduced::add_nodes_load(
            &nodes, &w.dofmap, &frame, 1.0, force, &mut b,
        );
        loads.push(b);
    }
    // Pb = b − M Φ_r Φ_rᵀ b with the basis' rigid modes (M-orthonormal).
    let mv = |x: &[f64]| {
        let a = mats.m.as_ref();
        let (cp, ri, v) = (a.symbolic().col_ptr(), a.symbolic().row_idx(), a.val());
        let mut y = vec![0.0; n];
        for j in 0..n {
            for p in cp[j]..cp[j + 1] {
                y[ri[p]] += v[p] * x[j];
            }
        }
        y
    };
    let balanced: Vec<Vec<f64>> = loads
        .iter()
        .map(|b| {
            let mut pb = b.clone();
            for c in (0..omega2.len()).filter(|&c| omega2[c] == 0.0) {
                let phi: Vec<f64> = (0..n).map(|i| basis.modes[(i, c)]).collect();
                let a: f64 = (0..n).map(|i| phi[i] * b[i]).sum();
                let mphi = mv(&phi);
                pb.iter_mut().zip(&mphi).for_each(|(x, y)| *x -= a * y);
            }
            pb
        })
        .collect();
    let sigma = 10.0;
    let mut f = [[0.0; 2]; 3];
    for (si, sg) in [sigma, 2.0 * sigma].into_iter().enumerate() {
        let fac = sys.factorize(-sg).unwrap().expect("K + σM is regular");
        for d in 0..3 {
            for i in 0..n {
                rhs[(i, d)] = balanced[d][i];
            }
        }
        let mut ws = sys.solve_buffer(3);
        sys.solve_in_place(&fac, rhs.as_mut(), &mut ws);
        for (d, fd) in f.iter_mut().enumerate() {
            fd[si] = (0..n).map(|i| loads[d][i] * rhs[(i, d)]).sum();
        }
    }
    for (d, fd) in f.iter().enumerate() {
        let g = 2.0 * fd[0] - fd[1];
        eprintln!(
            "direction {d}: inertia relief {:.6e}, shifted solves {g:.6e} m/N (f(σ) {:.6e})",
            r.static_m_per_n[d], fd[0]
        );
        assert!(
            (r.static_m_per_n[d] - g).abs() < 1e-4 * g,
            "{d}: {} vs {g}",
            r.static_m_per_n[d]
        );
        let sum = r.modal_m_per_n[d] + r.point_residual_m_per_n[d];
        assert!((sum - g).abs() < 1e-4 * g);
        // Not negligible against the Hertz compliance (6.9e-10 m/N at 100 kN): above 10 % of it.
        assert!(
            r.point_residual_m_per_n[d] > 6.9e-11 && r.structural_m_per_n[d] > 0.0,
            "{d}"
        );
    }
}

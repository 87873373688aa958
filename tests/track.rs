//! The assembled track substructure against closed forms and conservation laws.

use corrugation::fe::assembly::{apply_full_stiffness, mass_per_part};
use corrugation::fe::solve::static_solve;
use corrugation::mesh::Part;
use corrugation::model::{load_model, Model, ModelSource, RigidRegion};
use corrugation::structure::layout::Layout;
use corrugation::structure::TrackStructure;

/// A smaller track that keeps the physics (10 bays, coarser mesh) so tests stay fast.
fn small(extra: &[&str]) -> Model {
    let mut o: Vec<String> = [
        "track.bays=10",
        "mesh.element_length=0.06",
        "mesh.fine_element_length=0.06",
        "mesh.section_size=0.03",
        "mesh.head_size=0.015",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    o.extend(extra.iter().map(|s| s.to_string()));
    load_model(&ModelSource::Builtin, &o).unwrap()
}

#[test]
fn static_deflection_matches_beam_on_elastic_foundation_and_reactions_balance_the_load() {
    let m = small(&["fastening.model=RPM3"]);
    let t = TrackStructure::build(&m).unwrap();
    let (mats, _) = t.assemble().unwrap();
    // 100 kN down at mid-span (x = L/2 lies midway between two sleepers for an even bay count),
    // shared equally by the running-surface nodes of the nearest node plane.
    let p_load = 100e3;
    let l = t.layout.length;
    let plane = (0..t.rail.n_planes())
        .min_by(|&a, &b| {
            (t.rail.planes_x_m[a] - l / 2.0)
                .abs()
                .total_cmp(&(t.rail.planes_x_m[b] - l / 2.0).abs())
        })
        .unwrap();
    assert!(
        (t.rail.planes_x_m[plane] - l / 2.0).abs() < 0.031,
        "a node plane near mid-span"
    );
    let top = t.rail.running_surface_nodes(plane);
    let mut f_full = vec![0.0; 3 * t.mesh.nodes.len()];
    for &n in &top {
        f_full[3 * n + 2] = -p_load / top.len() as f64;
    }
    let f = t.dofmap.restrict(&f_full).unwrap();
    let u = static_solve(&mats.k, &f).unwrap();
    let u_full = t.dofmap.expand(&u).unwrap();

    // Deflection of the rail at the load: the mean vertical displacement of the section's
    // foot-underside nodes (away from the local Hertz-like indentation under the load).
    let foot = t.rail.foot_underside_nodes(plane);
    let w = -foot.iter().map(|&n| u_full[3 * n + 2]).sum::<f64>() / foot.len() as f64;
    // Closed form (Winkler beam, Hetényi): w0 = P β / (2 k), β = (k / 4EI)^(1/4), with k the
    // support stiffness per metre: railpad and ballast in series per sleeper, over the spacing.
    let k_support =
        1.0 / (1.0 / m.fastening.springs.vertical_stiffness + 1.0 / m.ballast.vertical_stiffness);
    let k = k_support / m.track.sleeper_spacing;
    let ei = m.rail.youngs_modulus * t.section_properties.i_vertical_bending_m4;
    let beta = (k / (4.0 * ei)).powf(0.25);
    let w0 = p_load * beta / (2.0 * k);
    println!(
        "static deflection: FE {:.4} mm, Winkler beam {:.4} mm",
        w * 1e3,
        w0 * 1e3
    );
    assert!(
        w > 0.5e-3 && w < 1.5e-3,
        "plausible order (0.5-1.5 mm): {w}"
    );
    // Discrete supports at mid-span, shear and sleeper flexibility add a few per cent.
    assert!((w - w0).abs() / w0 < 0.10, "FE {w} vs BOEF {w0}");

    // Equilibrium: ballast spring forces + reactions at held DOFs = applied load, per direction.
    let ku = apply_full_stiffness(&t.mesh, &t.materials, &t.springs, &u_full).unwrap();
    for d in 0..3 {
        // Reaction at a held DOF: R = (K_full u − f); a ground spring (no second side) pushes
        // the structure with −k r. Equilibrium of the whole track: Σ f + Σ R − Σ k r = 0.
        let held: f64 = t
            .dofmap
            .constrained_dofs()
            .filter(|g| g % 3 == d)
            .map(|g| ku[g] - f_full[g])
            .sum();
        let ground: f64 = t
            .springs
            .iter()
            .filter(|s| s.side_b.is_empty() && s.side_a[0].0 % 3 == d)
            .map(|s| s.stiffness * s.relative_displacement(&u_full))
            .sum();
        let applied: f64 = f_full.iter().skip(d).step_by(3).sum();
        let residual = applied + held - ground;
        println!("direction {d}: held {held:.6e} N, ground springs {ground:.6e} N, applied {applied:.6e} N");
        assert!(
            residual.abs() <= 1e-9 * p_load,
            "direction {d}: residual {residual:e} N"
        );
    }
}

#[test]
fn rail_mass_per_metre_and_section_match_54e1() {
    let m = Model::default_model();
    let t = TrackStructure::build(&m).unwrap();
    let mass = mass_per_part(&t.mesh, &t.materials).unwrap();
    let per_m = mass.get(Part::Rail) / t.layout.length;
    // EN 13674-1 54E1: 54.77 kg/m (at 7850 kg/m³); with ρ = 7800: A·ρ = 6977e-6·7800 = 54.42.
    assert!((per_m - 54.77).abs() / 54.77 < 0.01, "{per_m} kg/m");
    let sp = t.section_properties;
    assert!(
        (sp.area_m2 - 6977e-6).abs() / 6977e-6 < 0.01,
        "area {}",
        sp.area_m2
    );
    assert!((sp.i_vertical_bending_m4 - 2338e-8).abs() / 2338e-8 < 0.03);
    assert!((sp.i_lateral_bending_m4 - 419.2e-8).abs() / 419.2e-8 < 0.03);
    assert!((sp.centroid_z_m - 0.0751).abs() < 1e-3);
    // Sleepers: volume × density.
    let sleeper = m.sleeper.length * m.sleeper.width * m.sleeper.height * m.sleeper.density;
    assert!((mass.get(Part::Sleeper) - sleeper * m.track.bays as f64).abs() < 1e-6 * sleeper);
}

/// Upright lateral coordinate of a node (undo the cant about the foot centre).
fn upright_y(m: &Model, p: [f64; 3]) -> f64 {
    let th = m.rail.inclination.atan();
    p[1] * th.cos() + p[2] * th.sin()
}

#[test]
fn fastening_models_hold_exactly_the_dofs_of_the_method_table() {
    for name in ["RPM1", "RPM2", "RPM3", "RPM4", "RPM5"] {
        let set = format!("fastening.model={name}");
        let m = small(&[&set]);
        let t = TrackStructure::build(&m).unwrap();
        let l = Layout::new(&m);
        let hold = m.fastening.hold_pattern();
        let w = m.fastening.strip_width / 2.0 + 1e-7;
        let foot: std::collections::HashSet<usize> = (0..t.rail.n_planes())
            .flat_map(|i| t.rail.foot_underside_nodes(i))
            .collect();
        // Independent predicate from node coordinates: is DOF (node, d) in a held region?
        let expected = |n: usize, d: usize| -> bool {
            if !foot.contains(&n) {
                return false;
            }
            let p = t.mesh.nodes[n];
            let h = [&hold.x, &hold.y, &hold.z][d];
            match h.rigid {
                RigidRegion::None => false,
                RigidRegion::GridPoints => unreachable!("no preset holds grid points"),
                RigidRegion::Continuous => true,
                RigidRegion::Columns => l.sleepers.iter().any(|&xs| {
                    h.indices
                        .iter()
                        .any(|&c| (p[0] - l.column_centre(xs, c)).abs() <= w)
                }),
                RigidRegion::Rows => l.sleepers.iter().any(|&xs| {
                    (p[0] - xs).abs() <= l.footprint_length / 2.0 + 1e-7
                        && h.indices
                            .iter()
                            .any(|&r| (upright_y(&m, p) - l.row_centre(r)).abs() <= w)
                }),
            }
        };
        let mut counts = [0usize; 3];
        for n in 0..t.mesh.nodes.len() {
            for (d, count) in counts.iter_mut().enumerate() {
                let held = t.dofmap.is_constrained(3 * n + d);
                assert_eq!(
                    held,
                    expected(n, d),
                    "{name}: node {n} dir {d} at {:?}",
                    t.mesh.nodes[n]
                );
                *count += held as usize;
            }
        }
        println!(
            "{name}: held DOFs x {} y {} z {}",
            counts[0], counts[1], counts[2]
        );
        // The table itself: which directions are held at all, and how much.
        let n_foot = foot.len();
        match name {
            "RPM1" | "RPM3" => assert!(counts[0] > 0 && counts[0] < n_foot && counts[2] == 0),
            "RPM2" => assert!(counts[0] == n_foot && counts[2] == 0),
            "RPM4" => assert!(counts[0] > 0 && counts[0] < n_foot && counts[2] == n_foot),
            "RPM5" => assert!(counts[0] == n_foot && counts[2] == n_foot),
            _ => unreachable!(),
        }
        assert!(
            counts[1] > 0 && counts[1] < n_foot,
            "lateral rows held over footprints only"
        );
    }
    // Mesh independence of the held regions: for RPM1 and RPM3 the held x planes of each
    // column span exactly the strip [x_c − w/2, x_c + w/2], whatever the grading put inside.
    for (name, cols) in [("RPM1", vec![0, 1, 2]), ("RPM3", vec![1])] {
        for h in [0.06, 0.035] {
            let set = format!("fastening.model={name}");
            let eh = format!("mesh.element_length={h}");
            let fh = format!("mesh.fine_element_length={h}");
            let m = small(&[&set, &eh, &fh]);
            let t = TrackStructure::build(&m).unwrap();
            let l = Layout::new(&m);
            let w = m.fastening.strip_width / 2.0;
            for &xs in &l.sleepers {
                for &c in &cols {
                    let xc = l.column_centre(xs, c);
                    let held: Vec<f64> = (0..t.rail.n_planes())
                        .filter(|&i| {
                            t.dofmap
                                .is_constrained(3 * t.rail.foot_underside_nodes(i)[0])
                        })
                        .map(|i| t.rail.planes_x_m[i])
                        .filter(|x| (x - xc).abs() < 0.03)
                        .collect();
                    let lo = held.iter().cloned().fold(f64::INFINITY, f64::min);
                    let hi = held.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                    assert!(
                        (lo - (xc - w)).abs() < 1e-9 && (hi - (xc + w)).abs() < 1e-9,
                        "{name} h={h}: {held:?} vs {xc}±{w}"
                    );
                }
            }
        }
    }
}

#[test]
fn railpad_and_ballast_stiffness_sum_to_the_model_values() {
    // Spreading by tributary area must not change the total stiffness: a rigid vertical
    // translation of the rail relative to fixed sleepers stretches every pad spring by 1.
    let m = small(&[]);
    let t = TrackStructure::build(&m).unwrap();
    use corrugation::structure::track::SpringKind;
    let mut u = vec![0.0; 3 * t.mesh.nodes.len()];
    for i in 0..t.rail.n_planes() {
        for j in 0..t.rail.n_section_nodes() {
            u[3 * t.rail.node(i, j) + 2] = 1.0;
        }
    }
    let total: f64 = t
        .springs
        .iter()
        .zip(&t.spring_kinds)
        .filter(|(_, k)| **k == SpringKind::Fastening)
        .map(|(s, _)| s.stiffness * s.relative_displacement(&u).powi(2))
        .sum();
    let want = m.fastening.springs.vertical_stiffness * m.track.bays as f64;
    assert!((total - want).abs() < 1e-9 * want, "{total} vs {want}");
    let ballast_z: f64 = t
        .springs
        .iter()
        .zip(&t.spring_kinds)
        .filter(|(s, k)| **k == SpringKind::Ballast && s.side_a[0].0 % 3 == 2)
        .map(|(s, _)| s.stiffness)
        .sum();
    let want = m.ballast.vertical_stiffness * m.track.bays as f64;
    assert!((ballast_z - want).abs() < 1e-9 * want);
}

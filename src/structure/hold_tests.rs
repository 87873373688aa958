//! Elastic holds against closed forms: their springs sum to the stated stiffness per
//! fastening, a preset made elastic equals the same custom pattern, the rail's longitudinal
//! cut-on on elastic x-holds is √(k/m)/2π, and k → ∞ reproduces the rigid hold.

use faer::sparse::SparseColMat;

use super::track::{SpringKind, TrackStructure};
use crate::eigen::{solve, EigenOptions};
use crate::fe::assembly::mass_per_part;
use crate::mesh::Part;
use crate::model::Model;

/// A short, coarse track (4 bays): the physics of the holds, fast to build and solve.
fn short(extra: &[&str]) -> Model {
    let coarse = ["mesh.section_size=0.04", "mesh.head_size=0.02"];
    let sets: Vec<&str> = coarse.iter().chain(extra).copied().collect();
    crate::model::test_problems::small_model_with_elements(0.1, &sets).unwrap()
}

fn custom_x(x: &str) -> Model {
    short(&[
        "fastening.model=custom",
        &format!("fastening.custom.x={x}"),
        "fastening.custom.y={ rigid = \"rows\", indices = [0, 1, 2, 3] }",
        "fastening.custom.z={ rigid = \"none\" }",
    ])
}

/// The hold springs: every one grounded, on one rail-foot DOF in direction `d`; their
/// stiffness sum (N/m).
fn hold_sum(t: &TrackStructure, d: usize) -> (f64, f64, usize) {
    let foot: std::collections::HashSet<usize> = (0..t.rail.n_planes())
        .flat_map(|i| t.rail.foot_underside_nodes(i))
        .collect();
    let (mut k, mut c, mut n) = (0.0, 0.0, 0);
    for (s, kind) in t.springs.iter().zip(&t.spring_kinds) {
        if *kind != SpringKind::Hold {
            continue;
        }
        assert!(s.side_b.is_empty(), "grounded");
        assert_eq!(s.side_a.len(), 1);
        let (dof, w) = s.side_a[0];
        assert_eq!((dof % 3, w), (d, 1.0), "direction {d}");
        assert!(foot.contains(&(dof / 3)), "on the foot underside");
        k += s.stiffness;
        c += s.damping;
        n += 1;
    }
    (k, c, n)
}

#[test]
fn elastic_hold_springs_sum_to_the_stated_stiffness_per_fastening() {
    let k = 1e9;
    for region in [
        "elastic = \"columns\", indices = [1]",
        "elastic = \"columns\", indices = [0, 2]",
        "elastic = \"rows\", indices = [0, 3]",
        "elastic = \"continuous\"",
        "elastic = \"grid_points\"",
    ] {
        let m = custom_x(&format!("{{ {region}, stiffness = {k:e}, damping = 2e4 }}"));
        let t = TrackStructure::build(&m).unwrap();
        let (sum_k, sum_c, n) = hold_sum(&t, 0);
        let bays = m.track.bays as f64;
        assert!(
            (sum_k - k * bays).abs() < 1e-9 * k * bays,
            "{region}: {sum_k:e}"
        );
        assert!(
            (sum_c - 2e4 * bays).abs() < 1e-9 * 2e4 * bays,
            "{region}: {sum_c:e}"
        );
        // Nothing is fixed in x: the hold is elastic.
        let fixed_x = (0..t.mesh.nodes.len())
            .filter(|&i| t.dofmap.is_constrained(3 * i))
            .count();
        assert_eq!(fixed_x, 0, "{region}");
        if region.contains("grid_points") {
            assert_eq!(n, 12 * m.track.bays, "one node per grid point");
        }
        println!("{region}: {n} springs, Σk = {sum_k:e} N/m");
    }
}

#[test]
fn rigid_grid_points_fix_one_node_per_grid_point() {
    let m = custom_x("{ rigid = \"grid_points\" }");
    let t = TrackStructure::build(&m).unwrap();
    let l = &t.layout;
    let held: Vec<usize> = (0..t.mesh.nodes.len())
        .filter(|&i| t.dofmap.is_constrained(3 * i))
        .collect();
    assert_eq!(held.len(), l.rows * l.columns * l.sleepers.len());
    let th = m.rail.inclination.atan();
    for &n in &held {
        let [x, y, z] = t.mesh.nodes[n];
        // Upright lateral coordinate (undo the cant).
        let y = y * th.cos() + z * th.sin();
        let at_grid_point = l
            .sleepers
            .iter()
            .any(|&xs| (0..l.columns).any(|c| (x - l.column_centre(xs, c)).abs() < 1e-7))
            && (0..l.rows).any(|r| (y - l.row_centre(r)).abs() < 1e-6);
        assert!(at_grid_point, "node {n} at ({x}, {y})");
    }
}

fn same_matrix(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> bool {
    a.col_ptr() == b.col_ptr() && a.row_idx() == b.row_idx() && a.val() == b.val()
}

#[test]
fn elastic_preset_equals_the_same_custom_pattern() {
    // RPM3 with hold = "elastic" in x: the middle column on springs of 1e9 N/m per fastening,
    // the lateral rows still rigid.
    let preset = short(&[
        "fastening.model=RPM3",
        "fastening.hold=\"elastic\"",
        "fastening.hold_stiffness=1e9",
        "fastening.hold_damping=3e3",
        "fastening.hold_directions=[\"x\"]",
    ]);
    let custom =
        custom_x("{ elastic = \"columns\", indices = [1], stiffness = 1e9, damping = 3e3 }");
    let (a, _) = TrackStructure::build(&preset).unwrap().assemble().unwrap();
    let (b, _) = TrackStructure::build(&custom).unwrap().assemble().unwrap();
    assert!(same_matrix(&a.k, &b.k) && same_matrix(&a.m, &b.m) && same_matrix(&a.c, &b.c));
    // hold_directions defaults to all: the lateral rows become elastic too.
    let all = short(&[
        "fastening.model=RPM3",
        "fastening.hold=\"elastic\"",
        "fastening.hold_stiffness=1e9",
    ]);
    let t = TrackStructure::build(&all).unwrap();
    assert_eq!(t.dofmap.n_constrained(), 0);
    assert!((hold_sum_all(&t) - 2e9 * all.track.bays as f64).abs() < 1e-9 * 8e9);
}

fn hold_sum_all(t: &TrackStructure) -> f64 {
    t.springs
        .iter()
        .zip(&t.spring_kinds)
        .filter(|(_, k)| **k == SpringKind::Hold)
        .map(|(s, _)| s.stiffness)
        .sum()
}

/// Modes of the track below `f_max` (Hz): frequencies and, per mode, the fraction of the rail's
/// mass that moves with it as a rigid translation along x (effective modal mass, 0 to 1).
fn longitudinal_participation(t: &TrackStructure, f_max: f64) -> (Vec<f64>, Vec<f64>) {
    let (mats, _) = t.assemble().unwrap();
    let mut opts = EigenOptions::new(f_max);
    opts.parallel = false;
    let sol = solve(mats.k.as_ref(), mats.m.as_ref(), &opts, None).unwrap();
    let n = t.dofmap.n_free();
    let mut r_full = vec![0.0; 3 * t.mesh.nodes.len()];
    for i in 0..t.rail.n_planes() {
        for j in 0..t.rail.n_section_nodes() {
            r_full[3 * t.rail.node(i, j)] = 1.0;
        }
    }
    let r = t.dofmap.restrict(&r_full).unwrap();
    // M r (CSC, full storage).
    let mut mr = vec![0.0; n];
    let (cp, ri, v) = (mats.m.col_ptr(), mats.m.row_idx(), mats.m.val());
    for j in 0..n {
        for p in cp[j]..cp[j + 1] {
            mr[ri[p]] += v[p] * r[j];
        }
    }
    let rail_mass: f64 = r.iter().zip(&mr).map(|(a, b)| a * b).sum();
    let part = (0..sol.modes.ncols())
        .map(|k| {
            let g: f64 = (0..n).map(|i| sol.modes[(i, k)] * mr[i]).sum();
            g * g / rail_mass
        })
        .collect();
    (sol.frequencies_hz, part)
}

#[test]
fn longitudinal_cut_on_on_elastic_x_holds_is_sqrt_k_over_m() {
    // The rail held along x only by springs of k per fastening (no longitudinal pad, lateral
    // rows rigid, vertical railpads): its lowest longitudinal mode is the rigid translation
    // on those springs, f = √(k/m)/2π with m the rail mass per bay (ρA·s). The closed form
    // ignores the coupling with vertical bending (the holds act at the foot, below the
    // centroid) and the section's shear: a few per mille at these k.
    let k = 1e8;
    for region in [
        "elastic = \"continuous\"",
        "elastic = \"columns\", indices = [1]",
        "elastic = \"columns\", indices = [0, 1, 2]",
    ] {
        let m = custom_x(&format!("{{ {region}, stiffness = {k:e} }}"));
        let t = TrackStructure::build(&m).unwrap();
        let rail_mass = mass_per_part(&t.mesh, &t.materials)
            .unwrap()
            .get(Part::Rail);
        let m_bay = rail_mass / m.track.bays as f64;
        let f0 = (k / m_bay).sqrt() / (2.0 * std::f64::consts::PI);
        let (f, part) = longitudinal_participation(&t, 1.5 * f0);
        let (i, p) = part
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, &p)| (i, p))
            .unwrap();
        let err = (f[i] - f0) / f0;
        println!(
            "{region}: f = {:.2} Hz, closed form {f0:.2} Hz ({:+.3} %), participation {p:.4}",
            f[i],
            100.0 * err
        );
        assert!(p > 0.9, "{region}: a rail translation mode ({p})");
        assert!(err.abs() < 0.02, "{region}: {} vs {f0} Hz", f[i]);
    }
}

#[test]
fn stiff_elastic_holds_reproduce_the_rigid_holds() {
    // RPM4 holds every region kind rigidly (x: middle column, y: four rows, z: continuous);
    // the elastic variant with k = 1e13 N/m per fastening must give the same spectrum.
    let rigid = short(&["fastening.model=RPM4"]);
    let stiff = short(&[
        "fastening.model=RPM4",
        "fastening.hold=\"elastic\"",
        "fastening.hold_stiffness=1e13",
    ]);
    let f_max = 1500.0;
    let (fr, _) = longitudinal_participation(&TrackStructure::build(&rigid).unwrap(), f_max);
    let (fs, _) = longitudinal_participation(&TrackStructure::build(&stiff).unwrap(), f_max);
    assert!(fr.len() >= 10, "{} modes", fr.len());
    let n = fr.len().min(fs.len());
    let worst = (0..n)
        .map(|i| (fs[i] - fr[i]) / fr[i])
        .fold(0.0f64, |a, e| a.max(e.abs()));
    println!(
        "{} rigid / {} elastic modes below {f_max} Hz; worst relative deviation {worst:.2e}",
        fr.len(),
        fs.len()
    );
    // Springs are softer than constraints: frequencies approach from below.
    assert!((0..n).all(|i| fs[i] <= fr[i] * (1.0 + 1e-9)));
    assert!(worst < 5e-3, "{worst}");
}

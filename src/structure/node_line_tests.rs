//! Holds on node lines and the railpad's longitudinal springs against hand-built systems and
//! closed forms: a rigid node-line hold equals the elimination (and the penalty) of exactly
//! the DOFs of those lines found from the node coordinates, with reactions summing to the
//! applied force; elastic node-line springs sum to the stated stiffness per line and hold the
//! rail at `F/(n k)`; railpad x-springs hold it at `F/(n k_pad)`, and their x-dampers reach
//! the damping matrix the reduced engine reads.

use std::collections::{BTreeSet, HashMap};

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use super::track::{SpringKind, TrackStructure};
use crate::dynamics::residual::StiffnessFactor;
use crate::fe::assembly::DofMap;
use crate::model::test_problems::all_modes_model;
use crate::model::Model;

/// The all-modes track (2 bays, coarse: a few thousand DOFs, quick to solve) with a
/// custom hold pattern and `extra` overrides.
fn tiny(x: &str, y: &str, z: &str, extra: &[&str]) -> Model {
    let holds = [
        "fastening.model=custom".to_string(),
        format!("fastening.custom.x={x}"),
        format!("fastening.custom.y={y}"),
        format!("fastening.custom.z={z}"),
    ];
    let mut sets: Vec<&str> = holds.iter().map(String::as_str).collect();
    sets.extend_from_slice(extra);
    all_modes_model(&sets).unwrap()
}

/// `a⁻¹ f` by the sparse LDLᵀ factorisation of a stiffness matrix.
fn solve(a: &SparseColMat<usize, f64>, f: &[f64]) -> Vec<f64> {
    let factor = StiffnessFactor::new(a.as_ref()).expect("positive definite");
    let mut x = Mat::from_fn(f.len(), 1, |i, _| f[i]);
    let mut ws = factor.workspace(1);
    factor.solve_in_place(x.as_mut(), &mut ws);
    (0..f.len()).map(|i| x[(i, 0)]).collect()
}

/// The entries `(row, column, value)` of a sparse matrix.
fn entries(a: &SparseColMat<usize, f64>) -> Vec<(usize, usize, f64)> {
    let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
    (0..a.ncols())
        .flat_map(|j| (cp[j]..cp[j + 1]).map(move |p| (ri[p], j, v[p])))
        .collect()
}

fn from_entries(n: usize, e: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
    let t: Vec<Triplet<usize, usize, f64>> =
        e.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |a, x| a.max(x.abs()))
}

/// The rail-foot underside nodes.
fn foot_nodes(t: &TrackStructure) -> BTreeSet<usize> {
    (0..t.rail.n_planes())
        .flat_map(|i| t.rail.foot_underside_nodes(i))
        .collect()
}

/// All rail nodes.
fn rail_nodes(t: &TrackStructure) -> Vec<usize> {
    (0..t.rail.n_planes())
        .flat_map(|i| (0..t.rail.n_section_nodes()).map(move |j| (i, j)))
        .map(|(i, j)| t.rail.node(i, j))
        .collect()
}

/// Upright lateral coordinate of a node (the cant about the foot centre undone).
fn upright_y(m: &Model, p: [f64; 3]) -> f64 {
    let th = m.rail.inclination.atan();
    p[1] * th.cos() + p[2] * th.sin()
}

#[test]
fn rigid_node_lines_equal_the_hand_eliminated_and_penalised_dofs() {
    // RPM1 as the reference describes it: x held on the node lines of all three pad columns,
    // y on the node lines of the four rows, z on the pads alone.
    let m = tiny(
        "{ rigid = \"columns\", indices = [0, 1, 2], node_lines = true }",
        "{ rigid = \"rows\", indices = [0, 1, 2, 3], node_lines = true }",
        "{ rigid = \"none\" }",
        &[],
    );
    let t = TrackStructure::build(&m).unwrap();
    let l = &t.layout;
    let n_dofs = 3 * t.mesh.nodes.len();

    // The held DOFs from the node coordinates alone: foot nodes on a column centre's plane
    // (x), foot nodes on a row centre's line within a footprint (y).
    let foot = foot_nodes(&t);
    let mut expected = BTreeSet::new();
    for &n in &foot {
        let p = t.mesh.nodes[n];
        let on_column = l
            .sleepers
            .iter()
            .any(|&xs| (0..l.columns).any(|c| (p[0] - l.column_centre(xs, c)).abs() < 1e-9));
        if on_column {
            expected.insert(3 * n);
        }
        let in_footprint = l
            .sleepers
            .iter()
            .any(|&xs| (p[0] - xs).abs() <= 0.5 * l.footprint_length + 1e-9);
        let on_row = (0..l.rows).any(|r| (upright_y(&m, p) - l.row_centre(r)).abs() < 1e-6);
        if in_footprint && on_row {
            expected.insert(3 * n + 1);
        }
    }
    let held: BTreeSet<usize> = t.dofmap.constrained_dofs().collect();
    assert_eq!(held, expected, "exactly the node lines' DOFs are held");
    let per_plane = t.rail.foot_underside_nodes(0).len();
    let n_x = held.iter().filter(|&&d| d % 3 == 0).count();
    assert_eq!(
        n_x,
        l.sleepers.len() * l.columns * per_plane,
        "three planes"
    );
    let n_y = held.len() - n_x;
    assert!(n_y >= l.sleepers.len() * l.rows * 2, "{n_y} y DOFs");

    // A longitudinal and a vertical force on the head nodes of the plane in the middle of
    // the track (mid-bay, not on a held line).
    let (fx, fz) = (1e4, -5e4);
    let mid = (0..t.rail.n_planes())
        .min_by(|&a, &b| {
            let d = |i: usize| (t.rail.planes_x_m[i] - 0.5 * l.length).abs();
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    let head: Vec<usize> = (0..t.rail.n_section_nodes())
        .map(|j| t.rail.node(mid, j))
        .filter(|&n| t.mesh.nodes[n][2] > 0.14)
        .collect();
    assert!(!head.is_empty());
    let mut f = vec![0.0; n_dofs];
    for &n in &head {
        f[3 * n] += fx / head.len() as f64;
        f[3 * n + 2] += fz / head.len() as f64;
    }

    // The library: K over the free DOFs.
    let (mats, _) = t.assemble().unwrap();
    let u_lib = t
        .dofmap
        .expand(&solve(&mats.k, &t.dofmap.restrict(&f).unwrap()))
        .unwrap();

    // By hand: the same structure with nothing held, its full K, then the lines' DOFs
    // eliminated (rows and columns removed), and penalised instead.
    let mut free_all = t.clone();
    free_all.dofmap = DofMap::new(t.mesh.nodes.len());
    let k0 = entries(&free_all.assemble().unwrap().0.k);
    let keep: Vec<usize> = (0..n_dofs).filter(|d| !expected.contains(d)).collect();
    let mut index = vec![usize::MAX; n_dofs];
    for (i, &d) in keep.iter().enumerate() {
        index[d] = i;
    }
    let k_red: Vec<_> = k0
        .iter()
        .filter(|&&(i, j, _)| index[i] != usize::MAX && index[j] != usize::MAX)
        .map(|&(i, j, v)| (index[i], index[j], v))
        .collect();
    let f_red: Vec<f64> = keep.iter().map(|&d| f[d]).collect();
    let mut u_hand = vec![0.0; n_dofs];
    for (&d, u) in keep
        .iter()
        .zip(solve(&from_entries(keep.len(), &k_red), &f_red))
    {
        u_hand[d] = u;
    }
    let scale = max_abs(u_lib.iter().copied());
    let diff = max_abs(u_lib.iter().zip(&u_hand).map(|(a, b)| a - b));
    // Reactions at the held DOFs: K₀u − f.
    let mut k0u = vec![0.0; n_dofs];
    for &(i, j, v) in &k0 {
        k0u[i] += v * u_hand[j];
    }
    let r: HashMap<usize, f64> = expected.iter().map(|&d| (d, k0u[d] - f[d])).collect();
    let sum_rx: f64 = r.iter().filter(|(d, _)| *d % 3 == 0).map(|(_, v)| v).sum();

    let kappa = 1e6
        * k0.iter()
            .filter(|e| e.0 == e.1)
            .fold(0.0f64, |a, e| a.max(e.2));
    let mut k_pen = k0.clone();
    k_pen.extend(expected.iter().map(|&d| (d, d, kappa)));
    let k_pen = from_entries(n_dofs, &k_pen);
    let u_pen = solve(&k_pen, &f);
    let pen_diff = max_abs(u_lib.iter().zip(&u_pen).map(|(a, b)| a - b));
    let r_scale = max_abs(r.values().copied());
    let r_diff = max_abs(expected.iter().map(|&d| r[&d] + kappa * u_pen[d]));
    println!(
        "held x {n_x} y {n_y} DOFs; max |u| {scale:.3e} m; elimination {diff:.1e} m, penalty {pen_diff:.1e} m; \
         Σ x-reactions {sum_rx:.6e} N (applied {fx:e}); reactions max {r_scale:.3e} N, penalty's off by {r_diff:.1e} N"
    );
    assert!(diff <= 1e-9 * scale, "elimination: {diff:e} of {scale:e}");
    assert!(
        pen_diff <= 1e-4 * scale,
        "penalty: {pen_diff:e} of {scale:e}"
    );
    assert!(
        r_diff <= 1e-4 * r_scale,
        "penalty reactions: {r_diff:e} of {r_scale:e}"
    );
    // Nothing else holds the rail along x: the lines take the whole longitudinal force.
    assert!((sum_rx + fx).abs() <= 1e-8 * fx, "Σ R_x = {sum_rx}");
}

/// The static mean x-displacement (m) of the rail's nodes under a longitudinal force `fx`
/// (N) spread evenly over the rail-foot underside nodes (no moment about the foot, where the
/// springs act).
fn rail_translation(t: &TrackStructure, fx: f64) -> f64 {
    let foot = foot_nodes(t);
    let mut f = vec![0.0; 3 * t.mesh.nodes.len()];
    for &n in &foot {
        f[3 * n] = fx / foot.len() as f64;
    }
    let (mats, _) = t.assemble().unwrap();
    let u = t
        .dofmap
        .expand(&solve(&mats.k, &t.dofmap.restrict(&f).unwrap()))
        .unwrap();
    let rail = rail_nodes(t);
    rail.iter().map(|&n| u[3 * n]).sum::<f64>() / rail.len() as f64
}

const ROWS_RIGID: &str = "{ rigid = \"rows\", indices = [0, 1, 2, 3] }";

#[test]
fn elastic_node_lines_carry_the_stiffness_per_line_and_hold_the_rail_at_f_over_nk() {
    // Springs: per held line (two per fastening), the stated k and c, on that line only.
    let (k, c) = (2e8, 5e3);
    let m = tiny(
        &format!(
            "{{ elastic = \"columns\", indices = [0, 2], node_lines = true, line_stiffness = {k:e}, line_damping = {c:e} }}"
        ),
        ROWS_RIGID,
        "{ rigid = \"none\" }",
        &[],
    );
    let t = TrackStructure::build(&m).unwrap();
    let l = &t.layout;
    let mut per_line: HashMap<i64, (f64, f64)> = HashMap::new();
    for (s, kind) in t.springs.iter().zip(&t.spring_kinds) {
        if *kind != SpringKind::Hold {
            continue;
        }
        assert!(
            s.side_b.is_empty() && s.side_a.len() == 1,
            "grounded, one DOF"
        );
        let (dof, w) = s.side_a[0];
        assert_eq!((dof % 3, w), (0, 1.0), "along x");
        let x = t.mesh.nodes[dof / 3][0];
        let line = l
            .sleepers
            .iter()
            .flat_map(|&xs| [0, 2].map(|col| l.column_centre(xs, col)))
            .find(|xc| (x - xc).abs() < 1e-9)
            .unwrap_or_else(|| panic!("spring at x = {x} off the held lines"));
        let e = per_line.entry((line * 1e6).round() as i64).or_default();
        e.0 += s.stiffness;
        e.1 += s.damping;
    }
    assert_eq!(per_line.len(), 2 * l.sleepers.len());
    for (kl, cl) in per_line.values() {
        assert!((kl - k).abs() <= 1e-12 * k && (cl - c).abs() <= 1e-12 * c);
    }
    assert!((0..t.mesh.nodes.len()).all(|n| !t.dofmap.is_constrained(3 * n)));

    // Soft springs on the middle column's line, the rail's only longitudinal restraint: the
    // rail translates by F/(n k) for n fastenings.
    let k = 1e6;
    let m = tiny(
        &format!(
            "{{ elastic = \"columns\", indices = [1], node_lines = true, line_stiffness = {k:e} }}"
        ),
        ROWS_RIGID,
        "{ rigid = \"none\" }",
        &[],
    );
    let t = TrackStructure::build(&m).unwrap();
    let fx = 1e3;
    let u = rail_translation(&t, fx);
    let want = fx / (m.track.bays as f64 * k);
    println!(
        "elastic middle line: u = {u:.6e} m, F/(n k) = {want:.6e} m ({:+.3} %)",
        100.0 * (u - want) / want
    );
    assert!((u - want).abs() <= 5e-3 * want, "{u} vs {want}");
}

#[test]
fn railpad_x_springs_hold_the_rail_at_f_over_n_k_pad_and_their_dampers_reach_c() {
    // No longitudinal hold: the railpad's x-springs (k_p per fastening over the 12 cells) are
    // the rail's only x restraint; in series the ballast's (k_b per half sleeper), stiff.
    let (k_p, k_b, c_p) = (1e6, 1e11, 7e3);
    let pads = [
        format!("fastening.longitudinal_stiffness={k_p:e}"),
        format!("fastening.longitudinal_damping={c_p:e}"),
        format!("ballast.longitudinal_stiffness={k_b:e}"),
        format!("ballast.lateral_stiffness={k_b:e}"),
        format!("ballast.vertical_stiffness={k_b:e}"),
    ];
    let sets: Vec<&str> = pads.iter().map(String::as_str).collect();
    let m = tiny(
        "{ rigid = \"none\" }",
        ROWS_RIGID,
        "{ rigid = \"none\" }",
        &sets,
    );
    let t = TrackStructure::build(&m).unwrap();
    let n = m.track.bays as f64;
    let fx = 1e3;
    let u = rail_translation(&t, fx);
    let want = fx / n * (1.0 / k_p + 1.0 / k_b);
    println!(
        "pad x-springs: u = {u:.6e} m, F/n (1/k_p + 1/k_b) = {want:.6e} m ({:+.3} %)",
        100.0 * (u - want) / want
    );
    assert!((u - want).abs() <= 5e-3 * want, "{u} vs {want}");

    // The x-dampers: with the rail moving at 1 m/s along x and the sleepers at rest, the
    // damper forces on the rail sum to n c_p, in the C the reduced engine projects (the
    // explicit path's C: explicit::model's tests).
    let c = t.assemble_damping().unwrap();
    let mut v = vec![0.0; 3 * t.mesh.nodes.len()];
    for n in rail_nodes(&t) {
        v[3 * n] = 1.0;
    }
    let v = t.dofmap.restrict(&v).unwrap();
    let cv = {
        let mut out = vec![0.0; v.len()];
        let (cp, ri, val) = (c.col_ptr(), c.row_idx(), c.val());
        for j in 0..v.len() {
            for p in cp[j]..cp[j + 1] {
                out[ri[p]] += val[p] * v[j];
            }
        }
        out
    };
    let on_rail: f64 = (0..v.len()).filter(|&i| v[i] == 1.0).map(|i| cv[i]).sum();
    println!(
        "pad x-dampers: Σ (C v) on the rail {on_rail:.6e} N s/m, n c_p = {:e}",
        n * c_p
    );
    assert!((on_rail - n * c_p).abs() <= 1e-9 * n * c_p, "{on_rail}");
}

/// A measurement, run on demand (`--ignored`): the rail's longitudinal translation under a
/// force spread over its foot, held along x only by the rigid node line of each fastening's
/// middle column, as the mesh is refined (section size and element length halved). A line
/// hold's compliance is that of a line load on a solid, which grows as the elements beside
/// the line shrink (docs/theory.md §3.3).
#[test]
#[ignore]
fn rigid_node_line_hold_under_mesh_refinement() {
    let fx = 1e4;
    for (section, element) in [(0.05, 0.15), (0.025, 0.075), (0.0125, 0.0375)] {
        let sizes = [
            format!("mesh.section_size={section}"),
            format!("mesh.head_size={section}"),
        ];
        let mut sets: Vec<&str> = sizes.iter().map(String::as_str).collect();
        sets.push("mesh.sleeper_elements=[2,2,2]");
        let mut m = tiny(
            "{ rigid = \"columns\", indices = [1], node_lines = true }",
            ROWS_RIGID,
            "{ rigid = \"none\" }",
            &sets,
        );
        m.mesh.element_length = element;
        m.mesh.fine_element_length = element;
        let t = TrackStructure::build(&m).unwrap();
        let u = rail_translation(&t, fx);
        println!(
            "section {section} m, elements {element} m: {} free DOFs, u = {u:.4e} m, F/u = {:.4e} N/m",
            t.dofmap.n_free(),
            fx / u
        );
    }
}

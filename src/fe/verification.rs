//! Verification of elements and assembly against closed forms (tests only).

use faer::{Mat, Side};

use super::block::{block_mesh, block_node};
use super::{
    apply_full_stiffness, assemble, hex8, mass_per_part, reactions, spring_energy, static_solve,
    strain_energy_per_part, strain_energy_per_part_many, AssemblyOptions, Direction, DofMap,
    FeError, MassKind, PointMass, Spring,
};
use crate::fe::material::IsotropicElastic;
use crate::mesh::{Mesh, Part};

const STEEL: IsotropicElastic = IsotropicElastic::STEEL;

/// Deterministic pseudo-random numbers in [−1, 1] (xorshift), for mesh distortion.
fn rng(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    (*seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// Moves every node by up to `amp` (m) in each direction.
fn distort(mesh: &mut Mesh, amp: f64) {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    for p in &mut mesh.nodes {
        for c in p.iter_mut() {
            *c += amp * rng(&mut s);
        }
    }
}

fn sym_dense(a: &faer::sparse::SparseColMat<usize, f64>) -> Mat<f64> {
    a.to_dense()
}

fn max_asym(a: &Mat<f64>) -> f64 {
    let mut m = 0.0f64;
    let mut s = 0.0f64;
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            m = m.max((a[(i, j)] - a[(j, i)]).abs());
            s = s.max(a[(i, j)].abs());
        }
    }
    m / s
}

#[test]
fn patch_test_distorted_mesh_reproduces_linear_field() {
    // 3×3×3 block of a 1 m cube, every node moved by up to ±0.12 m (elements are general
    // non-parallelepiped hexahedra). u = A x + b is imposed on the 56 boundary nodes; the
    // 8 interior nodes must reproduce it, and every element's strain energy must equal
    // ½ ε·Dε V_e (constant strain, incompatible modes inactive).
    let n = 3;
    let mut mesh = block_mesh([n, n, n], [1.0; 3], 0, Part::Rail);
    distort(&mut mesh, 0.12);
    let a = [
        [1e-3, 2e-4, -3e-4],
        [5e-4, -7e-4, 1e-4],
        [-2e-4, 3e-4, 6e-4],
    ];
    let b = [1e-4, -2e-4, 3e-5];
    let exact = |p: [f64; 3]| -> [f64; 3] {
        let mut u = b;
        for i in 0..3 {
            for j in 0..3 {
                u[i] += a[i][j] * p[j];
            }
        }
        u
    };
    let mut boundary = Vec::new();
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                if i == 0 || j == 0 || k == 0 || i == n || j == n || k == n {
                    boundary.push(block_node(n, n, i, j, k));
                }
            }
        }
    }
    let cons: Vec<usize> = boundary
        .iter()
        .flat_map(|&b| (0..3).map(move |d| 3 * b + d))
        .collect();
    let dm = DofMap::with_constraints(mesh.nodes.len(), &cons).unwrap();
    let mats = [STEEL];
    let fm = assemble(&mesh, &mats, &[], &[], &dm, AssemblyOptions::default()).unwrap();
    // Inhomogeneous Dirichlet: K_ff u_f = −K_fc u_c.
    let mut uc = vec![0.0; dm.n_dofs()];
    for &nb in &boundary {
        let u = exact(mesh.nodes[nb]);
        uc[3 * nb..3 * nb + 3].copy_from_slice(&u);
    }
    let kuc = apply_full_stiffness(&mesh, &mats, &[], &uc).unwrap();
    let f: Vec<f64> = dm.restrict(&kuc).unwrap().iter().map(|x| -x).collect();
    let uf = static_solve(&fm.k, &f).unwrap();
    let mut u = dm.expand(&uf).unwrap();
    for &nb in &boundary {
        u[3 * nb..3 * nb + 3].copy_from_slice(&uc[3 * nb..3 * nb + 3]);
    }
    let mut max_err = 0.0f64;
    for (node, p) in mesh.nodes.iter().enumerate() {
        let ue = exact(*p);
        for d in 0..3 {
            max_err = max_err.max((u[3 * node + d] - ue[d]).abs() / 1e-3);
        }
    }
    assert!(max_err < 1e-10, "relative nodal error {max_err:e}");
    // Constant strain: element energies.
    let eps = nalgebra::SVector::<f64, 6>::from_column_slice(&[
        a[0][0],
        a[1][1],
        a[2][2],
        a[1][2] + a[2][1],
        a[0][2] + a[2][0],
        a[0][1] + a[1][0],
    ]);
    let w = 0.5 * eps.dot(&(STEEL.elasticity_matrix() * eps));
    let mut max_e = 0.0f64;
    for el in &mesh.elements {
        let c = el.nodes.map(|n| mesh.nodes[n]);
        let mut ue = [0.0; 24];
        for i in 0..8 {
            ue[3 * i..3 * i + 3].copy_from_slice(&u[3 * el.nodes[i]..3 * el.nodes[i] + 3]);
        }
        let e = hex8::strain_energy(&c, &STEEL, &ue).unwrap();
        let ex = w * hex8::volume(&c).unwrap();
        max_e = max_e.max((e - ex).abs() / ex);
    }
    assert!(max_e < 1e-10, "element energy error {max_e:e}");
    eprintln!("patch test: max nodal error {max_err:.2e}, max element energy error {max_e:.2e}");
}

#[test]
fn free_distorted_block_has_six_rigid_body_modes() {
    // Dense eigenvalues (faer self-adjoint) of the assembled K of a free 3×2×2 distorted
    // block: exactly 6 below 1e-10 of the largest.
    let mut mesh = block_mesh([3, 2, 2], [0.3, 0.2, 0.2], 0, Part::Sleeper);
    distort(&mut mesh, 0.015);
    let dm = DofMap::new(mesh.nodes.len());
    let fm = assemble(&mesh, &[STEEL], &[], &[], &dm, AssemblyOptions::default()).unwrap();
    let k = sym_dense(&fm.k);
    assert!(max_asym(&k) < 1e-14, "K asymmetry {:e}", max_asym(&k));
    let ev = k.self_adjoint_eigenvalues(Side::Lower).unwrap();
    let max = ev.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let zeros = ev.iter().filter(|&&x| x.abs() < 1e-10 * max).count();
    assert_eq!(zeros, 6);
    eprintln!(
        "rigid-body: 6 zeros, 6th = {:.1e}, 7th = {:.1e} (relative)",
        ev[5] / max,
        ev[6] / max
    );
    assert!(ev[6] / max > 1e-6);
}

/// Cantilever L × b × h (x, y, z) with `nx × 1 × 2` elements, tip load P in z.
/// Returns (mean tip deflection (m), Σ z reactions (N)).
fn cantilever(nx: usize, incompatible: bool, p: f64) -> (f64, f64) {
    let (l, b, h) = (1.0, 0.05, 0.1);
    let (ny, nz) = (1, 2);
    let mesh = block_mesh([nx, ny, nz], [l, b, h], 0, Part::Rail);
    // Root: u_x = 0 on the whole face (plane section, zero rotation ψ(0) = 0); u_z = 0 on
    // the neutral-axis line (w(0) = 0, and σ_xx = 0 there so no Poisson restraint); u_y = 0
    // at one neutral-axis node (rigid lateral motion); the root otherwise contracts freely.
    let mut cons = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            let n = block_node(nx, ny, 0, j, k);
            cons.push(3 * n);
            if k == 1 {
                cons.push(3 * n + 2);
            }
        }
    }
    cons.push(3 * block_node(nx, ny, 0, 0, 1) + 1);
    let dm = DofMap::with_constraints(mesh.nodes.len(), &cons).unwrap();
    let mats = [STEEL];
    // Tip load: consistent nodal loads of a parabolic shear traction, 3/16, 5/8, 3/16 of P
    // over the depth, split equally over the 2 nodes across the width.
    let frac = [3.0 / 16.0, 5.0 / 8.0, 3.0 / 16.0];
    let mut f = vec![0.0; dm.n_dofs()];
    for (k, fr) in frac.iter().enumerate() {
        for j in 0..=ny {
            f[3 * block_node(nx, ny, nx, j, k) + 2] = p * fr / 2.0;
        }
    }
    let u = if incompatible {
        let fm = assemble(&mesh, &mats, &[], &[], &dm, AssemblyOptions::default()).unwrap();
        dm.expand(&static_solve(&fm.k, &dm.restrict(&f).unwrap()).unwrap())
            .unwrap()
    } else {
        // Plain trilinear: assemble densely from stiffness_trilinear (small model).
        let nf = dm.n_free();
        let mut kd = Mat::<f64>::zeros(nf, nf);
        for el in &mesh.elements {
            let ke = hex8::stiffness_trilinear(&el.nodes.map(|n| mesh.nodes[n]), &STEEL).unwrap();
            for p in 0..24 {
                for q in 0..24 {
                    if let (Some(r), Some(c)) = (
                        dm.free_index(3 * el.nodes[p / 3] + p % 3),
                        dm.free_index(3 * el.nodes[q / 3] + q % 3),
                    ) {
                        kd[(r, c)] += ke[(p, q)];
                    }
                }
            }
        }
        let ff = dm.restrict(&f).unwrap();
        let mut rhs = Mat::<f64>::from_fn(nf, 1, |i, _| ff[i]);
        let llt = kd.llt(Side::Lower).unwrap();
        use faer::linalg::solvers::Solve;
        llt.solve_in_place(rhs.as_mut());
        dm.expand(&(0..nf).map(|i| rhs[(i, 0)]).collect::<Vec<_>>())
            .unwrap()
    };
    let mut tip = 0.0;
    for k in 0..=nz {
        for j in 0..=ny {
            tip += u[3 * block_node(nx, ny, nx, j, k) + 2];
        }
    }
    tip /= ((nz + 1) * (ny + 1)) as f64;
    let r = reactions(&mesh, &mats, &[], &dm, &u, &f).unwrap();
    let rz: f64 = r.iter().filter(|(d, _)| d % 3 == 2).map(|(_, v)| v).sum();
    (tip, rz)
}

#[test]
fn cantilever_matches_timoshenko_and_trilinear_locks() {
    // Timoshenko: δ = PL³/(3EI) + PL/(κGA), κ = 10(1+ν)/(12+11ν) (Cowper 1966, rectangle).
    let p = 1000.0;
    let (l, b, h) = (1.0, 0.05, 0.1);
    let (e, nu, g) = (
        STEEL.youngs_modulus,
        STEEL.poisson_ratio,
        STEEL.shear_modulus(),
    );
    let i = b * h * h * h / 12.0;
    let kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
    let exact = p * l * l * l / (3.0 * e * i) + p * l / (kappa * g * b * h);
    // 20 × 1 × 2 (cubic elements, 50 mm) , 10 × 1 × 2 and 5 × 1 × 2 (aspect ratios 2 and 4): the incompatible
    // modes represent pure bending exactly on rectangular elements; the plain trilinear
    // element shear-locks, the more so the more elongated the element.
    let mut rz = 0.0;
    for (nx, lock_bound) in [(20, 0.9), (10, 0.75), (5, 0.5)] {
        let (tip, r) = cantilever(nx, true, p);
        rz = r;
        let err = (tip - exact) / exact;
        let (tip_lin, _) = cantilever(nx, false, p);
        eprintln!(
            "cantilever {nx}x1x2: exact {exact:.6e} m, Wilson–Taylor {tip:.6e} m ({:+.3} %), trilinear {tip_lin:.6e} m (ratio {:.3}), Σ R_z = {r:.6} N",
            100.0 * err,
            tip_lin / exact
        );
        assert!(err.abs() < 0.03, "relative error {err}");
        assert!(
            tip_lin < lock_bound * exact,
            "trilinear ratio {}",
            tip_lin / exact
        );
    }
    assert!((rz + p).abs() < 1e-8 * p, "Σ R_z = {rz}");
}

#[test]
fn free_free_bar_longitudinal_frequencies() {
    // Steel bar 1 m × 20 mm × 20 mm, 40 × 1 × 1 elements, free-free. Longitudinal modes
    // (picked by shape: > 90 % of the kinetic energy in x) vs f_n = n c / (2L), c = √(E/ρ)
    // (the Rayleigh–Love lateral-inertia correction, ≈ (nπν r_p/L)²/2 < 3e-4, is below
    // the 1 % tolerance).
    let (l, a) = (1.0, 0.02);
    let mesh = block_mesh([40, 1, 1], [l, a, a], 0, Part::Rail);
    let dm = DofMap::new(mesh.nodes.len());
    let c = STEEL.bar_wave_speed();
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let fm = assemble(
            &mesh,
            &[STEEL],
            &[],
            &[],
            &dm,
            AssemblyOptions { mass: kind },
        )
        .unwrap();
        let (k, m) = (sym_dense(&fm.k), sym_dense(&fm.m));
        assert!(max_asym(&m) < 1e-14);
        let (vals, phi) = super::solve::dense_generalised_eigen(&k, &m).unwrap();
        let mut found = Vec::new();
        for (i, &lam) in vals.iter().enumerate() {
            if lam <= 1e-6 * vals[vals.len() - 1] {
                continue; // rigid-body modes
            }
            // Kinetic-energy share in x: φ_xᵀ M φ_x / φᵀ M φ (M couples only equal directions).
            let v = phi.col(i);
            let vx = Mat::<f64>::from_fn(v.nrows(), 1, |r, _| if r % 3 == 0 { v[r] } else { 0.0 });
            let vf = Mat::<f64>::from_fn(v.nrows(), 1, |r, _| v[r]);
            let ex = (vx.transpose() * &m * &vx)[(0, 0)];
            let et = (vf.transpose() * &m * &vf)[(0, 0)];
            if ex / et > 0.9 {
                found.push(lam.sqrt() / (2.0 * std::f64::consts::PI));
            }
            if found.len() == 3 {
                break;
            }
        }
        assert_eq!(found.len(), 3);
        for (n, f) in found.iter().enumerate() {
            let exact = (n + 1) as f64 * c / (2.0 * l);
            let err = (f - exact) / exact;
            eprintln!(
                "bar {kind:?}: mode {} f = {f:.2} Hz, c/2L·n = {exact:.2} Hz, error {:+.4} %",
                n + 1,
                100.0 * err
            );
            assert!(err.abs() < 0.01, "{kind:?} mode {} error {err}", n + 1);
        }
    }
}

#[test]
fn total_mass_equals_rho_v_and_per_part() {
    let mut mesh = block_mesh([3, 2, 2], [0.3, 0.2, 0.2], 0, Part::Rail);
    distort(&mut mesh, 0.01);
    let mut other = block_mesh([2, 1, 1], [0.2, 0.1, 0.1], 1, Part::Sleeper);
    for p in &mut other.nodes {
        p[2] -= 0.5;
    }
    mesh.append(&other);
    let concrete = IsotropicElastic {
        youngs_modulus: 38e9,
        poisson_ratio: 0.2,
        density: 2500.0,
    };
    let mats = [STEEL, concrete];
    let mut rv = [0.0; 2];
    for el in &mesh.elements {
        rv[el.material] +=
            mats[el.material].density * hex8::volume(&el.nodes.map(|n| mesh.nodes[n])).unwrap();
    }
    let pm = [PointMass {
        node: 3,
        mass: 12.5,
    }];
    let dm = DofMap::new(mesh.nodes.len());
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let fm = assemble(&mesh, &mats, &[], &pm, &dm, AssemblyOptions { mass: kind }).unwrap();
        // 1_xᵀ M 1_x = total mass.
        let m = &fm.m;
        let mut tot = 0.0;
        for j in (0..dm.n_free()).step_by(3) {
            for (r, v) in m.as_ref().row_idx_of_col(j).zip(m.as_ref().val_of_col(j)) {
                if r % 3 == 0 {
                    tot += v;
                }
            }
        }
        let exact = rv[0] + rv[1] + 12.5;
        assert!(
            (tot - exact).abs() / exact < 1e-12,
            "{kind:?}: {tot} vs {exact}"
        );
    }
    let pp = mass_per_part(&mesh, &mats).unwrap();
    assert!((pp.get(Part::Rail) - rv[0]).abs() < 1e-12 * rv[0]);
    assert!((pp.get(Part::Sleeper) - rv[1]).abs() < 1e-12 * rv[1]);
    assert_eq!(pp.get(Part::Wheel), 0.0);
}

#[test]
fn springs_static_series_and_energy() {
    // Two nodes, no elements: ground–node0 spring k1 (z), node0–node1 spring k2 (z);
    // x, y constrained. Load F on node1: u0 = F/k1, u1 = F/k1 + F/k2 (series springs).
    let mesh = Mesh {
        nodes: vec![[0.0; 3], [0.0, 0.0, 1.0]],
        elements: vec![],
    };
    let (k1, k2, f) = (2.0e8, 5.0e7, 1.0e4);
    let springs = [
        Spring::node_to_ground(0, Direction::Z, k1, 1.0e3),
        Spring::node_to_node(1, 0, Direction::Z, k2, 2.0e3),
    ];
    let dm = DofMap::with_constraints(2, &[0, 1, 3, 4]).unwrap();
    let fm = assemble(&mesh, &[], &springs, &[], &dm, AssemblyOptions::default()).unwrap();
    let u = static_solve(&fm.k, &[0.0, f]).unwrap();
    assert!((u[0] - f / k1).abs() < 1e-12 * f / k1);
    assert!((u[1] - (f / k1 + f / k2)).abs() < 1e-12 * (f / k1 + f / k2));
    // Damping matrix: c g gᵀ.
    let c = fm.c.to_dense();
    assert!((c[(0, 0)] - 3.0e3).abs() < 1e-9 && (c[(0, 1)] + 2.0e3).abs() < 1e-9);
    // Energy: ½ uᵀ K u = Σ ½ k r².
    let uf = dm.expand(&u).unwrap();
    let e_spring = spring_energy(&springs, &uf);
    let exact = 0.5 * k1 * (f / k1).powi(2) + 0.5 * k2 * (f / k2).powi(2);
    assert!((e_spring - exact).abs() < 1e-12 * exact);
    let k = fm.k.to_dense();
    let e_mat = 0.5
        * (u[0] * (k[(0, 0)] * u[0] + k[(0, 1)] * u[1])
            + u[1] * (k[(1, 0)] * u[0] + k[(1, 1)] * u[1]));
    assert!((e_mat - exact).abs() < 1e-12 * exact);
}

#[test]
fn strain_energy_per_part_sums_to_quadratic_form() {
    // Conservation check: Σ_parts Σ_e ½ u_eᵀK_e u_e + Σ springs ½ k r² = ½ uᵀ K u of the
    // assembled matrix, for an arbitrary displacement; also the patch spring to a
    // hexahedron face point is assembled consistently.
    let mut mesh = block_mesh([2, 2, 2], [0.2, 0.2, 0.2], 0, Part::Rail);
    distort(&mut mesh, 0.01);
    let mut sl = block_mesh([1, 1, 1], [0.1, 0.1, 0.1], 1, Part::Sleeper);
    for p in &mut sl.nodes {
        p[2] -= 0.2;
    }
    let off = mesh.append(&sl);
    let concrete = IsotropicElastic {
        youngs_modulus: 38e9,
        poisson_ratio: 0.2,
        density: 2500.0,
    };
    let mats = [STEEL, concrete];
    let hex = mesh.elements.last().unwrap().nodes;
    let springs = [
        Spring::node_to_point(0, &hex, [0.2, -0.3, 1.0], Direction::Z, 1e8, 0.0),
        Spring::patch(&[(1, 0.5), (2, 0.5)], &[(off, 1.0)], Direction::X, 3e7, 0.0),
        Spring::node_to_ground(off + 1, Direction::Y, 4e7, 0.0),
    ];
    let dm = DofMap::new(mesh.nodes.len());
    let fm = assemble(&mesh, &mats, &springs, &[], &dm, AssemblyOptions::default()).unwrap();
    let mut s = 12345u64;
    let u: Vec<f64> = (0..dm.n_dofs()).map(|_| 1e-4 * rng(&mut s)).collect();
    let k = fm.k.to_dense();
    assert!(max_asym(&k) < 1e-14);
    let uv = Mat::<f64>::from_fn(u.len(), 1, |i, _| u[i]);
    let quad = 0.5 * (uv.transpose() * &k * &uv)[(0, 0)];
    let pp = strain_energy_per_part(&mesh, &mats, &u).unwrap();
    let es = spring_energy(&springs, &u);
    let sum = pp.total() + es;
    assert!((sum - quad).abs() < 1e-12 * quad, "{sum} vs {quad}");
    assert!(pp.get(Part::Rail) > 0.0 && pp.get(Part::Sleeper) > 0.0);
    // The batched evaluation (one pass over the elements for several vectors) gives each
    // vector's quadratic form: u, 2u (4x the energy) and a second random vector.
    let u2: Vec<f64> = u.iter().map(|x| 2.0 * x).collect();
    let w: Vec<f64> = (0..dm.n_dofs()).map(|_| 1e-4 * rng(&mut s)).collect();
    let wv = Mat::<f64>::from_fn(w.len(), 1, |i, _| w[i]);
    let quad_w = 0.5 * (wv.transpose() * &k * &wv)[(0, 0)];
    let many = strain_energy_per_part_many(&mesh, &mats, &[&u, &u2, &w]).unwrap();
    assert!((many[0].total() - pp.total()).abs() < 1e-12 * pp.total());
    assert!((many[1].total() - 4.0 * pp.total()).abs() < 1e-12 * pp.total());
    let sum_w = many[2].total() + spring_energy(&springs, &w);
    assert!(
        (sum_w - quad_w).abs() < 1e-12 * quad_w,
        "{sum_w} vs {quad_w}"
    );
    // apply_full_stiffness equals the assembled K (all DOFs free here).
    let ku = apply_full_stiffness(&mesh, &mats, &springs, &u).unwrap();
    let kd = &k * &uv;
    let maxk = ku.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    for i in 0..u.len() {
        assert!((ku[i] - kd[(i, 0)]).abs() < 1e-12 * maxk);
    }
}

#[test]
fn bad_input_is_reported() {
    let mut mesh = block_mesh([1, 1, 1], [1.0; 3], 0, Part::Rail);
    let dm = DofMap::new(mesh.nodes.len());
    let e = assemble(&mesh, &[], &[], &[], &dm, AssemblyOptions::default()).unwrap_err();
    assert!(
        matches!(e, FeError::MaterialIndex { element: 0, .. }),
        "{e}"
    );
    mesh.elements[0].nodes.swap(0, 4);
    mesh.elements[0].nodes.swap(1, 5);
    mesh.elements[0].nodes.swap(2, 6);
    mesh.elements[0].nodes.swap(3, 7);
    let e = assemble(&mesh, &[STEEL], &[], &[], &dm, AssemblyOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            FeError::NonPositiveJacobian {
                element: Some(0),
                ..
            }
        ),
        "{e}"
    );
    // Singular K (free body) is reported by the solver.
    let mesh = block_mesh([1, 1, 1], [1.0; 3], 0, Part::Rail);
    let fm = assemble(&mesh, &[STEEL], &[], &[], &dm, AssemblyOptions::default()).unwrap();
    let r = static_solve(&fm.k, &[1.0; 24]);
    assert!(r.is_err(), "{r:?}");
}

#[test]
fn assembly_is_independent_of_thread_count() {
    // Every entry is summed in element order, so 1 and 3 threads give bit-identical values;
    // more than one chunk (4096 elements) is exercised.
    let mut mesh = block_mesh([20, 15, 15], [1.0, 0.5, 0.5], 0, Part::Rail);
    distort(&mut mesh, 0.003);
    let dm = DofMap::with_constraints(mesh.nodes.len(), &[0, 1, 2, 5, 7]).unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                assemble(&mesh, &[STEEL], &[], &[], &dm, AssemblyOptions::default()).unwrap()
            })
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a.k.as_ref().val(), b.k.as_ref().val());
    assert_eq!(a.m.as_ref().val(), b.m.as_ref().val());
    assert_eq!(a.k.as_ref().row_idx(), b.k.as_ref().row_idx());
}

//! Checks of the local FE contact patch against closed forms.

use super::{
    rail_head, tread, FlatBlockPatch, IsotropicElastic, StripKernel, StructureError, SurfaceKernel,
};
use crate::contact::influence::single_body;

/// The largest error of a flat block's kernel against the single-body Boussinesq–Cerruti
/// coefficients, over the nine components (diagonal terms relative to themselves, off-diagonal
/// terms relative to `nn` at the same offset): at the loaded element, and over every other
/// offset with where it occurs.
struct Errors {
    at_source: f64,
    away: f64,
    /// `(ox, oy, component i, load j)` of `away`.
    worst: (isize, isize, usize, usize),
}

fn errors(patch: &FlatBlockPatch, kernel: &SurfaceKernel) -> Errors {
    let a = patch.element_m;
    let (e, nu) = (patch.material.youngs_modulus, patch.material.poisson_ratio);
    let h = kernel.half() as isize;
    let mut out = Errors {
        at_source: 0.0,
        away: 0.0,
        worst: (0, 0, 0, 0),
    };
    for ox in -h..=h {
        for oy in -h..=h {
            let fe = kernel.get(ox, oy).unwrap();
            let cf = single_body(ox as f64 * a, oy as f64 * a, a, a, e, nu);
            for i in 0..3 {
                for j in 0..3 {
                    let scale = if i == j {
                        cf[i][i].abs()
                    } else {
                        cf[2][2].abs()
                    };
                    let err = (fe[i][j] - cf[i][j]).abs() / scale;
                    if ox == 0 && oy == 0 {
                        out.at_source = out.at_source.max(err);
                    } else if err > out.away {
                        out.away = err;
                        out.worst = (ox, oy, i, j);
                    }
                }
            }
        }
    }
    out
}

#[test]
fn flat_block_reproduces_boussinesq_and_cerruti() {
    let mut patch = FlatBlockPatch::steel(0.8e-3);
    patch.half_elements = 4;
    patch.fine_depth_elements = 4;
    patch.extent_m = 0.25;
    let kernel = patch.kernel().unwrap();
    let Errors {
        away, at_source, ..
    } = errors(&patch, &kernel);
    // smoke version of P1 (validation/contact_patch.md): the fixed far faces of a 0.25 m block
    // alone account for about r / extent ≈ 1.8 % at the farthest offset (4, 4)
    assert!(
        away < 0.04,
        "largest error away from the loaded element {away}"
    );
    assert!(at_source < 0.05, "error at the loaded element {at_source}");
}

/// Where the largest error of one P1 case sits, and whether finer faces over the whole fine
/// zone remove it (`CASE="extent refine zone_refine"`, default "1 3 1").
#[test]
#[ignore = "validation: one P1 case (minutes)"]
fn flat_block_case() {
    let v = case_from_env("1 3 1");
    let mut patch = FlatBlockPatch::steel(0.8e-3);
    patch.extent_m = v[0];
    patch.refine = v[1] as usize;
    patch.zone_refine = v[2] as usize;
    print_case(&patch);
}

fn print_case(patch: &FlatBlockPatch) {
    let t = std::time::Instant::now();
    let kernel = patch.kernel().unwrap();
    let e = errors(patch, &kernel);
    let (ox, oy, i, j) = e.worst;
    let axis = ["x", "y", "n"];
    println!(
        "extent {} m refine {} zone_refine {}: {} DOFs, {:.1} s: largest error away {:.2} % \
         (offset ({ox}, {oy}), component {}{}), at the loaded element {:.2} %",
        patch.extent_m,
        patch.refine,
        patch.zone_refine,
        kernel.n_dofs(),
        t.elapsed().as_secs_f64(),
        100.0 * e.away,
        axis[i],
        axis[j],
        100.0 * e.at_source
    );
}

/// The P1 table of validation/contact_patch.md.
#[test]
#[ignore = "validation: the P1 convergence table (minutes)"]
fn flat_block_convergence_table() {
    let cases = [(1.0, 1), (1.0, 3), (1.0, 5), (0.5, 3), (2.0, 3)];
    for (extent, refine) in cases {
        let mut patch = FlatBlockPatch::steel(0.8e-3);
        patch.refine = refine;
        patch.extent_m = extent;
        print_case(&patch);
    }
}

/// The numbers of a validation case from the environment variable `CASE` (whitespace
/// separated), or `default`.
pub(super) fn case_from_env(default: &str) -> Vec<f64> {
    std::env::var("CASE")
        .unwrap_or_else(|_| default.into())
        .split_whitespace()
        .map(|w| w.parse().expect("CASE holds numbers"))
        .collect()
}

/// A kernel of a body symmetric about y = 0: mirroring both columns keeps the x and normal
/// terms and flips the sign of the y couplings (to 1e-6 of nn; exact up to round-off).
fn assert_mirror_symmetric(k: &StripKernel) {
    let (nx, ny) = k.dims();
    for o in -(nx as isize - 1)..=nx as isize {
        for j in 0..ny {
            for jp in 0..ny {
                let (c, m) = (
                    k.get(o, j, jp).unwrap(),
                    k.get(o, ny - 1 - j, ny - 1 - jp).unwrap(),
                );
                let scale = c[2][2].abs();
                for (i, jj) in [(0, 0), (1, 1), (2, 2), (0, 2), (2, 0)] {
                    assert!((c[i][jj] - m[i][jj]).abs() < 1e-6 * scale, "{o} {j} {jp}");
                }
                for (i, jj) in [(1, 2), (2, 1), (0, 1)] {
                    assert!((c[i][jj] + m[i][jj]).abs() < 1e-6 * scale, "{o} {j} {jp}");
                }
            }
        }
    }
}

/// The split holds within 2 % in x, y and n, and the naive sum misses by more than `naive_min`.
fn assert_split(r: &SplitCheck, naive_min: f64) {
    for i in 0..3 {
        assert!(rel(r.split[i], r.full[i]) < 0.02, "{i}: {r:?}");
        assert!(
            rel(r.naive[i], r.full[i]) > naive_min,
            "the naive sum must fail: {i}: {r:?}"
        );
    }
}

#[test]
fn rail_head_kernel_is_mirror_symmetric() {
    // a small segment: the check is of the load placement and the field sampling across the
    // rail, exact up to round-off; the kernel's values are the validation run's business
    let mut patch = rail_head::RailHeadPatch::steel(0.8e-3, 2, 4);
    patch.refine = 1;
    patch.half_length_m = 0.05;
    let k = patch.kernel().unwrap();
    // the upright UIC54 section is symmetric about y = 0
    assert_mirror_symmetric(&k);
    // the split takes `g` off any traction shape's compliance exactly (the shape is
    // normalised): an identity of the definitions, checked on an uneven shape
    let g = [
        [1e-10, 2e-11, -3e-11],
        [4e-11, 5e-10, 6e-11],
        [-7e-11, 8e-11, 9e-10],
    ];
    let shape: Vec<f64> = (0..8).map(|i| 1.0 + (i * i) as f64).collect();
    let (before, after) = (
        k.patch_compliance(&shape).unwrap(),
        k.split(&g).patch_compliance(&shape).unwrap(),
    );
    for r in 0..3 {
        for q in 0..3 {
            approx::assert_relative_eq!(after[r][q], before[r][q] - g[r][q], epsilon = 1e-22);
        }
    }
    assert!(k.patch_compliance(&shape[1..]).is_none());
}

/// The largest difference of two kernels' coefficients over the largest coefficient (−).
fn kernel_difference(a: &StripKernel, b: &StripKernel) -> f64 {
    let (va, vb) = (a.values(), b.values());
    assert_eq!(va.len(), vb.len());
    let flat =
        |v: &[[[f64; 3]; 3]]| -> Vec<f64> { v.iter().flatten().flatten().copied().collect() };
    let (fa, fb) = (flat(va), flat(vb));
    let scale = fa.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    fa.iter()
        .zip(&fb)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

/// With an even number of FE faces across the source row the rail head's segment and the
/// tread's prism are mirror-symmetric about the row's middle plane, and their kernels are
/// solved as two half problems (symmetric: tractions across and normal, `u_x = 0` on the
/// plane; antisymmetric: traction along x, `u_y = u_z = 0`): every coefficient equals the
/// whole submodel's solved directly (the independent computation) to rounding, 1e-9 of the
/// largest — the x terms, the couplings and the offsets behind the source (`x < 0`, read
/// from the mirror image) included. With an odd number no plane lies there and the whole
/// submodel is solved.
#[test]
fn kernels_by_half_problems_equal_the_whole_submodels() {
    let mut rail = rail_head::RailHeadPatch::steel(0.8e-3, 3, 4);
    rail.refine = 2;
    rail.half_length_m = 0.05;
    let mut tread = tread::TreadPatch::steel(2e-3, 3, 4);
    tread.refine = 2;
    tread.half_length_m = 0.06;
    let pairs = [
        (
            "rail head",
            rail.kernel_solved(true),
            rail.kernel_solved(false),
        ),
        (
            "tread",
            tread.kernel_solved(true),
            tread.kernel_solved(false),
        ),
    ];
    for (name, halves, whole) in pairs {
        let d = kernel_difference(&halves.unwrap(), &whole.unwrap());
        eprintln!("{name}: halves against whole {d:.2e}");
        assert!(d < 1e-9, "{name} {d}");
    }
    // the rows behind the source carry x terms of the opposite sign to those ahead
    let k = rail.kernel().unwrap();
    let (ahead, behind) = (k.get(1, 1, 1).unwrap(), k.get(-1, 1, 1).unwrap());
    assert!(ahead[0][2] * behind[0][2] < 0.0, "{ahead:?} {behind:?}");
    // odd: no middle plane
    assert!(super::half_planes(&[-1.0, -0.5, 0.5, 1.0]).is_none());
    assert_eq!(
        super::half_planes(&[-1.0, -0.25, 1e-17, 0.25, 1.0]),
        Some(vec![0.0, 0.25, 1.0])
    );
    assert!(super::half_planes(&[-1.0, -0.3, 0.0, 0.25, 1.0]).is_none());
}

/// The ratio of the rail head's diagonal terms to the half-space's at the source element and
/// at the farthest offset along and across the grid.
fn print_rail_head_ratios(k: &StripKernel, material: IsotropicElastic) {
    let (nx, ny) = k.dims();
    let a = k.element_m();
    let ratio = |o: isize, j: usize, jp: usize| {
        let fe = k.get(o, j, jp).unwrap();
        let dy = (j as f64 - jp as f64) * a;
        let (e, nu) = (material.youngs_modulus, material.poisson_ratio);
        let cf = single_body(o as f64 * a, dy, a, a, e, nu);
        [0, 1, 2].map(|i| fe[i][i] / cf[i][i])
    };
    let mid = ny / 2;
    println!(
        "{} DOFs; FE / half-space (xx, yy, nn): at the source {:.3?}, {} rows on {:.3?}, across the grid {:.3?}",
        k.n_dofs(),
        ratio(0, mid, mid),
        nx,
        ratio(nx as isize, mid, mid),
        ratio(0, ny - 1, 0)
    );
}

/// The rail head's kernel against the half-space on a passage-sized grid (P2's first
/// measurement in validation/contact_patch.md).
#[test]
#[ignore = "validation: the rail head's kernel (minutes)"]
fn rail_head_kernel_against_the_half_space() {
    let v = case_from_env("0.8 3 4 4");
    let mut patch = rail_head::RailHeadPatch::steel(v[0] * 1e-3, v[2] as usize, v[3] as usize);
    patch.refine = v[1] as usize;
    println!("{} DOFs", patch.n_dofs().unwrap());
    let t = std::time::Instant::now();
    let k = patch.kernel().unwrap();
    println!(
        "a {} mm refine {} grid {}×{}: {:.1} s",
        v[0],
        v[1],
        v[2],
        v[3],
        t.elapsed().as_secs_f64()
    );
    print_rail_head_ratios(&k, patch.material);
}

/// The Hertz pressure's shape on an `nx × ny` grid of elements `a` (m) centred on the contact
/// point (row-major, `i` along x): `√(1 − x²/ha² − y²/hb²)` at the element centres, and the
/// grid size that holds the ellipse of semi-axes `ha`, `hb` (m).
fn hertz_shape(ha: f64, hb: f64, a: f64) -> (usize, usize, Vec<f64>) {
    let n = |h: f64| (2.0 * h / a).ceil() as usize;
    let (nx, ny) = (n(ha), n(hb));
    let c = |i: usize, n: usize| (i as f64 - 0.5 * (n as f64 - 1.0)) * a;
    let shape = (0..nx)
        .flat_map(|i| (0..ny).map(move |j| (i, j)))
        .map(|(i, j)| {
            (1.0 - (c(i, nx) / ha).powi(2) - (c(j, ny) / hb).powi(2))
                .max(0.0)
                .sqrt()
        })
        .collect();
    (nx, ny, shape)
}

/// The split's check (P3 in validation/contact_patch.md): the compliance (m/N, x, y, n) of a
/// Hertz pressure on a long refined segment (`full`), against the long segment's global twin
/// plus a short refined segment's kernel split against its own twin, and against the naive
/// sum without the split. Returns `(full, split, naive)`.
#[derive(Debug)]
struct SplitCheck {
    full: [f64; 3],
    split: [f64; 3],
    naive: [f64; 3],
}

fn split_check(
    element_m: f64,
    refine: usize,
    (ha, hb): (f64, f64),
    (half_sub_m, half_full_m): (f64, f64),
    half_width_m: f64,
) -> SplitCheck {
    let (nx, ny, shape) = hertz_shape(ha, hb, element_m);
    let mut sub = rail_head::RailHeadPatch::steel(element_m, nx, ny);
    sub.refine = refine;
    sub.half_length_m = half_sub_m;
    let full = rail_head::RailHeadPatch {
        half_length_m: half_full_m,
        ..sub
    };
    split_errors(
        (
            &sub.kernel().unwrap(),
            sub.global_compliance(half_width_m).unwrap(),
        ),
        (
            &full.kernel().unwrap(),
            full.global_compliance(half_width_m).unwrap(),
        ),
        &shape,
    )
}

/// The split's check from the short and the long patch's kernels and global twins.
fn split_errors(
    (k_sub, g_sub): (&StripKernel, [[f64; 3]; 3]),
    (k_full, g_full): (&StripKernel, [[f64; 3]; 3]),
    shape: &[f64],
) -> SplitCheck {
    let diag = |c: [[f64; 3]; 3]| [c[0][0], c[1][1], c[2][2]];
    let g_full = diag(g_full);
    let c_full = diag(k_full.patch_compliance(shape).unwrap());
    let c_sub = diag(k_sub.patch_compliance(shape).unwrap());
    let c_split = diag(k_sub.split(&g_sub).patch_compliance(shape).unwrap());
    SplitCheck {
        full: c_full,
        split: [0, 1, 2].map(|i| g_full[i] + c_split[i]),
        naive: [0, 1, 2].map(|i| g_full[i] + c_sub[i]),
    }
}

/// The default model's static Hertz semi-axes (m) under a vertical load `load_n` (N).
fn default_hertz(load_n: f64) -> (f64, f64) {
    let m = crate::model::Model::default_model();
    let h = crate::contact::HertzContact::solve(&crate::contact::HertzInput {
        radius_x_m: m.wheel.radius,
        radius_y_m: m.contact.rail_crown_radius,
        youngs_pa: IsotropicElastic::STEEL.youngs_modulus,
        poisson: IsotropicElastic::STEEL.poisson_ratio,
        load_n,
    })
    .unwrap();
    (h.a_m, h.b_m)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn split_matches_the_long_refined_segment() {
    // a coarse grid keeps it quick; the split's identity does not depend on the grid
    let (ha, hb) = default_hertz(15e3);
    println!("Hertz semi-axes {ha:.5} {hb:.5} m");
    let r = split_check(2e-3, 1, (ha, hb), (0.1, 0.3), hb);
    println!("{r:?}");
    assert_split(&r, 0.1);
}

/// P3 in validation/contact_patch.md: the split's check at the reference's grid, one long
/// segment against short ones (`CASE="a_mm refine load_kN half_full_m half_sub_m..."`,
/// default "0.8 3 15 0.3 0.1 0.05").
#[test]
#[ignore = "validation: the split against a long refined segment (minutes)"]
fn split_case() {
    let v = case_from_env("0.8 3 15 0.3 0.1 0.05");
    let (a, refine) = (v[0] * 1e-3, v[1] as usize);
    let (ha, hb) = default_hertz(v[2] * 1e3);
    let (nx, ny, shape) = hertz_shape(ha, hb, a);
    let segment = |half: f64| {
        let mut p = rail_head::RailHeadPatch::steel(a, nx, ny);
        p.refine = refine;
        p.half_length_m = half;
        p
    };
    let diag = |c: [[f64; 3]; 3]| [c[0][0], c[1][1], c[2][2]];
    println!(
        "a {} mm, refine {refine}, {} kN: Hertz {:.2} × {:.2} mm, grid {nx} × {ny}",
        v[0],
        v[2],
        ha * 1e3,
        hb * 1e3
    );
    let t = std::time::Instant::now();
    let full = segment(v[3]);
    let c_full = diag(full.kernel().unwrap().patch_compliance(&shape).unwrap());
    let g_full = diag(full.global_compliance(hb).unwrap());
    println!(
        "long segment ±{} m: {} DOFs, {:.0} s; refined (x, y, n) {c_full:?} m/N, twin {g_full:?}",
        v[3],
        full.n_dofs().unwrap(),
        t.elapsed().as_secs_f64()
    );
    for &half in &v[4..] {
        let t = std::time::Instant::now();
        let sub = segment(half);
        let k = sub.kernel().unwrap();
        let g = sub.global_compliance(hb).unwrap();
        let c_split = diag(k.split(&g).patch_compliance(&shape).unwrap());
        let c_sub = diag(k.patch_compliance(&shape).unwrap());
        println!(
            "short segment ±{half} m: {} DOFs, {:.0} s",
            sub.n_dofs().unwrap(),
            t.elapsed().as_secs_f64()
        );
        for (i, name) in ["x", "y", "n"].iter().enumerate() {
            let (split, naive) = (g_full[i] + c_split[i], g_full[i] + c_sub[i]);
            println!(
                "  {name}: long {:.4e} m/N, split {:.4e} ({:+.2} %), naive {:.4e} ({:+.1} %)",
                c_full[i],
                split,
                100.0 * (split / c_full[i] - 1.0),
                naive,
                100.0 * (naive / c_full[i] - 1.0)
            );
        }
    }
}

/// The Hertz problem (the default model's wheel on the R300 crown, `load_n`) solved on an
/// `nx × ny` grid of elements `a` with the normal kernel `kernel(o, j, j')` (m/Pa, both
/// bodies): the moment-equivalent semi-axes (m), the peak pressure (Pa) and the approach (m).
fn hertz_on_grid(
    (nx, ny, a): (usize, usize, f64),
    load_n: f64,
    kernel: impl Fn(isize, usize, usize) -> f64,
) -> [f64; 4] {
    use crate::contact::influence::strip::StripNormal;
    use crate::contact::normal::{NormalMode, NormalSolver};
    let m = crate::model::Model::default_model();
    let c = |i: usize, n: usize| (i as f64 - 0.5 * (n as f64 - 1.0)) * a;
    let x: Vec<f64> = (0..nx).map(|i| c(i, nx)).collect();
    let y: Vec<f64> = (0..ny).map(|j| c(j, ny)).collect();
    let gap: Vec<f64> = x
        .iter()
        .flat_map(|xi| {
            y.iter().map(move |yj| {
                xi * xi / (2.0 * m.wheel.radius) + yj * yj / (2.0 * m.contact.rail_crown_radius)
            })
        })
        .collect();
    let mut op = StripNormal::new(nx, ny, kernel);
    let mut p = vec![0.0; nx * ny];
    let out = NormalSolver::new(nx * ny)
        .solve(&mut op, &gap, a * a, NormalMode::Load(load_n), &mut p)
        .unwrap();
    let (sa, sb) = crate::contact::report::equivalent_semi_axes(&x, &y, &p);
    let pmax = p.iter().cloned().fold(0.0, f64::max);
    [sa, sb, pmax, out.approach_m]
}

/// P2 in validation/contact_patch.md: the Hertz problem with the rail head's FE kernel and
/// the wheel as a half-space, and with both FE kernels (rail head and tread), against Hertz
/// and against both bodies as half-spaces on the same grid (`CASE="a_mm refine load_kN"`,
/// default "0.8 3 15").
#[test]
#[ignore = "validation: Hertz on the rail head's fe-patch (minutes)"]
fn hertz_on_the_rail_head_patch() {
    let v = case_from_env("0.8 3 15");
    let (a, refine, load) = (v[0] * 1e-3, v[1] as usize, v[2] * 1e3);
    let (ha, hb) = default_hertz(load);
    // the grid holds the patch with a margin of 1.4 on each semi-axis
    let n = |h: f64| (2.8 * h / a).ceil() as usize;
    let (nx, ny) = (n(ha), n(hb));
    let mut patch = rail_head::RailHeadPatch::steel(a, nx, ny);
    patch.refine = refine;
    let t = std::time::Instant::now();
    let rail = patch.kernel().unwrap();
    println!(
        "rail head ±{} m, {} DOFs: {:.0} s",
        patch.half_length_m,
        rail.n_dofs(),
        t.elapsed().as_secs_f64()
    );
    let (e, nu) = (patch.material.youngs_modulus, patch.material.poisson_ratio);
    let wheel = |o: isize, j: usize, jp: usize| {
        single_body(o as f64 * a, (j as f64 - jp as f64) * a, a, a, e, nu)[2][2]
    };
    let fe = hertz_on_grid((nx, ny, a), load, |o, j, jp| {
        rail.get(o, j, jp).unwrap()[2][2] + wheel(o, j, jp)
    });
    let hs = hertz_on_grid((nx, ny, a), load, |o, j, jp| 2.0 * wheel(o, j, jp));
    let mut tread_patch = tread::TreadPatch::steel(a, nx, ny);
    tread_patch.refine = refine;
    let t = std::time::Instant::now();
    let tread = tread_patch.kernel().unwrap();
    println!(
        "tread ±{} m, {} DOFs: {:.0} s",
        tread_patch.half_length_m,
        tread.n_dofs(),
        t.elapsed().as_secs_f64()
    );
    let both = hertz_on_grid((nx, ny, a), load, |o, j, jp| {
        rail.get(o, j, jp).unwrap()[2][2] + tread.get(o, j, jp).unwrap()[2][2]
    });
    let h = crate::contact::HertzContact::solve(&crate::contact::HertzInput {
        radius_x_m: crate::model::Model::default_model().wheel.radius,
        radius_y_m: crate::model::Model::default_model()
            .contact
            .rail_crown_radius,
        youngs_pa: e,
        poisson: nu,
        load_n: load,
    })
    .unwrap();
    let closed = [h.a_m, h.b_m, h.p0_pa];
    println!("grid {nx} × {ny} of {} mm, {} kN", v[0], v[2]);
    for (i, name) in ["a", "b", "p0"].iter().enumerate() {
        let pct = |v: &[f64; 4], r: f64| 100.0 * (v[i] / r - 1.0);
        println!(
            "{name}: Hertz {:.4e}; half-space grid {:.4e} ({:+.2} %); FE rail + half-space wheel {:.4e} ({:+.2} % of Hertz, {:+.2} % of the half-space grid); FE rail + FE tread {:.4e} ({:+.2} %, {:+.2} %)",
            closed[i],
            hs[i],
            pct(&hs, closed[i]),
            fe[i],
            pct(&fe, closed[i]),
            pct(&fe, hs[i]),
            both[i],
            pct(&both, closed[i]),
            pct(&both, hs[i]),
        );
    }
}

#[test]
fn tread_kernel_is_mirror_symmetric_on_a_symmetric_rim() {
    // a rim symmetric about the rolling circle: the kernel in the rail's frame must be
    // mirror-symmetric as the rail head's is (a check of the turned-over block's column and
    // component mapping)
    let mut patch = tread::TreadPatch::steel(2e-3, 2, 4);
    patch.refine = 1;
    patch.half_length_m = 0.06;
    patch.rim = tread::RimSection {
        thickness_m: 0.07,
        y_m: [-0.06, 0.06],
        web_y_m: [-0.015, 0.015],
    };
    let k = patch.kernel().unwrap();
    assert_mirror_symmetric(&k);
}

#[test]
fn tread_kernel_near_the_load_is_the_half_space_in_the_rails_frame() {
    // Near the load the rim is nearly a half-space (its faces and the web are 30 mm and more
    // away; its held ends 60 mm away lower the displacement at r by about r/L, 5–8 % at two
    // rows): every term within 10 % of nn of Boussinesq–Cerruti, and the couplings in the
    // rail's frame as one half-space turned over about x gives them — xn unchanged, yn and xy
    // of opposite sign to the same body's in its own frame (measured: 8.0 % at most, at two
    // rows in xx).
    let a = 2e-3;
    let mut patch = tread::TreadPatch::steel(a, 3, 3);
    patch.half_length_m = 0.06;
    let k = patch.kernel().unwrap();
    let (e, nu) = (patch.material.youngs_modulus, patch.material.poisson_ratio);
    let mut worst: f64 = 0.0;
    for (o, j, jp) in [(1isize, 1usize, 1usize), (0, 2, 1), (1, 2, 1), (2, 1, 1)] {
        let fe = k.get(o, j, jp).unwrap();
        let dy = (j as f64 - jp as f64) * a;
        // the same body in its own (turned-over) frame sees the offset (o a, −dy)
        let own = single_body(o as f64 * a, -dy, a, a, e, nu);
        let sign = [1.0, -1.0, 1.0];
        for r in 0..3 {
            for q in 0..3 {
                let want = sign[r] * sign[q] * own[r][q];
                let err = (fe[r][q] - want).abs() / own[2][2].abs();
                worst = worst.max(err);
                // a sign error in the mapping would be twice the coupling: 27–54 % of nn here
                assert!(
                    err < 0.1,
                    "({o}, {j}, {jp}) [{r}][{q}]: {} vs {want}",
                    fe[r][q]
                );
            }
        }
    }
    println!("largest error relative to nn: {:.2} %", 100.0 * worst);
}

#[test]
fn tread_split_matches_the_long_refined_prism() {
    // On a global wheel mesh of 15 mm at the contact: with the default model's 30 mm (two
    // elements through the 70 mm rim) the split misses by about 4 % in n, the coarse twins
    // resolving the rim's response between the two prism lengths no better (validation/
    // contact_patch.md, P3 tread; `tread_split_against_the_global_mesh`)
    let (ha, hb) = default_hertz(15e3);
    let (nx, ny, shape) = hertz_shape(ha, hb, 2e-3);
    let mut sub = tread::TreadPatch::steel(2e-3, nx, ny);
    sub.refine = 1;
    sub.half_length_m = 0.1;
    sub.global.contact_size_m = 0.015;
    let full = tread::TreadPatch {
        half_length_m: 0.3,
        ..sub
    };
    let r = split_errors(
        (&sub.kernel().unwrap(), sub.global_compliance(hb).unwrap()),
        (&full.kernel().unwrap(), full.global_compliance(hb).unwrap()),
        &shape,
    );
    println!("{r:?}");
    assert_split(&r, 0.2);
}

/// The tread's split against the global wheel mesh's contact size (P3, tread): the split's
/// error with the default wheel mesh (0.03 m at the contact) and finer global meshes
/// (`CASE="a_mm refine load_kN half_sub_m half_full_m"`, default "2 1 15 0.1 0.3").
#[test]
#[ignore = "validation: the tread's split against the global mesh (a minute)"]
fn tread_split_against_the_global_mesh() {
    let v = case_from_env("2 1 15 0.1 0.3");
    let (a, refine) = (v[0] * 1e-3, v[1] as usize);
    let (ha, hb) = default_hertz(v[2] * 1e3);
    let (nx, ny, shape) = hertz_shape(ha, hb, a);
    for contact_size in [0.03, 0.015, 0.0075] {
        let mut sub = tread::TreadPatch::steel(a, nx, ny);
        sub.refine = refine;
        sub.half_length_m = v[3];
        sub.global = tread::GlobalWheelMesh {
            contact_size_m: contact_size,
            size_m: 0.06,
            contact_half_width_m: 0.03,
        };
        let full = tread::TreadPatch {
            half_length_m: v[4],
            ..sub
        };
        let r = split_errors(
            (&sub.kernel().unwrap(), sub.global_compliance(hb).unwrap()),
            (&full.kernel().unwrap(), full.global_compliance(hb).unwrap()),
            &shape,
        );
        let pct = |i: usize| 100.0 * (r.split[i] / r.full[i] - 1.0);
        let naive = |i: usize| 100.0 * (r.naive[i] / r.full[i] - 1.0);
        println!(
            "global contact size {contact_size} m: split x {:+.2} % y {:+.2} % n {:+.2} %; naive x {:+.1} % y {:+.1} % n {:+.1} %; long refined (x, y, n) {:?} m/N",
            pct(0),
            pct(1),
            pct(2),
            naive(0),
            naive(1),
            naive(2),
            r.full
        );
    }
}

#[test]
fn patch_parameters_out_of_range_are_refused_by_name() {
    // checked before anything is built: a clear error naming the parameter, no panic
    let name = |e: StructureError| match e {
        StructureError::PatchParameter { name, .. } => name,
        other => panic!("{other:?}"),
    };
    let mut rail = rail_head::RailHeadPatch::steel(0.8e-3, 10, 8);
    rail.half_length_m = 0.01;
    assert_eq!(name(rail.kernel().unwrap_err()), "half_length_m");
    let mut rail = rail_head::RailHeadPatch::steel(0.8e-3, 10, 8);
    rail.global.element_length_m = 0.5e-3;
    assert_eq!(name(rail.n_dofs().unwrap_err()), "global.element_length_m");
    let rail = rail_head::RailHeadPatch::steel(0.8e-3, 10, 8);
    assert_eq!(
        name(rail.global_compliance(0.0).unwrap_err()),
        "half_width_m"
    );
    let tread = tread::TreadPatch::steel(2e-3, 4, 80);
    assert_eq!(name(tread.kernel().unwrap_err()), "ny");
    let mut tread = tread::TreadPatch::steel(2e-3, 4, 4);
    tread.rim.web_y_m = [0.07, 0.08];
    assert_eq!(name(tread.n_dofs().unwrap_err()), "rim.web_y_m");
    let mut tread = tread::TreadPatch::steel(0.8e-3, 4, 4);
    tread.global.contact_size_m = 0.5e-3;
    assert_eq!(name(tread.kernel().unwrap_err()), "global.contact_size_m");
}

/// The level of the local compliance (validation/contact_patch.md, P6): the compliance (x, y,
/// n; m/N) of a Hertz pressure on the rail head's and the tread's split kernels (what the
/// fe-patch adds to the global model) against two half-spaces' (what the contact adds today)
/// (`CASE="a_mm refine load_kN"`, default "0.8 3 15").
#[test]
#[ignore = "validation: the local compliance against the half-space's (minutes)"]
fn local_compliance_against_the_half_space() {
    let v = case_from_env("0.8 3 15");
    let (a, refine, load) = (v[0] * 1e-3, v[1] as usize, v[2] * 1e3);
    let (ha, hb) = default_hertz(load);
    let (nx, ny, shape) = hertz_shape(ha, hb, a);
    let mut rail = rail_head::RailHeadPatch::steel(a, nx, ny);
    rail.refine = refine;
    let mut tread = tread::TreadPatch::steel(a, nx, ny);
    tread.refine = refine;
    let t = std::time::Instant::now();
    let diag = |c: [[f64; 3]; 3]| [c[0][0], c[1][1], c[2][2]];
    let c_rail = diag(
        rail.kernel()
            .unwrap()
            .split(&rail.global_compliance(hb).unwrap())
            .patch_compliance(&shape)
            .unwrap(),
    );
    let c_tread = diag(
        tread
            .kernel()
            .unwrap()
            .split(&tread.global_compliance(hb).unwrap())
            .patch_compliance(&shape)
            .unwrap(),
    );
    // two half-spaces: the single body's coefficients twice (the couplings cancel)
    let (e, nu) = (rail.material.youngs_modulus, rail.material.poisson_ratio);
    let total: f64 = shape.iter().sum();
    let mut c_hs = [0.0; 3];
    for (f, &wf) in shape.iter().enumerate() {
        for (s, &ws) in shape.iter().enumerate() {
            let dx = ((f / ny) as f64 - (s / ny) as f64) * a;
            let dy = ((f % ny) as f64 - (s % ny) as f64) * a;
            let k = single_body(dx, dy, a, a, e, nu);
            for (i, c) in c_hs.iter_mut().enumerate() {
                *c += 2.0 * wf * ws * k[i][i];
            }
        }
    }
    let c_hs = c_hs.map(|c| c / (total * total * a * a));
    println!(
        "a {} mm, refine {refine}, {} kN, grid {nx} × {ny}: {:.0} s",
        v[0],
        v[2],
        t.elapsed().as_secs_f64()
    );
    for (i, name) in ["x", "y", "n"].iter().enumerate() {
        let fe = c_rail[i] + c_tread[i];
        println!(
            "{name}: two half-spaces {:.4e} m/N; fe-patch (split) rail {:.4e} + tread {:.4e} = {fe:.4e} ({:+.1} % of the half-spaces')",
            c_hs[i],
            c_rail[i],
            c_tread[i],
            100.0 * (fe / c_hs[i] - 1.0)
        );
    }
}

//! Checks of the local FE contact patch against closed forms.

use super::*;
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
    let case = std::env::var("CASE").unwrap_or_else(|_| "1 3 1".into());
    let v: Vec<f64> = case
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
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

//! The penalty contact on the refined bodies (P4a in validation/contact_patch.md): the point
//! compliance it reads against Boussinesq's point load, and its static Hertz problem against
//! Hertz's closed form as the penalty stiffens and the mesh refines.

use nalgebra::DMatrix;

use super::{rail_head::RailHeadPatch, tread::TreadPatch, FlatBlockPatch};
use crate::contact::penalty::{segment_stiffness, solve_static_normal};
use crate::contact::report::equivalent_semi_axes;
use crate::contact::{HertzContact, HertzInput};
use crate::fe::material::IsotropicElastic;
use crate::model::Model;

#[test]
fn point_compliance_of_a_flat_block_is_boussinesq_away_from_the_load() {
    // Boussinesq: a point force P on a half-space's surface approaches a surface point at
    // distance r by (1 − ν²) P / (π E r) (Johnson 1985, eq. 3.22 with z = 0)
    let h = 1e-3;
    let mut patch = FlatBlockPatch::steel(h);
    patch.refine = 1;
    patch.half_elements = 8;
    patch.fine_depth_elements = 8;
    patch.extent_m = 0.25;
    let surface = patch.factorised_surface().unwrap();
    // the FE faces are the grid's: nodes at (k + ½) h
    let points: Vec<[f64; 2]> = (0..8).map(|k| [(k as f64 - 0.5) * h, 0.5 * h]).collect();
    let c = surface.point_compliance(&points).unwrap();
    let asym = (&c - c.transpose()).abs().max();
    assert!(asym < 1e-9 * c.abs().max(), "not symmetric: {asym:e}");
    let IsotropicElastic {
        youngs_modulus: e,
        poisson_ratio: nu,
        ..
    } = patch.material;
    let mut worst: f64 = 0.0;
    for k in 2..8 {
        let r = k as f64 * h;
        let closed = (1.0 - nu * nu) / (std::f64::consts::PI * e * r);
        let err = c[(k, 0)] / closed - 1.0;
        println!(
            "r = {k} h: FE {:.4e} m/N, Boussinesq {closed:.4e} ({:+.2} %)",
            c[(k, 0)],
            100.0 * err
        );
        worst = worst.max(err.abs());
    }
    // a nodal point load's discrete response on hex8 faces departs from the continuum by a
    // few per cent within a few elements (measured −8.3 % at 3 h, −3.4 to −5.3 % at 4–7 h,
    // where the fixed far faces add about r / extent ≈ 3 %)
    assert!(worst < 0.10, "largest error at 2–7 h: {worst}");
}

/// The static Hertz problem solved with the penalty on both refined bodies, one scale.
#[derive(Debug, Clone, Copy)]
struct PenaltyRow {
    /// The segment-stiffness scale `s` (∞: the rigid limit).
    scale: f64,
    /// The penalty per node (N/m).
    k_n_per_m: f64,
    /// Moment semi-axes of the nodal pressures (m).
    a_m: f64,
    b_m: f64,
    /// Peak nodal pressure (Pa).
    p0_pa: f64,
    /// Largest penetration (m) and the bodies' approach (m).
    penetration_m: f64,
    approach_m: f64,
    /// Nodes in contact.
    contact_nodes: usize,
}

/// The default model's wheel on the R300 crown, `load_n`, both bodies refined submodels with
/// FE faces `h_m` at the contact (`refine` 1: the surface nodes are the grid's corners): the
/// penalty's static solution for each scale, the submodels' DOFs and the Hertz solution.
fn penalty_on_patch(
    h_m: f64,
    load_n: f64,
    scales: &[f64],
) -> (Vec<PenaltyRow>, [usize; 2], HertzContact) {
    let m = Model::default_model();
    let material = IsotropicElastic::STEEL;
    let hertz = HertzContact::solve(&HertzInput {
        radius_x_m: m.wheel.radius,
        radius_y_m: m.contact.rail_crown_radius,
        youngs_pa: material.youngs_modulus,
        poisson: material.poisson_ratio,
        load_n,
    })
    .unwrap();
    // the grid holds the patch with a margin of 1.4 on each semi-axis (as P2)
    let n = |c: f64| (2.8 * c / h_m).ceil() as usize;
    let (nx, ny) = (n(hertz.a_m), n(hertz.b_m));
    let mut rail = RailHeadPatch::steel(h_m, nx, ny);
    rail.refine = 1;
    let mut tread = TreadPatch::steel(h_m, nx, ny);
    tread.refine = 1;
    let rail = rail.factorised_surface().unwrap();
    let tread = tread.factorised_surface().unwrap();
    // the slaves: the tread's surface nodes over the patch and a margin
    let slaves = tread.surface_points(1.4 * hertz.a_m, 1.4 * hertz.b_m);
    let points: Vec<[f64; 2]> = slaves.iter().map(|s| s.at).collect();
    let area = slaves[0].area_m2;
    assert!(
        slaves.iter().all(|s| (s.area_m2 / area - 1.0).abs() < 1e-6),
        "the slaves' faces are the grid's"
    );
    let c: DMatrix<f64> =
        rail.point_compliance(&points).unwrap() + tread.point_compliance(&points).unwrap();
    let gap: Vec<f64> = points
        .iter()
        .map(|p| {
            p[0] * p[0] / (2.0 * m.wheel.radius) + p[1] * p[1] / (2.0 * m.contact.rail_crown_radius)
        })
        .collect();
    // the tensor lattice of the slaves (ordered by x, then y)
    let mut xs: Vec<f64> = points.iter().map(|p| p[0]).collect();
    xs.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let ys: Vec<f64> = points[..points.len() / xs.len()]
        .iter()
        .map(|p| p[1])
        .collect();
    assert_eq!(xs.len() * ys.len(), points.len());
    let volume = area * tread.layer_m().min(rail.layer_m());
    let rows = scales
        .iter()
        .map(|&scale| {
            let k = if scale.is_finite() {
                segment_stiffness(
                    material.youngs_modulus,
                    material.poisson_ratio,
                    area,
                    volume,
                    scale,
                )
                .unwrap()
            } else {
                f64::INFINITY
            };
            let s = solve_static_normal(&c, &gap, k, load_n).unwrap();
            let p: Vec<f64> = s.forces_n.iter().map(|f| f / area).collect();
            let (a_m, b_m) = equivalent_semi_axes(&xs, &ys, &p);
            PenaltyRow {
                scale,
                k_n_per_m: k,
                a_m,
                b_m,
                p0_pa: p.iter().cloned().fold(0.0, f64::max),
                penetration_m: s.penetration_m.iter().cloned().fold(0.0, f64::max),
                approach_m: s.approach_m,
                contact_nodes: s.forces_n.iter().filter(|&&f| f > 0.0).count(),
            }
        })
        .collect();
    (rows, [rail.n_dofs(), tread.n_dofs()], hertz)
}

fn print_rows(h_m: f64, rows: &[PenaltyRow], dofs: [usize; 2], hertz: &HertzContact) {
    println!(
        "h {:.3} mm: rail {} DOFs, tread {} DOFs; Hertz a {:.4} mm, b {:.4} mm, p0 {:.4e} Pa, approach {:.3e} m",
        h_m * 1e3,
        dofs[0],
        dofs[1],
        hertz.a_m * 1e3,
        hertz.b_m * 1e3,
        hertz.p0_pa,
        hertz.approach_m
    );
    let pct = |v: f64, r: f64| 100.0 * (v / r - 1.0);
    for r in rows {
        println!(
            "  s {:>6}: k {:.3e} N/m, {} nodes; a {:+.2} %, b {:+.2} %, p0 {:+.2} % of Hertz; penetration {:.3e} m ({:.1} % of the Hertz approach), approach {:.3e} m",
            r.scale,
            r.k_n_per_m,
            r.contact_nodes,
            pct(r.a_m, hertz.a_m),
            pct(r.b_m, hertz.b_m),
            pct(r.p0_pa, hertz.p0_pa),
            r.penetration_m,
            100.0 * r.penetration_m / hertz.approach_m,
            r.approach_m
        );
    }
}

const SCALES: [f64; 5] = [0.1, 1.0, 10.0, 100.0, f64::INFINITY];

#[test]
fn penalty_on_the_refined_bodies_converges_to_the_rigid_limit_and_hertz() {
    // a coarse mesh (2 mm faces) under 100 kN (Hertz 7.2 × 5.4 mm) keeps it quick
    let h = 2e-3;
    let (rows, dofs, hertz) = penalty_on_patch(h, 100e3, &SCALES);
    print_rows(h, &rows, dofs, &hertz);
    let rigid = rows[4];
    for r in &rows[..4] {
        // a softer penalty spreads the load: larger patch, lower peak
        assert!(r.a_m >= rigid.a_m * (1.0 - 1e-9) && r.p0_pa <= rigid.p0_pa * (1.0 + 1e-9));
    }
    // near the rigid limit the forces settle, so the penetration falls as 1/k
    let ratio = rows[2].penetration_m / rows[3].penetration_m;
    assert!(
        (ratio / 10.0 - 1.0).abs() < 0.05,
        "penetration s = 10 / s = 100: {ratio}"
    );
    let close = |v: f64, w: f64| (v / w - 1.0).abs();
    assert!(close(rows[3].a_m, rigid.a_m) < 0.01 && close(rows[3].p0_pa, rigid.p0_pa) < 0.01);
    // the rigid limit on 2 mm faces: a, b within 10 %, p0 within 20 % of Hertz
    assert!(close(rigid.a_m, hertz.a_m) < 0.10, "{rigid:?}");
    assert!(close(rigid.b_m, hertz.b_m) < 0.10, "{rigid:?}");
    assert!(close(rigid.p0_pa, hertz.p0_pa) < 0.20, "{rigid:?}");
}

/// P4a in validation/contact_patch.md (`CASE="h_mm... load_kN"`, default "0.8 0.533 0.4 15").
#[test]
#[ignore = "validation: P4a, the penalty's static Hertz problem on the refined bodies (minutes)"]
fn penalty_static_case() {
    let v = super::tests::case_from_env("0.8 0.533 0.4 15");
    let (hs, load) = v.split_at(v.len() - 1);
    for &h_mm in hs {
        let t = std::time::Instant::now();
        let (rows, dofs, hertz) = penalty_on_patch(h_mm * 1e-3, load[0] * 1e3, &SCALES);
        print_rows(h_mm * 1e-3, &rows, dofs, &hertz);
        println!("  {:.0} s", t.elapsed().as_secs_f64());
    }
}

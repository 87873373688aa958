//! The fe-patch of a passage: its disk entry reads back what was written, and the operators
//! carry the split as a negative uniform compliance.

use super::{
    build_estimate, influence_of, model_patch_cached, patch_dofs, patch_grid, read,
    refined_influence, write, Influence, Model, PatchGrid, StripKernel, MARKER,
};
use crate::structure::contact_patch::of_model::ModelPatch;

/// A small patch made up of known values (not an FE result): enough to check the storage.
fn made_up_patch(nx: usize, ny: usize) -> ModelPatch {
    let values: Vec<[[f64; 3]; 3]> = (0..2 * nx * ny * ny)
        .map(|k| {
            std::array::from_fn(|a| {
                std::array::from_fn(|b| {
                    let diag = if a == b { 1e-12 } else { 0.0 };
                    diag + 1e-15 * (k as f64 + 0.1 * (3 * a + b) as f64)
                })
            })
        })
        .collect();
    let refined = StripKernel::from_values((nx, ny), (0.6e-3, 0.5e-3), values, 1234).unwrap();
    let rail = [[3e-10, 1e-13, 0.0], [1e-13, 4e-10, 0.0], [0.0, 0.0, 5e-10]];
    let wheel = [[1e-10, 0.0, 2e-13], [0.0, 2e-10, 0.0], [2e-13, 0.0, 3e-10]];
    ModelPatch {
        refined,
        twins_m_per_n: std::array::from_fn(|a| std::array::from_fn(|b| rail[a][b] + wheel[a][b])),
        rail_twin_m_per_n: rail,
        wheel_twin_m_per_n: wheel,
    }
}

#[test]
fn a_written_patch_reads_back_bit_for_bit_and_only_for_its_grid() {
    let (nx, ny) = (3, 2);
    let p = made_up_patch(nx, ny);
    let dir = std::env::temp_dir().join(format!("corrugation-fe-patch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let grid = PatchGrid {
        nx,
        ny,
        dx_m: 0.6e-3,
        dy_m: 0.5e-3,
        hertz_half_width_m: 5e-3,
        refine: 2,
    };
    assert!(read(&dir, &grid).is_none(), "nothing written yet");
    write(&dir, &p).unwrap();
    assert_eq!(read(&dir, &grid).unwrap(), p);
    // another grid is not this entry
    assert!(read(&dir, &PatchGrid { nx: 4, ..grid }).is_none());
    // without the completion marker the entry does not count
    std::fs::remove_file(dir.join(MARKER)).unwrap();
    assert!(read(&dir, &grid).is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_operators_carry_the_twins_as_a_negative_uniform_compliance() {
    let p = made_up_patch(3, 2);
    let mut op = influence_of(&p);
    let t = p.twins_m_per_n;
    assert_eq!(op.uniform(), [-t[0][0], -t[1][1], -t[2][2]]);
    // the normal product is the symmetric part of the kernel's nn term (the made-up kernel
    // is not reciprocal): a unit pressure on element (0, 0) read at element (1, 1) is
    // ½ (K_nn(1, 1, 0) + K_nn(−1, 0, 1))
    let mut pr = vec![0.0; 6];
    pr[0] = 1.0;
    let mut u = vec![0.0; 6];
    op.ops_mut().normal(&pr, &mut u);
    let (a, b) = (
        p.refined.get(1, 1, 0).unwrap(),
        p.refined.get(-1, 0, 1).unwrap(),
    );
    let k = [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.5 * (a[2][2] + b[2][2])],
    ];
    assert!(
        (u[3] - k[2][2]).abs() < 1e-9 * k[2][2].abs(),
        "{} {}",
        u[3],
        k[2][2]
    );
    assert_eq!(op.dims(), (3, 2));
}

/// The default model's fe-patch: its grid, submodel sizes and estimate for `refine` 1–3
/// (printed; no build). `cargo test --profile test-opt --lib default_patch_sizes -- --ignored
/// --nocapture`
#[test]
#[ignore = "prints the default fe-patch's sizes (about 10 s)"]
fn default_patch_sizes() {
    let m = Model::default_model();
    let cfg = crate::passage::setup::contact_config_for(&m, m.run.speed()).unwrap();
    let b = crate::passage::setup::static_hertz(&m, m.vehicle.wheel_load)
        .unwrap()
        .b_m;
    for refine in 1..=3 {
        let grid = PatchGrid {
            refine,
            ..patch_grid(&cfg, b)
        };
        let (r, t) = patch_dofs(&m, &grid).unwrap();
        let (s, gb, _) = build_estimate(&m, &grid).unwrap();
        println!(
            "refine {refine}: grid {} x {} of {:.3} x {:.3} mm, b {:.2} mm; rail {r} DOFs, tread {t}; about {s:.0} s, {gb:.1} GB",
            grid.nx,
            grid.ny,
            grid.dx_m * 1e3,
            grid.dy_m * 1e3,
            grid.hertz_half_width_m * 1e3
        );
    }
}

/// The steady creep curve and the normal patch of the default model at its wheel load on
/// the fe-patch against the half-space on the same grid (validation/contact_patch.md, the
/// creep curve: registered within 3 %). Builds the default fe-patch (about 70 s, 8.4 GB)
/// unless it is cached. `cargo test --profile test-opt --lib creep_curve_on_the_fe_patch --
/// --ignored --nocapture`
#[test]
#[ignore = "builds or reads the default model's fe-patch (minutes, up to 18 GB)"]
fn creep_curve_on_the_fe_patch() {
    use crate::contact::report::{case_config, solve_case_on, ContactCase, TangentialLoading};
    let m = Model::default_model();
    let (youngs_pa, poisson) = crate::passage::setup::contact_steel(&m);
    let case = |xi: f64| ContactCase {
        wheel_radius_m: m.wheel.radius,
        crown_radius_m: m.contact.rail_crown_radius,
        youngs_pa,
        poisson,
        normal_load_n: m.vehicle.wheel_load,
        friction: m.contact.friction,
        tangential: TangentialLoading::Creepage(xi),
        speed_m_per_s: m.run.speed(),
        steps: 1,
        grid_nx: m.contact.grid_nx,
        grid_ny: m.contact.grid_ny,
        grid_margin: m.contact.grid_margin,
        ..ContactCase::default()
    };
    let cfg = case_config(&case(0.0)).unwrap();
    let b = crate::passage::setup::static_hertz(&m, m.vehicle.wheel_load)
        .unwrap()
        .b_m;
    let grid = patch_grid(&cfg, b);
    let p = model_patch_cached(&m, &grid, None).unwrap();
    let Influence::Strip(op) = refined_influence(&p) else {
        unreachable!()
    };
    println!(
        "grid {} x {}; normal-tangential coupling / direct: {:.4}; departure from reciprocity: {:.2e}; twins (m/N) rail {:?} wheel {:?}",
        grid.nx,
        grid.ny,
        op.coupling_ratio(),
        op.asymmetry(),
        p.rail_twin_m_per_n,
        p.wheel_twin_m_per_n
    );
    let mut worst = 0.0_f64;
    for xi in [-1e-4, -2e-4, -5e-4, -1e-3, -2e-3, -4e-3, -8e-3] {
        let hs = solve_case_on(&case(xi), None).unwrap();
        let fe = match solve_case_on(&case(xi), Some(Influence::Strip(op.clone()))) {
            Ok(s) => s,
            Err(e) => panic!("fe-patch at xi {xi}: {e}"),
        };
        let d = fe.result.fx_n / hs.result.fx_n - 1.0;
        worst = worst.max(d.abs());
        println!(
            "xi {xi:+.1e}: F_x half-space {:9.1} N, fe-patch {:9.1} N ({:+.2} %); a {:.3}/{:.3} mm, b {:.3}/{:.3} mm, p0 {:.1}/{:.1} MPa, approach {:.2}/{:.2} um, slip {:.3}/{:.3}",
            hs.result.fx_n,
            fe.result.fx_n,
            100.0 * d,
            hs.a_m * 1e3,
            fe.a_m * 1e3,
            hs.b_m * 1e3,
            fe.b_m * 1e3,
            hs.p_max_pa / 1e6,
            fe.p_max_pa / 1e6,
            hs.result.approach_m * 1e6,
            fe.result.approach_m * 1e6,
            hs.result.slip_elements as f64 / hs.result.contact_elements as f64,
            fe.result.slip_elements as f64 / fe.result.contact_elements as f64,
        );
    }
    println!("largest difference of F_x: {:.2} %", 100.0 * worst);
    assert!(
        worst < 0.03,
        "creep curve on the fe-patch differs by {worst}"
    );
}

/// The energy ledger of the default model's smooth passage at its speed on the half-space
/// and on the fe-patch (printed: the relative error and the terms). Reads the modal cache and
/// the fe-patch (building either if absent: minutes, up to 10 GB). `cargo test --profile
/// test-opt --lib default_fe_patch_passage_energy -- --ignored --nocapture`
#[test]
#[ignore = "reads or builds the default model's modes and fe-patch (minutes)"]
fn default_fe_patch_passage_energy() {
    use crate::dynamics::{passage::PassageOptions, prepared::PreparedModel};
    let cache = crate::eigen::cache::ModalCache::new(crate::eigen::cache::default_cache_dir());
    for influence in ["half-space", "fe-patch"] {
        let m = crate::model::load_model(
            &crate::model::ModelSource::Builtin,
            &[format!("contact.influence=\"{influence}\"")],
        )
        .unwrap();
        let opts = PassageOptions::default();
        let p = PreparedModel::new(&m, &cache, &opts).unwrap();
        let rec = p.engine.passage(m.run.speed(), None, &opts, None).unwrap();
        let e = &rec.energy;
        println!(
            "{influence}: energy balance {:+.3} % ({e:?})",
            100.0 * e.relative_error()
        );
    }
}

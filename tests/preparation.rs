//! The preparation of the reduced-order model (`PreparedModel`) on the small model: the
//! track's damping assembled alone equals the full assembly's, and a preparation from a warm
//! cache (bases, residual flexibilities read back) gives the engine of a cold one bit for bit.

use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::ModalCache;
use corrugation::structure::TrackStructure;

fn small_model() -> corrugation::model::Model {
    corrugation::model::test_problems::small_passage_model(&[]).expect("valid model")
}

/// The nonzero entries `(column, row, value)` of a sparse matrix, in storage order.
fn nonzeros(c: faer::sparse::SparseColMatRef<'_, usize, f64>) -> Vec<(usize, usize, u64)> {
    let (cp, ri) = (c.symbolic().col_ptr(), c.symbolic().row_idx());
    (0..c.ncols())
        .flat_map(|j| (cp[j]..cp[j + 1]).map(move |p| (j, p)))
        .filter(|&(_, p)| c.val()[p] != 0.0)
        .map(|(j, p)| (j, ri[p], c.val()[p].to_bits()))
        .collect()
}

/// `C` assembled alone has exactly the nonzero entries (positions and bit patterns, in the
/// same column-major order) of the `C` of the full assembly of K, M and C.
#[test]
fn damping_alone_equals_the_full_assemblys_damping() {
    let m = small_model();
    let track = TrackStructure::build(&m).unwrap();
    let (full, _) = track.assemble().unwrap();
    let alone = track.assemble_damping().unwrap();
    let want = nonzeros(full.c.as_ref());
    assert!(want.len() > 100, "the small track has dampers");
    assert_eq!(nonzeros(alone.as_ref()), want);
    assert_eq!(alone.nrows(), full.c.nrows());
}

/// A preparation from a warm cache (modes, the track's and the wheel's residual
/// flexibilities read back) runs the passage of a cold one bit for bit, and the wheel's
/// residual flexibility read back is the computed one.
#[test]
fn a_warm_preparation_gives_the_cold_ones_passage() {
    let m = small_model();
    assert!(m.run.residual_flexibility && m.run.wheel_residual_flexibility);
    let dir = std::env::temp_dir().join(format!(
        "corrugation-test-cache-preparation-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let cache = ModalCache::new(&dir);
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let cold = PreparedModel::new(&m, &cache, &opts).unwrap();
    let warm = PreparedModel::new(&m, &cache, &opts).unwrap();
    assert!(!cold.cached && warm.cached);
    let aux = std::fs::read_dir(&dir)
        .unwrap()
        // the cache's entries (directories; the cache's own `CACHEDIR.TAG` is a file)
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .flat_map(|p| std::fs::read_dir(p).unwrap())
        .filter(|f| {
            let name = f.as_ref().unwrap().file_name();
            name.to_string_lossy().starts_with("wheel-residual-")
        })
        .count();
    assert_eq!(aux, 1, "the wheel's residual flexibility is cached once");
    assert_eq!(cold.engine.wheel_residual(), warm.engine.wheel_residual());
    assert!(warm.engine.wheel_residual().is_some());
    let v = m.run.speed();
    let a = cold.engine.passage(v, None, &opts, None).unwrap();
    let b = warm.engine.passage(v, None, &opts, None).unwrap();
    assert_eq!(a.histories.normal_n, b.histories.normal_n);
    assert_eq!(a.histories.longitudinal_n, b.histories.longitudinal_n);
    assert_eq!(a.wear_j_per_m, b.wear_j_per_m);
    std::fs::remove_dir_all(&dir).ok();
}

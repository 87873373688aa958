//! The preparation of the reduced-order model (`PreparedModel`) on the small model: the
//! track's damping assembled alone equals the full assembly's, and a preparation from a warm
//! cache (bases, residual flexibilities read back) gives the engine of a cold one bit for bit;
//! a cold preparation reports its stages one at a time, each with its own name and count.

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

/// Records every progress event, in order, from whichever thread.
#[derive(Default)]
struct Log(std::sync::Mutex<Vec<String>>);

impl corrugation::progress::Progress for Log {
    fn stage(&self, name: &str, total: u64) {
        self.0.lock().unwrap().push(format!("stage {name}|{total}"));
    }
    fn done(&self, done: u64) {
        self.0.lock().unwrap().push(format!("done {done}"));
    }
    fn total(&self, total: u64) {
        self.0.lock().unwrap().push(format!("total {total}"));
    }
    fn finish(&self) {
        self.0.lock().unwrap().push("finish".into());
    }
}

/// A cold preparation's stages do not interleave: each begins after the previous one
/// finished, and the counts reported inside a stage never pass its total; the eigen-solve
/// stage named after the track ends at the track's mode count, the wheel's at the wheel's.
#[test]
fn a_cold_preparation_reports_one_stage_at_a_time_with_its_own_counts() {
    let m = small_model();
    let dir = std::env::temp_dir().join(format!(
        "corrugation-test-cache-preparation-progress-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let log = std::sync::Arc::new(Log::default());
    let cache = ModalCache::new(&dir).with_progress(log.clone());
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let p = PreparedModel::new(&m, &cache, &opts).unwrap();
    let events = log.0.lock().unwrap().clone();
    let _ = std::fs::remove_dir_all(&dir);
    let mut open: Option<(String, u64, u64)> = None; // (name, total, last done)
    let mut last_done = std::collections::BTreeMap::new();
    for e in &events {
        if let Some(rest) = e.strip_prefix("stage ") {
            let (name, total) = rest.split_once('|').unwrap();
            assert!(
                open.is_none(),
                "stage {name} began inside {open:?}: {events:?}"
            );
            open = Some((name.to_string(), total.parse().unwrap(), 0));
        } else if let Some(t) = e.strip_prefix("total ") {
            let o = open
                .as_mut()
                .unwrap_or_else(|| panic!("{e} outside a stage"));
            o.1 = t.parse().unwrap();
        } else if let Some(d) = e.strip_prefix("done ") {
            let o = open
                .as_mut()
                .unwrap_or_else(|| panic!("{e} outside a stage"));
            let d: u64 = d.parse().unwrap();
            assert!(
                o.1 == 0 || d <= o.1,
                "{} at {d} of {}: {events:?}",
                o.0,
                o.1
            );
            o.2 = d;
        } else {
            let (name, _, done) = open.take().expect("finish inside a stage");
            last_done.insert(name, done);
        }
    }
    let n_track = p.track_frequencies_hz.len() as u64;
    let n_wheel = p.wheel_frequencies_hz.len() as u64;
    let solve = |who: &str| {
        last_done
            .iter()
            .find(|(k, _)| k.starts_with(&format!("{who} modes below")))
            .map(|(_, &v)| v)
            .unwrap_or_else(|| panic!("no {who} eigen-solve stage: {events:?}"))
    };
    assert_eq!(solve("track"), n_track);
    assert_eq!(solve("wheel"), n_wheel);
}

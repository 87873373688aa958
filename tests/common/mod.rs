//! Helpers shared by the integration tests: running the real binary, the small test model,
//! and the dense reference eigen-solver of an explicit operator.
#![allow(dead_code)]

use std::process::Command;

/// The small test model ([`corrugation::model::test_problems::SMALL_MODEL`]) as `--set`
/// arguments for any command.
pub const SMALL_MODEL: [&str; 14] = {
    let sets = corrugation::model::test_problems::SMALL_MODEL;
    let mut a = ["--set"; 14];
    let mut i = 0;
    while i < sets.len() {
        a[2 * i + 1] = sets[i];
        i += 1;
    }
    a
};

/// Runs the `corrugation` binary; returns (exit code, stdout, stderr).
pub fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(args)
        .output()
        .expect("binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Whether `stderr` ends in exactly one error line (`error: …`, the whole cause chain on one
/// line) and holds no other error line; plain progress lines before it (stderr is not a
/// terminal in the tests) do not count.
pub fn is_one_line_error(stderr: &str) -> bool {
    let lines: Vec<&str> = stderr.trim_end().lines().collect();
    let errors = lines.iter().filter(|l| l.starts_with("error")).count();
    errors == 1 && lines.last().is_some_and(|l| l.starts_with("error"))
}

/// The eigenpairs of `M^{-½} K M^{-½}` of an explicit operator, by a dense symmetric
/// eigen-solver (nalgebra): eigenvalues ω² (rad²/s²) ascending, and the mode shapes
/// `M^{-½} z` (M-normalised). The independent reference of the explicit path's tests.
pub fn dense_modes(op: &corrugation::explicit::ExplicitOperator) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = op.n();
    let m = op.mass();
    let mut e = vec![0.0; n];
    let mut col = vec![0.0; n];
    let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
    for j in 0..n {
        e.iter_mut().for_each(|x| *x = 0.0);
        e[j] = 1.0;
        op.apply_scaled(&e, &mut col);
        a.set_column(j, &nalgebra::DVector::from_column_slice(&col));
    }
    let eig = nalgebra::SymmetricEigen::new(0.5 * (&a + a.transpose()));
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y]));
    let vals = idx.iter().map(|&i| eig.eigenvalues[i]).collect();
    let vecs = idx
        .iter()
        .map(|&i| {
            (0..n)
                .map(|r| eig.eigenvectors[(r, i)] / m[r].sqrt())
                .collect()
        })
        .collect();
    (vals, vecs)
}

/// A modal cache for the small test model shared by the integration tests (in the system's
/// temporary directory, kept between runs): the first test to need the small model's modes
/// solves them, the others load them. The cache is safe for processes running side by side.
pub fn small_model_cache() -> std::path::PathBuf {
    std::env::temp_dir().join("corrugation-test-small-model-cache")
}

/// All files under `dir` (relative path → bytes).
pub fn tree(dir: &std::path::Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

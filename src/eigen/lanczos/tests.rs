//! Unit tests of the Lanczos internals (the solver as a whole is tested in `eigen::tests`).

use super::band::{CAP_RATIO, TWO_SIDED_CAP_RATIO};

/// Closed form: a two-sided slice `[lo, lo + w)` with `w = TWO_SIDED_CAP_RATIO · (lo − b)`
/// has its shift at `m = lo + w/2`, and its half-width is exactly `CAP_RATIO` times the
/// distance from `m` down to the band bound `b` (the one-sided margin), for any `lo > b`.
#[test]
fn two_sided_cap_keeps_the_one_sided_margin() {
    for (b, lo) in [(0.0, 1.0), (4.1e8, 4.2e8), (1e3, 9e9)] {
        let w = TWO_SIDED_CAP_RATIO * (lo - b);
        let (h, m) = (0.5 * w, lo + 0.5 * w);
        approx::assert_relative_eq!(h / (m - b), CAP_RATIO, max_relative = 1e-12);
    }
}

//! The speeds of a sweep and their shards.
//!
//! **Range** `start:stop:step` (km/h): the grid `v_k = start + k·step`, `k = 0, 1, …, K` with
//! `K = ⌊(stop − start)/step + 10⁻⁹⌋`. The stop is included when it falls on the grid (within
//! 10⁻⁹ steps); otherwise the last speed is the last grid point below it — the stop is **not**
//! appended. So `54.8:219:1` is the 165 speeds 54.8 … 218.8 and `54.8:219:2` the 83
//! speeds 54.8 … 218.8. Each `v_k` is computed from `k` (no accumulated round-off) and rounded
//! to 10⁻⁹ km/h, so that `0.1`-steps print as written.
//!
//! **List** `60,80,100` (one value is a list of one). Lists are sorted ascending; duplicates
//! are an error.
//!
//! Every speed must be finite and within `MIN_SPEED_KMH` to `MAX_SPEED_KMH`, the range of
//! the model's `run.speed_kmh`; at most `MAX_SPEEDS`.
//!
//! **Shard** `I/N` (`I = 0 … N−1`): the speeds at positions `I, I+N, I+2N, …` of the sorted
//! list, so the `N` shards partition the list (every speed in exactly one shard).
//!
//! A speed's result file is named by `speed_file_stem`: the speed in km/h with six decimals,
//! zero-padded to four integer digits (`0054.800000`), so names sort like speeds.

/// The speeds of a `sweep` when none are given (km/h): 54.8 to 219 km/h in steps of 2 km/h
/// (83 speeds), the range of the reference study's sweeps.
pub const DEFAULT_SWEEP_SPEEDS: &str = "54.8:219:2";
use super::StudiesError;

/// Lowest accepted speed (km/h): that of `run.speed_kmh` ([`crate::model::SPEED_KMH`]).
pub(crate) const MIN_SPEED_KMH: f64 = crate::model::SPEED_KMH[0];

/// Highest accepted speed (km/h): that of `run.speed_kmh` ([`crate::model::SPEED_KMH`]).
pub(crate) const MAX_SPEED_KMH: f64 = crate::model::SPEED_KMH[1];

/// Most speeds in one speed list (−): a sweep's or `predict`'s `--speeds`, a study's
/// `speeds_kmh`; checked by [`check_speed_count`].
pub(crate) const MAX_SPEEDS: usize = 100_000;

/// Refuses a speed list of more than [`MAX_SPEEDS`] speeds (`n`, a float: a range's count may
/// exceed any index), with the reason naming the cap; the one check of every speed list.
pub(crate) fn check_speed_count(n: f64) -> Result<(), String> {
    if n <= MAX_SPEEDS as f64 {
        return Ok(());
    }
    Err(format!(
        "{n} speeds; at most {MAX_SPEEDS} in one speed list (use a larger step or fewer speeds)"
    ))
}

/// Parses `start:stop:step` or `v1,v2,...` (km/h) into sorted speeds (km/h).
pub fn parse_speeds(spec: &str) -> Result<Vec<f64>, StudiesError> {
    let bad = |reason: String| StudiesError::Speeds {
        spec: spec.to_string(),
        reason,
    };
    let num = |s: &str| {
        s.trim()
            .parse::<f64>()
            .map_err(|_| bad(format!("`{}` is not a number (km/h)", s.trim())))
    };
    let mut speeds = if spec.contains(':') {
        let parts: Vec<&str> = spec.split(':').collect();
        if parts.len() != 3 {
            return Err(bad(
                "a range is start:stop:step in km/h, e.g. 54.8:219:2".into()
            ));
        }
        let (a, b, s) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        if !(a.is_finite() && b.is_finite() && s.is_finite()) {
            return Err(bad("start, stop and step must be finite".into()));
        }
        if s <= 0.0 {
            return Err(bad(format!("step {s} must be positive")));
        }
        if b < a {
            return Err(bad(format!("stop {b} is below start {a}")));
        }
        let k_max = ((b - a) / s + 1e-9).floor();
        check_speed_count(k_max + 1.0).map_err(bad)?;
        (0..=k_max as usize)
            .map(|k| ((a + k as f64 * s) * 1e9).round() / 1e9)
            .collect::<Vec<f64>>()
    } else {
        let v = spec
            .split(',')
            .map(num)
            .collect::<Result<Vec<f64>, StudiesError>>()?;
        check_speed_count(v.len() as f64).map_err(bad)?;
        v
    };
    if let Some(v) = speeds
        .iter()
        .find(|v| !(v.is_finite() && **v >= MIN_SPEED_KMH && **v <= MAX_SPEED_KMH))
    {
        return Err(bad(format!(
            "speed {v} km/h out of range, allowed {MIN_SPEED_KMH} to {MAX_SPEED_KMH} {} (as run.speed_kmh)",
            crate::model::SPEED_KMH_WHY
        )));
    }
    crate::lists::check_no_repeats_by_key("speeds", "km/h", &speeds, |v| speed_file_stem(*v))
        .map_err(|e| bad(format!("{e} (speeds closer than 1e-6 km/h count as equal)")))?;
    speeds.sort_by(f64::total_cmp);
    Ok(speeds)
}

/// A shard `index/count` of a sweep's speeds or a study's cases: every `count`-th item from
/// the `index`-th.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard's index, `0 … count−1`.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole sweep (shard `0/1`).
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N`.
    pub fn parse(spec: &str) -> Result<Self, StudiesError> {
        let bad = |reason: &str| StudiesError::Shard {
            spec: spec.to_string(),
            reason: reason.to_string(),
        };
        let (i, n) = spec
            .split_once('/')
            .ok_or_else(|| bad("expected I/N, e.g. 0/4 (shard I of N, I = 0 … N−1)"))?;
        let i: usize = i
            .trim()
            .parse()
            .map_err(|_| bad("I must be a whole number ≥ 0"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N must be a whole number ≥ 1"))?;
        if n == 0 {
            return Err(bad("N must be at least 1"));
        }
        if i >= n {
            return Err(bad("I must be below N (shards are numbered 0 … N−1)"));
        }
        Ok(Shard { index: i, count: n })
    }

    /// The speeds of this shard: positions `index, index+count, …` of `speeds`.
    pub fn select(&self, speeds: &[f64]) -> Vec<f64> {
        speeds
            .iter()
            .enumerate()
            .filter(|(i, _)| self.holds(*i))
            .map(|(_, &v)| v)
            .collect()
    }

    /// Whether position `i` (0-based) of the whole list belongs to this shard.
    pub fn holds(&self, i: usize) -> bool {
        i % self.count.max(1) == self.index
    }

    /// Whether this is the whole list (`0/1`).
    pub fn is_all(&self) -> bool {
        self.count <= 1
    }
}

/// File stem of a speed's result (`0054.800000` for 54.8 km/h).
pub(crate) fn speed_file_stem(speed_kmh: f64) -> String {
    format!("{speed_kmh:011.6}")
}

#[cfg(test)]
mod tests {
    use super::{parse_speeds, speed_file_stem, Shard};
    #[test]
    fn range_excludes_an_off_grid_stop_and_includes_an_on_grid_one() {
        let v = parse_speeds("54.8:219:2").unwrap();
        assert_eq!(v.len(), 83);
        assert_eq!(v[0], 54.8);
        assert_eq!(*v.last().unwrap(), 218.8);
        assert_eq!(parse_speeds("54.8:219:1").unwrap().len(), 165);
        let v = parse_speeds("60:100:10").unwrap();
        assert_eq!(v, vec![60.0, 70.0, 80.0, 90.0, 100.0]);
        // 0.1 steps: no accumulated round-off, the stop on the grid is kept.
        let v = parse_speeds("40:41:0.1").unwrap();
        assert_eq!(v.len(), 11);
        assert_eq!(v[3], 40.3);
        assert_eq!(v[10], 41.0);
        assert_eq!(parse_speeds("140:140:5").unwrap(), vec![140.0]);
    }

    #[test]
    fn list_is_sorted_and_checked() {
        assert_eq!(parse_speeds("100, 60,80").unwrap(), vec![60.0, 80.0, 100.0]);
        assert_eq!(parse_speeds("140").unwrap(), vec![140.0]);
        for (spec, needle) in [
            ("60,60", "twice"),
            ("60,abc", "`abc` is not a number"),
            ("0,60", "out of range"),
            ("-5", "out of range"),
            // The model's run.speed_kmh stops at 500 km/h: a sweep may not go beyond it.
            ("600", "allowed 40 to 500 km/h"),
            ("400:600:100", "speed 600 km/h out of range"),
            // nor below 40 km/h, where a passage does not run
            ("39", "allowed 40 to 500 km/h"),
            ("10:50:10", "speed 10 km/h out of range"),
            ("60:50:1", "below start"),
            ("60:70:0", "positive"),
            ("60:70", "start:stop:step"),
            ("40:1e9:1e-3", "at most"),
        ] {
            let e = parse_speeds(spec).unwrap_err().to_string();
            assert!(e.contains(needle) && e.contains(spec), "{spec}: {e}");
        }
    }

    #[test]
    fn shards_partition_the_speeds() {
        let v = parse_speeds("54.8:219:2").unwrap();
        for n in 1..=7 {
            let mut all: Vec<f64> = (0..n)
                .flat_map(|i| Shard { index: i, count: n }.select(&v))
                .collect();
            assert_eq!(all.len(), v.len(), "n = {n}");
            all.sort_by(f64::total_cmp);
            assert_eq!(all, v, "every speed in exactly one of {n} shards");
        }
        assert_eq!(Shard::parse("1/3").unwrap().select(&v)[..2], [56.8, 62.8]);
        assert_eq!(Shard::ALL.select(&v), v);
        for (spec, needle) in [
            ("3/3", "below N"),
            ("0/0", "at least 1"),
            ("a/2", "I must"),
            ("1", "I/N"),
        ] {
            let e = Shard::parse(spec).unwrap_err().to_string();
            assert!(e.contains(needle), "{spec}: {e}");
        }
    }

    #[test]
    fn file_stems_sort_like_speeds() {
        assert_eq!(speed_file_stem(54.8), "0054.800000");
        assert_eq!(speed_file_stem(218.8), "0218.800000");
        assert!(speed_file_stem(99.5) < speed_file_stem(100.0));
    }
}

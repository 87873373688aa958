//! Checks of list-valued inputs (a flag's comma-separated or repeated values, a file key's
//! array): a value given twice is refused, naming the list and the value, since it would
//! silently run or write the same case twice (or once, overwriting itself); positions along
//! the rail must ascend strictly.

use std::fmt::Display;

/// A list that gives one value twice.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{list}: {value} is given twice; give each value once")]
pub struct RepeatedValue {
    /// The flag or key of the list, e.g. `--amplitudes-um` or `speeds_kmh`.
    pub list: String,
    /// The repeated value with its unit, e.g. `40 µm`.
    pub value: String,
}

/// Refuses `values` (the list `list`, values in `unit`, `""` for none) when one equals an
/// earlier one (quadratic in the length: for the short lists of flags and file keys).
pub fn check_no_repeats<T: PartialEq + Display>(
    list: &str,
    unit: &str,
    values: &[T],
) -> Result<(), RepeatedValue> {
    match (0..values.len()).find(|&i| values[..i].contains(&values[i])) {
        Some(i) => Err(repeated(list, unit, &values[i])),
        None => Ok(()),
    }
}

/// As [`check_no_repeats`], two values counting as one when their `key`s are equal (e.g.
/// speeds that name the same file); `n log n` in the length.
pub fn check_no_repeats_by_key<T: Display, K: Ord>(
    list: &str,
    unit: &str,
    values: &[T],
    key: impl Fn(&T) -> K,
) -> Result<(), RepeatedValue> {
    let mut seen = std::collections::BTreeSet::new();
    match values.iter().find(|v| !seen.insert(key(v))) {
        Some(v) => Err(repeated(list, unit, v)),
        None => Ok(()),
    }
}

/// The first place where `x_m` (positions along the rail, m) fails to ascend strictly, as a
/// message naming the two positions and their 1-based rows; `None` when it ascends. Shared by
/// the rail profiles a passage runs over and the measured roughness profiles.
pub fn strictly_ascending_error(x_m: &[f64]) -> Option<String> {
    let i = x_m.windows(2).position(|w| w[1] <= w[0])?;
    Some(format!(
        "positions must ascend strictly: x = {} m then {} m (rows {} and {})",
        x_m[i],
        x_m[i + 1],
        i + 1,
        i + 2
    ))
}

fn repeated<T: Display>(list: &str, unit: &str, v: &T) -> RepeatedValue {
    let value = if unit.is_empty() {
        v.to_string()
    } else {
        format!("{v} {unit}")
    };
    RepeatedValue {
        list: list.to_string(),
        value,
    }
}

#[cfg(test)]
mod tests {
    use super::{check_no_repeats, check_no_repeats_by_key, strictly_ascending_error};
    #[test]
    fn a_repeated_value_is_named_with_its_list_and_unit() {
        assert_eq!(check_no_repeats("--at", "m", &[1.0, 2.0, 3.0]), Ok(()));
        let e = check_no_repeats("--amplitudes-um", "µm", &[40.0, 80.0, 40.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--amplitudes-um: 40 µm is given twice; give each value once"
        );
        let e = check_no_repeats("--variants", "", &["RPM1", "RPM2", "RPM2"]).unwrap_err();
        assert_eq!(e.value, "RPM2");
        let stem = |v: &f64| format!("{v:.6}");
        let e = check_no_repeats_by_key("speeds", "km/h", &[60.0, 80.0, 60.0 + 1e-9], stem);
        assert_eq!(e.unwrap_err().value, "60.000000001 km/h");
        let empty: [f64; 0] = [];
        assert_eq!(check_no_repeats("--at", "m", &empty), Ok(()));
    }

    /// The first descent or repeat is named by its positions and rows; an ascending list and
    /// the empty and one-element lists pass.
    #[test]
    fn the_first_position_that_does_not_ascend_is_named() {
        assert_eq!(strictly_ascending_error(&[]), None);
        assert_eq!(strictly_ascending_error(&[1.0]), None);
        assert_eq!(strictly_ascending_error(&[0.0, 0.5, 2.0]), None);
        let e = strictly_ascending_error(&[0.0, 0.5, 0.5, 0.2]).unwrap();
        assert!(e.contains("x = 0.5 m then 0.5 m (rows 2 and 3)"), "{e}");
    }
}

//! Verification tests of the contact module against closed forms, published tables and
//! conservation laws: the normal solver ([`normal`]) and rolling contact, steady and
//! transient ([`rolling`]), with the fixtures they share.

use super::transient::{HertzGridParams, TransientConfig};
use super::{HertzContact, HertzInput};

mod normal;
mod rolling;

/// The reference wheel-on-rail contact's input: a wheel of rolling radius 0.46 m (laterally
/// flat) on a rail crown of radius 0.3 m, E = 210 GPa, ν = 0.3, 100 kN.
fn reference_hertz_input() -> HertzInput {
    HertzInput::wheel_on_rail(0.46, f64::INFINITY, 0.3, 210e9, 0.3, 100e3)
}

/// The reference contact's Hertz solution.
fn reference_hertz() -> HertzContact {
    HertzContact::solve(&reference_hertz_input()).unwrap()
}

/// The reference case's grid configuration at 38.9 m/s with `nx × ny` elements and the
/// given margin.
fn rolling_config(nx: usize, ny: usize, margin: f64) -> TransientConfig {
    TransientConfig::around_hertz(&HertzGridParams {
        speed_m_per_s: 38.9,
        nx,
        ny,
        margin,
        ..HertzGridParams::default()
    })
    .unwrap()
}

/// Kalker's combined constants of two different steels reproduce Hertz's combined modulus
/// `1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂` (the closed form) and the mean compliance of the
/// shear moduli; identical steels are returned unchanged.
#[test]
fn quasi_identical_pair_keeps_the_hertz_modulus() {
    use super::{combined_modulus, quasi_identical_pair, shear_modulus};
    let (rail, wheel) = ((210e9, 0.3), (180e9, 0.27));
    let (e, nu) = quasi_identical_pair(rail, wheel);
    let hertz = 1.0 / ((1.0 - rail.1 * rail.1) / rail.0 + (1.0 - wheel.1 * wheel.1) / wheel.0);
    approx::assert_relative_eq!(combined_modulus(e, nu), hertz, max_relative = 1e-14);
    let g_mean =
        2.0 / (1.0 / shear_modulus(rail.0, rail.1) + 1.0 / shear_modulus(wheel.0, wheel.1));
    approx::assert_relative_eq!(shear_modulus(e, nu), g_mean, max_relative = 1e-14);
    assert!(nu > wheel.1 && nu < rail.1);
    assert_eq!(quasi_identical_pair(rail, rail), rail);
}

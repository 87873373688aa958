//! Verification tests of the contact module against closed forms, published tables and
//! conservation laws: the normal solver ([`normal`]) and rolling contact, steady and
//! transient ([`rolling`]), with the fixtures they share.

use super::transient::{HertzGridParams, TransientConfig};
use super::{HertzContact, HertzInput};

mod normal;
mod rolling;

/// The reference wheel-on-rail contact: a wheel of rolling radius 0.46 m (laterally flat)
/// on a rail crown of radius 0.3 m, E = 210 GPa, ν = 0.3, 100 kN.
fn reference_hertz() -> HertzContact {
    HertzContact::solve(&HertzInput::wheel_on_rail(
        0.46,
        f64::INFINITY,
        0.3,
        210e9,
        0.3,
        100e3,
    ))
    .unwrap()
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

//! The contact step at which the explicit path's frequency selection has been shown
//! converged, and the warning a passage with a longer one gets.
//!
//! The explicit passage couples the contact to the structures once per contact step
//! `Δt_c = Δx/V` (one contact-grid element over the speed, docs/theory.md §8.1). On the
//! default model at 140 km/h its selected wear frequency depends on that step until it is
//! short enough to resolve the stiff contact oscillation: at `contact.grid_nx` 32 (Δt_c
//! 16 µs, the model's default grid) the strongest wear component is a spurious 622 Hz, at
//! 64 (8.1 µs) and 128 (4.0 µs) it is the 1066 Hz wheel mode, the two within 0.7 %
//! (validation/explicit.md). The reduced passage is converged at the default grid (its
//! residual flexibility stands in for the local stiffness), so only the explicit path warns.

use crate::model::Model;
use crate::passage::setup::contact_config_for;
use crate::passage::PassageError;
use crate::units::ms_to_kmh;

/// The longest contact step `Δx/V` (s) at which the explicit path's frequency selection has
/// been shown converged: 8.1 µs, `contact.grid_nx` 64 on the default grid at 140 km/h
/// (8.06 µs), whose dominant wear frequency is within 0.7 % of grid_nx 128's.
pub(crate) const CONVERGED_CONTACT_STEP_S: f64 = 8.1e-6;

/// The warning for an explicit passage of `model` at `speed_m_per_s` (m/s) whose contact
/// step is longer than `CONVERGED_CONTACT_STEP_S`, with the `contact.grid_nx` that would
/// bring it there; `None` when it is within.
pub fn unconverged_contact_step(
    model: &Model,
    speed_m_per_s: f64,
) -> Result<Option<String>, PassageError> {
    let grid = contact_config_for(model, speed_m_per_s)?.grid;
    let dt_c = grid.dx() / speed_m_per_s;
    if dt_c <= CONVERGED_CONTACT_STEP_S {
        return Ok(None);
    }
    let nx = (grid.nx as f64 * dt_c / CONVERGED_CONTACT_STEP_S).ceil();
    Ok(Some(format!(
        "the explicit passage's contact step Δx/V = {:.1} µs (contact.grid_nx {} at {:.1} km/h) is longer than the {:.1} µs at which its frequency selection was shown converged: on the default model the 16 µs step of grid_nx 32 selects a spurious 622 Hz, 8.1 and 4.0 µs (grid_nx 64, 128) the 1066 Hz wheel mode (validation/explicit.md); set contact.grid_nx to at least {nx} (contact.grid_ny 16 keeps the cost down)",
        dt_c * 1e6,
        grid.nx,
        ms_to_kmh(speed_m_per_s),
        CONVERGED_CONTACT_STEP_S * 1e6,
    )))
}

#[cfg(test)]
mod tests {
    use super::{unconverged_contact_step, Model};
    /// The default model's grid at 140 km/h: 2 × 10.03 mm / 32 / 38.9 m/s = 16.1 µs, warned
    /// with grid_nx 64 proposed; grid_nx 64 (8.06 µs) and 128 are within; a slower train on
    /// grid_nx 64 is warned again (the step grows as 1/V).
    #[test]
    fn the_default_grid_is_warned_and_grid_nx_64_is_not() {
        let m = Model::default_model();
        let v = m.run.speed();
        let w = unconverged_contact_step(&m, v).unwrap().expect("a warning");
        assert!(w.contains("16.1 µs") && w.contains("at least 64"), "{w}");
        for nx in [64, 128] {
            let m = crate::model::load_model(
                &crate::model::ModelSource::Builtin,
                &[format!("contact.grid_nx={nx}"), "contact.grid_ny=16".into()],
            )
            .unwrap();
            assert!(unconverged_contact_step(&m, v).unwrap().is_none(), "{nx}");
            let slow = unconverged_contact_step(&m, 0.5 * v).unwrap();
            assert_eq!(slow.is_some(), nx == 64, "{nx}: {slow:?}");
        }
    }
}

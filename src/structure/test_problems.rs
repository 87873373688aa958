//! The test problems that need substructures: the all-modes model's track and wheel,
//! small enough for a dense eigen-solve of each (a few thousand DOFs). Beside the model's
//! own test problems ([`crate::model::test_problems`]), one layer up, because they build
//! [`TrackStructure`] and [`WheelStructure`].

use crate::mesh::wheel::WheelParams;
use crate::model::Model;
use crate::structure::{StructureError, TrackStructure, WheelStructure};

/// The all-modes wheel's mesh: the model's wheel ([`WheelStructure::params_of`]) with 8
/// circumferential segments, 0.4 m elements, a 10 mm fine zone at the contact, one element
/// through the web, no brake disc (the keys allow at least 12 segments and at most 0.1 m,
/// and always mesh the disc), and a short, thick-walled half axle: the symmetry plane
/// 0.15 m from the rolling circle (0.75 m on the default wheel), the hub from −0.1 m, the
/// journal at 0.09–0.13 m with a 0.08 m radius and a 0.05 m bore. About 3,000 free DOFs
/// instead of 17,645; not a physical wheel (its unsprung mass is smaller, and the sprung
/// mass makes up the static load).
pub(crate) fn all_modes_wheel_params(m: &Model) -> WheelParams {
    WheelParams {
        symmetry_plane_distance_m: 0.15,
        hub_y_m: [-0.1, 0.065],
        journal_y_m: [0.09, 0.13],
        journal_radius_m: 0.08,
        bore_radius_m: 0.05,
        circumferential_divisions: 8,
        axial_size_m: 0.4,
        radial_size_m: 0.4,
        contact_size_m: 0.4,
        contact_half_width_m: 0.01,
        web_layers: 1,
        brake_disc: None,
        ..WheelStructure::params_of(m)
    }
}

/// The track and the wheel of an all-modes model ([`all_modes_model`](crate::model::test_problems::all_modes_model)): the track as the
/// model builds it, the wheel on `all_modes_wheel_params`.
pub fn all_modes_structures(m: &Model) -> Result<(TrackStructure, WheelStructure), StructureError> {
    let track = TrackStructure::build(m)?;
    let wheel = WheelStructure::with_params(m, all_modes_wheel_params(m))?;
    Ok((track, wheel))
}

#[cfg(test)]
mod tests {
    use super::all_modes_structures;
    use crate::model::test_problems::{all_modes_model, ALL_MODES_ELEMENT_LENGTH_M};

    /// The all-modes structures are within reach of a dense eigen-solve (a few thousand
    /// DOFs each) and undamped, and the model keeps the element length outside its key's
    /// range.
    #[test]
    fn the_all_modes_structures_are_small_and_undamped() {
        let m = all_modes_model(&[]).unwrap();
        assert_eq!(m.mesh.element_length, ALL_MODES_ELEMENT_LENGTH_M);
        let (track, wheel) = all_modes_structures(&m).unwrap();
        let dofs = [track.dofmap.n_free(), wheel.dofmap.n_free()];
        assert!(dofs.iter().all(|&n| n < 3100), "free DOFs {dofs:?}");
        let (tm, _) = track.assemble().unwrap();
        let (wm, _) = wheel.assemble().unwrap();
        for c in [&tm.c, &wm.c] {
            assert!(c.as_ref().val().iter().all(|&x| x == 0.0));
        }
    }
}

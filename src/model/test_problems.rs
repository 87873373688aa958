//! Small models for the tests, the examples and quick checks: the default track cut to
//! four bays with a coarse rail section and wheel, which keeps every part of the physics and
//! builds in well under a second (the default model takes minutes to solve).

use super::{load_model, Model, ModelError, ModelSource};

/// The overrides (`key=value`, as `--set` takes them) that turn the default model into the
/// small test model: 4 bays, 80 mm elements along the rail, a 30 mm rail section (15 mm in
/// the head), a wheel of 12 segments and 0.1 m elements.
pub const SMALL_MODEL: [&str; 7] = [
    "track.bays=4",
    "mesh.element_length=0.08",
    "mesh.fine_element_length=0.08",
    "mesh.section_size=0.03",
    "mesh.head_size=0.015",
    "mesh.wheel_segments=12",
    "mesh.wheel_element_size=0.1",
];

/// The small test model with `extra` overrides applied after [`SMALL_MODEL`] (so they win).
pub fn small_model(extra: &[&str]) -> Result<Model, ModelError> {
    let sets: Vec<String> = SMALL_MODEL
        .iter()
        .chain(extra)
        .map(|s| s.to_string())
        .collect();
    load_model(&ModelSource::Builtin, &sets)
}

/// The small test model with elements of `element_length_m` (m) along the whole rail, and
/// `extra` overrides after that.
pub fn small_model_with_elements(
    element_length_m: f64,
    extra: &[&str],
) -> Result<Model, ModelError> {
    let lengths = [
        format!("mesh.element_length={element_length_m}"),
        format!("mesh.fine_element_length={element_length_m}"),
    ];
    let mut all: Vec<&str> = lengths.iter().map(String::as_str).collect();
    all.extend_from_slice(extra);
    small_model(&all)
}

/// The overrides, after [`SMALL_MODEL`], of the small passage model: 6 bays so that the
/// wheel runs up to a 0.4 m solution zone, modes to 1.5 kHz, a 16 × 12 contact grid. A
/// passage over it takes a fraction of a second.
pub const SMALL_PASSAGE: [&str; 6] = [
    "track.bays=6",
    "run.fmax=1500",
    "run.solution_zone_offset=0.3",
    "run.solution_zone_length=0.4",
    "contact.grid_nx=16",
    "contact.grid_ny=12",
];

/// The small passage model ([`SMALL_MODEL`] then [`SMALL_PASSAGE`]) with `extra` overrides
/// after them.
pub fn small_passage_model(extra: &[&str]) -> Result<Model, ModelError> {
    let all: Vec<&str> = SMALL_PASSAGE.iter().chain(extra).copied().collect();
    small_model(&all)
}

/// The overrides, after [`SMALL_MODEL`], of the all-modes model: 2 bays of the RPM5
/// fastening (fewest node planes along the rail), one-element sleepers, a 50 mm rail section
/// throughout, a 0.3 m zone 0.2 m after the wheel's start, every damper off (fastenings,
/// ballast, rail, primary suspension, wheel modes) and a 32 × 12 contact grid.
pub(crate) const ALL_MODES: [&str; 22] = [
    "track.bays=2",
    "fastening.model=\"RPM5\"",
    "mesh.sleeper_elements=[1,1,1]",
    "mesh.element_length=0.15",
    "mesh.fine_element_length=0.15",
    "mesh.section_size=0.05",
    "mesh.head_size=0.05",
    "mesh.mass=\"lumped\"",
    "run.solution_zone_offset=0.2",
    "run.solution_zone_length=0.3",
    "contact.grid_nx=32",
    "contact.grid_ny=12",
    "fastening.vertical_damping=0",
    "fastening.lateral_damping=0",
    "fastening.longitudinal_damping=0",
    "ballast.vertical_damping=0",
    "ballast.lateral_damping=0",
    "ballast.longitudinal_damping=0",
    "vehicle.primary_damping=0",
    "wheel.damping_ratio=0",
    "run.residual_flexibility=false",
    "run.wheel_residual_flexibility=false",
];

/// Element length along the whole rail of the all-modes track (m): 0.3 m, half the sleeper
/// spacing, twice the longest the key `mesh.element_length` allows (a quarter of the
/// spacing, which keeps the sleeper-pitch bending of a real track resolved).
pub const ALL_MODES_ELEMENT_LENGTH_M: f64 = 0.3;

/// The all-modes model: [`SMALL_MODEL`], `ALL_MODES` and `extra` (the last wins), then the
/// rail's element length set to [`ALL_MODES_ELEMENT_LENGTH_M`] *without* the range check of
/// `mesh.element_length` (the only value outside its key's range). A model for tests that
/// need every mode of both substructures from a dense eigen-solve (a few thousand DOFs
/// each; `structure::test_problems::all_modes_structures`), such as the identity of the reduced and the explicit
/// passage with complete bases (docs/theory.md §8.6): it is not a physical track model.
pub fn all_modes_model(extra: &[&str]) -> Result<Model, ModelError> {
    let all: Vec<&str> = ALL_MODES.iter().chain(extra).copied().collect();
    let mut m = small_model(&all)?;
    m.mesh.element_length = ALL_MODES_ELEMENT_LENGTH_M;
    m.mesh.fine_element_length = ALL_MODES_ELEMENT_LENGTH_M;
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::{small_model, small_model_with_elements};
    #[test]
    fn the_small_model_is_small_and_extra_overrides_win() {
        let m = small_model(&["track.bays=3"]).unwrap();
        assert_eq!(m.track.bays, 3);
        assert_eq!(m.mesh.element_length, 0.08);
        let m = small_model_with_elements(0.04, &[]).unwrap();
        assert_eq!(
            (m.mesh.element_length, m.mesh.fine_element_length),
            (0.04, 0.04)
        );
        assert_eq!(m.track.bays, 4);
    }
}

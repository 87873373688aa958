//! The one place where the commands `sweep`, `study` and `initiation` get their passage
//! engine. Until the reduced-order passage (src/dynamics) is finished these return an error;
//! wiring the engine in means replacing the bodies of the functions below, nothing else.

use std::collections::BTreeMap;
use std::path::Path;

use corrugation::dynamics::PassageRunner;
use corrugation::model::Model;

const NOT_WIRED: &str = "the passage engine is not wired yet (src/cli/engine.rs)";

/// The passage runner of a model: modal basis from the cache in `cache` (default cache
/// directory when `None`), built once, then any number of passages.
pub fn runner_for(model: &Model, cache: Option<&Path>) -> anyhow::Result<Box<dyn PassageRunner>> {
    let _ = (model, cache);
    anyhow::bail!(NOT_WIRED)
}

/// The longitudinal-compression eigenfrequencies of the model's track below the passage's
/// f_max (Hz), for the lines of the frequency-selection maps.
pub fn longitudinal_frequencies_hz(
    model: &Model,
    cache: Option<&Path>,
) -> anyhow::Result<Vec<f64>> {
    let _ = (model, cache);
    anyhow::bail!(NOT_WIRED)
}

/// The growth loop of one study case (`growth = true` in a study file): named scalar results
/// (e.g. `limiting_amplitude_um`) that become columns of the study table.
pub fn study_growth(
    model: &Model,
    runner: &dyn PassageRunner,
) -> anyhow::Result<BTreeMap<String, f64>> {
    let _ = (model, runner);
    anyhow::bail!("the growth loop is not wired into studies yet (src/cli/engine.rs)")
}

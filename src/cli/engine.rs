//! The one place where the commands get their passage engine: the reduced-order engine of
//! [`corrugation::dynamics::prepared::PreparedModel`] (modal bases from the cache, built once
//! per model), or with `--engine explicit` the full explicit FE path
//! ([`corrugation::explicit::ExplicitModel`], docs/theory.md §8).

use std::path::Path;

use anyhow::Context;
use corrugation::dynamics::PassageRunner;
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::explicit::{ExplicitModel, ExplicitOptions, ExplicitRunner};
use corrugation::model::Model;

/// Which engine runs the passages (`--engine`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// The reduced-order modal passage (default).
    #[default]
    Reduced,
    /// The full explicit FE path (untruncated track and wheel; minutes per passage).
    Explicit,
}

/// The explicit FE model of `model` (its `[explicit]` options); warns when its contact step at
/// the model's speed is longer than the converged one
/// ([`corrugation::explicit::contact_step::unconverged_contact_step`]).
pub(crate) fn explicit_model(model: &Model) -> anyhow::Result<ExplicitModel> {
    if let Some(w) =
        corrugation::explicit::contact_step::unconverged_contact_step(model, model.run.speed())?
    {
        eprintln!("warning: {w}");
    }
    ExplicitModel::new(model, ExplicitOptions::from_model(model))
        .context("building the explicit FE model")
}

/// The passage runner of a model on `engine` (see [`runner_for`]).
pub(crate) fn runner_for_engine(
    model: &Model,
    cache: Option<&Path>,
    engine: Engine,
) -> anyhow::Result<Box<dyn PassageRunner>> {
    match engine {
        Engine::Reduced => runner_for(model, cache),
        Engine::Explicit => Ok(Box::new(ExplicitRunner {
            model: explicit_model(model)?,
        })),
    }
}

fn cache_of(cache: Option<&Path>) -> ModalCache {
    ModalCache::new(
        cache
            .map(Path::to_path_buf)
            .unwrap_or_else(default_cache_dir),
    )
}

/// The prepared reduced-order model (modal bases loaded from or stored in the cache).
/// The eigen-solves and their classification are shown as they run (a bar on a terminal,
/// plain lines every interval otherwise).
pub fn prepared(model: &Model, cache: Option<&Path>) -> anyhow::Result<PreparedModel> {
    let pb = std::sync::Arc::new(super::progress::bar(&format!(
        "modal bases below {} Hz (track and wheel; loaded from the cache or computed)",
        model.run.fmax
    )));
    let cache = cache_of(cache).with_progress(pb.clone());
    let p = PreparedModel::new(model, &cache, &PassageOptions::default())
        .context("preparing the modal model")?;
    pb.finish_and_clear();
    Ok(p)
}

/// The passage runner of a model: modal basis from the cache in `cache` (default cache
/// directory when `None`), built once, then any number of passages.
pub(crate) fn runner_for(
    model: &Model,
    cache: Option<&Path>,
) -> anyhow::Result<Box<dyn PassageRunner>> {
    Ok(Box::new(prepared(model, cache)?))
}

//! Command definitions (clap) and dispatch. Each command lives in its own file.

mod cache_cmd;
mod compliance_cmd;
mod contact_cmd;
pub(crate) mod coupled_modes_cmd;
pub mod engine;
mod explicit_cmd;
mod grow_cmd;
mod initiation_cmd;
mod merge_cmd;
mod mesh_cmd;
mod model_cmd;
mod modes_cmd;
mod passage_cmd;
mod predict_cmd;
mod progress;
mod receptance_cmd;
pub(crate) mod reference_outputs;
mod roughness_cmd;
mod study_cmd;
mod sweep_cmd;

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use corrugation::model::{load_model, Model, ModelSource};

/// Short-pitch rail corrugation predictor (3D FE track model, modal reduction, transient
/// rolling contact, wear growth). All inputs are SI unless a key or flag names its unit.
#[derive(Debug, Parser)]
#[command(name = "corrugation", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The model every command works on.
#[derive(Debug, Clone, Args)]
pub(crate) struct ModelArgs {
    /// Model file (TOML). Default: the embedded Dutch track model (RPM3).
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    /// Override a model value, TOML syntax: --set fastening.model=RPM1 --set track.bays=20.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

impl ModelArgs {
    /// The model source.
    pub fn source(&self) -> ModelSource {
        match &self.model {
            Some(p) => ModelSource::File(p.clone()),
            None => ModelSource::Builtin,
        }
    }

    /// Loads and validates the model; warns on stderr about values whose magnitude looks
    /// like a unit slip ([`Model::unit_slips`]).
    pub fn load(&self) -> anyhow::Result<Model> {
        let m = load_model(&self.source(), &self.set)?;
        let name = self
            .model
            .as_ref()
            .map_or("builtin:dutch".to_string(), |p| p.display().to_string());
        warn_unit_slips(&name, &m);
        Ok(m)
    }
}

/// Warns on stderr about the values of `m` (named `name`) whose magnitude looks like a unit
/// slip ([`Model::unit_slips`]) and about a solution-zone mesh whose element-passing ripple
/// falls in the analysis band ([`Model::mesh_in_band`]).
pub(crate) fn warn_unit_slips(name: &str, m: &Model) {
    for slip in m.unit_slips() {
        eprintln!("warning: {name}: {slip}");
    }
    if let Some(w) = m.mesh_in_band() {
        eprintln!("warning: {name}: {w}");
    }
}

/// Reads the rail profile of `--corrugation FILE` (x in m, height in µm) and checks, before
/// any work, that the contact grid a passage of `m` over it needs is within its bound
/// ([`corrugation::passage::setup::check_profile_grid`]); warns when its depth looks like a
/// unit slip.
pub(crate) fn read_profile(
    path: &std::path::Path,
    m: &Model,
) -> anyhow::Result<corrugation::dynamics::RailProfile> {
    let p = corrugation::dynamics::RailProfile::read_csv_um(path)?;
    let warning = corrugation::passage::setup::check_profile_grid(m, p.peak_to_trough_m())
        .map_err(|e| anyhow::anyhow!("--corrugation {}: {e}", path.display()))?;
    if let Some(w) = warning {
        eprintln!("warning: --corrugation {}: {w}", path.display());
    }
    Ok(p)
}

/// Checks, before any work, that the largest trial amplitude of `--amplitudes-um` (µm,
/// peak-to-trough) gives a contact grid within its bound on the model `m`
/// ([`corrugation::passage::setup::check_profile_grid`]); warns when it looks like a unit
/// slip.
pub(crate) fn check_trial_profile_grid(amplitudes_um: &[f64], m: &Model) -> anyhow::Result<()> {
    let Some(a) = amplitudes_um.iter().copied().reduce(f64::max) else {
        return Ok(());
    };
    let ptp = corrugation::units::um_to_m(a);
    if let Some(w) = corrugation::passage::setup::check_profile_grid(m, ptp)
        .map_err(|e| anyhow::anyhow!("--amplitudes-um {a}: {e}"))?
    {
        eprintln!("warning: --amplitudes-um {a}: {w}");
    }
    Ok(())
}

/// Refuses an `--out` that is the modal cache's directory (`--cache`, or the default one) or
/// lies inside it, before anything is created or computed (see
/// [`corrugation::eigen::cache::ensure_outside_cache`]).
pub(crate) fn check_out_outside_cache(
    out: &std::path::Path,
    cache: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    let cache_dir = cache.map_or_else(
        corrugation::eigen::cache::default_cache_dir,
        std::path::Path::to_path_buf,
    );
    check_cache_dir(&cache_dir, cache.is_some())?;
    corrugation::eigen::cache::ensure_outside_cache(out, &cache_dir)
        .map_err(|e| anyhow::anyhow!("--out: {e}"))
}

/// Refuses a modal cache path that exists and is not a directory (`given`: it is the
/// `--cache` flag's, else the default): the modes could not be stored there, and every run
/// would recompute them without a word.
pub(crate) fn check_cache_dir(dir: &std::path::Path, given: bool) -> anyhow::Result<()> {
    match std::fs::metadata(dir) {
        Ok(md) if !md.is_dir() => {
            let what = if given {
                "--cache".to_string()
            } else {
                "the default modal cache directory".to_string()
            };
            anyhow::bail!(
                "{what} {}: is a file, not a directory: the modes could not be cached there; give a directory (created if missing){}",
                dir.display(),
                if given { "" } else { " with --cache" }
            )
        }
        _ => Ok(()),
    }
}

/// Creates the output directory `--out` and checks that it can be written, before any work;
/// removes the temp files a killed earlier run left in it
/// ([`corrugation::io::remove_stale_temp_files`]: the writers' own temp names of dead
/// processes, in this directory only).
pub(crate) fn check_out_dir(dir: &std::path::Path) -> anyhow::Result<()> {
    let fail =
        |e: std::io::Error| anyhow::anyhow!("--out {}: cannot write there: {e}", dir.display());
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(format!(".write-check.{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(fail)?;
    std::fs::remove_file(&probe).map_err(fail)?;
    corrugation::io::remove_stale_temp_files(dir).map_err(fail)?;
    Ok(())
}

/// Every command whose flags take numbers accepts negative ones
/// (`allow_negative_numbers`), so that its range check refuses them with the flag, the unit
/// and the range (not clap's "unexpected argument").
#[derive(Debug, Subcommand)]
enum Command {
    /// Print the resolved model (after `extends` and `--set`) as TOML.
    Model(model_cmd::ModelCmd),
    /// Build the 3D FE track model and print its summary (nodes, DOFs, section, masses).
    Mesh(mesh_cmd::MeshCmd),
    /// Solve the wheel-rail contact (Hertz, half-space grid, Kalker tangential contact).
    #[command(allow_negative_numbers = true)]
    Contact(contact_cmd::ContactCmd),
    /// Eigenmodes of the track and the wheel (classified, cached): modes.csv, wheel_modes.csv.
    #[command(allow_negative_numbers = true)]
    Modes(modes_cmd::ModesCmd),
    /// One reduced-order wheel passage: contact forces, wear along the rail, PSDs, plots.
    #[command(allow_negative_numbers = true)]
    Passage(passage_cmd::PassageCmd),
    /// One passage of the full explicit FE path (untruncated track and wheel): the files of
    /// `passage` plus explicit.json.
    #[command(allow_negative_numbers = true)]
    Explicit(explicit_cmd::ExplicitCmd),
    /// Receptances of the rail and the wheel at the contact and the contact force per unit
    /// roughness, with their peaks (which resonances a sweep can lock on).
    #[command(allow_negative_numbers = true)]
    Receptance(receptance_cmd::ReceptanceCmd),
    /// Trial-amplitude growth (consistency, phase, limiting amplitude); --rounds for iterative growth.
    #[command(allow_negative_numbers = true)]
    Grow(grow_cmd::GrowCmd),
    /// The main job: modes (cached), smooth passage, trial growth, short speed sweep, report.
    #[command(allow_negative_numbers = true)]
    Predict(predict_cmd::PredictCmd),
    /// Speed sweep (parallel, resumable, --shard I/N): frequency-selection maps, dominant
    /// wavelength and frequency vs speed.
    #[command(allow_negative_numbers = true)]
    Sweep(sweep_cmd::SweepCmd),
    /// Join the output directories of a sharded sweep into the unsharded result.
    Merge(merge_cmd::MergeCmd),
    /// A measured rail roughness (profile or one-third-octave spectrum): which wavelengths
    /// grow at which speeds, how fast, the levels after a traffic against the ISO 3095 limit.
    #[command(allow_negative_numbers = true)]
    Roughness(roughness_cmd::RoughnessCmd),
    /// Design study from a TOML file: parameters varied over a base model, indicators per case.
    Study(study_cmd::StudyCmd),
    /// Initiation table of RPM1–RPM5 (or any models) on the smooth rail.
    #[command(allow_negative_numbers = true)]
    Initiation(initiation_cmd::InitiationCmd),
    /// Static longitudinal compliance of RPM1–RPM5, rigid and with elastic x-holds: u_x of
    /// the rail head, web and foot ahead of a wheel load with a longitudinal force.
    #[command(allow_negative_numbers = true)]
    Compliance(compliance_cmd::ComplianceCmd),
    /// Coupled wheel–track modes (contact linearised at the static state): frequency,
    /// damping, energy shares in wheel, rail (by family) and support.
    #[command(allow_negative_numbers = true)]
    CoupledModes(coupled_modes_cmd::CoupledModesCmd),
    /// The modal cache: its entries (size, basis, last use); --max-size-gb or --max-idle-days
    /// remove the least recently used.
    Cache(cache_cmd::CacheCmd),
}

/// Runs the parsed command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Model(c) => c.run(),
        Command::Mesh(c) => c.run(),
        Command::Contact(c) => c.run(),
        Command::Modes(c) => c.run(),
        Command::Passage(c) => c.run(),
        Command::Explicit(c) => c.run(),
        Command::Receptance(c) => c.run(),
        Command::Grow(c) => c.run(),
        Command::Predict(c) => c.run(),
        Command::Sweep(c) => c.run(),
        Command::Merge(c) => c.run(),
        Command::Roughness(c) => c.run(),
        Command::Study(c) => c.run(),
        Command::Initiation(c) => c.run(),
        Command::Compliance(c) => c.run(),
        Command::Cache(c) => c.run(),
        Command::CoupledModes(c) => c.run(),
    }
}

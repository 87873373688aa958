//! `corrugation explicit`: one passage of the full explicit FE path (docs/theory.md §8): the
//! untruncated track and wheel, central difference, the same contact, wear and analysis as
//! `passage`. The wheel does not rotate (its contact point is fixed on the wheel, as in the
//! reduced model) unless `--wheel rotating` (or `explicit.wheel = "rotating"`) spins it at
//! V/R. Writes the files of `passage` plus `explicit.json` (time steps, ω_max, step counts,
//! energy error, wall and CPU time, wheel treatment and spin rate).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::dynamics::RailProfile;
use corrugation::explicit::{ExplicitModel, ExplicitOptions};
use corrugation::model::ExplicitWheel;

use super::ModelArgs;

/// One explicit FE passage: contact forces, wear along the rail, PSDs, plots, explicit.json.
#[derive(Debug, Args)]
pub(crate) struct ExplicitCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Rail-top profile (CSV with a header: x in m, height in µm), e.g. a corrugation.
    #[arg(long, value_name = "FILE.csv")]
    corrugation: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/explicit", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary (the keys of `passage --json` plus the explicit figures) as JSON.
    #[arg(long)]
    json: bool,
    /// The wheel treatment (overrides `explicit.wheel`): `fixed` (not rotating, the contact
    /// point fixed on the wheel) or `rotating` (spinning at V/R, docs/theory.md §8.7).
    #[arg(long, value_enum, value_name = "fixed|rotating")]
    wheel: Option<WheelArg>,
    /// Also keep the energy audit (every contact step replayed with the forces the
    /// structures carried, its nodal work summed; twice the structural cost) in
    /// explicit.json (docs/theory.md §8.8). Fixed wheel only: refused with the rotating
    /// wheel.
    #[arg(long)]
    audit: bool,
}

/// `--wheel`: the explicit path's wheel treatment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum WheelArg {
    /// Not rotating (the reduced model's wheel).
    Fixed,
    /// Spinning at V/R with the Coriolis and spin-softening terms.
    Rotating,
}

impl ExplicitCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let mut m = self.model.load()?;
        match self.wheel {
            Some(WheelArg::Fixed) => m.explicit.wheel = ExplicitWheel::Fixed,
            Some(WheelArg::Rotating) => m.explicit.wheel = ExplicitWheel::Rotating,
            None => {}
        }
        if self.audit && m.explicit.wheel == ExplicitWheel::Rotating {
            anyhow::bail!(
                "--audit replays the fixed wheel's passage only; the rotating wheel (--wheel \
                 rotating or explicit.wheel = \"rotating\") keeps its energy ledger without an \
                 audit (docs/theory.md §8.8): drop --audit or use --wheel fixed"
            );
        }
        let profile = match &self.corrugation {
            Some(p) => Some(super::read_profile(p, &m)?),
            None => None,
        };
        let opts = ExplicitOptions {
            audit: self.audit,
            ..ExplicitOptions::from_model(&m)
        };
        run_explicit(&m, opts, profile.as_ref(), &self.out, self.json)
    }
}

/// One explicit passage of `m` over `profile`, its files in `out` (those of `passage` plus
/// `explicit.json`) and its summary on stdout (`json`: as JSON).
pub(crate) fn run_explicit(
    m: &corrugation::model::Model,
    opts: ExplicitOptions,
    profile: Option<&RailProfile>,
    out: &Path,
    json: bool,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let pb = super::progress::bar("explicit: set-up (assembly, static solves, stable step)");
    let em = ExplicitModel::new(m, opts).context("building the explicit model")?;
    if let Some(w) = em
        .check_profile(m.run.speed(), profile)
        .context("--corrugation")?
    {
        corrugation::progress::Progress::warn(&pb, &w);
    }
    if let Some(w) =
        corrugation::explicit::contact_step::unconverged_contact_step(m, m.run.speed())?
    {
        corrugation::progress::Progress::warn(&pb, &w);
    }
    let estimate = em.passage_estimate(m.run.speed(), profile)?;
    pb.finish_and_clear();
    eprintln!("explicit passage: estimated {estimate}");
    pb.set_message("explicit passage (contact steps)");
    let opts = PassageOptions::default();
    let rec = em
        .passage(m.run.speed(), profile, &opts, Some(&pb))
        .context("running the explicit passage")?;
    pb.finish_and_clear();
    let summary = corrugation::passage::analysis::summarise(&rec.record)?;
    corrugation::studies::passage::write_passage(
        out,
        &rec.record,
        &summary,
        m.mesh.fine_element_length,
    )?;
    corrugation::studies::passage::write_explicit_json(out, &rec)?;
    if json {
        let mut v = serde_json::to_value(&summary)?;
        if let (Some(o), serde_json::Value::Object(e)) =
            (v.as_object_mut(), serde_json::to_value(&rec.info)?)
        {
            for (k, x) in e {
                o.insert(format!("explicit_{k}"), x);
            }
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        for line in corrugation::studies::passage::summary_lines(&summary, &rec.record) {
            println!("{line}");
        }
        println!("  outputs in {}", out.display());
        let i = &rec.info;
        println!(
                "  explicit: track {} + wheel {} DOFs ({} wheel{}); dt {:.3e} s (track, {} per contact step), {:.3e} s (wheel, {}); ω_max {:.4e} rad/s (Gershgorin bound {:.4e}); {} FE steps in {:.1} s wall{}",
                i.dofs[0],
                i.dofs[1],
                i.wheel,
                if i.wheel == "rotating" {
                    format!(" at {:.2} rad/s", i.spin_rate_rad_s)
                } else {
                    String::new()
                },
                i.dt_s,
                i.track_substeps,
                i.dt_wheel_s,
                i.wheel_substeps,
                i.omega_max_estimate,
                i.omega_max_bound,
                i.steps,
                i.seconds,
                i.cpu_seconds
                    .map_or(String::new(), |c| format!(", {c:.1} s CPU"))
            );
    }
    Ok(())
}

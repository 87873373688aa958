//! The printed side of the outputs of a passage that relate its frequencies to the structure: the coupled
//! wheel–track mode each selected frequency belongs to (docs/theory.md §7.10), and the
//! reference study's own procedure, the nodal spectrum of rail-top points (docs/theory.md
//! §9.7), beside the longitudinal-compression eigenfrequencies.
//!
//! Files in the passage's output directory:
//! * `coupled_modes.csv/.npy/.json` (see `corrugation coupled-modes`);
//! * `coupled_attribution.json` — `{wear, fl, fn}`: each component's frequency attributed to
//!   the nearest coupled mode the contact sees, with its energy shares;
//! * `nodal_spectrum.json` — per rail-top point (default the sleeper and the mid-span nearest
//!   the solution-zone centre) the peaks of the longitudinal displacement's spectrum over
//!   the reference's short record (contact from 0.1 m before to 0.2 m after the point) and
//!   over the whole solution zone, each with its duration and frequency resolution, and the
//!   longitudinal-compression eigenfrequencies.

use std::path::Path;

use clap::Args;

use corrugation::dynamics::coupled::attribution_text;
use corrugation::dynamics::prepared::PreparedModel;
use corrugation::dynamics::RailProfile;
use corrugation::passage::summary::PassageSummary;
use corrugation::studies::coupled::{passage_attribution, SummaryAttribution};
use corrugation::studies::nodal::{nodal_outputs, NodalPoint};

/// Options of the structural outputs of a passage.
#[derive(Debug, Clone, Args)]
pub(crate) struct ReferenceArgs {
    /// Skip the coupled wheel–track modes and the attribution of the selected frequencies.
    #[arg(long)]
    pub no_coupled: bool,
    /// Rail-top points (m along the rail) whose longitudinal displacement spectrum is
    /// reported ("f_L by the nodal spectrum"); default: the sleeper and the mid-span nearest
    /// the solution-zone centre. One extra passage per point.
    #[arg(allow_hyphen_values = true, long = "nodal-at", value_name = "M")]
    pub nodal_at_m: Vec<f64>,
    /// Skip the nodal spectra.
    #[arg(long)]
    pub no_nodal: bool,
}

impl ReferenceArgs {
    /// Refuses, before any work, a `--nodal-at` point given twice or off the track of `m` (0
    /// to the track's length, `track.bays × track.sleeper_spacing`, m).
    pub fn check(&self, m: &corrugation::model::Model) -> anyhow::Result<()> {
        corrugation::lists::check_no_repeats("--nodal-at", "m", &self.nodal_at_m)?;
        Ok(m.check_on_track("--nodal-at", &self.nodal_at_m)?)
    }
}

/// The coupled modes at the passage speed, written to `out`, and the summary's components
/// attributed to them ([`passage_attribution`]); prints one line per wear component.
pub fn coupled_attribution(
    prepared: &PreparedModel,
    s: &PassageSummary,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<SummaryAttribution> {
    let (_, a) = passage_attribution(prepared, s, out)?;
    if !quiet {
        println!("  wear components by coupled mode:");
        for x in &a.wear {
            println!("    {}", attribution_text(x));
        }
    }
    Ok(a)
}

/// The nodal spectra of the rail-top points of `args` ([`nodal_outputs`], written to
/// `nodal_spectrum.json`); prints one line per record unless `quiet`.
pub(crate) fn nodal_outputs_printed(
    prepared: &mut PreparedModel,
    speed_m_per_s: f64,
    profile: Option<&RailProfile>,
    args: &ReferenceArgs,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<Vec<NodalPoint>> {
    let (res, lc) = nodal_outputs(prepared, speed_m_per_s, profile, &args.nodal_at_m, out)?;
    if !quiet {
        print_nodal(&res, &lc, prepared.engine.model().run.fmax);
    }
    Ok(res)
}

fn print_nodal(points: &[NodalPoint], lc_hz: &[f64], fmax: f64) {
    for p in points {
        for s in &p.spectra {
            let peaks: Vec<String> = s
                .peaks
                .iter()
                .map(|k| format!("{:.0}", k.frequency_hz))
                .collect();
            println!(
                "  f_L by the nodal spectrum, {} at x = {:.3} m, {} record ({:.1} ms, resolution {:.0} Hz): {} Hz",
                p.label,
                s.point_x_m,
                s.record,
                corrugation::units::s_to_ms(s.duration_s),
                s.resolution_hz,
                peaks.join(", ")
            );
        }
    }
    let lc: Vec<String> = lc_hz
        .iter()
        .filter(|&&f| f <= fmax)
        .take(12)
        .map(|f| format!("{f:.0}"))
        .collect();
    println!(
        "  longitudinal-compression eigenfrequencies: {} Hz",
        lc.join(", ")
    );
}

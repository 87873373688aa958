//! `corrugation compliance`: the static longitudinal-compliance check
//! ([`corrugation::dynamics::compliance`]) for RPM1–RPM5, rigid and with elastic x-holds.

use std::path::PathBuf;

use clap::Args;

use corrugation::dynamics::compliance::ComplianceLoad;
use corrugation::studies::compliance::{
    check_compliance_load, check_elastic, compliance_rows, variant_models, write_compliance,
    ComplianceRow,
};
use corrugation::units::{m_to_um, n_to_kn};

use super::ModelArgs;

/// Static longitudinal compliance of the fastening models: u_x of the rail head, web and foot
/// ahead of a wheel load with a longitudinal force (compliance.csv, compliance.json).
#[derive(Debug, Args)]
pub(crate) struct ComplianceCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Fastening models, each applied as --set fastening.model=NAME.
    #[arg(
        long,
        value_delimiter = ',',
        default_values = corrugation::model::PRESET_NAMES,
        value_name = "NAMES"
    )]
    variants: Vec<String>,
    /// Elastic longitudinal hold stiffnesses per fastening (N/m): each model is also run with
    /// its x-holds made elastic (fastening.hold = "elastic", hold_directions = ["x"]).
    /// Give --elastic none for rigid holds only.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_delimiter = ',',
        default_values_t = [format!("{:e}", corrugation::studies::compliance::DEFAULT_ELASTIC_N_PER_M)],
        value_name = "N_PER_M"
    )]
    elastic: Vec<String>,
    /// Vertical wheel load on the rail (N).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = ComplianceLoad::default().vertical_n,
        value_name = "N"
    )]
    vertical: f64,
    /// Longitudinal force on the rail, along +x (N).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = ComplianceLoad::default().longitudinal_n,
        value_name = "N"
    )]
    longitudinal: f64,
    /// Load position along the rail (m); default mid-track.
    #[arg(allow_hyphen_values = true, long, value_name = "M")]
    x: Option<f64>,
    /// Distance ahead of the load where u_x is reported (m).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = ComplianceLoad::default().ahead_m,
        value_name = "M"
    )]
    ahead: f64,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/compliance", value_name = "DIR")]
    out: PathBuf,
    /// Print the table as JSON on stdout.
    #[arg(long)]
    json: bool,
}

impl ComplianceCmd {
    /// Runs the command: the arguments, every model variant (all loaded before any solve,
    /// so that a bad name or key stops early), their compliances, the files, the table.
    pub fn run(self) -> anyhow::Result<()> {
        let load = ComplianceLoad {
            vertical_n: self.vertical,
            longitudinal_n: self.longitudinal,
            x_m: self.x,
            ahead_m: self.ahead,
        };
        check_compliance_load(&load)?;
        let stiffnesses = check_elastic(&self.elastic)?;
        super::check_out_dir(&self.out)?;
        let models = variant_models(
            &self.model.source(),
            &self.model.set,
            &self.variants,
            &stiffnesses,
        )?;
        for (name, _, m) in &models {
            super::warn_unit_slips(&format!("--variants {name}"), m);
            // the library's default load position, mid-track
            let x = self.x.unwrap_or(0.5 * m.track_length());
            m.check_on_track("--x", &[x])?;
            m.check_on_track("--x + --ahead", &[x + self.ahead])?;
        }
        let rows = compliance_rows(&models, &load)?;
        let (csv_path, json) = write_compliance(&self.out, &load, &rows)?;
        if self.json {
            println!("{json}");
        } else {
            self.print_table(&rows);
            println!("wrote {} and compliance.json", csv_path.display());
        }
        Ok(())
    }

    /// The table on stdout (µm).
    fn print_table(&self, rows: &[ComplianceRow]) {
        println!(
            "u_x {} m ahead of {} kN down + {} kN along x (µm; in brackets the longitudinal force alone; w at the load in µm)",
            self.ahead,
            n_to_kn(self.vertical),
            n_to_kn(self.longitudinal)
        );
        println!(
            "{:<6} {:<8} {:>10} {:>20} {:>20} {:>20} {:>8}",
            "model", "hold", "k (N/m)", "head", "web", "foot", "w"
        );
        for r in rows {
            let k = r
                .hold_stiffness_n_per_m
                .map(|k| format!("{k:.1e}"))
                .unwrap_or_else(|| "rigid".into());
            let pair = |a: f64, b: f64| format!("{:.3} ({:.3})", m_to_um(a), m_to_um(b));
            println!(
                "{:<6} {:<8} {:>10} {:>20} {:>20} {:>20} {:>8.1}",
                r.model,
                r.hold,
                k,
                pair(r.head_m, r.head_longitudinal_only_m),
                pair(r.web_m, r.web_longitudinal_only_m),
                pair(r.foot_m, r.foot_longitudinal_only_m),
                m_to_um(r.vertical_at_load_m)
            );
        }
    }
}

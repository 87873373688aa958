//! `corrugation model`: print the resolved model.

use clap::Args;

use super::ModelArgs;

/// Prints the resolved model as TOML (every key, with the values in force).
#[derive(Debug, Args)]
pub(crate) struct ModelCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Print JSON instead of TOML.
    #[arg(long)]
    json: bool,
}

impl ModelCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let m = self.model.load()?;
        if self.json {
            println!("{}", serde_json::to_string_pretty(&m)?);
        } else {
            print!("{}", toml::to_string(&m)?);
        }
        Ok(())
    }
}

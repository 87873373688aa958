//! `corrugation` command-line interface. Run `corrugation --help`.
//!
//! Every command reads the model (the embedded Dutch RPM3 model unless `--model FILE`), applies
//! `--set dotted.key=value` overrides, and reports errors as one line on stderr with a non-zero
//! exit code.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", corrugation::progress::one_line(e.as_ref()));
            ExitCode::FAILURE
        }
    }
}

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
            eprintln!("error: {}", one_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, `: `-separated. A cause whose text the message
/// already holds (an error that prints its source) is not repeated.
fn one_line(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg.lines().map(str::trim).collect::<Vec<_>>().join(" ")
}

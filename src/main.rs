//! `corrugation` command-line interface. Run `corrugation --help`.
//!
//! Every command reads the model (the embedded Dutch RPM3 model unless `--model FILE`), applies
//! `--set dotted.key=value` overrides, and reports errors as one line on stderr with a non-zero
//! exit code.

mod cli;

use std::process::ExitCode;

use clap::Parser;

/// The system allocator with transparent huge pages advised for large blocks (the contact
/// patch's sparse factors build faster; `corrugation::huge_pages`).
#[global_allocator]
static ALLOCATOR: corrugation::huge_pages::HugePageAlloc = corrugation::huge_pages::HugePageAlloc;

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

//! `trol`: the TROL utilities in one binary.

mod bench;

use clap::{Parser, Subcommand};

/// TROL, the TU Vienna Robot Control Library: utilities for the CRS A465 link.
#[derive(Parser)]
#[command(name = "trol", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Measure the protocol: link throughput over a paced in-memory line.
    #[command(subcommand)]
    Bench(bench::Bench),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Bench(b) => bench::run(b),
    };
    if let Err(e) = result {
        eprintln!("trol: {e}");
        std::process::exit(1);
    }
}

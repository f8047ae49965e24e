//! `soup`: the command-line face of the superpixel-soup library.
//!
//! Each subcommand lives in its own file and returns the library's error; `main` prints it as one
//! readable line and exits non-zero.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod eval;
mod flow;
mod params;
mod reconstruct;
mod superpixels;
mod synth;

/// Dense 3D reconstruction of a dynamic scene from two photos (Superpixel Soup).
#[derive(Parser)]
#[command(name = "soup", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render the synthetic scenes (frames, exact depth and flow) in the evaluation case layout.
    Synth(synth::Args),
    /// Dense optical flow both ways between two frames (.flo, colour picture), or its EPE on cases.
    Flow(flow::Args),
    /// Segment an image into SLIC superpixels (16-bit label PNG, overlay and mean-colour pictures).
    Superpixels(superpixels::Args),
    /// Reconstruct both frames: depth.pfm, frame1.ply, frame2.ply, flow.flo, labels.png, depth.png,
    /// report.json.
    Reconstruct(reconstruct::Args),
    /// Reconstruct evaluation cases and print MRE, AbsRel, δ<1.25, coverage and time per case.
    Eval(eval::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: superpixel_soup::Result<()> = match cli.command {
        Command::Synth(args) => synth::run(args),
        Command::Flow(args) => flow::run(args),
        Command::Superpixels(args) => superpixels::run(args),
        Command::Reconstruct(args) => reconstruct::run(args),
        Command::Eval(args) => eval::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}

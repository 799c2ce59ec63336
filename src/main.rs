//! The `lumest` command line: arguments in, library calls, exit code out.

use clap::{Parser, Subcommand};
use lumest::commands::{
    bench, glare, grid, illuminance, merge, photometry, render, shfit, sobolev, ugr_table, validate,
};
use std::process::ExitCode;

/// Monte Carlo illumination by local estimation, with exact references.
#[derive(Parser)]
#[command(name = "lumest", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Illuminance (lx) at CSV points by light-tracing chains and the local estimate.
    Illuminance(illuminance::IlluminanceArgs),
    /// Luminance [cd/m^2] along CSV views by the double local estimate.
    Luminance(illuminance::LuminanceArgs),
    /// A luminance picture: HDR (cd/m^2), display PNG and false-colour PNG.
    Render(render::RenderArgs),
    /// Exact Sobolev solution (two Lambertian planes, isotropic point source) as CSV.
    Sobolev(sobolev::SobolevArgs),
    /// Monte Carlo against exact solutions: error against run time, table and plot.
    #[command(subcommand)]
    Validate(validate::ValidateCase),
    /// Throughput and figure of merit on the Sobolev scene.
    Bench(bench::BenchArgs),
    /// Fit a star-shaped OBJ mesh by spherical harmonics (least squares); compare them.
    #[command(name = "sh-fit")]
    ShFit(shfit::ShFitArgs),
    /// Summary and polar candela plot of an IES or EULUMDAT file.
    Photometry(photometry::PhotometryArgs),
    /// Merge the shard states of a sharded `illuminance` run into its CSV.
    Merge(merge::MergeArgs),
    /// Points of the scene's calculation surfaces (`[[grid]]`) as a points CSV.
    Grid(grid::GridArgs),
    /// Unified Glare Rating (CIE 117) at observers (eye and line of sight).
    Glare(glare::GlareArgs),
    /// A luminaire's UGR table (CIE 117 tabular method) from its IES or EULUMDAT file.
    #[command(name = "ugr-table")]
    UgrTable(ugr_table::UgrTableArgs),
}

fn main() -> ExitCode {
    // A reader that stops early (`lumest sobolev ... | head`) ends the
    // program quietly, as it ends other Unix tools, instead of making every
    // later write to standard output fail (Rust ignores SIGPIPE, and
    // `println!` then panicked).
    #[cfg(unix)]
    // SAFETY: restoring the default action of one signal before any thread
    // starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let res = match &cli.command {
        Command::Illuminance(a) => illuminance::illuminance(a),
        Command::Luminance(a) => illuminance::luminance(a),
        Command::Render(a) => render::render(a),
        Command::Sobolev(a) => sobolev::sobolev(a),
        Command::Validate(c) => validate::validate(c),
        Command::Bench(a) => bench::bench(a),
        Command::ShFit(a) => shfit::sh_fit(a),
        Command::Photometry(a) => photometry::photometry(a),
        Command::Merge(a) => merge::merge(a),
        Command::Grid(a) => grid::grid(a),
        Command::Glare(a) => glare::glare(a),
        Command::UgrTable(a) => ugr_table::ugr_table_command(a),
    };
    match res {
        // An interrupted run wrote what it had: not a success for a script
        // (`lumest ... && publish`), the shell's code for a signal.
        Ok(()) if lumest::io::interrupt::interrupted() => {
            eprintln!(
                "lumest: exiting with status 130: the run was interrupted, its outputs hold the batches done"
            );
            ExitCode::from(130)
        }
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lumest: error: {e:#}");
            // Interrupted before anything could be written: still the
            // shell's code for a signal.
            if lumest::io::interrupt::interrupted() {
                ExitCode::from(130)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

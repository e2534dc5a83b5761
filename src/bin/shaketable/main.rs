//! The `shaketable` command line: thin; every subcommand parses its arguments and calls
//! the library. One file per subcommand.

mod bench;
mod campaign;
mod campaign_init;
mod diagnose;
mod drive;
mod fmu;
mod frf;
mod identify;
mod limits;
mod outputs;
mod params;
mod record;
mod simulate;
mod tune;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "shaketable",
    version,
    about = "Servo-hydraulic shake table model (EUCENTRE TREES Lab): parameters, frequency response, simulation, campaigns, identification, diagnosis"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print or check a parameter file (TOML).
    Params(params::Args),
    /// Analytic closed-loop frequency response: CSV, Bode PNG and peak/phase figures.
    Frf(frf::Args),
    /// Simulate the table driven by a recorded reference (a campaign CSV).
    Simulate(simulate::Args),
    /// Campaigns: synthesise the paper's test program.
    Campaign(campaign::Args),
    /// Identify the model's parameters from a campaign (paper section 4).
    Identify(identify::Args),
    /// Diagnose what the identified model misses and extend it.
    Diagnose(diagnose::Args),
    /// Target motions: import a ground motion as a table target, check it against the envelope.
    Record(record::Args),
    /// The drive that reproduces a target on the table: offline from the model, or one
    /// online iteration from the previous drive and the measured run.
    Drive(drive::Args),
    /// TVC gains that flatten the table's transfer with its specimen, poles kept damped.
    Tune(tune::Args),
    /// Real-time factors of the simulator and of campaign synthesis.
    Bench(bench::Args),
    /// The FMU's generated files (modelDescription.xml, documentation); see scripts/build_fmu.sh.
    Fmu(fmu::Args),
}

fn main() {
    // Die quietly on a closed pipe (`shaketable ... | head`) like other Unix tools,
    // instead of panicking in println!.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Params(a) => params::run(a),
        Command::Frf(a) => frf::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Campaign(a) => campaign::run(a),
        Command::Identify(a) => identify::run(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Record(a) => record::run(a),
        Command::Drive(a) => drive::run(a),
        Command::Tune(a) => tune::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Fmu(a) => fmu::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {}", error_text(&e));
        std::process::exit(1);
    }
}

/// The error and its causes, each said once: a cause whose text is already in the
/// message (an error that shows its source, e.g. `file: cannot read: {source}`) is not
/// repeated, as `{e:#}` would.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if text.contains(&c) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&c);
    }
    text
}

/// Read a parameter file, or the TREES Lab defaults when none is given.
pub fn load_params(path: Option<&std::path::Path>) -> anyhow::Result<shaketable::Params> {
    Ok(match path {
        Some(p) => shaketable::Params::from_file(p)?,
        None => shaketable::Params::trees_lab(),
    })
}

/// A spinner with `message` and the elapsed time on stderr, for work without steps to
/// count; hidden when stderr is not a terminal (indicatif's default target).
pub fn spinner(message: String) -> indicatif::ProgressBar {
    let b = indicatif::ProgressBar::new_spinner();
    b.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    b.set_message(message);
    b.enable_steady_tick(std::time::Duration::from_millis(200));
    b
}

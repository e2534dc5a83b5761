//! `shaketable campaign`: synthesise the paper's test program (`synth`) or check a
//! campaign directory (`check`).

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use shaketable::campaign::format::read_campaign;
use shaketable::campaign::synth::{self, NoiseLevels, SynthOptions, DEFAULT_RANDOM_DURATION_S};
use shaketable::campaign::TestSpec;
use shaketable::output::{self, Inputs};
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Subcommand)]
enum Command {
    /// Write the paper's test program (R1-R3, S1-S9, T1-T6) simulated with seeded sensor
    /// noise inside the loop, plus truth.toml (the parameters used) and synthesis.toml.
    Synth(SynthArgs),
    /// Read a campaign, check every rule of the format, and summarise it.
    Check(CheckArgs),
    /// Write a campaign.toml skeleton for a folder of a laboratory's recordings: every
    /// file, its columns with sample values, a guessed sample rate (never overwrites).
    Init(crate::campaign_init::InitArgs),
}

/// `--effect` long help: the syntax, then the catalogue's effects and parameters.
fn effect_long_help() -> String {
    format!(
        "Switch on a catalogue effect, e.g. `specimen:mass_kg=20000,frequency_hz=6,damping_ratio=0.02` \
         (repeatable); keys left out keep their defaults. Effects (spec section 7):\n{}",
        shaketable::effects::effect_syntax_help()
    )
}

#[derive(clap::Args)]
struct SynthArgs {
    /// Parameter file (TOML); the TREES Lab defaults when omitted.
    #[arg(long, value_name = "FILE")]
    params: Option<PathBuf>,
    /// Switch on a catalogue effect, e.g. `specimen:mass_kg=20000,frequency_hz=6,damping_ratio=0.02`
    /// (repeatable).
    #[arg(long = "effect", value_name = "NAME:KEY=VALUE,...", long_help = effect_long_help())]
    effects: Vec<String>,
    /// Seed of the random references and of the sensor noise (same seed, same bytes).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Length of the band-limited part of the random tests, s.
    #[arg(long, default_value_t = DEFAULT_RANDOM_DURATION_S, value_name = "S")]
    random_duration: f64,
    /// Spool position noise, RMS (normalised; measured only, not fed back).
    #[arg(long, default_value_t = NoiseLevels::default().spool, value_name = "RMS")]
    noise_spool: f64,
    /// Displacement (LVDT) noise, m RMS (inside the loop).
    #[arg(long, default_value_t = NoiseLevels::default().displacement_m, value_name = "M")]
    noise_displacement: f64,
    /// Acceleration noise, m/s^2 RMS (inside the loop).
    #[arg(long, default_value_t = NoiseLevels::default().acceleration_m_s2, value_name = "M_S2")]
    noise_acceleration: f64,
    /// Force (delta-P cell) noise, N RMS (inside the loop).
    #[arg(long, default_value_t = NoiseLevels::default().force_n, value_name = "N")]
    noise_force: f64,
    /// No sensor noise at all (overrides the --noise-* options).
    #[arg(long)]
    no_noise: bool,
    /// Only these tests, e.g. `R1,R2,S3`.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    tests: Option<Vec<String>>,
    /// Largest solver sub-step, s.
    #[arg(long, default_value_t = DEFAULT_MAX_SUBSTEP_S, value_name = "S")]
    max_substep: f64,
    /// Sample rate of every record, Hz (a laboratory's data-acquisition rate; the
    /// references are the same continuous signals at any rate).
    #[arg(long, default_value_t = synth::SAMPLE_RATE_HZ, value_name = "HZ")]
    sample_rate: f64,
    /// Overwrite OUT_DIR even if it holds a campaign that is not synthetic.
    #[arg(long)]
    force: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Output directory (created if needed).
    out_dir: PathBuf,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// Campaign directory (holding campaign.toml).
    dir: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        Command::Synth(a) => run_synth(a),
        Command::Check(a) => run_check(a),
        Command::Init(a) => crate::campaign_init::run_init(a),
    }
}

fn run_synth(a: SynthArgs) -> anyhow::Result<()> {
    let mut params = crate::load_params(a.params.as_deref())?;
    for e in &a.effects {
        params
            .apply_effect_spec(e)
            .map_err(|m| anyhow::anyhow!("--effect {e}: {m}"))?;
    }
    let opts = SynthOptions {
        seed: a.seed,
        noise: if a.no_noise {
            NoiseLevels::none()
        } else {
            NoiseLevels {
                spool: a.noise_spool,
                displacement_m: a.noise_displacement,
                acceleration_m_s2: a.noise_acceleration,
                force_n: a.noise_force,
            }
        },
        random_duration_s: a.random_duration,
        max_substep_s: a.max_substep,
        tests: a
            .tests
            .as_ref()
            .map(|v| v.iter().map(|s| s.trim().to_string()).collect()),
    };
    check_synth_limits(&a)?;
    opts.validate()?;
    let mut inputs = Inputs::new();
    if let Some(p) = &a.params {
        inputs.add(p);
    }
    let out = output::plan_dir(&a.out_dir, SYNTH_COMMAND, a.force, &inputs)?;
    let program = at_rate(synth::selected_program(&opts), a.sample_rate);
    warn_if_unstable(&params, &program, "");
    let table_s: f64 = program
        .iter()
        .map(|(_, s)| synth::test_duration_s(s, opts.random_duration_s))
        .sum();
    let total: u64 = program
        .iter()
        .map(|(_, s)| synth::test_samples(s, opts.random_duration_s, a.sample_rate) as u64)
        .sum();
    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} simulating [{bar:40}] {percent:>3}% of {msg} ({elapsed}, eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        b.set_message(format!("{table_s} s of table time"));
        b
    };
    let start = Instant::now();
    let cb = |done: u64, _total: u64| bar.set_position(done.max(bar.position()));
    let campaign = synth::synthesise_program(&params, &program, &opts, Some(&cb))?;
    let sim_s = start.elapsed().as_secs_f64();
    bar.set_message("writing".to_string());
    let staging = out.stage()?;
    synth::write_synthetic(&campaign, &params, &opts, staging.path())?;
    staging.commit()?;
    bar.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    let bytes: u64 = campaign
        .info
        .tests
        .iter()
        .filter_map(|t| std::fs::metadata(a.out_dir.join(&t.file)).ok())
        .map(|m| m.len())
        .sum();
    eprintln!(
        "wrote {} tests ({table_s} s of table time, {total} samples, {:.1} MB) to {} in {wall:.2} s \
         (simulation {sim_s:.2} s, writing {:.2} s); seed {}",
        campaign.info.tests.len(),
        bytes as f64 / 1e6,
        a.out_dir.display(),
        wall - sim_s,
        opts.seed
    );
    Ok(())
}

/// The program with every test at `rate_hz` (the synthesis default leaves it unset).
fn at_rate(program: Vec<(usize, TestSpec)>, rate_hz: f64) -> Vec<(usize, TestSpec)> {
    if rate_hz == synth::SAMPLE_RATE_HZ {
        return program;
    }
    program
        .into_iter()
        .map(|(i, mut s)| {
            s.sample_rate_hz = Some(rate_hz);
            (i, s)
        })
        .collect()
}

/// The marker name of folders `campaign synth` makes (see [`output::plan_dir`]).
const SYNTH_COMMAND: &str = "campaign synth";

/// Lowest synthesis rate: the paper program's R1 and R3 are band-limited to 125 Hz, so
/// their Nyquist frequency must lie above it.
const MIN_SYNTH_RATE_HZ: f64 = 256.0;

/// The options that size memory and run time, by their command-line names.
fn check_synth_limits(a: &SynthArgs) -> anyhow::Result<()> {
    use crate::limits::{
        at_least, within, MAX_RANDOM_DURATION_S, MAX_SAMPLE_RATE_HZ, MIN_SUBSTEP_S,
    };
    within(
        "--sample-rate",
        a.sample_rate,
        MIN_SYNTH_RATE_HZ,
        MAX_SAMPLE_RATE_HZ,
        "Hz; the paper program's random tests reach 125 Hz, MAX_SAMPLE_RATE_HZ at most",
    )?;
    within(
        "--random-duration",
        a.random_duration,
        2.0,
        MAX_RANDOM_DURATION_S,
        "s; two 0.5 s fades at least, MAX_RANDOM_DURATION_S at most",
    )?;
    // the memory bound is on samples: MAX_RANDOM_DURATION_S at the synthesis' own rate
    let most_samples = MAX_RANDOM_DURATION_S * synth::SAMPLE_RATE_HZ;
    if a.random_duration * a.sample_rate > most_samples {
        anyhow::bail!(
            "--random-duration {} s at --sample-rate {} Hz: {:.3e} samples per random record, more than {most_samples:.3e} (MAX_RANDOM_DURATION_S at 512 Hz; the memory bound); shorten the record or lower the rate",
            a.random_duration,
            a.sample_rate,
            a.random_duration * a.sample_rate
        );
    }
    at_least(
        "--max-substep",
        a.max_substep,
        MIN_SUBSTEP_S,
        "s; MIN_SUBSTEP_S",
    )
}

/// The tests at a rate of their own (campaign-format.md, "campaign.toml additions"), as
/// a note after the campaign's rate; empty when every test is at the campaign's.
fn own_rates(info: &shaketable::campaign::CampaignInfo) -> String {
    let own: Vec<String> = info
        .tests
        .iter()
        .filter(|t| info.sample_rate_for(t) != info.sample_rate_hz)
        .map(|t| format!("{} at {} Hz", t.name, info.sample_rate_for(t)))
        .collect();
    if own.is_empty() {
        String::new()
    } else {
        format!(" (the default; {})", own.join(", "))
    }
}

/// The channel names of `c` that look like misspelled project channels, as warnings on
/// stderr (for the commands that go on to use the campaign: `identify`, `diagnose`).
pub fn warn_near_misses(c: &shaketable::campaign::Campaign) {
    for m in c.near_misses() {
        eprintln!("warning: {m}");
    }
}

fn run_check(a: CheckArgs) -> anyhow::Result<()> {
    let c = read_campaign(&a.dir).with_context(|| format!("campaign {}", a.dir.display()))?;
    println!(
        "{}: \"{}\", {} Hz{}",
        a.dir.display(),
        c.info.name,
        c.info.sample_rate_hz,
        own_rates(&c.info)
    );
    let screening = shaketable::campaign::screen::screen(&c);
    let read = &screening.read;
    print!("{}", shaketable::report::read::text(read));
    let total: f64 = read.tests.iter().map(|t| t.duration_s).sum();
    let near_misses = c.near_misses();
    for m in &near_misses {
        println!("warning: {m}");
    }
    let doubts = match near_misses.len() {
        0 => String::new(),
        1 => ", but 1 channel name looks misspelled (warning above)".to_string(),
        n => format!(", but {n} channel names look misspelled (warnings above)"),
    };
    println!(
        "{} tests, {total:.3} s of table time: every rule of the format holds{doubts}",
        read.tests.len()
    );
    print!(
        "{}",
        shaketable::report::read::screening_text(&screening.findings)
    );
    if let Some(k) = shaketable::diagnose::kinematics::check(&c) {
        println!("{}", k.text());
    }
    if let Err(e) = c.gains_known() {
        println!("not simulated: {e}");
        return Ok(());
    }
    let mut p = shaketable::Params::trees_lab();
    c.info.apply_known(&mut p);
    let tests: Vec<_> = c.info.tests.iter().cloned().enumerate().collect();
    warn_if_unstable(
        &p,
        &tests,
        " (with the campaign's geometry and gains, the rest at the TREES Lab defaults)",
    );
    Ok(())
}

/// Warn of each test whose controller (the base gains of `p` with the test's override)
/// makes the closed loop unstable at rest (spec section 8); `context` says with what.
fn warn_if_unstable(
    p: &shaketable::Params,
    tests: &[(usize, shaketable::campaign::TestSpec)],
    context: &str,
) {
    let mut seen = Vec::new();
    for (_, t) in tests {
        let mut q = *p;
        q.controller = t.controller.apply(&p.controller);
        if seen.contains(&q.controller) {
            continue;
        }
        seen.push(q.controller);
        if let Some(w) = shaketable::linear::stability_warning(&q) {
            eprintln!("warning: test {}{context}: {w}", t.name);
        }
    }
}

//! `shaketable record import|check`: a ground motion made a table target, and a target
//! checked against the table's envelope with its specimen (issue 19, part 1).

use crate::limits::within;
use clap::{Args as ClapArgs, Subcommand};
use shaketable::motion::envelope::{check_target, EnvelopeCheck};
use shaketable::motion::prepare::{prepare, PrepareOptions, PrepareSummary, DEFAULT_PAD_S};
use shaketable::motion::read::{read_motion, AccelerationUnit, ReadOptions};
use shaketable::motion::target_file::{read_target, to_csv};
use shaketable::motion::STANDARD_GRAVITY_M_S2;
use shaketable::output::{self, Inputs};
use std::path::PathBuf;

/// Controller rate targets are resampled to by default, Hz: the MTS 469D's (spec section 2).
const DEFAULT_RATE_HZ: f64 = 1024.0;
/// Rates a target may be resampled to, Hz: an accelerograph's 50 Hz to 20 kHz.
const RATE_RANGE_HZ: (f64, f64) = (50.0, 20_000.0);
/// Longest quiet pad at each end, s.
const MAX_PAD_S: f64 = 60.0;
/// Largest PGA asked for, m/s^2 (10 g: beyond any table).
const MAX_PGA_M_S2: f64 = 10.0 * STANDARD_GRAVITY_M_S2;
/// Longest prepared target, s (an hour): bounds the memory of the FFTs.
const MAX_TARGET_S: f64 = 3600.0;

#[derive(ClapArgs)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// A ground motion (PEER .AT2, one or two columns, a CSV channel) as a table target.
    Import(ImportArgs),
    /// Does a target fit the table's envelope (stroke, velocity, valve flow, pressure)
    /// with these parameters and their specimen?
    Check(CheckArgs),
}

#[derive(ClapArgs)]
struct ImportArgs {
    /// The ground motion: a PEER NGA .AT2 file, or text with one column (give --dt),
    /// two columns (time, acceleration) or named columns.
    file: PathBuf,
    /// The target CSV to write (time_s, acceleration_m_s2, velocity_m_s, displacement_m).
    #[arg(long)]
    out: PathBuf,
    /// Time step of a file without a time column, s.
    #[arg(long)]
    dt: Option<f64>,
    /// Unit of the acceleration where the file does not say: g, m/s2 or cm/s2.
    #[arg(long)]
    units: Option<String>,
    /// The acceleration column (a header name or a 1-based number).
    #[arg(long)]
    column: Option<String>,
    /// The file writes decimal commas (`0,0125`). Only needed for a file of one column:
    /// with a semicolon, tab or space between cells they are recognised.
    #[arg(long)]
    decimal_comma: bool,
    /// Peak acceleration of the target, with its unit: 0.3g, 2.94m/s2, 294gal.
    #[arg(long)]
    scale_pga: Option<String>,
    /// Sample rate of the target, Hz (the controller's).
    #[arg(long, default_value_t = DEFAULT_RATE_HZ)]
    rate_hz: f64,
    /// High-pass corner, Hz; by default the lowest from 0.1 Hz that keeps the target
    /// within 80 % of the stroke and velocity limits of --params.
    #[arg(long)]
    highpass_hz: Option<f64>,
    /// Quiet time added at each end, s.
    #[arg(long, default_value_t = DEFAULT_PAD_S)]
    pad_s: f64,
    /// Parameter file whose [limits] bound the automatic high-pass (TREES Lab defaults).
    #[arg(long)]
    params: Option<PathBuf>,
    /// Also write what the preparation did as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Overwrite outputs that exist.
    #[arg(long)]
    force: bool,
}

#[derive(ClapArgs)]
struct CheckArgs {
    /// The target CSV (time_s, acceleration_m_s2; uniform time).
    target: PathBuf,
    /// Parameter file (with the specimen, if any); TREES Lab defaults without one.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Also write the demands as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Overwrite the JSON file if it exists.
    #[arg(long)]
    force: bool,
}

pub fn run(a: Args) -> anyhow::Result<()> {
    match a.command {
        Command::Import(a) => import(a),
        Command::Check(a) => check(a),
    }
}

/// `0.3g`, `2.94m/s2`, `294gal`, `294cm/s2` in m/s^2; a bare number is refused.
fn parse_pga(text: &str) -> anyhow::Result<f64> {
    let t = text.trim();
    let split = t
        .find(|c: char| c.is_ascii_alphabetic())
        .ok_or_else(|| anyhow::anyhow!("--scale-pga {t}: give a unit, e.g. 0.3g or 2.94m/s2"))?;
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--scale-pga {t}: `{number}` is not a number"))?;
    let unit = AccelerationUnit::parse(unit).ok_or_else(|| {
        anyhow::anyhow!("--scale-pga {t}: unknown unit `{unit}` (g, m/s2, cm/s2, gal)")
    })?;
    let pga = value * unit.to_m_s2();
    within(
        "--scale-pga",
        pga,
        1e-6,
        MAX_PGA_M_S2,
        "m/s^2: above 0 and at most 10 g",
    )?;
    Ok(pga)
}

fn import(a: ImportArgs) -> anyhow::Result<()> {
    within(
        "--rate-hz",
        a.rate_hz,
        RATE_RANGE_HZ.0,
        RATE_RANGE_HZ.1,
        "Hz",
    )?;
    within("--pad-s", a.pad_s, 0.0, MAX_PAD_S, "s")?;
    if let Some(fc) = a.highpass_hz {
        within(
            "--highpass-hz",
            fc,
            1e-3,
            a.rate_hz / 4.0,
            "Hz: below a quarter of the rate",
        )?;
    }
    let unit = match &a.units {
        Some(u) => Some(
            AccelerationUnit::parse(u)
                .ok_or_else(|| anyhow::anyhow!("--units {u}: unknown unit (g, m/s2, cm/s2)"))?,
        ),
        None => None,
    };
    let pga = a.scale_pga.as_deref().map(parse_pga).transpose()?;
    let params = crate::load_params(a.params.as_deref())?;
    let mut inputs = Inputs::new();
    inputs.add(&a.file);
    if let Some(p) = &a.params {
        inputs.add(p);
    }
    output::check_file(&a.out, a.force, &inputs)?;
    if let Some(j) = &a.json {
        output::check_distinct(&[&a.out, j])?;
        output::check_file(j, a.force, &inputs)?;
    }
    let read = ReadOptions {
        step_s: a.dt,
        unit,
        column: a.column.clone(),
        decimal_comma: a.decimal_comma,
    };
    let motion = read_motion(&a.file, &read)?;
    let seconds = motion.acceleration_m_s2.len() as f64 * motion.step_s + 2.0 * a.pad_s;
    within("the target's duration", seconds, 0.0, MAX_TARGET_S, "s")?;
    let options = PrepareOptions {
        rate_hz: a.rate_hz,
        highpass_hz: a.highpass_hz,
        pga_m_s2: pga,
        pad_s: a.pad_s,
    };
    let (target, summary) = prepare(&motion, &params, &options)?;
    output::write_file(&a.out, to_csv(&target).as_bytes(), a.force, &inputs)?;
    print_summary(&summary);
    println!("wrote {}", a.out.display());
    if let Some(j) = &a.json {
        let text = serde_json::to_string_pretty(&summary)? + "\n";
        output::write_file(j, text.as_bytes(), a.force, &inputs)?;
        println!("wrote {}", j.display());
    }
    Ok(())
}

fn print_summary(s: &PrepareSummary) {
    let g = STANDARD_GRAVITY_M_S2;
    println!("read: {}", s.source);
    println!(
        "mean removed: {:.4e} m/s^2; ends tapered; {:.2} s at rest added at each end; \
         resampled from {} Hz to {} Hz",
        s.mean_removed_m_s2,
        s.pad_s,
        1.0 / s.source_step_s,
        s.rate_hz
    );
    println!(
        "high-pass: Butterworth magnitude of order {}, zero phase, corner {:.3} Hz ({})",
        s.highpass_order, s.highpass_hz, s.highpass_chosen_by
    );
    println!(
        "removed: {:.1} % of the record's RMS acceleration (the drift below the corner \
         and the bringing to rest at the ends)",
        100.0 * s.removed_rms_fraction
    );
    println!(
        "scaled by {:.4}: PGA {:.3} m/s^2 ({:.3} g; the record's {:.3} g); peak velocity \
         {:.3} m/s, peak displacement {:.4} m; {:.2} s at {} Hz",
        s.scale_factor,
        s.pga_m_s2,
        s.pga_m_s2 / g,
        s.source_pga_m_s2 / g,
        s.peak_velocity_m_s,
        s.peak_displacement_m,
        s.duration_s,
        s.rate_hz
    );
}

fn check(a: CheckArgs) -> anyhow::Result<()> {
    let params = crate::load_params(a.params.as_deref())?;
    let mut inputs = Inputs::new();
    inputs.add(&a.target);
    if let Some(p) = &a.params {
        inputs.add(p);
    }
    if let Some(j) = &a.json {
        output::check_file(j, a.force, &inputs)?;
    }
    if let Some(w) = shaketable::linear::stability_warning(&params) {
        eprintln!("warning: {w}");
    }
    let target = read_target(&a.target)?;
    let c = check_target(&params, &target);
    print_check(&a.target, &params, &target, &c);
    if let Some(j) = &a.json {
        let text = serde_json::to_string_pretty(&c)? + "\n";
        output::write_file(j, text.as_bytes(), a.force, &inputs)?;
        println!("wrote {}", j.display());
    }
    if !c.within {
        let over = c.exceeded();
        anyhow::bail!(
            "{} leaves the table's envelope: {}",
            a.target.display(),
            over.join("; ")
        );
    }
    Ok(())
}

fn print_check(
    file: &std::path::Path,
    p: &shaketable::Params,
    t: &shaketable::motion::prepare::Target,
    c: &EnvelopeCheck,
) {
    let n = t.acceleration_m_s2.len();
    println!(
        "{}: {n} samples at {:.2} Hz ({:.2} s)",
        file.display(),
        t.rate_hz,
        t.duration_s()
    );
    let end_v = t.velocity_m_s[n - 1];
    let end_x = t.displacement_m[n - 1];
    if end_v.abs() > 0.01 * c.demands[1].peak.max(1e-6) {
        println!(
            "note: the target does not end at rest (velocity {end_v:.3e} m/s, displacement \
             {end_x:.3e} m at its end): prepare it with `shaketable record import`"
        );
    }
    match p.specimen.enabled {
        true => println!(
            "with the specimen: {} kg, {} Hz, damping ratio {}",
            p.specimen.mass_kg, p.specimen.frequency_hz, p.specimen.damping_ratio
        ),
        false => println!("bare table (no specimen in the parameters)"),
    }
    println!("peak actuator force {:.4e} N", c.peak_force_n);
    println!(
        "{:<15} {:>12} {:>10} {:>12} {:>7}  limit",
        "demand", "peak", "at (s)", "limit", "use"
    );
    for d in &c.demands {
        println!(
            "{:<15} {:>12.4e} {:>10.3} {:>12.4e} {:>6.0}%  {} ({})",
            d.name,
            d.peak,
            d.at_time_s,
            d.limit,
            100.0 * d.fraction,
            d.unit,
            d.limit_is
        );
    }
    println!(
        "verdict: {}",
        if c.within {
            "inside the envelope"
        } else {
            "OUTSIDE the envelope"
        }
    );
}

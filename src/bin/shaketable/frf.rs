//! `shaketable frf`: the analytic closed-loop frequency response of a parameter file
//! (spec section 6): printed peak and phase figures, closed-loop poles, a CSV of the
//! four transfer functions, a Bode PNG of the table TF and a JSON of the figures.

use anyhow::Context;
use shaketable::linear::{log_grid, Linearisation, OilColumn, Pole, TfFigures};
use shaketable::output::{self, Inputs};
use shaketable::report::plot::{bode_png, BodeCurve};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Parameter file (TOML); the TREES Lab defaults when omitted.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Directory for frf.csv, bode.png and figures.json (created); print only when omitted.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write into --out even if it is not empty and not made by `frf` (same-named files
    /// are replaced, others kept; never an input or a symlink).
    #[arg(long)]
    force: bool,
    /// Lowest frequency of the CSV and plot, Hz.
    #[arg(long, default_value_t = 0.1)]
    f_min: f64,
    /// Highest frequency of the CSV and plot, Hz.
    #[arg(long, default_value_t = 100.0)]
    f_max: f64,
    /// Number of log-spaced frequencies in the CSV.
    #[arg(long, default_value_t = 1000)]
    points: usize,
}

#[derive(serde::Serialize)]
struct Figures {
    table_tf: TfFigures,
    oil_column: OilColumn,
    poles: Vec<Pole>,
    notes: Vec<String>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    check_range(&args)?;
    let mut inputs = Inputs::new();
    if let Some(p) = &args.params {
        inputs.add(p);
    }
    let plan = match &args.out {
        Some(dir) => Some(output::plan_dir(dir, "frf", args.force, &inputs)?),
        None => None,
    };
    let p = crate::load_params(args.params.as_deref())?;
    let lin = Linearisation::new(&p);
    if let Some(w) = shaketable::linear::stability_warning(&p) {
        eprintln!("warning: {w}");
    }
    let fig = lin
        .table_tf_figures()
        .context("the table TF has no peak between 0.5 and 50 Hz with +-1 Hz around it")?;
    let oil = OilColumn::of(&p);
    let poles = lin.upper_poles().context(
        "the closed-loop poles could not be computed (the eigenvalue iteration did not converge)",
    )?;
    let figures = Figures {
        table_tf: fig,
        oil_column: oil,
        poles,
        notes: lin.notes.clone(),
    };
    print_figures(&args, &p, &figures);
    let Some(plan) = plan else { return Ok(()) };
    let staging = plan.stage()?;
    write_files(staging.path(), &args, &lin, &figures)
        .with_context(|| format!("writing {}", plan.target().display()))?;
    staging.commit()?;
    let dir = plan.target();
    println!(
        "wrote {}, {}, {}",
        dir.join("frf.csv").display(),
        dir.join("bode.png").display(),
        dir.join("figures.json").display()
    );
    Ok(())
}

/// The frequency range and point count asked for, checked before anything is read.
fn check_range(args: &Args) -> anyhow::Result<()> {
    if !(args.f_min > 0.0 && args.f_max > args.f_min && args.f_max.is_finite()) {
        anyhow::bail!(
            "--f-min and --f-max must satisfy 0 < f-min < f-max (got {} and {})",
            args.f_min,
            args.f_max
        );
    }
    crate::limits::within(
        "--points",
        args.points,
        10,
        crate::limits::MAX_FRF_POINTS,
        "MAX_FRF_POINTS",
    )
}

/// The figures on standard output, one a line.
fn print_figures(args: &Args, p: &shaketable::Params, f: &Figures) {
    let (fig, oil) = (&f.table_tf, &f.oil_column);
    let source = args
        .params
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "built-in TREES Lab defaults".into());
    println!("shaketable frf: {source}");
    println!(
        "  servovalve {}, actuator {}",
        p.servovalve.model.name(),
        p.actuator.model.name()
    );
    println!("table TF (reference acceleration -> table acceleration), linearised at rest:");
    println!("  peak frequency        {:8.3} Hz", fig.peak_hz);
    println!(
        "  peak gain             {:8.3}  ({:.2} x the low-frequency gain)",
        fig.peak_gain, fig.peak_ratio
    );
    println!(
        "  low-frequency gain    {:8.4}  (at {} Hz)",
        fig.low_frequency_gain,
        shaketable::linear::LOW_FREQUENCY_HZ
    );
    println!("  phase drop, peak +-1 Hz {:6.1} deg", fig.phase_drop_deg);
    println!("  steepest phase        {:8.3} Hz", fig.steepest_hz);
    println!(
        "oil column: f_oil = {:.3} Hz, zeta_oil = {:.4}, k_oil = {:.4e} N/m",
        oil.frequency_hz, oil.damping_ratio, oil.stiffness_n_m
    );
    println!("closed-loop poles (frequency, damping ratio):");
    for q in &f.poles {
        if q.frequency_hz < 1e-6 {
            println!(
                "  {:10.3} Hz  (zero pole: the linearised Bouc-Wen state duplicates the stroke)",
                0.0
            );
        } else {
            println!("  {:10.3} Hz  {:.4}", q.frequency_hz, q.damping_ratio);
        }
    }
    for n in &f.notes {
        println!("note: {n}");
    }
}

/// frf.csv, bode.png and figures.json into `out` (a fresh folder).
fn write_files(
    out: &std::path::Path,
    args: &Args,
    lin: &Linearisation,
    figures: &Figures,
) -> anyhow::Result<()> {
    let fig = &figures.table_tf;
    let grid = log_grid(args.f_min, args.f_max, args.points);
    let table = lin.sample(&grid, Linearisation::table_tf);
    let spool = lin.sample(&grid, Linearisation::command_to_spool);
    let force = lin.sample(&grid, Linearisation::spool_to_force);
    let mass = lin.sample(&grid, Linearisation::acceleration_to_force);
    let csv_path = out.join("frf.csv");
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "frequency_hz",
        "table_gain",
        "table_phase_deg",
        "command_to_spool_gain",
        "command_to_spool_phase_deg",
        "spool_to_force_n",
        "spool_to_force_phase_deg",
        "acceleration_to_force_kg",
        "acceleration_to_force_phase_deg",
    ])?;
    let phases: Vec<Vec<f64>> = [&table, &spool, &force, &mass]
        .iter()
        .map(|f| {
            shaketable::linear::unwrapped_phase(&f.response)
                .iter()
                .map(|p| p.to_degrees())
                .collect()
        })
        .collect();
    for k in 0..grid.len() {
        let mut row = vec![grid[k]];
        for (i, f) in [&table, &spool, &force, &mass].iter().enumerate() {
            row.push(f.response[k].norm());
            row.push(phases[i][k]);
        }
        w.write_record(
            row.iter()
                .map(|v| ryu::Buffer::new().format(*v).to_string()),
        )?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}", e.error()))?;
    output::atomic_write(&csv_path, &bytes)?;
    let png = out.join("bode.png");
    bode_png(
        &png,
        &format!(
            "Table TF, reference -> table acceleration (peak {:.2} Hz)",
            fig.peak_hz
        ),
        "gain (-)",
        &[BodeCurve {
            label: "analytic, linearised at rest",
            frequency_hz: &table.frequency_hz,
            response: &table.response,
        }],
        args.f_min,
        args.f_max,
    )?;
    let json_path = out.join("figures.json");
    let text = serde_json::to_string_pretty(figures)? + "\n";
    output::atomic_write(&json_path, text.as_bytes())?;
    Ok(())
}

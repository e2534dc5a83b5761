//! `shaketable tune`: TVC gains that flatten the table's transfer with its specimen over
//! the useful band, every closed-loop pole kept damped (issue 19, part 4).

use crate::limits::within;
use shaketable::linear::{log_grid, Linearisation};
use shaketable::motion::tune::{tune, Tuning, MIN_POLE_DAMPING, TUNE_POINTS};
use shaketable::output::{self, Inputs};
use shaketable::report::plot::{bode_png, BodeCurve};
use std::fmt::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Parameter file of the table with its specimen; TREES Lab defaults without one.
    #[arg(long)]
    params: Option<PathBuf>,
    /// The tuned parameter file to write (the input's, with the new [controller] gains).
    #[arg(long)]
    out: PathBuf,
    /// Lowest frequency of the band to flatten, Hz.
    #[arg(long, default_value_t = 0.5)]
    band_min_hz: f64,
    /// Highest frequency of the band to flatten, Hz.
    #[arg(long, default_value_t = 20.0)]
    band_max_hz: f64,
    /// Folder for the FRF before and after: frf.csv and bode.png.
    #[arg(long)]
    frf: Option<PathBuf>,
    /// Replace outputs that exist.
    #[arg(long)]
    force: bool,
}

pub fn run(a: Args) -> anyhow::Result<()> {
    within("--band-min-hz", a.band_min_hz, 0.01, 100.0, "Hz")?;
    within(
        "--band-max-hz",
        a.band_max_hz,
        a.band_min_hz * 1.5,
        500.0,
        "Hz: above 1.5 x --band-min-hz",
    )?;
    let params = crate::load_params(a.params.as_deref())?;
    let mut inputs = Inputs::new();
    if let Some(p) = &a.params {
        inputs.add(p);
    }
    output::check_file(&a.out, a.force, &inputs)?;
    let frf_plan = match &a.frf {
        Some(d) => Some(output::plan_dir(d, "tune --frf", a.force, &inputs)?),
        None => None,
    };
    let band = (a.band_min_hz, a.band_max_hz);
    let t = tune(&params, band).map_err(|m| anyhow::anyhow!("tune: {m}"))?;
    print_tuning(&t, band);
    let mut tuned = params;
    tuned.controller = t.after;
    output::write_file(&a.out, tuned.to_toml_string().as_bytes(), a.force, &inputs)?;
    println!("wrote {}", a.out.display());
    if let Some(plan) = frf_plan {
        let stage = plan.stage()?;
        write_frf(stage.path(), &params, &tuned)?;
        stage.commit()?;
        println!("wrote {}/ (frf.csv, bode.png)", plan.target().display());
    }
    Ok(())
}

/// The objective, the margin, the gains before and after and what they achieve.
fn print_tuning(t: &Tuning, band: (f64, f64)) {
    println!(
        "objective: RMS over {TUNE_POINTS} log-spaced frequencies from {} to {} Hz of the table \
         gain in dB (reference to table acceleration, linearised, specimen included)",
        band.0, band.1
    );
    println!(
        "margin: every closed-loop pole damped at least {:.3} (the lesser of {MIN_POLE_DAMPING} and \
         the given gains' least-damped pole)",
        t.damping_margin
    );
    println!("{:<6} {:>14} {:>14}", "gain", "before", "after");
    let (b, c) = (t.before, t.after);
    for (name, x, y) in [
        ("kp", b.kp, c.kp),
        ("kv", b.kv, c.kv),
        ("ka", b.ka, c.ka),
        ("fv", b.fv, c.fv),
        ("fa", b.fa, c.fa),
        ("kdp", b.kdp, c.kdp),
    ] {
        println!("{name:<6} {x:>14.5e} {y:>14.5e}");
    }
    println!(
        "flatness {:.2} dB RMS -> {:.2} dB RMS; least pole damping {:.4} -> {:.4}",
        t.flatness_db_before, t.flatness_db_after, t.min_damping_before, t.min_damping_after
    );
}

/// frf.csv and bode.png of the table transfer before and after tuning into `dir`.
fn write_frf(
    dir: &std::path::Path,
    params: &shaketable::Params,
    tuned: &shaketable::Params,
) -> anyhow::Result<()> {
    let grid = log_grid(0.1, 100.0, 400);
    let before = Linearisation::new(params).sample(&grid, Linearisation::table_tf);
    let after = Linearisation::new(tuned).sample(&grid, Linearisation::table_tf);
    let mut csv =
        String::from("frequency_hz,gain_before,phase_before_deg,gain_after,phase_after_deg\n");
    for (k, f) in grid.iter().enumerate() {
        let (x, y) = (before.response[k], after.response[k]);
        let _ = writeln!(
            csv,
            "{f},{},{},{},{}",
            x.norm(),
            x.arg().to_degrees(),
            y.norm(),
            y.arg().to_degrees()
        );
    }
    std::fs::write(dir.join("frf.csv"), csv)?;
    let curves = [
        BodeCurve {
            label: "before",
            frequency_hz: &grid,
            response: &before.response,
        },
        BodeCurve {
            label: "after (tuned)",
            frequency_hz: &grid,
            response: &after.response,
        },
    ];
    bode_png(
        &dir.join("bode.png"),
        "table transfer, reference to table acceleration",
        "gain",
        &curves,
        0.1,
        100.0,
    )?;
    Ok(())
}

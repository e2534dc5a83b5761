//! `shaketable drive`: the drive that makes the table reproduce a target, offline from the
//! model, or one online iteration from the previous drive and the measured run (issue 19).

use crate::limits::within;
use clap::Args as ClapArgs;
use shaketable::motion::drive::{check_drive, offline, online, DriveOptions};
use shaketable::motion::drive_files::{folder_files, read_measured, read_previous};
use shaketable::motion::metrics::Metrics;
use shaketable::motion::target_file::read_target;
use shaketable::output::{self, Inputs};
use std::path::PathBuf;

/// Default share of the correction applied per online iteration: below 1 so that an
/// error the transfer estimate gets wrong is not overshot (labs use 0.5-1).
const DEFAULT_GAIN: f64 = 0.8;
/// Default highest frequency corrected, Hz: above the TREES table's oil column (14 Hz)
/// and the spectral metric's 30 Hz, below where the table's gain has fallen away.
const DEFAULT_BAND_HZ: f64 = 40.0;

#[derive(ClapArgs)]
pub struct Args {
    /// Parameter file of the table with its specimen (e.g. from `diagnose`).
    #[arg(long)]
    params: Option<PathBuf>,
    /// The target (time_s, acceleration_m_s2), as `record import` writes it.
    #[arg(long)]
    target: PathBuf,
    /// Output folder: drive.csv, predicted.csv, metrics.json, transfer.csv.
    #[arg(long)]
    out: PathBuf,
    /// The previous iteration's folder (online iteration; needs --measured).
    #[arg(long, requires = "measured")]
    previous: Option<PathBuf>,
    /// The run the lab recorded playing the previous drive (time_s, acceleration_m_s2).
    #[arg(long, requires = "previous")]
    measured: Option<PathBuf>,
    /// Share of the correction applied (online).
    #[arg(long, default_value_t = DEFAULT_GAIN)]
    gain: f64,
    /// Highest frequency corrected, Hz.
    #[arg(long, default_value_t = DEFAULT_BAND_HZ)]
    band_hz: f64,
    /// Replace an output folder that exists.
    #[arg(long)]
    force: bool,
}

fn show(label: &str, m: &Metrics) {
    println!(
        "{label}: RMS error {:.1} %, PGA error {:+.1} %, spectral ordinates outside +-10 %: {:.1} %",
        100.0 * m.rms_error,
        100.0 * m.pga_error,
        100.0 * m.spectral_outside_fraction
    );
}

pub fn run(a: Args) -> anyhow::Result<()> {
    within("--gain", a.gain, 0.0, 1.5, "share of the correction")?;
    let params = crate::load_params(a.params.as_deref())?;
    let target = read_target(&a.target)?;
    within(
        "--band-hz",
        a.band_hz,
        1.0,
        target.rate_hz / 2.0,
        "Hz: up to the Nyquist frequency",
    )?;
    let mut inputs = Inputs::new();
    inputs.add(&a.target);
    for p in [&a.params, &a.measured].into_iter().flatten() {
        inputs.add(p);
    }
    if let Some(prev) = &a.previous {
        for f in ["drive.csv", "predicted.csv", "metrics.json", "transfer.csv"] {
            inputs.add(&prev.join(f));
        }
    }
    let plan = output::plan_dir(&a.out, "drive", a.force, &inputs)?;
    if let Some(w) = shaketable::linear::stability_warning(&params) {
        eprintln!("warning: {w}");
    }
    let options = DriveOptions {
        gain: a.gain,
        band_hz: a.band_hz,
    };
    let bar = crate::spinner("computing the drive".into());
    let (result, iteration) = match (&a.previous, &a.measured) {
        (Some(prev), Some(meas)) => {
            let previous = read_previous(prev, &params, &target)?;
            let n = target.acceleration_m_s2.len();
            let measured = read_measured(meas, target.rate_hz, n)?;
            let iteration = previous.iteration + 1;
            (
                online(&params, &target, previous, &measured, &options)?,
                iteration,
            )
        }
        _ => (offline(&params, &target, &options)?, 0),
    };
    bar.finish_and_clear();
    if let Some(m) = &result.naive_metrics {
        show("naive drive (the target played as is), predicted", m);
    }
    if let Some(m) = &result.measured_metrics {
        show("measured run of the previous drive", m);
        if let Some(d) = result.trigger_delay_s {
            println!(
                "measured response aligned to the drive: shifted by {:.1} ms",
                1000.0 * d
            );
        }
        if !result.noise_weighted {
            println!("note: no quiet lead-in in the measured run: the correction is not weighted by the noise");
        }
    }
    show(
        &format!("iteration {iteration} drive, predicted by the model"),
        &result.predicted_metrics,
    );
    check_drive(&params, &result)?;
    let stage = plan.stage()?;
    for (name, text) in folder_files(&result, iteration, a.gain, a.band_hz) {
        std::fs::write(stage.path().join(name), text)?;
    }
    shaketable::motion::figures::draw(stage.path(), &target, &result, iteration)?;
    stage.commit()?;
    println!(
        "wrote {}/ (drive.csv, predicted.csv, metrics.json, transfer.csv, time_history.png, spectra.png)",
        a.out.display()
    );
    Ok(())
}

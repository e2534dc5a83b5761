//! `shaketable diagnose DIR`: what the identified baseline misses, the physical cause,
//! the extended model and its gain on held-out tests.

use shaketable::campaign::format::read_campaign;
use shaketable::diagnose::{
    diagnose, unexplained_responses, Channel, Diagnosis, Effort, ModelErrorPeak,
};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Campaign directory (campaign.toml and one CSV per test).
    campaign: PathBuf,
    /// Write the diagnosis as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the extended parameter file (baseline plus the causes found) here.
    #[arg(long)]
    params_out: Option<PathBuf>,
    /// Write the refined baseline (the model the gain is measured against) here.
    #[arg(long)]
    baseline_out: Option<PathBuf>,
    /// Write the report (index.html, README.md, figures) into this directory.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Replace existing --json/--params-out files, and write the report into a folder that
    /// is not a report of this command (never over an input, never through a symlink).
    #[arg(long)]
    force: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// The quick diagnosis of the development loop: every step of the full one with
    /// half the fit iterations (seconds on a short campaign); rougher numbers, not for
    /// a decision.
    #[arg(long)]
    quick: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let campaign = read_campaign(&args.campaign)?;
    crate::campaign::warn_near_misses(&campaign);
    let inputs = crate::outputs::campaign_inputs(&campaign);
    let outputs = crate::outputs::Outputs::check(
        "diagnose",
        args.json.as_deref(),
        args.params_out.as_deref(),
        args.report.as_deref(),
        args.force,
        inputs,
    )?
    .with_baseline_out(args.baseline_out.as_deref())?;
    let bar = progress_bar(args.quiet);
    // SHAKETABLE_TRACE=1: each step's start time on stderr (for timing runs)
    let trace = shaketable::diagnose::trace_enabled();
    let report = |i: usize, n: usize, what: &str| {
        if trace {
            eprintln!("{:7.2} s  {i}/{n} {what}", t0.elapsed().as_secs_f64());
        }
        if let Some(b) = &bar {
            b.set_length(n as u64);
            b.set_position(i as u64);
            b.set_message(what.to_string());
        }
    };
    let effort = if args.quick {
        Effort::Quick
    } else {
        Effort::Full
    };
    let d = diagnose(&campaign, effort, Some(&report));
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let d = d.map_err(|e| anyhow::anyhow!("{}: {e}", args.campaign.display()))?;
    print_baseline(&d, &args.campaign, t0);
    print_searches(&d)?;
    let mut j = d.to_json();
    // issue 17 part 4: where the worst unexplained cell's model-error response peaks
    // (null when explained or when no cell has a response)
    // the report draws the worst few: the first one's simulation serves both
    let cells = match args.report {
        Some(_) => shaketable::report::MODEL_ERROR_FIGURES,
        None => 1,
    };
    let responses = unexplained_responses(&d, &campaign, cells);
    let peak = responses
        .iter()
        .find_map(|c| c.response.as_ref().ok()?.peak());
    j["model_error_peak"] = serde_json::to_value(&peak)?;
    print_verdict(&d, &j, peak.as_ref());
    print_fits(&d);
    if let Some(note) = d.structure_change() {
        println!("{note}");
    }
    outputs.write_baseline(&d.baseline.to_toml_string())?;
    outputs.write(
        &(serde_json::to_string_pretty(&j)? + "\n"),
        &d.extended.to_toml_string(),
        |dir| {
            Ok(shaketable::report::diagnose::write(
                dir, &campaign, &d, &responses,
            )?)
        },
    )?;
    Ok(())
}

/// The progress bar naming the running stage; none with `--quiet`.
fn progress_bar(quiet: bool) -> Option<indicatif::ProgressBar> {
    (!quiet).then(|| {
        let b = indicatif::ProgressBar::new(1);
        b.set_style(
            indicatif::ProgressStyle::with_template("{elapsed:>4} [{bar:30}] {pos}/{len} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    })
}

/// The notes, the timing and the baseline: its structure, noise floor and residual per
/// test and channel, and its scores on the cells it misses.
fn print_baseline(d: &Diagnosis, campaign: &std::path::Path, t0: std::time::Instant) {
    for f in &d.identification.screening {
        println!("screening: {f}");
    }
    if let Some(r) = &d.cause_rejected {
        println!("note: {r}");
    }
    if let Some(r) = &d.baseline_unscorable {
        println!("note: {r}");
    }
    println!(
        "diagnosis of {} ({:.1} s)",
        campaign.display(),
        t0.elapsed().as_secs_f64()
    );
    if d.effort == Effort::Quick {
        println!("quick diagnosis: half the fit iterations, rougher numbers; not for a decision");
    }
    println!("baseline from the {}", d.baseline_from());
    println!(
        "baseline: servovalve {}, actuator {}; noise floor from {}",
        d.valve_model.name(),
        d.actuator_model.name(),
        d.noise.method
    );
    println!(
        "baseline residual / noise RMS per test ({}):",
        Channel::ALL.map(Channel::name).join(", ")
    );
    for (name, r) in &d.baseline_rows {
        let cells: Vec<String> = r
            .values()
            .map(|v| match v.finite() {
                Some(v) => format!("{v:8.2}"),
                _ => "       -".into(),
            })
            .collect();
        println!("  {name:4} {}", cells.join(" "));
    }
    println!(
        "split: every test fits on its first half, selects on its third quarter, reports on its last"
    );
    println!(
        "baseline: selection score on its missed cells {:.3}, report residual on its missed cells {:.3}",
        d.baseline_score, d.baseline_heldout
    );
}

/// The first search's candidates, the causes accepted, what could not be tested and
/// what explains only in part.
fn print_searches(d: &Diagnosis) -> anyhow::Result<()> {
    println!("first search's candidates (selection residual, score, report residual, parameters):");
    for c in &d.candidates {
        let ps: Vec<String> = c
            .parameters
            .iter()
            .map(|(k, v)| format!("{k}={v:.5}"))
            .collect();
        println!(
            "  {:16} {:8.3} {:8.3} {:8.3}  {}{}",
            c.effect.name(),
            c.select_residual,
            c.score,
            c.report_residual,
            ps.join(", "),
            c.not_evidence
                .as_ref()
                .map(|w| format!("  (not evidence: {w})"))
                .unwrap_or_default()
        );
    }
    for (k, c) in d.causes.iter().enumerate() {
        println!(
            "cause {}: {}  gain {:.2}  parameters {}",
            k + 1,
            c.effect.name(),
            c.gain,
            serde_json::to_string(&c.parameters)?
        );
    }
    for why in &d.not_testable {
        println!("{why}");
    }
    if let Some(v) = d.mass_scale_text() {
        println!("{v}.");
    }
    if let Some(v) = d.visibility_text() {
        println!("{v}.");
    }
    for p in &d.partial {
        println!(
            "partial explanation (not a cause): {}: {}",
            p.effect.name(),
            p.why_not_a_cause
        );
    }
    Ok(())
}

/// The verdict (`j` is the JSON written), where the residual left lies, the sensors'
/// findings and the model-error response's `peak`.
fn print_verdict(d: &Diagnosis, j: &serde_json::Value, peak: Option<&ModelErrorPeak>) {
    println!(
        "cause: {}  gain {:.2}  explained {}  parameters {}",
        j["cause"].as_str().unwrap_or("none"),
        d.gain,
        d.explained,
        j["parameters"]
    );
    for u in &d.unexplained {
        println!(
            "  unexplained: {} {} residual {:.2}, worst in {:.0}-{:.0} Hz ({:.2}){}",
            u.test,
            u.channel,
            u.residual,
            u.band_hz[0],
            u.band_hz[1],
            u.band_residual,
            u.removed_by
                .map_or(String::new(), |r| format!("; {}", r.describe()))
        );
    }
    for f in &d.sensor_findings {
        println!("  sensor: {}", f.describe());
    }
    if let Some(k) = &d.kinematics {
        println!("  {}", k.text().replace('\n', "\n  "));
    }
    if let Some(p) = peak {
        println!(
            "  model-error response of {} {} (per {}) peaks at {:.2} Hz: gain {:.3e} {}, coherence {:.2}",
            p.test, p.channel, p.input, p.frequency_hz, p.gain, p.unit, p.coherence
        );
    }
}

/// The median fit per channel on the report quarters, baseline and extended, beside
/// what the noise at rest allows.
fn print_fits(d: &Diagnosis) {
    let median = |x: Option<(f64, usize)>| {
        x.map_or("no run got through".to_string(), |(m, n)| {
            format!("{m:.1} % (median of {n} tests)")
        })
    };
    for m in shaketable::diagnose::medians_by_channel(&d.fits) {
        // the ceiling needs a rest segment, which a lab's records may not have
        let ceiling = m
            .noise_ceiling
            .map_or("no rest segment bounds it by the noise".to_string(), |c| {
                format!("the noise at rest allows {}", median(Some(c)))
            });
        println!(
            "  fit of {} on the report quarters: baseline {}, extended {}; {ceiling}",
            m.channel,
            median(m.baseline),
            median(m.extended),
        );
    }
}

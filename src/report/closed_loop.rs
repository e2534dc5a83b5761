//! The closed-loop (grey-box) fit in the identification report and on the command line
//! (issue 16, parts 3 and 7): what was fitted and held, the identifiable combinations with
//! their uncertainty, what the data cannot separate, and measured against simulated per
//! test and channel, predictions marked as such.

use super::page::Section;
use super::plot::{xy_png, Series};
use crate::identify::greybox::{ClosedLoopFit, Role, Trace};
use std::fmt::Write as _;
use std::path::Path;

/// Most measured-against-simulated figures in a report: every test of a week's campaign
/// gets its own (a dozen tests), more would bury the page; the table has them all.
const MAX_FIGURES: usize = 12;

/// `x` with its one-sigma, or "not determined".
fn with_sigma(x: f64, sigma: Option<f64>) -> String {
    match sigma {
        Some(s) => format!("{x:.5e} +- {s:.2e}"),
        None => format!("{x:.5e} (sigma not determined: singular covariance)"),
    }
}

/// The fit as text, one fact a line.
pub fn text(cl: &ClosedLoopFit) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "closed loop (grey-box output error): fitted on {}; predicted: {}",
        cl.estimation_tests.join(", "),
        if cl.validation_tests.is_empty() {
            "none (one usable test)".into()
        } else {
            cl.validation_tests.join(", ")
        }
    );
    write_estimates(&mut t, cl);
    write_fits(&mut t, cl);
    write_caveats(&mut t, cl);
    t
}

/// What was fitted, the identifiable combinations, what the data cannot separate, the
/// valve's order and what was held, one line each.
fn write_estimates(t: &mut String, cl: &ClosedLoopFit) {
    for e in &cl.estimates {
        let bound = if e.at_bound {
            " AT A BOUND of its range: not an estimate"
        } else {
            ""
        };
        let _ = writeln!(
            t,
            "  fitted    {:<32} {}{bound}",
            e.key,
            with_sigma(e.value, e.sigma)
        );
    }
    for c in &cl.combinations {
        let _ = writeln!(
            t,
            "  combination {:<30} {} {} ({})",
            c.name,
            with_sigma(c.value, c.sigma),
            c.unit,
            c.meaning
        );
    }
    for s in &cl.inseparable {
        let _ = writeln!(t, "  not separable: {s}");
    }
    if let Some(v) = &cl.valve_order {
        let second = v
            .second_order_cost
            .map_or("not simulated".to_string(), |c| format!("{c:.5}"));
        let _ = writeln!(
            t,
            "  valve     {} (cost first order {:.5}, second order {second}; {:.0} effective samples; {})",
            v.chosen, v.first_order_cost, v.effective_samples, v.rule
        );
    }
    for c in &cl.conventions {
        let _ = writeln!(
            t,
            "  held      {:<32} {:.5e} ({})",
            c.key, c.value, c.reason
        );
    }
}

/// Measured against simulated per test and channel, predictions marked, and how many of
/// those fits the sensors' noise limits.
fn write_fits(t: &mut String, cl: &ClosedLoopFit) {
    for f in &cl.fits {
        let role = match f.role {
            Role::Estimation => "fitted on",
            Role::Validation => "PREDICTED",
        };
        let ceiling = f
            .noise_ceiling_percent
            .map(|c| format!("  (noise at rest allows at most {c:.0} %)"))
            .unwrap_or_default();
        let _ = writeln!(
            t,
            "  {:<10} {:<20} {:<18} NRMSE {:.4}  fit {:6.2} %{ceiling}",
            role, f.test, f.channel, f.nrmse, f.fit_percent
        );
    }
    let limited = cl.fits.iter().filter(|f| f.noise_limited).count();
    if limited > 0 {
        let _ = writeln!(
            t,
            "  {limited} of these fits are noise-limited (the noise at rest is more than half the channel's RMS): their fit % tells of the sensors, not of the model"
        );
    }
}

/// The runs that stopped, the warning when none ran through, and the sigmas' widening.
fn write_caveats(t: &mut String, cl: &ClosedLoopFit) {
    for s in &cl.stopped {
        let _ = writeln!(t, "  stopped: {s}");
    }
    if cl.fits.is_empty() && !cl.stopped.is_empty() {
        let _ = writeln!(
            t,
            "  warning: the identified model could not be simulated through any test, so \
             nothing shows it follows the records; its parameters and sigmas describe the \
             fit's last step, not a model to use"
        );
    }
    let _ = writeln!(
        t,
        "  (sigmas widened {:.1} times in variance for the residuals' correlation)",
        cl.correlation_factor
    );
}

/// The report's sections: the fit's text, then measured against simulated: the first
/// channel of every test (predictions first), then the other channels, up to
/// [`MAX_FIGURES`] (the comparison table gives every test and channel).
pub fn sections(dir: &Path, cl: &ClosedLoopFit) -> Result<Vec<Section>, super::ReportError> {
    let mut out = vec![Section::tables(
        "Closed loop (grey-box output error)",
        text(cl),
        Vec::new(),
    )];
    let order = figure_order(&cl.traces);
    for (k, tr) in order.iter().take(MAX_FIGURES).enumerate() {
        out.push(trace_section(dir, cl, tr, k)?);
    }
    if order.len() > MAX_FIGURES {
        out.push(Section::tables(
            "Closed loop: figures not drawn",
            format!(
                "{} more test channels are not drawn (at most {MAX_FIGURES} figures); their NRMSE \
                 and fit % are in the measured-against-simulated table.",
                order.len() - MAX_FIGURES
            ),
            Vec::new(),
        ));
    }
    Ok(out)
}

/// The traces in the order they are drawn: every test's first channel (validation tests
/// first), then the remaining channels in the same order.
fn figure_order(traces: &[Trace]) -> Vec<&Trace> {
    let mut sorted: Vec<&Trace> = traces.iter().collect();
    sorted.sort_by_key(|t| t.role != Some(Role::Validation));
    let (mut firsts, mut rest): (Vec<&Trace>, Vec<&Trace>) = (Vec::new(), Vec::new());
    for t in sorted {
        match firsts.iter().any(|f| f.test == t.test) {
            true => rest.push(t),
            false => firsts.push(t),
        }
    }
    firsts.into_iter().chain(rest).collect()
}

/// One measured-against-simulated figure (the `k`-th) with its fit figures.
fn trace_section(
    dir: &Path,
    cl: &ClosedLoopFit,
    tr: &Trace,
    k: usize,
) -> Result<Section, super::ReportError> {
    let fig = format!("closed_loop_{k}.png");
    let role = match tr.role == Some(Role::Validation) {
        true => "predicted, not fitted",
        false => "fitted",
    };
    let title = format!(
        "{} {}: measured and simulated ({role})",
        tr.test, tr.channel
    );
    xy_png(
        &dir.join(&fig),
        &title,
        "time (s)",
        tr.channel,
        &[
            Series {
                label: "measured",
                x: &tr.time_s,
                y: &tr.measured,
                points: false,
            },
            Series {
                label: "simulated",
                x: &tr.time_s,
                y: &tr.simulated,
                points: false,
            },
        ],
    )?;
    let fit = cl
        .fits
        .iter()
        .find(|f| f.test == tr.test && f.channel == tr.channel)
        .map(|f| {
            format!(
                "NRMSE {:.4}, fit {:.2} % over the whole test (means removed){}; the figure \
                 shows ten seconds from just before the test moves.",
                f.nrmse,
                f.fit_percent,
                f.noise_ceiling_percent
                    .map(|c| format!(
                        ", where the noise at rest allows at most {c:.0} %{}",
                        if f.noise_limited {
                            ": noise-limited"
                        } else {
                            ""
                        }
                    ))
                    .unwrap_or_default()
            )
        })
        .unwrap_or_default();
    Ok(Section::figure(
        format!("Closed loop: {} {}", tr.test, tr.channel),
        fig,
        fit,
    ))
}

//! The closed-loop (grey-box) fit in the identification report and on the command line
//! (issue 16, parts 3 and 7): what was fitted and held, the identifiable combinations with
//! their uncertainty, what the data cannot separate, and measured against simulated per
//! test and channel, predictions marked as such.

use super::plot::{xy_png, Series};
use crate::identify::greybox::{ClosedLoopFit, Role};
use std::fmt::Write as _;
use std::path::Path;

/// Most measured-against-simulated figures in a report: the validation tests first.
const MAX_FIGURES: usize = 4;

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
    for c in &cl.conventions {
        let _ = writeln!(
            t,
            "  held      {:<32} {:.5e} ({})",
            c.key, c.value, c.reason
        );
    }
    for f in &cl.fits {
        let role = match f.role {
            Role::Estimation => "fitted on",
            Role::Validation => "PREDICTED",
        };
        let _ = writeln!(
            t,
            "  {:<10} {:<20} {:<18} NRMSE {:.4}  fit {:6.2} %",
            role, f.test, f.channel, f.nrmse, f.fit_percent
        );
    }
    for s in &cl.stopped {
        let _ = writeln!(t, "  stopped: {s}");
    }
    let _ = writeln!(
        t,
        "  (sigmas widened {:.1} times in variance for the residuals' correlation)",
        cl.correlation_factor
    );
    t
}

/// The report's sections: the fit's text, then measured against simulated for the
/// validation tests first. Each is `(title, figure, text)`.
pub fn sections(
    dir: &Path,
    cl: &ClosedLoopFit,
) -> Result<Vec<(String, String, String)>, super::ReportError> {
    let mut traces: Vec<_> = cl.traces.iter().collect();
    traces.sort_by_key(|t| t.role != Some(Role::Validation));
    let mut out = Vec::new();
    for (k, tr) in traces.into_iter().take(MAX_FIGURES).enumerate() {
        let fig = format!("closed_loop_{k}.png");
        let role = if tr.role == Some(Role::Validation) {
            "predicted, not fitted"
        } else {
            "fitted"
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
                    "NRMSE {:.4}, fit {:.2} % over the whole test (means removed).",
                    f.nrmse, f.fit_percent
                )
            })
            .unwrap_or_default();
        let body = if k == 0 {
            format!("{fit}\n\n{}", text(cl))
        } else {
            fit
        };
        out.push((
            format!("Closed loop: {} {}", tr.test, tr.channel),
            fig,
            body,
        ));
    }
    Ok(out)
}

//! The diagnosis report's account of causes: the accepted ones with their gain, the
//! partial explanations, and where the residual left lies (issue 17 parts 2-4).

use super::escape_html;
use crate::diagnose::{Diagnosis, Split};
use std::fmt::Write;

/// `a / b` of a split, `-` where a side has no figure.
fn split_text(s: &Split) -> String {
    let f = |x: Option<f64>| x.map(|v| format!("{v:.1}")).unwrap_or_else(|| "-".into());
    format!("{} / {}", f(s.when), f(s.otherwise))
}

/// `key = value +- sigma` for each parameter.
fn parameters_text(
    parameters: &std::collections::BTreeMap<String, f64>,
    sigma: &std::collections::BTreeMap<String, f64>,
) -> String {
    parameters
        .iter()
        .map(|(k, v)| match sigma.get(k) {
            Some(s) => format!("{k} = {v:.5} +- {s:.2e}"),
            None => format!("{k} = {v:.5}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The causes, partial explanations and unexplained cells as HTML and Markdown sections.
pub(super) fn write_causes(html: &mut String, md: &mut String, d: &Diagnosis) {
    write_cause_table(html, md, d);
    write_notes(html, md, d);
    if d.unexplained.is_empty() {
        return;
    }
    for f in &d.sensor_findings {
        paragraph(html, md, &format!("Sensor: {}.", f.describe()), true);
    }
    write_unexplained(html, md, d);
}

/// `line` as a paragraph of both documents, in bold when `bold`.
fn paragraph(html: &mut String, md: &mut String, line: &str, bold: bool) {
    if bold {
        let _ = write!(html, "<p><b>{}</b></p>", escape_html(line));
        let _ = writeln!(md, "\n**{line}**");
    } else {
        let _ = write!(html, "<p>{}</p>", escape_html(line));
        let _ = writeln!(md, "\n{line}");
    }
}

/// The accepted causes with their parameters and gains, `None.` without any.
fn write_cause_table(html: &mut String, md: &mut String, d: &Diagnosis) {
    html.push_str("<h2>Causes, in order of acceptance</h2>");
    md.push_str("\n## Causes, in order of acceptance\n\n");
    if d.causes.is_empty() {
        html.push_str("<p>None.</p>");
        md.push_str("None.\n");
        return;
    }
    html.push_str("<table><tr><th>effect</th><th>parameters (1 sigma)</th><th>gain</th></tr>");
    md.push_str("| effect | parameters (1 sigma) | gain |\n|---|---|---|\n");
    for c in &d.causes {
        let ps = parameters_text(&c.parameters, &c.sigma);
        let _ = write!(
            html,
            "<tr><td>{}</td><td style=\"text-align:left\">{}</td><td>{:.2}</td></tr>",
            c.effect.name(),
            escape_html(&ps),
            c.gain
        );
        let _ = writeln!(md, "| {} | {ps} | {:.2} |", c.effect.name(), c.gain);
    }
    html.push_str("</table>");
}

/// What could not be tested or scored, the partial explanations and the sensors' finding.
fn write_notes(html: &mut String, md: &mut String, d: &Diagnosis) {
    let notes = d
        .baseline_unscorable
        .iter()
        .cloned()
        .chain(d.mass_scale_text())
        .chain(d.visibility_text());
    for why in d.not_testable.iter().cloned().chain(notes) {
        paragraph(html, md, &format!("{why}."), false);
    }
    for p in &d.partial {
        let line = format!(
            "Partial explanation, not a cause: {} divides the selection score by {:.2}, but {}.",
            p.effect.name(),
            p.selection_gain,
            p.why_not_a_cause
        );
        paragraph(html, md, &line, false);
    }
    if let Some(f) = d.kinematics.as_ref().and_then(|k| k.finding.as_ref()) {
        paragraph(html, md, &format!("Sensors: {f}."), true);
    }
}

/// Where the residual left lies, one row per unexplained cell, worst first.
fn write_unexplained(html: &mut String, md: &mut String, d: &Diagnosis) {
    html.push_str(
        "<h2>What is left unexplained (report quarter, worst first)</h2>\
         <p>Residual in noise units; the band holds the cell's largest residual; the splits give \
         the RMS residual while the condition holds / while it does not; the last column gives \
         the sample-wise RMS residual and what is left of it when the channel is read with a \
         fitted scale and offset (a sensitivity, a unit, a zero) or a fitted delay (a filter, \
         an acquisition skew): a residual one such number removes is the sensor's, not the \
         table's.</p>\
         <table><tr><th>test</th><th>channel</th><th>band (Hz)</th><th>residual</th>\
         <th>band residual</th><th>moving + / -</th><th>large / small displacement</th>\
         <th>fast / slow</th><th>high / low load pressure</th>\
         <th>a sensor's scale, delay would leave</th></tr>",
    );
    md.push_str(
        "\n## What is left unexplained (report quarter, worst first)\n\n\
         | test | channel | band (Hz) | residual | band residual | moving + / - | large / small displacement | fast / slow | high / low load pressure | a sensor's scale, delay would leave |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for u in &d.unexplained {
        let cells = [
            u.test.clone(),
            u.channel.clone(),
            format!("{:.0}-{:.0}", u.band_hz[0], u.band_hz[1]),
            format!("{:.2}", u.residual),
            format!("{:.2}", u.band_residual),
            split_text(&u.depends_on.moving_positive),
            split_text(&u.depends_on.large_displacement),
            split_text(&u.depends_on.fast_motion),
            split_text(&u.depends_on.high_load_pressure),
            u.removed_by.map_or("-".into(), |r| r.describe()),
        ];
        html.push_str("<tr>");
        for c in &cells {
            let _ = write!(html, "<td>{}</td>", escape_html(c));
        }
        html.push_str("</tr>");
        let _ = writeln!(md, "| {} |", cells.join(" | "));
    }
    html.push_str("</table>");
}

//! The diagnosis report: the baseline's residual per test and channel against the noise
//! floor (a heat-map table), every candidate with its parameters and held-out residual,
//! the chosen cause, where the residual left lies with the model-error response of the
//! worst cells it is in, and before/after overlays of the worst tests and of the table TF.

use crate::campaign::Campaign;
use crate::diagnose::{readings, simulate_test, CellResponse, Channel, Diagnosis, Part};
use crate::identify::frf::{FrfEstimate, Welch, WelchOptions};
use crate::report::page::{html_table, markdown_cell, markdown_table, Table};
use crate::report::plot::{bode_png, xy_png, BodeCurve, Series};
use crate::report::{escape_html, markdown_code, safe_file_name};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

/// Background colour of a residual ratio: white at the noise floor, red above 5x, grey
/// where there is none.
fn heat(x: Option<f64>) -> String {
    let Some(x) = x.filter(|x| x.is_finite()) else {
        return "#eee".into();
    };
    let t = ((x - 1.0) / 4.0).clamp(0.0, 1.0);
    let g = (255.0 * (1.0 - 0.75 * t)) as u8;
    format!("rgb(255,{g},{g})")
}

/// A figure of the report: its title and its file's name in the report's folder.
type Figure = (String, String);

/// Write index.html, README.md and the figures into `dir`; `responses` are the worst
/// unexplained cells' model-error responses
/// ([`crate::diagnose::unexplained_responses`] with
/// [`super::diagnose_model_error::MODEL_ERROR_FIGURES`]), computed once by the caller,
/// which also prints the first one's peak.
pub fn write(
    dir: &Path,
    c: &Campaign,
    d: &Diagnosis,
    responses: &[CellResponse],
) -> Result<(), super::ReportError> {
    super::create_dir(dir)?;
    let cause = cause_names(d);
    let mut figures = worst_time_figures(dir, c, d, &cause)?;
    figures.extend(table_tf_figure(dir, c, d, &cause)?);
    // pages
    let mut html = String::from(
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>Diagnosis</title><style>\
         body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:collapse}\
         td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}td:first-child{text-align:left}\
         img{max-width:100%}</style></head><body>",
    );
    let mut md = String::new();
    write_summary(&mut html, &mut md, c, d, &cause);
    write_heat_map(&mut html, &mut md, d);
    super::diagnose_causes::write_causes(&mut html, &mut md, d);
    write_fits(&mut html, &mut md, d);
    super::diagnose_model_error::write_model_error(dir, responses, &mut html, &mut md)?;
    write_candidates(&mut html, &mut md, d);
    write_figures(&mut html, &mut md, &figures);
    html.push_str("</body></html>\n");
    crate::output::atomic_write(&dir.join("index.html"), html.as_bytes())?;
    crate::output::atomic_write(&dir.join("README.md"), md.as_bytes())?;
    Ok(())
}

/// The causes named, joined by " + " ("none" without one).
fn cause_names(d: &Diagnosis) -> String {
    if d.causes.is_empty() {
        "none".to_string()
    } else {
        d.causes
            .iter()
            .map(|c| c.effect.name())
            .collect::<Vec<_>>()
            .join(" + ")
    }
}

/// The overlays of the baseline's worst cells (three tests at most, one cell each, the
/// largest residual ratio first): measured, baseline and extended (`cause`).
fn worst_time_figures(
    dir: &Path,
    c: &Campaign,
    d: &Diagnosis,
    cause: &str,
) -> Result<Vec<Figure>, super::ReportError> {
    let mut figures = Vec::new();
    // the worst tests of the baseline: the largest residual ratio
    let mut worst: Vec<(usize, Channel, f64)> = d
        .baseline_rows
        .iter()
        .enumerate()
        .flat_map(|(i, (_, r))| {
            r.iter()
                .filter_map(move |(ch, x)| Some((i, ch, x.finite()?)))
        })
        .collect();
    worst.sort_by(|a, b| b.2.total_cmp(&a.2));
    let mut shown = Vec::new();
    for (i, ch, ratio) in worst {
        if shown.len() >= 3 || shown.iter().any(|(t, _)| *t == i) {
            continue;
        }
        shown.push((i, ch));
        figures.extend(time_figure(dir, c, d, (i, ch, ratio), cause)?);
    }
    Ok(figures)
}

/// The overlay of test `i`'s channel `ch` (baseline residual `ratio`) in a 1.5 s window
/// around the baseline's largest residual; `None` when the channel was not recorded.
fn time_figure(
    dir: &Path,
    c: &Campaign,
    d: &Diagnosis,
    (i, ch, ratio): (usize, Channel, f64),
    cause: &str,
) -> Result<Option<Figure>, super::ReportError> {
    let r = &c.records[i];
    let (base, ext) = (
        simulate_test(&d.baseline, c, i, Part::Whole),
        simulate_test(&d.extended, c, i, Part::Whole),
    );
    let (base, ext) = (readings(&base), readings(&ext));
    let Some(m) = ch.measured(r) else {
        return Ok(None);
    };
    let (lo, hi) = worst_window(m, base, ch, c.sample_rate_of(i));
    let t: Vec<f64> = r.time_s[lo..hi].to_vec();
    let meas: Vec<f64> = m[lo..hi].to_vec();
    // a run that stopped inside the window is drawn up to its stop
    let b = simulated_over(base, ch, lo..hi);
    let e = simulated_over(ext, ch, lo..hi);
    let name = &c.info.tests[i].name;
    let file = safe_file_name(&format!("time_{name}_{}.png", ch.name()));
    let ext_label = format!("extended ({cause})");
    xy_png(
        &dir.join(&file),
        &format!(
            "{name}: {} (baseline residual {ratio:.1} x noise)",
            ch.name()
        ),
        "time (s)",
        ch.name(),
        &[
            Series {
                label: "measured",
                x: &t,
                y: &meas,
                points: false,
            },
            Series {
                label: "baseline",
                x: &t[..b.len()],
                y: &b,
                points: false,
            },
            Series {
                label: &ext_label,
                x: &t[..e.len()],
                y: &e,
                points: false,
            },
        ],
    )?;
    Ok(Some((
        format!("{name}, {}: measured vs baseline vs extended", ch.name()),
        file,
    )))
}

/// Channel `ch` of a run's readings over `range`, up to its stop if it stopped inside.
fn simulated_over(run: &[crate::Outputs], ch: Channel, range: Range<usize>) -> Vec<f64> {
    let readings = run.iter().skip(range.start).take(range.len());
    readings.map(|o| ch.simulated(o)).collect()
}

/// The samples `lo..hi` of a 1.5 s window (at `sample_rate_hz`) around the largest
/// residual of the baseline's run `base` (its readings) against the measured channel `m`.
/// A run that stopped before the record's end has no bound on its residual after the
/// stop: the window is the record's end.
fn worst_window(
    m: &[f64],
    base: &[crate::Outputs],
    ch: Channel,
    sample_rate_hz: f64,
) -> (usize, usize) {
    let k = if base.len() < m.len() {
        m.len() - 1
    } else {
        (0..m.len())
            .max_by(|&a, &b| {
                (m[a] - ch.simulated(&base[a]))
                    .abs()
                    .total_cmp(&(m[b] - ch.simulated(&base[b])).abs())
            })
            .unwrap_or(0)
    };
    let half = (0.75 * sample_rate_hz) as usize;
    (k.saturating_sub(half), (k + half).min(m.len()))
}

/// The table TF of the mass test (R2 in the paper; identify::select): measured, baseline,
/// extended; `None` without such a test or an estimate of all three.
fn table_tf_figure(
    dir: &Path,
    c: &Campaign,
    d: &Diagnosis,
    cause: &str,
) -> Result<Option<Figure>, super::ReportError> {
    let roles = crate::identify::select::random_roles(c);
    let Some(i) = roles.mass.or(roles.oil_column) else {
        return Ok(None);
    };
    let Some([m, b, e]) = table_tfs(c, d, i) else {
        return Ok(None);
    };
    let ext_label = format!("extended ({cause})");
    bode_png(
        &dir.join("table_tf.png"),
        &format!(
            "Table TF of {}: measured, baseline, extended",
            c.info.tests[i].name
        ),
        "gain (-)",
        &[
            BodeCurve {
                label: "measured",
                frequency_hz: &m.frequency_hz,
                response: &m.h1,
            },
            BodeCurve {
                label: "baseline",
                frequency_hz: &b.frequency_hz,
                response: &b.h1,
            },
            BodeCurve {
                label: &ext_label,
                frequency_hz: &e.frequency_hz,
                response: &e.h1,
            },
        ],
        1.0,
        40.0,
    )?;
    Ok(Some((
        "Table TF before and after".into(),
        "table_tf.png".into(),
    )))
}

/// Test `i`'s table TF (acceleration over reference acceleration, Welch at 0.25 Hz):
/// measured, of the baseline, of the extended model; `None` unless all three estimate.
fn table_tfs(c: &Campaign, d: &Diagnosis, i: usize) -> Option<[FrfEstimate; 3]> {
    let r = &c.records[i];
    let fs = c.sample_rate_of(i);
    let w = Welch::new(
        fs,
        WelchOptions::for_resolution(fs, 0.25).fit_to(r.len(), 8),
    )
    .ok()?;
    let est = |acc: &[f64]| w.frf(&r.ref_acceleration_m_s2, acc).ok();
    // a run that stopped has no table TF
    let acceleration = |p| -> Option<Vec<f64>> {
        let run = simulate_test(p, c, i, Part::Whole).ok()?;
        Some(run.iter().map(|o| o.acceleration_m_s2).collect())
    };
    let (base, ext) = (acceleration(&d.baseline), acceleration(&d.extended));
    let measured = r.acceleration_m_s2.as_deref().and_then(est);
    let (base, ext) = (base.as_deref().and_then(est), ext.as_deref().and_then(est));
    let (Some(m), Some(b), Some(e)) = (measured, base, ext) else {
        return None;
    };
    Some([m, b, e])
}

/// A noise level as `show` writes it, or "not recorded" for a channel no test recorded
/// (it has no floor).
fn level(x: Option<f64>, show: impl Fn(f64) -> String) -> String {
    x.map_or_else(|| "not recorded".to_string(), show)
}

/// The summary: the causes, the gain, the baseline's structure and noise floor, the rule.
fn write_summary(html: &mut String, md: &mut String, c: &Campaign, d: &Diagnosis, cause: &str) {
    let force = level(d.noise.force_n, |x| format!("{x:.1} N"));
    let _ = write!(
        html,
        "<h1>Diagnosis of {}</h1><p><b>Cause: {cause}</b>, gain {:.2} on the report quarter (data no fit or decision saw), explained: {}.</p>\
         <p>Baseline: servovalve {}, actuator {} (chosen by output error: cost {:.4e} ideal, {:.4e} nonlinear); \
         noise floor from {}: displacement {}, acceleration {}, force {force}, spool {}, \
         valve command {}.</p>{}<p>Rule: {}</p>",
        escape_html(&c.info.name),
        d.gain,
        d.explained,
        d.valve_model.name(),
        d.actuator_model.name(),
        d.actuator_costs[0],
        d.actuator_costs[1],
        d.noise.method,
        level(d.noise.displacement_m, |x| format!("{x:.3e} m")),
        level(d.noise.acceleration_m_s2, |x| format!("{x:.3e} m/s^2")),
        level(d.noise.spool, |x| format!("{x:.3e}")),
        level(d.noise.valve_command, |x| format!("{x:.3e}")),
        d.structure_change()
            .map(|s| format!("<p>Note: {}.</p>", escape_html(&s)))
            .unwrap_or_default(),
        escape_html(&d.rule())
    );
    let _ = writeln!(
        md,
        "# Diagnosis of {}\n\n**Cause: {cause}**, gain {:.2}, explained: {}\n",
        markdown_code(&c.info.name),
        d.gain,
        d.explained
    );
    if let Some(s) = d.structure_change() {
        let _ = writeln!(md, "Note: {s}.\n");
    }
}

/// The heat map: the baseline's residual over the noise floor per test and channel.
fn write_heat_map(html: &mut String, md: &mut String, d: &Diagnosis) {
    html.push_str(
        "<h2>What the baseline gets wrong: residual RMS / noise RMS</h2><table><tr><th>test</th>",
    );
    md.push_str("## Baseline residual / noise RMS\n\n| test |");
    for ch in Channel::ALL.map(Channel::name) {
        let _ = write!(html, "<th>{ch}</th>");
        let _ = write!(md, " {ch} |");
    }
    html.push_str("</tr>");
    md.push_str("\n|---|---|---|---|---|---|\n");
    for (name, r) in &d.baseline_rows {
        let _ = write!(html, "<tr><td>{}</td>", escape_html(name));
        let _ = write!(md, "| {} |", markdown_cell(name));
        for x in r.values() {
            // absent channels and a diverged run's cells alike
            let shown = x.finite();
            let text = shown.map_or_else(|| "-".into(), |x| format!("{x:.2}"));
            let _ = write!(html, "<td style=\"background:{}\">{text}</td>", heat(shown));
            let _ = write!(md, " {text} |");
        }
        html.push_str("</tr>");
        md.push('\n');
    }
    html.push_str("</table>");
}

/// The first search's candidates with their report residual and selection score.
fn write_candidates(html: &mut String, md: &mut String, d: &Diagnosis) {
    html.push_str("<h2>Candidates of the first search</h2><table><tr><th>effect</th><th>parameters</th><th>report residual</th><th>selection score</th></tr>");
    md.push_str("\n## Candidates of the first search\n\n| effect | parameters | report residual | selection score |\n|---|---|---|---|\n");
    let _ = write!(
        html,
        "<tr><td>baseline</td><td></td><td>{:.3}</td><td>{:.3}</td></tr>",
        d.baseline_heldout, d.baseline_score
    );
    for cand in &d.candidates {
        let ps: Vec<String> = cand
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v:.5}"))
            .collect();
        let _ = write!(
            html,
            "<tr><td>{}</td><td style=\"text-align:left\">{}</td><td>{:.3}</td><td>{:.3}</td></tr>",
            cand.effect.name(),
            ps.join(", "),
            cand.report_residual,
            cand.score
        );
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} |",
            cand.effect.name(),
            ps.join(", "),
            cand.report_residual,
            cand.score
        );
    }
    html.push_str("</table>");
}

/// The overlays, each under its title.
fn write_figures(html: &mut String, md: &mut String, figures: &[Figure]) {
    html.push_str("<h2>Before and after</h2>");
    md.push_str("\n## Before and after\n\n");
    for (title, file) in figures {
        let _ = write!(
            html,
            "<h3>{}</h3><img src=\"{}\">",
            escape_html(title),
            escape_html(file)
        );
        let _ = write!(md, "### {title}\n\n![{title}]({file})\n\n");
    }
}

/// The fits of the baseline and the extended model on the report quarters (NRMSE and
/// fit % as the identification's), per test and channel.
fn write_fits(html: &mut String, md: &mut String, d: &Diagnosis) {
    const WHAT: &str = "Every test simulated as it was run (its reference, its gains) with \
        the refined baseline and with the extended model; per channel fit % = 100 (1 - \
        NRMSE), NRMSE = RMS(measured - simulated) / RMS(measured), means removed, over each \
        test's last quarter, which no fit and no decision used. \"noise allows\" is the \
        most a noise-free simulation of the true table reaches with the noise the channel \
        shows at rest.";
    let pct = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.2}"));
    let mut t = Table::new(&[
        "test",
        "channel",
        "baseline fit %",
        "extended fit %",
        "noise allows %",
    ]);
    for f in &d.fits {
        t.push(vec![
            f.test.clone(),
            f.channel.to_string(),
            pct(f.baseline_fit_percent),
            pct(f.extended_fit_percent),
            pct(f.noise_ceiling_percent),
        ]);
    }
    const TITLE: &str = "Measured against simulated (report quarters)";
    let _ = write!(html, "<h2>{TITLE}</h2><p>{}</p>", escape_html(WHAT));
    html_table(&t, html);
    let _ = write!(md, "\n## {TITLE}\n\n{WHAT}\n\n");
    markdown_table(&t, md);
}

//! What was read and what was screened out (issue 16, part 7): per test its file, kind,
//! rate, samples and duration, per channel its SI unit after mapping, its range and the
//! lab's column it came from; the geometry and gains nobody wrote down; the screening's
//! findings with their reasons. One text form (`campaign check`, `identify`) and the
//! report's sections.

use super::page::{Section, Table};
use crate::campaign::provenance::{CampaignRead, TestRead};
use crate::campaign::screen::{Action, Finding};
use std::fmt::Write as _;

fn lower(x: impl std::fmt::Debug) -> String {
    format!("{x:?}").to_lowercase()
}

/// A sample value with five significant digits (millimetres of stroke in metres too).
fn value(x: f64) -> String {
    match x.abs() {
        0.0 => "0".into(),
        a if (0.1..1e5).contains(&a) => format!("{x:.4}"),
        _ => format!("{x:.4e}"),
    }
}

/// A test's line: file, kind, control, rate, samples, duration.
fn test_line(t: &TestRead) -> String {
    format!(
        "{} ({}): {}, {} control, {} Hz{}, {} samples, {:.3} s",
        t.test,
        t.file,
        lower(t.kind),
        lower(t.control),
        t.sample_rate_hz,
        if t.own_rate { " (its own rate)" } else { "" },
        t.samples,
        t.duration_s
    )
}

/// The unit as shown: the SI unit, or the file's own for a column kept unmapped.
fn unit(u: Option<&str>) -> &str {
    u.unwrap_or("as in the file")
}

/// The sentence naming the keys campaign.toml does not give.
fn unknown_line(r: &CampaignRead) -> String {
    match r.unknown_keys.is_empty() {
        true => "every geometry and controller key is given in campaign.toml".into(),
        false => format!(
            "unknown (not in campaign.toml): {}; identification estimates what the recordings \
             allow and reports the rest as not identified",
            r.unknown_keys.join(", ")
        ),
    }
}

/// What was read, as text: a line per test, then its channels (unit, range, source).
pub fn text(r: &CampaignRead) -> String {
    let mut s = String::new();
    for t in &r.tests {
        let _ = writeln!(s, "test {}", test_line(t));
        let _ = writeln!(
            s,
            "  {:<24} {:<16} {:>12} {:>12}  source",
            "channel", "unit", "min", "max"
        );
        for c in &t.channels {
            let _ = writeln!(
                s,
                "  {:<24} {:<16} {:>12} {:>12}  {}",
                c.channel,
                unit(c.unit),
                value(c.min),
                value(c.max),
                c.source
            );
        }
        if !t.unread_columns.is_empty() {
            let _ = writeln!(s, "  not read: {}", t.unread_columns.join(", "));
        }
    }
    let _ = writeln!(s, "{}", unknown_line(r));
    s
}

/// The report's "What was read" section: a table of the tests and one of their channels.
pub fn section(r: &CampaignRead) -> Section {
    let mut tests = Table::new(&[
        "test",
        "file",
        "kind",
        "control",
        "rate (Hz)",
        "samples",
        "duration (s)",
        "columns not read",
    ]);
    let mut channels = Table::new(&["test", "channel", "unit", "min", "max", "source"]);
    for t in &r.tests {
        tests.push(vec![
            t.test.clone(),
            t.file.clone(),
            lower(t.kind),
            lower(t.control),
            format!(
                "{}{}",
                t.sample_rate_hz,
                if t.own_rate { " (own)" } else { "" }
            ),
            t.samples.to_string(),
            format!("{:.3}", t.duration_s),
            t.unread_columns.join(", "),
        ]);
        for c in &t.channels {
            channels.push(vec![
                t.test.clone(),
                c.channel.clone(),
                unit(c.unit).to_string(),
                value(c.min),
                value(c.max),
                c.source.to_string(),
            ]);
        }
    }
    let total: f64 = r.tests.iter().map(|t| t.duration_s).sum();
    Section::tables(
        "What was read",
        format!(
            "{} tests, {total:.3} s of recordings (before screening). Channels after mapping, in SI \
             units (value = scale x (column - offset)); a reference derivative not recorded is computed \
             from the recorded reference in the frequency domain.\n\n{}.",
            r.tests.len(),
            unknown_line(r)
        ),
        vec![tests, channels],
    )
}

/// The screening's findings as text lines (`screening: ...`).
pub fn screening_text(findings: &[Finding]) -> String {
    if findings.is_empty() {
        return "screening: no finding (finite, no spikes, no flat channel, signs consistent)\n"
            .into();
    }
    findings
        .iter()
        .map(|f| format!("screening: {f}\n"))
        .collect()
}

/// The report's "What was screened out" section.
pub fn screening_section(findings: &[Finding]) -> Section {
    let mut t = Table::new(&["test", "file", "channel", "action", "reason"]);
    for f in findings {
        t.push(vec![
            f.test.clone(),
            f.file.clone(),
            f.channel.clone(),
            f.action.label().into(),
            f.message.clone(),
        ]);
    }
    let excluded = findings
        .iter()
        .filter(|f| f.action == Action::TestExcluded)
        .count();
    let set_aside = findings.iter().any(|f| f.action == Action::ChannelSetAside);
    let text = match findings.is_empty() {
        true => "No finding: every channel finite, no spikes, no flat channel, signs consistent \
                 with physics, every declared kind matches its reference."
            .to_string(),
        false => format!(
            "Before estimating, every record is screened: isolated bad samples are repaired by \
             interpolation, anything worse excludes the test, with the reason ({excluded} \
             exclusion{}).{}",
            if excluded == 1 { "" } else { "s" },
            if set_aside {
                " A displacement that follows a reference nobody recorded is kept for section 4 \
                 but not compared with the model."
            } else {
                ""
            }
        ),
    };
    let tables = if findings.is_empty() { vec![] } else { vec![t] };
    Section::tables("What was screened out", text, tables)
}

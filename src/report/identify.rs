//! The identification report (index.html and README.md): what was read and what was
//! screened out, what was identified with its uncertainty (against the truth when known)
//! and what could not be with the reason, measured against simulated for every test, then
//! the figures of paper section 4 (Figures 4-10), the device and the closed loop. Every
//! part renders the typed results of [`Identification`].

use super::page::{self, Section, Table};
use super::{closed_loop, device, read, section4, summary};
use crate::campaign::screen::Action;
use crate::identify::greybox::Role;
use crate::identify::Identification;
use std::path::Path;

pub use summary::{summary_rows, text_table, Row};

/// Write the figures, index.html and README.md into `dir`.
pub fn write(
    dir: &Path,
    id: &Identification,
    rows: &[Row],
    with_truth: bool,
) -> Result<(), super::ReportError> {
    super::create_dir(dir)?;
    let mut sections = vec![
        read::section(&id.read),
        read::screening_section(&id.screening),
    ];
    // what the estimates should not be taken for, before the estimates
    let warnings = id.warnings();
    if !warnings.is_empty() {
        sections.push(Section::tables(
            "Warnings",
            warnings.join("\n\n"),
            Vec::new(),
        ));
    }
    sections.extend(summary::section(id, rows, with_truth));
    sections.push(comparison_section(id));
    let paper = section4::sections(dir, id)?;
    if !paper.is_empty() {
        sections.push(Section::tables(
            "Paper section 4",
            format!(
                "Welch estimates: Hann window, {} samples per segment, {:.0} % overlap.",
                id.welch.segment_len,
                100.0 * id.welch.overlap
            ),
            Vec::new(),
        ));
    }
    sections.extend(paper);
    if let Some(d) = &id.device {
        sections.extend(device::sections(dir, d)?);
    }
    if let Some(cl) = &id.closed_loop {
        sections.extend(closed_loop::sections(dir, cl)?);
    }
    let title = format!("Identification of {}", id.campaign);
    let md = page::markdown(&title, &sections);
    crate::output::atomic_write(&dir.join("README.md"), md.as_bytes())?;
    let html = page::html(&title, &sections);
    crate::output::atomic_write(&dir.join("index.html"), html.as_bytes())?;
    Ok(())
}

/// Why a test that was read has no measured-against-simulated figures: screened out,
/// its simulation stopped, or no model could simulate it (unknown gains, no fit).
fn not_compared(id: &Identification, test: &str) -> String {
    let excluded: Vec<String> = id
        .screening
        .iter()
        .filter(|f| f.test == test && f.action == Action::TestExcluded)
        .map(|f| format!("{}: {}", f.channel, f.message))
        .collect();
    if !excluded.is_empty() {
        return format!("screened out ({})", excluded.join("; "));
    }
    let stopped = id
        .closed_loop
        .iter()
        .flat_map(|cl| &cl.stopped)
        .find(|s| s.starts_with(&format!("{test}:")));
    match stopped {
        Some(s) => format!("simulation stopped: {s}"),
        None => "not simulated: no identified model could run it (gains unknown and no \
                 closed-loop fit, or the run left the operating envelope)"
            .into(),
    }
}

/// Measured against simulated for every test that was read: NRMSE and fit % per channel,
/// predictions marked; a test without figures says why.
fn comparison_section(id: &Identification) -> Section {
    let mut fits = Table::new(&[
        "test",
        "channel",
        "role",
        "NRMSE",
        "fit %",
        "noise allows %",
        "measured RMS",
    ]);
    for f in &id.comparison {
        fits.push(vec![
            f.test.clone(),
            f.channel.to_string(),
            match f.role {
                Role::Estimation => "fitted on".into(),
                Role::Validation => "predicted (not fitted)".into(),
            },
            format!("{:.4}", f.nrmse),
            format!("{:.2}", f.fit_percent),
            match f.noise_ceiling_percent {
                Some(c) if f.noise_limited => format!("{c:.0} (noise-limited)"),
                Some(c) => format!("{c:.0}"),
                None => "- (no rest segment)".into(),
            },
            format!("{:.4e}", f.measured_rms),
        ]);
    }
    let mut missing = Table::new(&["test", "why no comparison"]);
    for t in &id.read.tests {
        if !id.comparison.iter().any(|f| f.test == t.test) {
            missing.push(vec![t.test.clone(), not_compared(id, &t.test)]);
        }
    }
    let mut tables = vec![fits];
    if !missing.rows.is_empty() {
        tables.push(missing);
    }
    Section::tables(
        "Measured against simulated",
        "Every test simulated as it was run (its reference, its gains) with the identified \
         model; per channel NRMSE = RMS(measured - simulated) / RMS(measured) and fit % = \
         100 (1 - NRMSE), means removed (MATLAB's compare). A test the fit did not use is a \
         prediction. \"noise allows\" is the most fit % a noise-free simulation of the true \
         table can reach with the noise the channel shows at rest (where the recorded \
         references hold before the test moves): 100 (1 - RMS at rest / RMS). In motion \
         the loop's response to the noise is larger still, so the true table fits lower. \
         Below 50 % the channel is mostly noise (a slow test's acceleration) and its fit % \
         tells of the sensors, not the model."
            .into(),
        tables,
    )
}

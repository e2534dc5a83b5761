//! The diagnosis report's model-error responses (issue 17 part 4): when the data is not
//! explained, for the worst cells the final model still misses, the response from the
//! test's reference to the residual with its confidence band, and how to read it.

use super::plot::{gain_band_png, GainBand};
use super::{escape_html, safe_file_name, ReportError};
use crate::diagnose::model_error::BAND_SIGMAS;
use crate::diagnose::{CellResponse, ModelErrorResponse};
use std::fmt::Write;
use std::path::Path;

/// Unexplained cells drawn at most: the worst locate the missing physics, and beyond
/// three the figures mostly repeat the same band in another channel or test of the same
/// kind; each costs a simulation of its test.
pub const MODEL_ERROR_FIGURES: usize = 3;

/// How to read the figures, under the section's title.
const HOW_TO_READ: &str = "Each figure is the gain from the test's reference to the \
    residual the extended model leaves (measured - simulated) against frequency (Welch H1 \
    over the whole test), with its confidence band shaded, and the coherence of residual \
    and reference below. A peak says the model misses a resonance there (a specimen or \
    foundation mode); a gain that rises or falls steadily with frequency says it misses a \
    compliance or dynamics (a stiffness, a lag of the valve or the actuator); a flat, broad \
    gain at low coherence says the residual is not a linear response to the reference: a \
    nonlinearity (friction, deadband, saturation, free play) or noise. Where the band \
    reaches zero the gain is not distinguishable from none.";

/// The model-error section of the unexplained `cells` (nothing when the data is
/// explained, so none): figures in `dir`, text in `html` and `md`.
pub(super) fn write_model_error(
    dir: &Path,
    cells: &[CellResponse],
    html: &mut String,
    md: &mut String,
) -> Result<(), ReportError> {
    if cells.is_empty() {
        return Ok(());
    }
    let band = band_text();
    let _ = write!(
        html,
        "<h2>Model-error response of the worst unexplained cells</h2><p>{}</p><p>{}</p>",
        escape_html(HOW_TO_READ),
        escape_html(&band)
    );
    let _ = write!(
        md,
        "\n## Model-error response of the worst unexplained cells\n\n{HOW_TO_READ}\n\n{band}\n\n"
    );
    for cell in cells {
        let title = format!("{}, {}", cell.test, cell.channel);
        match &cell.response {
            Ok(m) => {
                let file = figure(dir, m)?;
                let caption = caption(m);
                let _ = write!(
                    html,
                    "<h3>{}</h3><p>{}</p><img src=\"{}\">",
                    escape_html(&title),
                    escape_html(&caption),
                    escape_html(&file)
                );
                let _ = write!(md, "### {title}\n\n{caption}\n\n![{title}]({file})\n\n");
            }
            Err(why) => {
                let line = format!("{title}: no model-error response ({why}).");
                let _ = write!(html, "<p>{}</p>", escape_html(&line));
                let _ = write!(md, "{line}\n\n");
            }
        }
    }
    Ok(())
}

/// What the shaded band is.
fn band_text() -> String {
    format!(
        "The band is the gain times 1 +- {BAND_SIGMAS} eps (about 95 %), eps = sqrt(1 - coherence) / \
         (sqrt(coherence) sqrt(2 n_d)) the normalised random error of a gain estimate from n_d \
         averages (Bendat & Piersol, Random Data, 4th ed., section 9.2); it leaves out the bias \
         of a peak narrower than the resolution, which flattens the peak."
    )
}

/// Where the response peaks and what it rests on.
fn caption(m: &ModelErrorResponse) -> String {
    let e = &m.estimate;
    let rests_on = format!(
        "input {}; {} averages at {} Hz resolution, {:.1}-{:.1} Hz",
        m.input,
        e.averages,
        e.resolution_hz,
        e.frequency_hz.first().copied().unwrap_or(f64::NAN),
        e.frequency_hz.last().copied().unwrap_or(f64::NAN),
    );
    match e.peak() {
        Some((f, gain, coherence)) => format!(
            "Peak at {f:.2} Hz: gain {gain:.3e} {}, coherence {coherence:.2} ({rests_on}).",
            m.unit
        ),
        None => format!("No bin's band excludes zero: no gain to speak of ({rests_on})."),
    }
}

/// Draw the response of `m`; its file name in the report folder.
fn figure(dir: &Path, m: &ModelErrorResponse) -> Result<String, ReportError> {
    let file = safe_file_name(&format!("model_error_{}_{}.png", m.test, m.channel.name()));
    gain_band_png(
        &dir.join(&file),
        &format!(
            "{}: model-error response, {} residual per {}",
            m.test,
            m.channel.name(),
            m.input
        ),
        &format!("gain ({})", m.unit),
        &format!("{BAND_SIGMAS}-sigma band (~95 %)"),
        &GainBand::from(&m.estimate),
    )?;
    Ok(file)
}

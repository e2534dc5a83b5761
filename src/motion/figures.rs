//! The figures of a drive folder (issue 19, part 3): target and achieved acceleration in
//! time, and their 5 %-damped response spectra.

use super::drive::DriveResult;
use super::metrics::{response_spectrum, spectrum_frequencies_hz};
use super::prepare::Target;
use crate::report::plot::{xy_png, PlotError, Series};
use std::path::Path;

/// Write `time_history.png` and `spectra.png` into `dir`.
pub fn draw(
    dir: &Path,
    target: &Target,
    r: &DriveResult,
    iteration: usize,
) -> Result<(), PlotError> {
    let n = target.acceleration_m_s2.len();
    let time: Vec<f64> = (0..n).map(|k| k as f64 / target.rate_hz).collect();
    let predicted: Vec<f64> = r.predicted.iter().map(|o| o.acceleration_m_s2).collect();
    let mut curves: Vec<(String, Vec<f64>)> =
        vec![("target".into(), target.acceleration_m_s2.clone())];
    if let Some(m) = &r.measured_response {
        curves.push((
            format!("measured (drive {})", iteration.saturating_sub(1)),
            m.clone(),
        ));
    }
    curves.push((format!("predicted (drive {iteration})"), predicted));
    let series: Vec<Series> = curves
        .iter()
        .map(|(label, y)| Series {
            label,
            x: &time,
            y,
            points: false,
        })
        .collect();
    let title = format!("table acceleration, iteration {iteration}");
    xy_png(
        &dir.join("time_history.png"),
        &title,
        "time (s)",
        "acceleration (m/s^2)",
        &series,
    )?;
    let freqs = spectrum_frequencies_hz();
    let spectra: Vec<(String, Vec<f64>)> = curves
        .iter()
        .map(|(label, y)| (label.clone(), response_spectrum(y, target.rate_hz)))
        .collect();
    let series: Vec<Series> = spectra
        .iter()
        .map(|(label, y)| Series {
            label,
            x: &freqs,
            y,
            points: false,
        })
        .collect();
    let title = format!("5 %-damped response spectra, iteration {iteration}");
    xy_png(
        &dir.join("spectra.png"),
        &title,
        "frequency (Hz)",
        "spectral acceleration (m/s^2)",
        &series,
    )
}

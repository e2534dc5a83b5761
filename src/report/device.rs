//! The device between actuator and reaction in the identification report: the model,
//! its parameters with sigma, its force fit on the test it was fitted on and on the tests
//! it was checked on, and the hysteresis loops (measured and modelled force against
//! displacement).

use super::page::Section;
use super::plot::{xy_png, Series};
use super::ReportError;
use crate::identify::DeviceFit;
use std::path::Path;

/// The device fit's text: the model, its parameters with sigma and its fit % per test.
fn parameters_text(d: &DeviceFit) -> String {
    let sig = |i: usize| d.sigma.get(i).copied().unwrap_or(f64::NAN);
    let checked = match d.validation.is_empty() {
        true => "no other test".to_string(),
        false => d
            .validation
            .iter()
            .map(|t| format!("{} fit {:.1} %", t.test, t.fit_percent))
            .collect::<Vec<_>>()
            .join(", "),
    };
    format!(
        "F = F_mu Z(x) + c v + k x + m a + F_0 with Z the Bouc-Wen variable of eqs. 4.14-4.15 driven by \
         the measured displacement (zero-phase, band-limited to {:.1} Hz, as the velocity{}), fitted on {} \
         by Levenberg-Marquardt: F_mu = {:.4e} N +- {:.2e}, Y = {:.4e} m +- {:.2e}, b = {:.3} +- {:.3}, \
         c = {:.4e} N s/m +- {:.2e}, k = {:.4e} N/m +- {:.2e}, m = {:.4e} kg +- {:.2e}, F_0 = {:.1} N \
         (sigma from the covariance times the root of the residual's correlation factor {:.1}). \
         Force-fit NRMSE {:.4}, fit {:.1} %. Checked on (only the load cell's zero re-estimated): {}.{}",
        d.corner_hz,
        if d.measured_acceleration { "; acceleration measured" } else { " and the acceleration" },
        d.test, d.force_n, sig(0), d.yield_displacement_m, sig(1), d.shape, sig(2),
        d.viscous_n_s_m, sig(3), d.stiffness_n_m, sig(4), d.mass_kg, sig(5), d.offset_n,
        d.sigma_correlation_factor, d.fit.nrmse, d.fit.fit_percent, checked,
        d.not_validated.iter().map(|m| format!(" Not checked: {m}.")).collect::<String>()
    )
}

/// The device's hysteresis loops (measured and modelled force against displacement, a
/// window around the peak stroke) on the test it was fitted on and the first test it was
/// checked on, with the text.
pub fn sections(dir: &Path, d: &DeviceFit) -> Result<Vec<Section>, ReportError> {
    let mut out = Vec::new();
    for (k, t) in std::iter::once(&d.fit)
        .chain(d.validation.first())
        .enumerate()
    {
        let (fig, role) = match k {
            0 => ("device_fit.png", "fitted"),
            _ => ("device_check.png", "checked"),
        };
        let title = format!(
            "Device force vs displacement, {} ({role}), fit {:.1} %",
            t.test, t.fit_percent
        );
        xy_png(
            &dir.join(fig),
            &title,
            "displacement (m)",
            "force (N)",
            &[
                Series {
                    label: "measured",
                    x: &t.displacement_m,
                    y: &t.measured_force_n,
                    points: true,
                },
                Series {
                    label: "model",
                    x: &t.displacement_m,
                    y: &t.model_force_n,
                    points: false,
                },
            ],
        )?;
        let text = match k {
            0 => parameters_text(d),
            _ => format!(
                "The parameters fitted on {} on {} (load cell zero {:.1} N): NRMSE {:.4}, fit {:.1} %.",
                d.test, t.test, t.offset_n, t.nrmse, t.fit_percent
            ),
        };
        out.push(Section::figure(
            format!("Device force ({})", t.test),
            fig,
            text,
        ));
    }
    Ok(out)
}

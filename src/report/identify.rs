//! The identification report: a table of estimates (against the truth when known), the
//! figures of paper section 4 (Figures 4-10) and the method behind each number.

use crate::identify::{FrfData, Identification};
use crate::params::Params;
use crate::report::plot::{bode_png, xy_png, BodeCurve, Series};
use crate::report::{escape_html, markdown_code};
use num_complex::Complex64;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

/// One line of the summary table.
#[derive(Debug, Clone)]
pub struct Row {
    pub key: &'static str,
    pub value: f64,
    pub sigma: Option<f64>,
    pub truth: Option<f64>,
}

impl Row {
    /// Relative error against the truth, percent (absolute value when the truth is 0).
    pub fn error(&self) -> Option<f64> {
        let t = self.truth?;
        if !self.value.is_finite() {
            return None;
        }
        Some(if t == 0.0 {
            self.value
        } else {
            100.0 * (self.value / t - 1.0)
        })
    }
}

/// The estimates of issue 5's JSON keys with the truth where a parameter file gives it.
pub fn summary_rows(id: &Identification, truth: Option<&Params>) -> Vec<Row> {
    // typed estimates, not the JSON read back (a renamed estimate fails `estimate_of`'s
    // test instead of turning a row into NaN)
    let estimate = |block: &str, key: &str| estimate_of(id, &format!("{block}.{key}"));
    let get = |block: &str, key: &str| estimate(block, key).value.unwrap_or(f64::NAN);
    let sig = |block: &str, key: &str| estimate(block, key).sigma.filter(|s| s.is_finite());
    let oil = truth.map(crate::linear::OilColumn::of);
    let t = |f: &dyn Fn(&Params) -> f64| truth.map(f);
    let valve_order = truth.map(|p| p.servovalve.model);
    use crate::params::ServovalveModel as V;
    let mut rows = vec![
        Row {
            key: "servovalve.gain",
            value: get("servovalve", "gain"),
            sigma: None,
            truth: t(&|p| p.servovalve.gain),
        },
        Row {
            key: "servovalve.time_constant_s",
            value: get("servovalve", "time_constant_s"),
            sigma: sig("servovalve", "time_constant_s"),
            truth: if valve_order == Some(V::SecondOrder) {
                None
            } else {
                t(&|p| p.servovalve.time_constant_s)
            },
        },
        Row {
            key: "servovalve.natural_frequency_hz",
            value: get("servovalve", "natural_frequency_hz"),
            sigma: sig("servovalve", "natural_frequency_hz"),
            truth: if valve_order == Some(V::SecondOrder) {
                t(&|p| p.servovalve.natural_frequency_hz)
            } else {
                None
            },
        },
        Row {
            key: "servovalve.damping_ratio",
            value: get("servovalve", "damping_ratio"),
            sigma: sig("servovalve", "damping_ratio"),
            truth: if valve_order == Some(V::SecondOrder) {
                t(&|p| p.servovalve.damping_ratio)
            } else {
                None
            },
        },
        Row {
            key: "table.mass_kg",
            value: get("table", "mass_kg"),
            sigma: None,
            truth: t(&|p| p.table.mass_kg),
        },
        Row {
            key: "table.mass_random_kg",
            value: get("table", "mass_random_kg"),
            sigma: sig("table", "mass_random_kg"),
            truth: t(&|p| p.table.mass_kg),
        },
        Row {
            key: "table.mass_periodic_kg",
            value: get("table", "mass_periodic_kg"),
            sigma: sig("table", "mass_periodic_kg"),
            truth: t(&|p| p.table.mass_kg),
        },
        Row {
            key: "table.stiffness_n_m",
            value: get("table", "stiffness_n_m"),
            sigma: sig("table", "stiffness_n_m"),
            truth: t(&|p| p.table.stiffness_n_m),
        },
        Row {
            key: "oil_column.frequency_hz",
            value: get("oil_column", "frequency_hz"),
            sigma: sig("oil_column", "frequency_hz"),
            truth: oil.map(|o| o.frequency_hz),
        },
        Row {
            key: "oil_column.damping_ratio",
            value: get("oil_column", "damping_ratio"),
            sigma: sig("oil_column", "damping_ratio"),
            truth: oil.map(|o| o.damping_ratio),
        },
        Row {
            key: "oil_column.bulk_modulus_pa",
            value: get("oil_column", "bulk_modulus_pa"),
            sigma: sig("oil_column", "bulk_modulus_pa"),
            truth: t(&|p| p.actuator.bulk_modulus_pa),
        },
        Row {
            key: "friction.force_n",
            value: get("friction", "force_n"),
            sigma: sig("friction", "force_n"),
            truth: t(&|p| p.friction.force_n),
        },
        Row {
            key: "friction.yield_displacement_m",
            value: get("friction", "yield_displacement_m"),
            sigma: None,
            truth: t(&|p| p.friction.yield_displacement_m),
        },
        Row {
            key: "friction.shape",
            value: get("friction", "shape"),
            sigma: None,
            truth: t(&|p| p.friction.shape),
        },
        Row {
            key: "validation.table_tf_error",
            value: get("validation", "table_tf_error"),
            sigma: None,
            truth: None,
        },
        Row {
            key: "validation.peak_hz",
            value: get("validation", "peak_hz"),
            sigma: None,
            truth: None,
        },
    ];
    // the device fit, when a test has displacement and force (no truth: a device is no
    // parameter of the table)
    if id.device.is_some() {
        rows.extend(DEVICE_ROWS.iter().map(|k| Row {
            key: *k,
            value: estimate_of(id, k).value.unwrap_or(f64::NAN),
            sigma: estimate_of(id, k).sigma.filter(|s| s.is_finite()),
            truth: None,
        }));
    }
    let validation_row = rows.iter().position(|r| r.key == "validation.peak_hz");
    if let Some(p) = truth {
        let mut q = *p;
        q.specimen.enabled = false;
        q.foundation.enabled = false;
        if let (Some(f), Some(i)) = (
            crate::linear::Linearisation::new(&q).table_tf_figures(),
            validation_row,
        ) {
            rows[i].truth = Some(f.peak_hz);
        }
    }
    rows
}

/// The device rows of the summary (after the table's).
const DEVICE_ROWS: [&str; 7] = [
    "device.force_n",
    "device.yield_displacement_m",
    "device.shape",
    "device.viscous_n_s_m",
    "device.stiffness_n_m",
    "device.mass_kg",
    "device.fit_percent",
];

/// The device fit's text: the model, its parameters with sigma and its fit % per test.
fn device_text(d: &crate::identify::DeviceFit) -> String {
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
fn device_section(
    dir: &Path,
    d: &crate::identify::DeviceFit,
) -> Result<Vec<(String, String, String)>, super::ReportError> {
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
            0 => device_text(d),
            _ => format!(
                "The parameters fitted on {} on {} (load cell zero {:.1} N): NRMSE {:.4}, fit {:.1} %.",
                d.test, t.test, t.offset_n, t.nrmse, t.fit_percent
            ),
        };
        out.push((format!("Device force ({})", t.test), fig.to_string(), text));
    }
    Ok(out)
}

/// The estimate `key` of `id`; every key the report asks for exists (see the test).
fn estimate_of(id: &Identification, key: &str) -> crate::identify::Estimate {
    id.estimate(key).unwrap_or(crate::identify::Estimate {
        key: "unknown",
        value: None,
        sigma: None,
    })
}

fn fmt(x: f64) -> String {
    if !x.is_finite() {
        "-".into()
    } else if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e5 || x.abs() < 1e-2 {
        format!("{x:.4e}")
    } else {
        format!("{x:.4}")
    }
}

/// The summary as a fixed-width text table.
pub fn text_table(rows: &[Row], with_truth: bool) -> String {
    let mut s = String::new();
    if with_truth {
        let _ = writeln!(
            s,
            "  {:34} {:>14} {:>14} {:>10}",
            "estimate", "identified", "truth", "error"
        );
    } else {
        let _ = writeln!(
            s,
            "  {:34} {:>14} {:>14}",
            "estimate", "identified", "+- 1 sigma"
        );
    }
    for r in rows {
        if with_truth {
            let err = match (r.error(), r.truth) {
                (Some(e), Some(t)) if t == 0.0 => format!("{} abs", fmt(e)),
                (Some(e), _) => format!("{e:+.2} %"),
                _ => "".into(),
            };
            let _ = writeln!(
                s,
                "  {:34} {:>14} {:>14} {:>10}",
                r.key,
                fmt(r.value),
                r.truth.map(fmt).unwrap_or_default(),
                err
            );
        } else {
            let _ = writeln!(
                s,
                "  {:34} {:>14} {:>14}",
                r.key,
                fmt(r.value),
                r.sigma.map(fmt).unwrap_or_default()
            );
        }
    }
    s
}

fn model_curve(f: &[f64], h: impl Fn(Complex64) -> Complex64) -> Vec<Complex64> {
    f.iter()
        .map(|&x| h(Complex64::new(0.0, 2.0 * PI * x)))
        .collect()
}

/// Write the figures, index.html and README.md into `dir`.
pub fn write(
    dir: &Path,
    id: &Identification,
    rows: &[Row],
    with_truth: bool,
) -> Result<(), super::ReportError> {
    super::create_dir(dir)?;
    let mut sections: Vec<(String, String, String)> = Vec::new(); // (title, figure, text)
    if let Some(v) = &id.servovalve {
        let f = &v.measured.frequency_hz;
        let first = model_curve(f, |s| v.first_order_gain / (1.0 + s * v.time_constant_s));
        let wn = 2.0 * PI * v.natural_frequency_hz;
        let second = model_curve(f, |s| {
            v.gain * wn * wn / (s * s + 2.0 * v.damping_ratio * wn * s + wn * wn)
        });
        let h = v.measured.complex();
        bode_png(
            &dir.join("servovalve.png"),
            "Servovalve, valve command -> spool (R1, Figure 4)",
            "gain (-)",
            &[
                BodeCurve {
                    label: "measured (H1)",
                    frequency_hz: f,
                    response: &h,
                },
                BodeCurve {
                    label: "first order (eq. 4.1)",
                    frequency_hz: f,
                    response: &first,
                },
                BodeCurve {
                    label: "second order (eq. 4.2)",
                    frequency_hz: f,
                    response: &second,
                },
            ],
            0.5,
            f.last().copied().unwrap_or(60.0),
        )?;
        sections.push((
            "Servovalve (4.1.1)".into(),
            "servovalve.png".into(),
            format!(
                "Least squares on the complex FRF valve_command -> spool_position of {} over {:.1}-{:.0} Hz \
                 (Welch H1, coherence-weighted complex least squares; the command is noise-free). First order: tau = {:.2} ms (a band-dependent \
                 equivalent when the valve is second order), RMS relative error {:.3}; its phase stays within \
                 5 degrees of the measurement up to {:.1} Hz. Second order: f_v = {:.2} Hz, xi = {:.3}, error {:.3}. \
                 Chosen: {} (the second order is chosen when it halves the error).",
                v.test, v.band_hz[0], v.band_hz[1], 1e3 * v.time_constant_s, v.first_order_error,
                v.first_order_phase_valid_to_hz, v.natural_frequency_hz, v.damping_ratio, v.second_order_error, v.chosen.name()
            ),
        ));
    }
    if let Some(m) = &id.mass_random {
        let f = &m.measured.frequency_hz;
        let fit: Vec<f64> = f
            .iter()
            .map(|x| m.mass_kg - m.stiffness_like_n_m / (2.0 * PI * x).powi(2))
            .collect();
        let flat = vec![m.mass_kg; f.len()];
        xy_png(
            &dir.join("mass_random.png"),
            "Apparent mass Re(F/a) from R2 (Figure 5)",
            "frequency (Hz)",
            "mass (kg)",
            &[
                Series {
                    label: "measured Re(F/a)",
                    x: f,
                    y: &m.measured.re,
                    points: true,
                },
                Series {
                    label: "fit M - k/w^2",
                    x: f,
                    y: &fit,
                    points: false,
                },
                Series {
                    label: "identified M",
                    x: f,
                    y: &flat,
                    points: false,
                },
            ],
        )?;
        sections.push((
            "Rigid mass from random data (4.1.2)".into(),
            "mass_random.png".into(),
            format!(
                "F/a of {} with the noise-free reference acceleration as instrument (S_rF/S_ra), fitted over \
                 {:.0}-{:.0} Hz by linear least squares with a mass, a viscous and a stiffness-like term \
                 (friction bends the low-frequency apparent mass): M = {:.0} kg +- {:.0}, c = {:.3e} N s/m, \
                 k = {:.3e} N/m. A plain average of Re(F/a) over 1-5 Hz gives {:.0} kg.",
                m.test, crate::identify::MASS_BAND_HZ[0], crate::identify::MASS_BAND_HZ[1], m.mass_kg, m.sigma_mass_kg,
                m.viscous_n_s_m, m.stiffness_like_n_m, m.plain_average_kg
            ),
        ));
    }
    if let Some(o) = &id.oil_column {
        let f = &o.measured.frequency_hz;
        let h = o.measured.complex();
        let p = &id.params;
        let area = p.actuator.piston_area_m2;
        let model = model_curve(f, |s| {
            let z = o.mass_used_kg * s * s;
            o.flow_gain_scale * p.actuator.flow_gain_m3_s * area
                / (area * area / o.stiffness_n_m * s + area * area * s / z + o.leakage_m3_s_pa)
        });
        bode_png(
            &dir.join("oil_column.png"),
            "Oil column, spool -> force (R3, Figure 6)",
            "force per unit spool (N)",
            &[
                BodeCurve {
                    label: "measured (valve command as instrument)",
                    frequency_hz: f,
                    response: &h,
                },
                BodeCurve {
                    label: "actuator model fit",
                    frequency_hz: f,
                    response: &model,
                },
            ],
            1.0,
            f.last().copied().unwrap_or(60.0),
        )?;
        sections.push((
            "Oil column (4.1.3)".into(),
            "oil_column.png".into(),
            format!(
                "spool -> force of {} estimated as S_uF/S_ux with the noise-free valve command u as instrument \
                 (H1 from the noisy spool is biased where the closed loop makes the spool vanish: the same fit \
                 on H1 gives {:.3} Hz and damping {:.4}). The ideal actuator model on the identified mass \
                 ({:.0} kg) fitted over {:.0}-{:.0} Hz: f_oil = {:.3} Hz, zeta_oil = {:.4}, k_oil = {:.4e} N/m, \
                 effective bulk modulus beta = {:.4e} Pa from the geometry (A, V_t); a mass error passes one \
                 for one into beta. Flow-gain scale {:.3}.",
                o.test, o.h1_frequency_hz, o.h1_damping_ratio, o.mass_used_kg, crate::identify::OIL_BAND_HZ[0],
                crate::identify::OIL_BAND_HZ[1], o.frequency_hz, o.damping_ratio, o.stiffness_n_m, o.bulk_modulus_pa,
                o.flow_gain_scale
            ),
        ));
    }
    if let Some(t) = &id.triangles {
        let (lo, hi) = t
            .displacement_m
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
        let line_x = [lo, hi];
        let line_y = [t.stiffness_n_m * lo, t.stiffness_n_m * hi];
        xy_png(
            &dir.join("triangles.png"),
            "Elastic force from triangles (Figure 7)",
            "displacement (m)",
            "F_A - M a - F_mu sign(v) (N)",
            &[
                Series {
                    label: "measured, |u| < 0.8 u_max",
                    x: &t.displacement_m,
                    y: &t.elastic_force_n,
                    points: true,
                },
                Series {
                    label: "k x",
                    x: &line_x,
                    y: &line_y,
                    points: false,
                },
            ],
        )?;
        sections.push((
            "Stiffness from triangles (4.2.1)".into(),
            "triangles.png".into(),
            format!(
                "Away from reversals (|u| < {:.0} % of the amplitude) a triangle has zero acceleration and \
                 F_A - M a = k x + F_mu sign(v) (eqs. 4.9-4.10, all pairs at once by least squares over {}): \
                 k = {:.4e} N/m +- {:.2e}, sliding friction {:.0} N.",
                100.0 * crate::identify::TRIANGLE_FRACTION, t.tests.join(", "), t.stiffness_n_m, t.sigma_stiffness_n_m,
                t.sliding_friction_n
            ),
        ));
    }
    if let Some(m) = &id.mass_periodic {
        let (lo, hi) = m
            .acceleration_m_s2
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
        xy_png(
            &dir.join("mass_periodic.png"),
            "Loop approach: force vs acceleration (Figure 8)",
            "acceleration (m/s^2)",
            "F_A - k x (N)",
            &[
                Series {
                    label: m.tests.first().map(|s| s.as_str()).unwrap_or(""),
                    x: &m.acceleration_m_s2,
                    y: &m.inertial_force_n,
                    points: true,
                },
                Series {
                    label: "M a",
                    x: &[lo, hi],
                    y: &[m.mass_kg * lo, m.mass_kg * hi],
                    points: false,
                },
            ],
        )?;
        sections.push((
            "Mass by the loop approach (4.2.2)".into(),
            "mass_periodic.png".into(),
            format!(
                "Pairing t with T/2 - t cancels the dissipative force (eqs. 4.11-4.12); over whole steady cycles \
                 this is the least squares F_A - F_D - k x = M a with the identified Bouc-Wen force removed. \
                 Per test ({}): {} kg; mean {:.0} kg +- {:.0}.",
                m.tests.join(", "),
                m.per_test_kg.iter().map(|x| format!("{x:.0}")).collect::<Vec<_>>().join(", "),
                m.mass_kg, m.sigma_mass_kg
            ),
        ));
    }
    if let Some(fr) = &id.friction {
        xy_png(
            &dir.join("friction.png"),
            "Dissipative force vs displacement (Figure 9)",
            "displacement (m)",
            "F_D (N)",
            &[
                Series {
                    label: "F_A - M a - k x (eq. 4.13)",
                    x: &fr.displacement_m,
                    y: &fr.dissipative_force_n,
                    points: true,
                },
                Series {
                    label: "Bouc-Wen fit (eqs. 4.14-4.15)",
                    x: &fr.displacement_m,
                    y: &fr.fitted_force_n,
                    points: false,
                },
            ],
        )?;
        xy_png(
            &dir.join("friction_velocity.png"),
            "Dissipative force vs velocity (Figure 9)",
            "velocity (m/s)",
            "F_D (N)",
            &[
                Series {
                    label: "F_A - M a - k x (eq. 4.13)",
                    x: &fr.velocity_m_s,
                    y: &fr.dissipative_force_n,
                    points: true,
                },
                Series {
                    label: "Bouc-Wen fit",
                    x: &fr.velocity_m_s,
                    y: &fr.fitted_force_n,
                    points: true,
                },
            ],
        )?;
        sections.push((
            "Friction vs velocity (4.2.3)".into(),
            "friction_velocity.png".into(),
            "The same dissipative force against the table velocity: a viscoplastic (Bouc-Wen) force \
             saturates at F_mu once the table slides, with no viscous slope."
                .into(),
        ));
        sections.push((
            "Friction (4.2.3)".into(),
            "friction.png".into(),
            format!(
                "The dissipative force of the slow sines ({}) fitted with Bouc-Wen driven by the measured \
                 (smoothed) displacement: F_mu = {:.0} N +- {:.0}, Y = {:.3e} m, b = {:.3}; RMS misfit {:.0} N.",
                fr.tests.join(", "), fr.force_n, fr.sigma_force_n, fr.yield_displacement_m, fr.shape, fr.rms_error_n
            ),
        ));
    }
    if let Some(v) = &id.validation {
        let f = &v.measured.frequency_hz;
        let (hm, hi, hn) = (
            v.measured.complex(),
            v.ideal.complex(),
            v.nonlinear.complex(),
        );
        bode_png(
            &dir.join("validation.png"),
            &format!(
                "Table TF, {}: measured vs identified model (Figure 10)",
                v.test
            ),
            "gain (-)",
            &[
                BodeCurve {
                    label: "measured",
                    frequency_hz: f,
                    response: &hm,
                },
                BodeCurve {
                    label: "model, ideal actuator (analytic)",
                    frequency_hz: f,
                    response: &hi,
                },
                BodeCurve {
                    label: "model, nonlinear actuator (simulated)",
                    frequency_hz: f,
                    response: &hn,
                },
            ],
            f.first().copied().unwrap_or(1.0),
            f.last().copied().unwrap_or(40.0),
        )?;
        sections.push((
            "Validation (section 5)".into(),
            "validation.png".into(),
            format!(
                "Reference acceleration -> table acceleration of {} (H1; the reference is noise-free). This \
                 channel pair was not fitted by any estimator. RMS complex relative error over {:.0}-{:.0} Hz: \
                 {:.4} (ideal actuator), {:.4} (nonlinear actuator). Identified peak {:.3} Hz; measured peak {}.",
                v.test, crate::identify::VALIDATION_BAND_HZ[0], crate::identify::VALIDATION_BAND_HZ[1],
                v.table_tf_error, v.table_tf_error_nonlinear, v.peak_hz,
                v.measured_figures.map(|m| format!("{:.3} Hz, phase drop {:.0} degrees over +-1 Hz", m.peak_hz, m.phase_drop_deg)).unwrap_or("-".into())
            ),
        ));
    }
    if let Some(d) = &id.device {
        sections.extend(device_section(dir, d)?);
    }
    if let Some(cl) = &id.closed_loop {
        sections.extend(super::closed_loop::sections(dir, cl)?);
    }
    let _ = FrfData::default();
    // README.md
    let mut md = format!(
        "# Identification of {}\n\n```\n{}```\n\n",
        markdown_code(&id.campaign),
        text_table(rows, with_truth)
    );
    for m in &id.missing {
        let _ = writeln!(md, "- not identified: {}", escape_html(m));
    }
    let _ = writeln!(
        md,
        "\nWelch estimates: Hann window, {} samples per segment, {:.0} % overlap.\n",
        id.welch.segment_len,
        100.0 * id.welch.overlap
    );
    for (title, fig, text) in &sections {
        let _ = write!(md, "## {title}\n\n![{title}]({fig})\n\n{text}\n\n");
    }
    crate::output::atomic_write(&dir.join("README.md"), md.as_bytes())?;
    // index.html
    let mut html = format!(
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>Identification of {0}</title>\
         <style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}td:first-child{{text-align:left}}\
         img{{max-width:100%}}</style></head><body><h1>Identification of {0}</h1><table><tr><th>estimate</th>\
         <th>identified</th><th>+- 1 sigma</th>{1}</tr>",
        escape_html(&id.campaign),
        if with_truth { "<th>truth</th><th>error</th>" } else { "" }
    );
    for r in rows {
        let _ = write!(
            html,
            "<tr><td>{}</td><td>{}</td><td>{}</td>",
            r.key,
            fmt(r.value),
            r.sigma.map(fmt).unwrap_or_default()
        );
        if with_truth {
            let _ = write!(
                html,
                "<td>{}</td><td>{}</td>",
                r.truth.map(fmt).unwrap_or_default(),
                r.error()
                    .map(|e| if r.truth == Some(0.0) {
                        fmt(e)
                    } else {
                        format!("{e:+.2} %")
                    })
                    .unwrap_or_default()
            );
        }
        html.push_str("</tr>");
    }
    html.push_str("</table>");
    for m in &id.missing {
        let _ = write!(html, "<p><b>not identified:</b> {}</p>", escape_html(m));
    }
    for (title, fig, text) in &sections {
        let _ = write!(
            html,
            "<h2>{}</h2><img src=\"{}\"><p>{}</p>",
            escape_html(title),
            escape_html(fig),
            escape_html(text)
        );
    }
    html.push_str("</body></html>\n");
    crate::output::atomic_write(&dir.join("index.html"), html.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::{synthesise, SynthOptions};

    #[test]
    fn every_report_row_is_an_estimate_and_carries_its_value() {
        let opts = SynthOptions {
            random_duration_s: 12.0,
            tests: Some(vec!["R2".into()]),
            ..SynthOptions::default()
        };
        let id = crate::identify::identify(&synthesise(&Params::trees_lab(), &opts, None));
        let rows = summary_rows(&id, None);
        for r in &rows {
            assert!(id.estimate(r.key).is_some(), "{} is not an estimate", r.key);
        }
        let mass = rows
            .iter()
            .find(|r| r.key == "table.mass_random_kg")
            .unwrap();
        assert!((mass.value / 41_258.0 - 1.0).abs() < 0.05, "{}", mass.value);
        assert!(mass.sigma.is_some_and(|s| s > 0.0));
    }
}

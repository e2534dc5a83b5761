//! The figures of paper section 4 in the identification report (Figures 4-10): each
//! estimator's measured data against its fit, with the method and the numbers behind it.

use super::page::Section;
use super::plot::{bode_png, xy_png, BodeCurve, Series};
use super::ReportError;
use crate::identify::{
    FrictionFit, Identification, MassFit, OilColumnFit, PeriodicMassFit, ServovalveFit,
    TriangleFit, Validation,
};
use crate::linear::ValveTf;
use crate::params::Params;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::path::Path;

fn model_curve(f: &[f64], h: impl Fn(Complex64) -> Complex64) -> Vec<Complex64> {
    f.iter()
        .map(|&x| h(Complex64::new(0.0, 2.0 * PI * x)))
        .collect()
}

/// The sections of every section-4 estimate `id` holds, in the paper's order.
pub fn sections(dir: &Path, id: &Identification) -> Result<Vec<Section>, ReportError> {
    let mut out = Vec::new();
    if let Some(v) = &id.servovalve {
        out.extend(servovalve(dir, v)?);
    }
    if let Some(m) = &id.mass_random {
        out.extend(mass_random(dir, m)?);
    }
    if let Some(o) = &id.oil_column {
        out.extend(oil_column(dir, o, &id.params)?);
    }
    if let Some(t) = &id.triangles {
        out.extend(triangles(dir, t)?);
    }
    if let Some(m) = &id.mass_periodic {
        out.extend(mass_periodic(dir, m)?);
    }
    if let Some(fr) = &id.friction {
        out.extend(friction(dir, fr)?);
    }
    if let Some(v) = &id.validation {
        out.extend(validation(dir, v)?);
    }
    Ok(out)
}

/// Figure 4: valve command -> spool, measured and both valve models (4.1.1).
fn servovalve(dir: &Path, v: &ServovalveFit) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
    let f = &v.measured.frequency_hz;
    let first_order = ValveTf::first_order(v.first_order_gain, v.time_constant_s);
    let first = model_curve(f, |s| first_order.response(s));
    let second_order = ValveTf::second_order(v.gain, v.natural_frequency_hz, v.damping_ratio);
    let second = model_curve(f, |s| second_order.response(s));
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
    sections.push(Section::figure(
        "Servovalve (4.1.1)",
        "servovalve.png",
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
    Ok(sections)
}

/// Figure 5: the apparent mass Re(F/a) and its fit (4.1.2).
fn mass_random(dir: &Path, m: &MassFit) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
    let f = &m.measured.frequency_hz;
    let fit: Vec<f64> = f
        .iter()
        .map(|&x| match &m.carried {
            Some(t) => t.apparent_mass(x).re,
            None => m.mass_kg - m.stiffness_like_n_m / (2.0 * PI * x).powi(2),
        })
        .collect();
    let fit_label = match m.carried {
        Some(_) => "fit: a table carrying modes",
        None => "fit M - k/w^2",
    };
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
                label: fit_label,
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
    sections.push(Section::figure(
        "Rigid mass from random data (4.1.2)",
        "mass_random.png",
        format!(
            "F/a of {} with the noise-free reference acceleration as instrument (S_rF/S_ra), fitted over \
             {:.0}-{:.0} Hz by linear least squares with a mass, a viscous and a stiffness-like term \
             (friction bends the low-frequency apparent mass): M = {:.0} kg +- {:.0}, c = {:.3e} N s/m, \
             k = {:.3e} N/m. A plain average of Re(F/a) over 1-5 Hz gives {:.0} kg.",
            m.test, crate::identify::MASS_BAND_HZ[0], crate::identify::MASS_BAND_HZ[1], m.mass_kg, m.sigma_mass_kg,
            m.viscous_n_s_m, m.stiffness_like_n_m, m.plain_average_kg
        ) + &carried_text(m),
    ));
    Ok(sections)
}

/// What the mass figure says of a table carrying modes, empty for a rigid one.
fn carried_text(m: &MassFit) -> String {
    m.carried.as_ref().map_or(String::new(), |t| {
        format!(
            " The apparent mass is not a rigid body's (misfit {:.2} of the mass, most at {:.2} Hz): \
             a table of {:.0} kg carrying {} fits it, and M is their sum, what moves below the modes.",
            m.rigid_misfit,
            m.rigid_misfit_peak_hz,
            t.table_kg,
            crate::identify::carried_modes_text(t)
        )
    })
}

/// Figure 6: spool -> force and the actuator model (4.1.3).
fn oil_column(dir: &Path, o: &OilColumnFit, p: &Params) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
    let f = &o.measured.frequency_hz;
    let h = o.measured.complex();
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
    sections.push(Section::figure(
        "Oil column (4.1.3)",
        "oil_column.png",
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
    Ok(sections)
}

/// Figure 7: the elastic force of the triangles (4.2.1).
fn triangles(dir: &Path, t: &TriangleFit) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
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
    sections.push(Section::figure(
        "Stiffness from triangles (4.2.1)",
        "triangles.png",
        format!(
            "Away from reversals (|u| < {:.0} % of the amplitude) a triangle has zero acceleration and \
             F_A - M a = k x + F_mu sign(v) (eqs. 4.9-4.10, all pairs at once by least squares over {}): \
             k = {:.4e} N/m +- {:.2e}, sliding friction {:.0} N.",
            100.0 * crate::identify::TRIANGLE_FRACTION, t.tests.join(", "), t.stiffness_n_m, t.sigma_stiffness_n_m,
            t.sliding_friction_n
        ),
    ));
    Ok(sections)
}

/// Figure 8: the loop approach, force against acceleration (4.2.2).
fn mass_periodic(dir: &Path, m: &PeriodicMassFit) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
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
    sections.push(Section::figure(
        "Mass by the loop approach (4.2.2)",
        "mass_periodic.png",
        format!(
            "Pairing t with T/2 - t cancels the dissipative force (eqs. 4.11-4.12); over whole steady cycles \
             this is the least squares F_A - F_D - k x = M a with the identified Bouc-Wen force removed. \
             Per test ({}): {} kg; mean {:.0} kg +- {:.0}.",
            m.tests.join(", "),
            m.per_test_kg.iter().map(|x| format!("{x:.0}")).collect::<Vec<_>>().join(", "),
            m.mass_kg, m.sigma_mass_kg
        ),
    ));
    Ok(sections)
}

/// Figure 9: the dissipative force against displacement and velocity (4.2.3).
fn friction(dir: &Path, fr: &FrictionFit) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
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
    sections.push(Section::figure(
        "Friction vs velocity (4.2.3)",
        "friction_velocity.png",
        "The same dissipative force against the table velocity: a viscoplastic (Bouc-Wen) force \
         saturates at F_mu once the table slides, with no viscous slope."
            .into(),
    ));
    sections.push(Section::figure(
        "Friction (4.2.3)",
        "friction.png",
        format!(
            "The dissipative force of the slow sines ({}) fitted with Bouc-Wen driven by the measured \
             (smoothed) displacement: F_mu = {:.0} N +- {:.0}, Y = {:.3e} m, b = {:.3}; RMS misfit {:.0} N.",
            fr.tests.join(", "), fr.force_n, fr.sigma_force_n, fr.yield_displacement_m, fr.shape, fr.rms_error_n
        ),
    ));
    Ok(sections)
}

/// Figure 10: the table TF, measured against the identified model (section 5).
fn validation(dir: &Path, v: &Validation) -> Result<Vec<Section>, ReportError> {
    let mut sections = Vec::new();
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
    sections.push(Section::figure(
        "Validation (section 5)",
        "validation.png",
        format!(
            "Reference acceleration -> table acceleration of {} (H1; the reference is noise-free). This \
             channel pair was not fitted by any estimator. RMS complex relative error over {:.0}-{:.0} Hz: \
             {:.4} (ideal actuator), {:.4} (nonlinear actuator). Identified peak {:.3} Hz; measured peak {}.",
            v.test, crate::identify::VALIDATION_BAND_HZ[0], crate::identify::VALIDATION_BAND_HZ[1],
            v.table_tf_error, v.table_tf_error_nonlinear, v.peak_hz,
            v.measured_figures.map(|m| format!("{:.3} Hz, phase drop {:.0} degrees over +-1 Hz", m.peak_hz, m.phase_drop_deg)).unwrap_or("-".into())
        ),
    ));
    Ok(sections)
}

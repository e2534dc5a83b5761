//! Identification of the model parameters from a campaign (paper section 4), automatic:
//! every estimator takes the tests it needs by name, and a missing test or channel
//! is reported, not failed.
//!
//! Order (each step uses the earlier ones): servovalve from R1 (4.1.1); stiffness and
//! sliding friction from the triangles T1-T6 (4.2.1); rigid mass from R2 (4.1.2);
//! Bouc-Wen friction from the slow sines (4.2.3, eqs. 4.13-4.15); mass by the loop
//! approach from S3, S6, S9 (4.2.2); oil column from R3 (4.1.3); validation of the
//! table TF (section 5).

pub mod frf;
pub mod lsq;
pub mod spool;

use crate::campaign::screen::{screen, Action, Finding, Screening};
use crate::campaign::{Campaign, Record, TestSpec};
use crate::linear::{Linearisation, OilColumn, TfFigures};
use crate::params::{ActuatorModel, Params, ServovalveModel};
use crate::solver::{simulate_record, DEFAULT_MAX_SUBSTEP_S};
use crate::Model;
use frf::{band_indices, FrfEstimate, Welch, WelchOptions};
use lsq::{minimise, LsqOptions};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

/// Frequency resolution of the Welch estimates, Hz (Hann, 50 % overlap).
pub const RESOLUTION_HZ: f64 = 0.25;
/// Band of the servovalve fits (paper Figure 4).
pub const VALVE_BAND_HZ: [f64; 2] = [0.5, 50.0];
/// Band of the apparent-mass fit (mass, viscous and stiffness-like terms).
pub const MASS_BAND_HZ: [f64; 2] = [2.0, 20.0];
/// Band of the oil-column fit.
pub const OIL_BAND_HZ: [f64; 2] = [4.0, 40.0];
/// Band of the validation error.
pub const VALIDATION_BAND_HZ: [f64; 2] = [1.0, 40.0];
/// Triangles: samples with |u| below this fraction of the amplitude (eq. 4.9).
pub const TRIANGLE_FRACTION: f64 = 0.8;
/// Shortest random record for a spectral estimate (R1, R2, R3), seconds: eight 50 %
/// overlapped Welch segments of 2 s (0.5 Hz resolution, coarser cannot place the valve
/// and oil-column corners; fewer averages leave an FRF variance above 1/8).
pub const MIN_RANDOM_S: f64 = 9.0;
/// Fewest steady cycles of a sine (between its first and last full-amplitude peaks) for
/// the loop approach and the Bouc-Wen fit: pairing `t` with `T/2 - t` needs one whole
/// cycle, and the hysteresis loop is only closed over one.
pub const MIN_SINE_CYCLES: f64 = 1.0;
/// Fewest steady cycles over all triangle tests (both directions of sliding needed).
pub const MIN_TRIANGLE_CYCLES: f64 = 1.0;
/// Physical bounds of a table's moving mass, kg: from a bench table to the largest
/// tables with payload (about 2000 t).
pub const MASS_BOUNDS_KG: [f64; 2] = [1.0, 2e6];
/// Physical bounds of the servovalve's and oil column's natural frequencies, Hz.
pub const FREQUENCY_BOUNDS_HZ: [f64; 2] = [0.1, 2000.0];
/// Physical bounds of a damping ratio.
pub const DAMPING_BOUNDS: [f64; 2] = [0.0, 10.0];

/// `Err` naming `what` of test `name` unless `x` is finite and within `bounds`.
fn check_bounds(name: &str, what: &str, x: f64, bounds: [f64; 2]) -> Result<(), String> {
    if x.is_finite() && x >= bounds[0] && x <= bounds[1] {
        Ok(())
    } else {
        Err(format!(
            "{name}: {what} = {x:.4e} is outside its physical bounds {bounds:?}: not identified"
        ))
    }
}

/// `Err` naming test `name` unless the record lasts `MIN_RANDOM_S`.
fn check_random_length(name: &str, rec: &Record, fs: f64, what: &str) -> Result<(), String> {
    let secs = rec.len() as f64 / fs;
    if secs >= MIN_RANDOM_S {
        Ok(())
    } else {
        Err(format!(
            "{name}: {secs:.2} s of data, the {what} needs at least {MIN_RANDOM_S} s (frequency resolution and averages): not identified"
        ))
    }
}

/// `Err` when a nonlinear fit did not move from its start (it would report the start).
fn check_moved(
    name: &str,
    what: &str,
    fit: &lsq::LsqFit,
    t0: &[f64],
    scale: &[f64],
) -> Result<(), String> {
    if fit.moved_from(t0, scale) {
        Ok(())
    } else {
        Err(format!(
            "{name}: the {what} did not move from its start values (no information in the data): not identified"
        ))
    }
}

/// A sampled FRF kept for the report's figures.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FrfData {
    pub frequency_hz: Vec<f64>,
    pub re: Vec<f64>,
    pub im: Vec<f64>,
    pub coherence: Vec<f64>,
}

impl FrfData {
    fn from(f: &[f64], h: &[Complex64], coh: &[f64], band: [f64; 2]) -> FrfData {
        let idx = band_indices(f, band[0], band[1]);
        FrfData {
            frequency_hz: idx.iter().map(|&i| f[i]).collect(),
            re: idx.iter().map(|&i| h[i].re).collect(),
            im: idx.iter().map(|&i| h[i].im).collect(),
            coherence: idx
                .iter()
                .map(|&i| coh.get(i).copied().unwrap_or(f64::NAN))
                .collect(),
        }
    }

    pub fn complex(&self) -> Vec<Complex64> {
        self.re
            .iter()
            .zip(&self.im)
            .map(|(a, b)| Complex64::new(*a, *b))
            .collect()
    }
}

/// Servovalve fits (paper 4.1.1, eqs. 4.1 and 4.2) on `valve_command -> spool_position`.
#[derive(Debug, Clone, Serialize)]
pub struct ServovalveFit {
    pub test: String,
    pub gain: f64,
    pub time_constant_s: f64,
    pub natural_frequency_hz: f64,
    pub damping_ratio: f64,
    pub first_order_gain: f64,
    pub sigma_natural_frequency_hz: f64,
    pub sigma_damping_ratio: f64,
    pub sigma_time_constant_s: f64,
    /// RMS complex relative error of each fit over the band.
    pub first_order_error: f64,
    pub second_order_error: f64,
    /// Highest frequency up to which the first-order phase is within 5 degrees.
    pub first_order_phase_valid_to_hz: f64,
    pub chosen: ServovalveModel,
    pub band_hz: [f64; 2],
    pub measured: FrfData,
}

/// Apparent mass `F/a = M + c/(j w) - k/w^2` fitted over [`MASS_BAND_HZ`] (paper 4.1.2).
#[derive(Debug, Clone, Serialize)]
pub struct MassFit {
    pub test: String,
    pub mass_kg: f64,
    pub sigma_mass_kg: f64,
    /// Viscous-like term, N s/m.
    pub viscous_n_s_m: f64,
    /// Stiffness-like term, N/m (the friction's pre-sliding stiffness at this amplitude).
    pub stiffness_like_n_m: f64,
    /// A plain average of Re(F/a) over 1-5 Hz, to show the friction's bias.
    pub plain_average_kg: f64,
    pub measured: FrfData,
}

/// Oil column (paper 4.1.3) from `spool -> force`, instrumented by the valve command.
#[derive(Debug, Clone, Serialize)]
pub struct OilColumnFit {
    pub test: String,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub bulk_modulus_pa: f64,
    pub leakage_m3_s_pa: f64,
    pub stiffness_n_m: f64,
    /// Fitted scale of the flow gain (1 when the geometry's `Kq` is right).
    pub flow_gain_scale: f64,
    pub sigma_frequency_hz: f64,
    pub sigma_damping_ratio: f64,
    pub sigma_bulk_modulus_pa: f64,
    /// The same fit on H1 from the noisy spool, to show its bias.
    pub h1_frequency_hz: f64,
    pub h1_damping_ratio: f64,
    pub measured: FrfData,
    pub mass_used_kg: f64,
}

/// Triangles (eqs. 4.9-4.10): elastic force vs displacement away from reversals.
#[derive(Debug, Clone, Serialize)]
pub struct TriangleFit {
    pub tests: Vec<String>,
    pub stiffness_n_m: f64,
    pub sigma_stiffness_n_m: f64,
    pub sliding_friction_n: f64,
    /// Elastic force points (displacement, force) for Figure 7 (decimated).
    pub displacement_m: Vec<f64>,
    pub elastic_force_n: Vec<f64>,
}

/// Bouc-Wen friction (eqs. 4.13-4.15) fitted to the dissipative force of the sines.
#[derive(Debug, Clone, Serialize)]
pub struct FrictionFit {
    pub tests: Vec<String>,
    pub force_n: f64,
    pub yield_displacement_m: f64,
    pub shape: f64,
    pub sigma_force_n: f64,
    pub rms_error_n: f64,
    /// Figure 9 data (decimated): displacement, velocity, dissipative force, fitted force.
    pub displacement_m: Vec<f64>,
    pub velocity_m_s: Vec<f64>,
    pub dissipative_force_n: Vec<f64>,
    pub fitted_force_n: Vec<f64>,
}

/// Mass by the loop approach (eqs. 4.11-4.12) per sine test.
#[derive(Debug, Clone, Serialize)]
pub struct PeriodicMassFit {
    pub tests: Vec<String>,
    pub per_test_kg: Vec<f64>,
    pub mass_kg: f64,
    pub sigma_mass_kg: f64,
    /// Figure 8 data of the first test: acceleration, inertial force.
    pub acceleration_m_s2: Vec<f64>,
    pub inertial_force_n: Vec<f64>,
}

/// Validation of the table TF (section 5, Figure 10).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    pub test: String,
    /// RMS of the complex relative error over [`VALIDATION_BAND_HZ`], ideal actuator.
    pub table_tf_error: f64,
    /// The same for the nonlinear actuator (simulated test, Welch).
    pub table_tf_error_nonlinear: f64,
    pub measured_figures: Option<TfFigures>,
    pub model_figures: Option<TfFigures>,
    pub peak_hz: f64,
    pub measured: FrfData,
    pub ideal: FrfData,
    pub nonlinear: FrfData,
}

/// Everything identification found, and what it could not do.
#[derive(Debug, Clone, Serialize)]
pub struct Identification {
    pub campaign: String,
    pub servovalve: Option<ServovalveFit>,
    pub triangles: Option<TriangleFit>,
    pub mass_random: Option<MassFit>,
    pub friction: Option<FrictionFit>,
    pub mass_periodic: Option<PeriodicMassFit>,
    pub oil_column: Option<OilColumnFit>,
    pub validation: Option<Validation>,
    /// The final mass: inverse-variance mean of the random and periodic estimates, `None`
    /// when neither exists (the parameter file then keeps the default, marked as such).
    pub mass_kg: Option<f64>,
    /// The identified model, usable by `simulate` and the FMU.
    #[serde(skip)]
    pub params: Params,
    /// What could not be identified, and why.
    pub missing: Vec<String>,
    /// What the screening of the records found and did.
    pub screening: Vec<Finding>,
    pub welch: WelchOptions,
}

/// The channels of a record as slices.
fn spool(r: &Record) -> Option<&[f64]> {
    r.spool_position.as_deref()
}

fn welch_for(fs: f64, n: usize) -> Result<Welch, frf::FrfError> {
    Welch::new(
        fs,
        WelchOptions::for_resolution(fs, RESOLUTION_HZ).fit_to(n, 8),
    )
}

/// Relative RMS complex error of `model` against `measured` on common bins.
pub fn relative_error(model: &[Complex64], measured: &[Complex64]) -> f64 {
    let n = measured.len().max(1) as f64;
    (model
        .iter()
        .zip(measured)
        .map(|(m, h)| ((m - h) / h).norm_sqr())
        .sum::<f64>()
        / n)
        .sqrt()
}

/// Servovalve from R1 (4.1.1): least squares on the complex FRF over the band.
pub fn fit_servovalve(name: &str, rec: &Record, fs: f64) -> Result<ServovalveFit, String> {
    let x = spool(rec).ok_or_else(|| {
        format!("{name} has no spool_position channel: servovalve not identified")
    })?;
    check_random_length(name, rec, fs, "servovalve fit")?;
    let w = welch_for(fs, rec.len()).map_err(|e| format!("{name}: {e}"))?;
    let e = w
        .frf(&rec.valve_command, x)
        .map_err(|e| format!("{name}: {e}"))?;
    let idx = e.band(VALVE_BAND_HZ[0], VALVE_BAND_HZ[1]);
    if idx.len() < 10 {
        return Err(format!(
            "{name}: too few frequency bins in {VALVE_BAND_HZ:?} Hz"
        ));
    }
    let f: Vec<f64> = idx.iter().map(|&i| e.frequency_hz[i]).collect();
    let h: Vec<Complex64> = idx.iter().map(|&i| e.h1[i]).collect();
    let wts: Vec<f64> = idx.iter().map(|&i| e.coherence[i].sqrt()).collect();
    let resid = |model: &dyn Fn(Complex64) -> Complex64| -> Vec<f64> {
        let mut r = Vec::with_capacity(2 * f.len());
        for k in 0..f.len() {
            let s = Complex64::new(0.0, 2.0 * PI * f[k]);
            let d = (model(s) - h[k]) * wts[k];
            r.push(d.re);
            r.push(d.im);
        }
        r
    };
    let opts = LsqOptions::default();
    // eq. 4.1: Ks / (1 + s tau)
    let (t1, s1) = ([1.0, 0.01], [1.0, 0.01]);
    let first = minimise(
        |p| Some(resid(&|s| p[0] / (1.0 + s * p[1]))),
        &t1,
        &[0.05, 1e-4],
        &[20.0, 1.0],
        &s1,
        opts,
    )
    .ok_or_else(|| format!("{name}: first-order valve fit failed"))?;
    check_moved(name, "first-order valve fit", &first, &t1, &s1)?;
    // eq. 4.2: Ks w^2 / (s^2 + 2 xi w s + w^2), from the first-order guess
    let w0 = 1.0 / first.theta[1];
    let t2 = [first.theta[0], 1.5 * w0 / (2.0 * PI), 1.0];
    let second = minimise(
        |p| {
            let wn = 2.0 * PI * p[1];
            Some(resid(&|s| {
                p[0] * wn * wn / (s * s + 2.0 * p[2] * wn * s + wn * wn)
            }))
        },
        &t2,
        &[0.05, 0.5, 0.05],
        &[20.0, 500.0, 5.0],
        &[1.0, 10.0, 1.0],
        opts,
    )
    .ok_or_else(|| format!("{name}: second-order valve fit failed"))?;
    check_moved(
        name,
        "second-order valve fit",
        &second,
        &t2,
        &[1.0, 10.0, 1.0],
    )?;
    let err_of = |model: &dyn Fn(Complex64) -> Complex64| {
        let m: Vec<Complex64> = f
            .iter()
            .map(|&x| model(Complex64::new(0.0, 2.0 * PI * x)))
            .collect();
        relative_error(&m, &h)
    };
    let (k1, tau) = (first.theta[0], first.theta[1]);
    let (k2, fv, xi) = (second.theta[0], second.theta[1], second.theta[2]);
    check_bounds(
        name,
        "servovalve natural frequency (Hz)",
        fv,
        FREQUENCY_BOUNDS_HZ,
    )?;
    check_bounds(name, "servovalve damping ratio", xi, DAMPING_BOUNDS)?;
    let wn = 2.0 * PI * fv;
    let first_err = err_of(&|s| k1 / (1.0 + s * tau));
    let second_err = err_of(&|s| k2 * wn * wn / (s * s + 2.0 * xi * wn * s + wn * wn));
    let mut valid_to = f[0];
    for k in 0..f.len() {
        let s = Complex64::new(0.0, 2.0 * PI * f[k]);
        let dp = ((k1 / (1.0 + s * tau)) / h[k]).arg().to_degrees().abs();
        if dp > 5.0 {
            break;
        }
        valid_to = f[k];
    }
    // the second-order model has one more parameter: choose it when it halves the error
    let chosen = if second_err < 0.5 * first_err {
        ServovalveModel::SecondOrder
    } else {
        ServovalveModel::FirstOrder
    };
    Ok(ServovalveFit {
        test: name.to_string(),
        gain: if chosen == ServovalveModel::SecondOrder {
            k2
        } else {
            k1
        },
        time_constant_s: tau,
        natural_frequency_hz: fv,
        damping_ratio: xi,
        first_order_gain: k1,
        sigma_natural_frequency_hz: second.sigma[1],
        sigma_damping_ratio: second.sigma[2],
        sigma_time_constant_s: first.sigma[1],
        first_order_error: first_err,
        second_order_error: second_err,
        first_order_phase_valid_to_hz: valid_to,
        chosen,
        band_hz: VALVE_BAND_HZ,
        measured: FrfData::from(&e.frequency_hz, &e.h1, &e.coherence, [0.0, 60.0]),
    })
}

/// Apparent mass from a random test (4.1.2): `acceleration -> force` instrumented by the
/// noise-free reference acceleration (`S_rF / S_ra`), then the linear least squares
/// `Re = M - k/w^2`, `Im = -c/w` over [`MASS_BAND_HZ`].
pub fn fit_mass(name: &str, rec: &Record, fs: f64) -> Result<MassFit, String> {
    fit_mass_corrected(name, rec, fs, None)
}

/// [`fit_mass`] on the force less the identified friction and stiffness,
/// `F_A - F_mu Z(x) - k x` (eqs. 4.4, 4.14-4.15 with `Z` along the measured path): the
/// hysteretic friction is not exactly a viscous plus a stiffness term, and removing it in
/// the time domain leaves the three-term fit only the residue.
pub fn fit_mass_corrected(
    name: &str,
    rec: &Record,
    fs: f64,
    friction: Option<(&FrictionFit, f64)>,
) -> Result<MassFit, String> {
    check_random_length(name, rec, fs, "apparent-mass fit")?;
    let w = welch_for(fs, rec.len()).map_err(|e| format!("{name}: {e}"))?;
    let force: Vec<f64> = match friction {
        Some((fr, k)) => {
            let x = smooth(&rec.displacement_m, 8);
            let z = bouc_wen_path(&x, fr.yield_displacement_m, fr.shape, 0.0);
            (0..rec.len())
                .map(|i| rec.force_n[i] - fr.force_n * z[i] - k * rec.displacement_m[i])
                .collect()
        }
        None => rec.force_n.clone(),
    };
    let e = w
        .frf_instrumental(&rec.ref_acceleration_m_s2, &rec.acceleration_m_s2, &force)
        .map_err(|e| format!("{name}: {e}"))?;
    let idx = e.band(MASS_BAND_HZ[0], MASS_BAND_HZ[1]);
    if idx.len() < 5 {
        return Err(format!("{name}: too few bins in {MASS_BAND_HZ:?} Hz"));
    }
    let mut a = DMatrix::zeros(2 * idx.len(), 3);
    let mut b = DVector::zeros(2 * idx.len());
    for (r, &i) in idx.iter().enumerate() {
        let om = 2.0 * PI * e.frequency_hz[i];
        a[(2 * r, 0)] = 1.0;
        a[(2 * r, 2)] = -1.0 / (om * om);
        b[2 * r] = e.h1[i].re;
        a[(2 * r + 1, 1)] = -1.0 / om;
        b[2 * r + 1] = e.h1[i].im;
    }
    let (x, sigma) = lsq::linear(&a, &b).ok_or_else(|| format!("{name}: mass fit failed"))?;
    check_bounds(name, "mass (kg)", x[0], MASS_BOUNDS_KG)?;
    let low = e.band(1.0, 5.0);
    let plain = low.iter().map(|&i| e.h1[i].re).sum::<f64>() / low.len().max(1) as f64;
    Ok(MassFit {
        test: name.to_string(),
        mass_kg: x[0],
        sigma_mass_kg: sigma[0],
        viscous_n_s_m: x[1],
        stiffness_like_n_m: x[2],
        plain_average_kg: plain,
        measured: FrfData::from(&e.frequency_hz, &e.h1, &e.coherence, [0.5, 50.0]),
    })
}

/// Mean-removed steady part of a periodic test: samples after the first cycle and
/// before the last, where the amplitude has settled (ramps excluded).
fn steady_range(spec: &TestSpec, rec: &Record) -> std::ops::Range<usize> {
    let n = rec.len();
    let x = &rec.ref_displacement_m;
    let amp = spec
        .amplitude_m
        .unwrap_or_else(|| x.iter().fold(0.0, |m: f64, v| m.max(v.abs())));
    // first and last samples where the reference reaches 99 % of the amplitude
    let first = x.iter().position(|v| v.abs() >= 0.99 * amp).unwrap_or(0);
    let last = x.iter().rposition(|v| v.abs() >= 0.99 * amp).unwrap_or(n);
    first..last.max(first)
}

/// Zero-phase smoothing: a centred moving average of `2 h + 1` samples.
fn smooth(x: &[f64], h: usize) -> Vec<f64> {
    let n = x.len();
    let mut c = vec![0.0; n + 1];
    for i in 0..n {
        c[i + 1] = c[i] + x[i];
    }
    (0..n)
        .map(|i| {
            let lo = i.saturating_sub(h);
            let hi = (i + h + 1).min(n);
            (c[hi] - c[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// Central-difference derivative.
fn derivative(x: &[f64], fs: f64) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (x[b] - x[a]) * fs / (b - a).max(1) as f64
        })
        .collect()
}

/// Triangles (eqs. 4.9-4.10): away from reversals the acceleration is zero and
/// `F_A - M a = k x + F_mu sign(v)`; least squares over every triangle.
pub fn fit_triangles(c: &Campaign, mass_kg: f64) -> Result<TriangleFit, String> {
    let fs = c.info.sample_rate_hz;
    let (mut rows, mut rhs, mut names) = (Vec::new(), Vec::new(), Vec::new());
    let mut cycles = 0.0;
    for (spec, rec) in c.info.tests.iter().zip(&c.records) {
        if spec.kind != crate::campaign::TestKind::Triangle {
            continue;
        }
        names.push(spec.name.clone());
        let range = steady_range(spec, rec);
        cycles +=
            range.len() as f64 / fs * spec.frequency_hz.filter(|f| f.is_finite()).unwrap_or(0.0);
        let amp = spec.amplitude_m.unwrap_or(1.0);
        let xs = smooth(&rec.displacement_m, 8);
        let v = derivative(&xs, fs);
        for i in range {
            let x = rec.ref_displacement_m[i];
            if x.abs() < TRIANGLE_FRACTION * amp && v[i].abs() > 1e-4 {
                rows.push([rec.displacement_m[i], v[i].signum()]);
                rhs.push(rec.force_n[i] - mass_kg * rec.acceleration_m_s2[i]);
            }
        }
    }
    if names.is_empty() {
        return Err("no triangle test (T1-T6): stiffness and sliding friction not identified from triangles".into());
    }
    if cycles.is_nan() || cycles < MIN_TRIANGLE_CYCLES || rows.len() < 10 {
        return Err(format!(
            "the triangle tests ({}) hold {cycles:.2} steady cycles and {} samples away from reversals; at least {MIN_TRIANGLE_CYCLES} cycle and 10 samples needed: stiffness and sliding friction not identified",
            names.join(", "),
            rows.len()
        ));
    }
    let a = DMatrix::from_fn(rows.len(), 2, |i, j| rows[i][j]);
    let b = DVector::from_vec(rhs.clone());
    let (x, sigma) = lsq::linear(&a, &b).ok_or("triangle fit failed")?;
    let who = names.join(", ");
    check_bounds(&who, "stiffness (N/m)", x[0], [-1e12, 1e12])?;
    check_bounds(&who, "sliding friction (N)", x[1], [-1e9, 1e9])?;
    let step = (rows.len() / 1500).max(1);
    Ok(TriangleFit {
        tests: names,
        stiffness_n_m: x[0],
        sigma_stiffness_n_m: sigma[0],
        sliding_friction_n: x[1],
        displacement_m: rows.iter().step_by(step).map(|r| r[0]).collect(),
        elastic_force_n: rows
            .iter()
            .zip(&rhs)
            .step_by(step)
            .map(|(r, f)| f - x[1] * r[1])
            .collect(),
    })
}

/// Bouc-Wen `Z` along a displacement path (eq. 4.15 is rate independent:
/// `dZ = (1 - Z^2 (b + (1 - b) sign(Z dx))) dx / Y`), sub-stepped for accuracy.
pub fn bouc_wen_path(x: &[f64], yield_m: f64, shape: f64, z0: f64) -> Vec<f64> {
    let mut z = z0;
    let mut out = Vec::with_capacity(x.len());
    out.push(z);
    for i in 1..x.len() {
        let dx = x[i] - x[i - 1];
        let n = ((dx.abs() / (0.2 * yield_m)).ceil() as usize).clamp(1, 1000);
        let h = dx / n as f64;
        for _ in 0..n {
            let s = (z * h).signum();
            z += (1.0 - z * z * (shape + (1.0 - shape) * s)) * h / yield_m;
            z = z.clamp(-1.0, 1.0);
        }
        out.push(z);
    }
    out
}

/// The steady part of a sine test: smoothed displacement and its velocity, measured
/// acceleration and force.
struct SineData {
    name: String,
    x: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    f: Vec<f64>,
}

/// The sine tests `names` of `c` with at least [`MIN_SINE_CYCLES`] steady cycles; the
/// others are named in the second list with the reason.
fn sine_data(c: &Campaign, names: &[&str]) -> (Vec<SineData>, Vec<String>) {
    let fs = c.info.sample_rate_hz;
    let mut short = Vec::new();
    let data = names
        .iter()
        .filter_map(|n| c.test(n))
        .filter(|(s, _)| s.kind == crate::campaign::TestKind::Sine)
        .filter(|(spec, rec)| {
            let r = steady_range(spec, rec);
            let f = spec.frequency_hz.filter(|f| f.is_finite()).unwrap_or(0.0);
            let cycles = r.len() as f64 / fs * f;
            let ok = cycles >= MIN_SINE_CYCLES;
            if !ok {
                short.push(format!(
                    "{} ({}): {cycles:.2} steady cycles, at least {MIN_SINE_CYCLES} needed: not used",
                    spec.name, spec.file
                ));
            }
            ok
        })
        .map(|(spec, rec)| {
            let r = steady_range(spec, rec);
            let xs = smooth(&rec.displacement_m, 8);
            let v = derivative(&xs, fs);
            SineData {
                name: spec.name.clone(),
                x: xs[r.clone()].to_vec(),
                v: v[r.clone()].to_vec(),
                a: rec.acceleration_m_s2[r.clone()].to_vec(),
                f: rec.force_n[r].to_vec(),
            }
        })
        .collect();
    (data, short)
}

/// Bouc-Wen parameters (eqs. 4.14-4.15) fitted to `F_D = F_A - M a - k x` (eq. 4.13)
/// of the slow sines; `F_mu` enters linearly, `Y` and `b` by Levenberg-Marquardt.
pub fn fit_friction(
    c: &Campaign,
    mass_kg: f64,
    stiffness: f64,
    f_mu0: f64,
) -> Result<FrictionFit, String> {
    let slow = ["S1", "S2", "S4", "S5", "S7", "S8"];
    let (data, short) = sine_data(c, &slow);
    if data.is_empty() {
        return Err(format!(
            "no slow sine test (S1, S2, S4, S5, S7, S8) usable: Bouc-Wen friction not identified{}",
            short.iter().map(|s| format!("; {s}")).collect::<String>()
        ));
    }
    let fd: Vec<Vec<f64>> = data
        .iter()
        .map(|d| {
            (0..d.x.len())
                .map(|i| d.f[i] - mass_kg * d.a[i] - stiffness * d.x[i])
                .collect()
        })
        .collect();
    // decimate: the friction changes over Y, well resolved at 128 Hz
    let dec = 4;
    let residual = |p: &[f64]| -> Option<Vec<f64>> {
        let (fmu, y, b) = (p[0], p[1], p[2]);
        let mut r = Vec::new();
        for (d, fdi) in data.iter().zip(&fd) {
            let z = bouc_wen_path(&d.x, y, b, d.v[0].signum());
            for i in (0..z.len()).step_by(dec) {
                r.push(fmu * z[i] - fdi[i]);
            }
        }
        Some(r)
    };
    let f0 = if f_mu0.is_finite() && f_mu0 > 0.0 {
        f_mu0
    } else {
        1000.0
    };
    let (t0, scale) = ([f0, 1e-3, 0.5], [f0, 1e-3, 0.5]);
    let fit = minimise(
        residual,
        &t0,
        &[0.0, 1e-5, 0.0],
        &[1e7, 0.05, 0.999],
        &scale,
        LsqOptions::default(),
    )
    .ok_or("Bouc-Wen fit failed")?;
    let who = data
        .iter()
        .map(|d| d.name.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    check_moved(&who, "Bouc-Wen fit", &fit, &t0, &scale)?;
    let (fmu, y, b) = (fit.theta[0], fit.theta[1], fit.theta[2]);
    let d0 = &data[0];
    let z = bouc_wen_path(&d0.x, y, b, d0.v[0].signum());
    let step = (d0.x.len() / 2000).max(1);
    Ok(FrictionFit {
        tests: data.iter().map(|d| d.name.clone()).collect(),
        force_n: fmu,
        yield_displacement_m: y,
        shape: b,
        sigma_force_n: fit.sigma[0],
        rms_error_n: (fit.cost / fit.residuals as f64).sqrt(),
        displacement_m: d0.x.iter().step_by(step).copied().collect(),
        velocity_m_s: d0.v.iter().step_by(step).copied().collect(),
        dissipative_force_n: fd[0].iter().step_by(step).copied().collect(),
        fitted_force_n: z.iter().step_by(step).map(|z| fmu * z).collect(),
    })
}

/// Mass by the loop approach (eqs. 4.11-4.12) from S3, S6, S9: pairing `t` with `T/2 - t`
/// cancels the dissipative force; over whole steady cycles that is the least squares
/// `F_A - F_D - k x = M a` with the identified friction removed first.
pub fn fit_mass_periodic(
    c: &Campaign,
    stiffness: f64,
    friction: Option<&FrictionFit>,
) -> Result<PeriodicMassFit, String> {
    let (data, short) = sine_data(c, &["S3", "S6", "S9"]);
    if data.is_empty() {
        return Err(format!(
            "no fast sine test (S3, S6, S9) usable: mass not identified by the loop approach{}",
            short.iter().map(|s| format!("; {s}")).collect::<String>()
        ));
    }
    let mut per = Vec::new();
    let mut sig = Vec::new();
    for d in &data {
        let fd: Vec<f64> = match friction {
            Some(fr) => bouc_wen_path(&d.x, fr.yield_displacement_m, fr.shape, d.v[0].signum())
                .iter()
                .map(|z| fr.force_n * z)
                .collect(),
            None => vec![0.0; d.x.len()],
        };
        // F - F_D - k x = M a + c0 (offset)
        let a = DMatrix::from_fn(d.a.len(), 2, |i, j| if j == 0 { d.a[i] } else { 1.0 });
        let b = DVector::from_iterator(
            d.a.len(),
            (0..d.a.len()).map(|i| d.f[i] - fd[i] - stiffness * d.x[i]),
        );
        let (x, s) =
            lsq::linear(&a, &b).ok_or_else(|| format!("{}: loop-approach fit failed", d.name))?;
        check_bounds(
            &d.name,
            "mass by the loop approach (kg)",
            x[0],
            MASS_BOUNDS_KG,
        )?;
        per.push(x[0]);
        sig.push(s[0]);
    }
    let mass = per.iter().sum::<f64>() / per.len() as f64;
    let spread = if per.len() > 1 {
        (per.iter().map(|m| (m - mass).powi(2)).sum::<f64>()
            / (per.len() as f64 * (per.len() - 1) as f64))
            .sqrt()
    } else {
        sig[0]
    };
    let d0 = &data[0];
    let step = (d0.a.len() / 1500).max(1);
    Ok(PeriodicMassFit {
        tests: data.iter().map(|d| d.name.clone()).collect(),
        per_test_kg: per,
        mass_kg: mass,
        sigma_mass_kg: spread,
        acceleration_m_s2: d0.a.iter().step_by(step).copied().collect(),
        inertial_force_n: (0..d0.a.len())
            .step_by(step)
            .map(|i| d0.f[i] - stiffness * d0.x[i])
            .collect(),
    })
}

/// `F / x_v` of the ideal actuator on a table of apparent stiffness `Z(s) = M s^2 + c s + k`:
/// `g Kq A / ((A^2/k_oil) s + A^2 s / Z(s) + C_l)` (spec section 4).
fn spool_to_force_model(
    s: Complex64,
    kq_a: f64,
    area: f64,
    k_oil: f64,
    leak: f64,
    z: Complex64,
) -> Complex64 {
    kq_a / (area * area / k_oil * s + area * area * s / z + leak)
}

/// Oil column from R3 (4.1.3): `spool -> force` with the valve command as instrument,
/// fitted with the actuator model for `k_oil`, `C_l` and a flow-gain scale; the table's
/// `Z(s) = F/x` uses the final mass plus R3's own measured non-inertial part of the
/// apparent mass (the friction at R3's amplitude, bin by bin).
pub fn fit_oil_column(
    name: &str,
    rec: &Record,
    fs: f64,
    geometry: &crate::campaign::Geometry,
    mass_kg: f64,
) -> Result<OilColumnFit, String> {
    let x = spool(rec).ok_or_else(|| {
        format!("{name} has no spool_position channel: oil column not identified")
    })?;
    check_random_length(name, rec, fs, "oil-column fit")?;
    check_bounds(
        name,
        "mass used by the oil-column fit (kg)",
        mass_kg,
        MASS_BOUNDS_KG,
    )?;
    let w = welch_for(fs, rec.len()).map_err(|e| format!("{name}: {e}"))?;
    let iv = w
        .frf_instrumental(&rec.valve_command, x, &rec.force_n)
        .map_err(|e| format!("{name}: {e}"))?;
    let area = geometry.piston_area_m2;
    let kq_a = geometry.flow_gain_m3_s * area;
    // the table's own dissipative/elastic part at R3's amplitude, measured: the apparent
    // mass of R3 less its fitted mass (friction is amplitude dependent, so R2's would not do)
    let own = fit_mass(name, rec, fs)?;
    let apparent = w
        .frf_instrumental(
            &rec.ref_acceleration_m_s2,
            &rec.acceleration_m_s2,
            &rec.force_n,
        )
        .map_err(|e| format!("{name}: {e}"))?;
    let fit_on = |h: &[Complex64], e: &FrfEstimate| -> Option<(lsq::LsqFit, Vec<usize>)> {
        let idx = e.band(OIL_BAND_HZ[0], OIL_BAND_HZ[1]);
        let k0 = mass_kg * (2.0 * PI * 14.0f64).powi(2);
        let l0 = 1e-10;
        let resid = |p: &[f64]| -> Option<Vec<f64>> {
            let mut r = Vec::with_capacity(2 * idx.len());
            for &i in &idx {
                let s = Complex64::new(0.0, 2.0 * PI * e.frequency_hz[i]);
                // Z(s) = F/x = s^2 (M + (F/a - M_R3))
                let z = s * s * (mass_kg + apparent.h1[i] - own.mass_kg);
                let m = spool_to_force_model(s, p[2] * kq_a, area, p[0], p[1], z);
                let d = (m - h[i]) / h[i].norm().max(1e-9) * e.coherence[i].sqrt();
                r.push(d.re);
                r.push(d.im);
            }
            Some(r)
        };
        let (t0, scale) = ([k0, l0, 1.0], [k0, l0, 1.0]);
        minimise(
            resid,
            &t0,
            &[k0 * 0.05, 0.0, 0.1],
            &[k0 * 20.0, 1e-7, 10.0],
            &scale,
            LsqOptions::default(),
        )
        .filter(|f| f.moved_from(&t0, &scale))
        .map(|f| (f, idx))
    };
    let (fit, _) = fit_on(&iv.h1, &iv).ok_or_else(|| {
        format!("{name}: oil-column fit failed or did not move from its start values")
    })?;
    // H1 from the noisy spool, for the report's comparison
    let plain = w.frf(x, &rec.force_n).map_err(|e| format!("{name}: {e}"))?;
    let h1fit = fit_on(&plain.h1, &plain).map(|(f, _)| f);
    let figures = |k_oil: f64, leak: f64| {
        let beta = k_oil * geometry.total_oil_volume_m3 / (4.0 * area * area);
        let f = (k_oil / mass_kg).sqrt() / (2.0 * PI);
        let zeta = leak / area * (beta * mass_kg / geometry.total_oil_volume_m3).sqrt();
        (f, zeta, beta)
    };
    let (f_oil, zeta, beta) = figures(fit.theta[0], fit.theta[1]);
    check_bounds(
        name,
        "oil-column frequency (Hz)",
        f_oil,
        FREQUENCY_BOUNDS_HZ,
    )?;
    check_bounds(name, "oil-column damping ratio", zeta, DAMPING_BOUNDS)?;
    check_bounds(name, "bulk modulus (Pa)", beta, [1e6, 1e11])?;
    let (h1f, h1z) = h1fit
        .map(|f| {
            let (a, b, _) = figures(f.theta[0], f.theta[1]);
            (a, b)
        })
        .unwrap_or((f64::NAN, f64::NAN));
    let rel_k = fit.sigma[0] / fit.theta[0];
    Ok(OilColumnFit {
        test: name.to_string(),
        frequency_hz: f_oil,
        damping_ratio: zeta,
        bulk_modulus_pa: beta,
        leakage_m3_s_pa: fit.theta[1],
        stiffness_n_m: fit.theta[0],
        flow_gain_scale: fit.theta[2],
        sigma_frequency_hz: 0.5 * rel_k * f_oil,
        sigma_damping_ratio: zeta * (fit.sigma[1] / fit.theta[1].max(1e-300)).hypot(0.5 * rel_k),
        sigma_bulk_modulus_pa: rel_k * beta,
        h1_frequency_hz: h1f,
        h1_damping_ratio: h1z,
        measured: FrfData::from(&iv.frequency_hz, &iv.h1, &iv.coherence, [1.0, 60.0]),
        mass_used_kg: mass_kg,
    })
}

/// Measured table TF of a random test: reference acceleration -> table acceleration.
fn table_tf_of(rec: &Record, fs: f64) -> Result<FrfEstimate, String> {
    let w = welch_for(fs, rec.len()).map_err(|e| e.to_string())?;
    w.frf(&rec.ref_acceleration_m_s2, &rec.acceleration_m_s2)
        .map_err(|e| e.to_string())
}

/// Validation (section 5): the measured table TF of `name` against the identified
/// model's, analytic (ideal actuator) and simulated (nonlinear actuator).
pub fn validate(c: &Campaign, name: &str, params: &Params) -> Result<Validation, String> {
    let (spec, rec) = c
        .test(name)
        .ok_or_else(|| format!("no {name} test: validation skipped"))?;
    let fs = c.info.sample_rate_hz;
    let mut p = *params;
    p.controller = c.controller_for(spec);
    let meas = table_tf_of(rec, fs)?;
    let idx = meas.band(VALIDATION_BAND_HZ[0], VALIDATION_BAND_HZ[1]);
    let h: Vec<Complex64> = idx.iter().map(|&i| meas.h1[i]).collect();
    let f: Vec<f64> = idx.iter().map(|&i| meas.frequency_hz[i]).collect();
    let mut pi = p;
    pi.actuator.model = ActuatorModel::Ideal;
    let lin = Linearisation::new(&pi);
    let ideal: Vec<Complex64> = f.iter().map(|&x| lin.table_tf(x)).collect();
    let mut pn = p;
    pn.actuator.model = ActuatorModel::Nonlinear;
    let sim = simulate_record(
        &Model::new(&pn),
        &rec.inputs(),
        fs,
        None,
        DEFAULT_MAX_SUBSTEP_S,
    );
    let acc: Vec<f64> = sim.iter().map(|o| o.acceleration_m_s2).collect();
    let w = welch_for(fs, rec.len()).map_err(|e| e.to_string())?;
    let simf = w
        .frf(&rec.ref_acceleration_m_s2, &acc)
        .map_err(|e| e.to_string())?;
    let nonlinear: Vec<Complex64> = idx.iter().map(|&i| simf.h1[i]).collect();
    // the peak search runs over the validation band only (issue 14, item 9)
    let measured_figures = TfFigures::from_frf(&crate::linear::Frf {
        frequency_hz: f.clone(),
        response: h.clone(),
    });
    let model_figures = lin.table_tf_figures();
    let ones = vec![1.0; f.len()];
    Ok(Validation {
        test: name.to_string(),
        table_tf_error: relative_error(&ideal, &h),
        table_tf_error_nonlinear: relative_error(&nonlinear, &h),
        peak_hz: model_figures.map(|m| m.peak_hz).unwrap_or(f64::NAN),
        measured_figures,
        model_figures,
        measured: FrfData::from(
            &f,
            &h,
            &idx.iter().map(|&i| meas.coherence[i]).collect::<Vec<_>>(),
            [0.0, f64::MAX],
        ),
        ideal: FrfData::from(&f, &ideal, &ones, [0.0, f64::MAX]),
        nonlinear: FrfData::from(&f, &nonlinear, &ones, [0.0, f64::MAX]),
    })
}

/// Identify everything the campaign allows (paper section 4), in dependency order, after
/// screening every record ([`crate::campaign::screen`]).
pub fn identify(c: &Campaign) -> Identification {
    identify_screened(&screen(c))
}

/// Why test `name` is not available: absent, or excluded by the screening.
fn absent(s: &Screening, name: &str, what: &str) -> String {
    let why: Vec<String> = s
        .findings
        .iter()
        .filter(|f| f.test == name && f.action == Action::TestExcluded)
        .map(|f| f.to_string())
        .collect();
    if why.is_empty() {
        format!("no {name} test: {what}")
    } else {
        format!("{name} excluded by screening ({}): {what}", why.join("; "))
    }
}

/// `r` with the file of test `name` appended to its error.
fn in_file<T>(c: &Campaign, name: &str, r: Result<T, String>) -> Result<T, String> {
    let file = c
        .test(name)
        .map(|(s, _)| s.file.clone())
        .unwrap_or_default();
    r.map_err(|e| format!("{e} [file {file}]"))
}

/// [`identify`] on an already screened campaign.
pub fn identify_screened(s: &Screening) -> Identification {
    let c = &s.campaign;
    let fs = c.info.sample_rate_hz;
    let g = &c.info.geometry;
    let mut missing = Vec::new();
    let mut note = |r: Result<(), String>| {
        if let Err(e) = r {
            missing.push(e);
        }
    };
    // start from the defaults with the lab's geometry and controller; `defaults` lists
    // what stays a default and why
    let mut p = Params::trees_lab();
    p.actuator.piston_area_m2 = g.piston_area_m2;
    p.actuator.total_oil_volume_m3 = g.total_oil_volume_m3;
    p.actuator.supply_pressure_pa = g.supply_pressure_pa;
    p.actuator.flow_gain_m3_s = g.flow_gain_m3_s;
    p.controller = c.info.controller;

    let valve = match c.test("R1") {
        Some((_, r)) => in_file(c, "R1", fit_servovalve("R1", r, fs)),
        None => Err(absent(s, "R1", "servovalve not identified (defaults kept)")),
    };
    let valve = valve.map_err(|e| note(Err(e))).ok();
    if let Some(v) = &valve {
        p.servovalve.model = v.chosen;
        p.servovalve.gain = v.gain;
        p.servovalve.time_constant_s = v.time_constant_s;
        p.servovalve.natural_frequency_hz = v.natural_frequency_hz;
        p.servovalve.damping_ratio = v.damping_ratio;
    }
    let mass_random = match c.test("R2") {
        Some((_, r)) => in_file(c, "R2", fit_mass("R2", r, fs)),
        None => Err(absent(s, "R2", "mass not identified from random data")),
    };
    let mass_random = mass_random.map_err(|e| note(Err(e))).ok();
    let m0 = mass_random.as_ref().map(|m| m.mass_kg);
    let triangles = fit_triangles(c, m0.unwrap_or(p.table.mass_kg))
        .map_err(|e| note(Err(e)))
        .ok();
    let k = triangles.as_ref().map(|t| t.stiffness_n_m).unwrap_or(0.0);
    let f_mu0 = triangles
        .as_ref()
        .map(|t| t.sliding_friction_n)
        .unwrap_or(p.friction.force_n);
    let friction = match m0 {
        Some(m0) => fit_friction(c, m0, k, f_mu0),
        None => Err("Bouc-Wen friction not identified: it needs the mass from R2".into()),
    };
    let friction = friction.map_err(|e| note(Err(e))).ok();
    let mass_periodic = fit_mass_periodic(c, k, friction.as_ref())
        .map_err(|e| note(Err(e)))
        .ok();
    // refine the random-data mass with the friction removed in the time domain
    let mass_random = match (&mass_random, &friction, c.test("R2")) {
        (Some(_), Some(fr), Some((_, r))) => fit_mass_corrected("R2", r, fs, Some((fr, k)))
            .ok()
            .or(mass_random),
        _ => mass_random,
    };
    let mass_kg = final_mass(mass_random.as_ref(), mass_periodic.as_ref());
    if mass_kg.is_none() {
        note(Err(
            "no mass estimate: table.mass_kg is not identified (the parameter file keeps the default)"
                .into(),
        ));
    }
    p.table.mass_kg = mass_kg.unwrap_or(p.table.mass_kg);
    p.table.stiffness_n_m = k.max(0.0);
    if let Some(fr) = &friction {
        p.friction.force_n = fr.force_n;
        p.friction.yield_displacement_m = fr.yield_displacement_m;
        p.friction.shape = fr.shape.min(0.999);
    }
    let oil = match (c.test("R3"), mass_kg) {
        (Some((_, r)), Some(m)) => in_file(c, "R3", fit_oil_column("R3", r, fs, g, m)),
        (Some(_), None) => Err("oil column not identified: it needs the identified mass".into()),
        (None, _) => Err(absent(s, "R3", "oil column not identified")),
    };
    let oil = oil.map_err(|e| note(Err(e))).ok();
    if let Some(o) = &oil {
        p.actuator.bulk_modulus_pa = o.bulk_modulus_pa;
        p.actuator.leakage_m3_s_pa = o.leakage_m3_s_pa;
    }
    let validation_test = if c.test("R2").is_some() { "R2" } else { "R3" };
    let validation = if c.test(validation_test).is_some() {
        in_file(c, validation_test, validate(c, validation_test, &p))
    } else {
        Err("no R2 or R3 test usable: validation skipped".into())
    };
    let validation = validation.map_err(|e| note(Err(e))).ok();
    if let Some(v) = &validation {
        if v.table_tf_error_nonlinear < v.table_tf_error {
            p.actuator.model = ActuatorModel::Nonlinear;
        }
    }
    let welch = WelchOptions::for_resolution(fs, RESOLUTION_HZ);
    Identification {
        campaign: c.info.name.clone(),
        servovalve: valve,
        triangles,
        mass_random,
        friction,
        mass_periodic,
        oil_column: oil,
        validation,
        mass_kg,
        params: p,
        missing,
        screening: s.findings.clone(),
        welch,
    }
}

/// The final mass: inverse-variance mean of the random and periodic estimates, `None`
/// when neither exists.
fn final_mass(random: Option<&MassFit>, periodic: Option<&PeriodicMassFit>) -> Option<f64> {
    let mut num = 0.0;
    let mut den = 0.0;
    for (m, s) in [
        random.map(|m| (m.mass_kg, m.sigma_mass_kg)),
        periodic.map(|m| (m.mass_kg, m.sigma_mass_kg)),
    ]
    .into_iter()
    .flatten()
    {
        let s = if s.is_finite() { s } else { m.abs() };
        let w = 1.0 / s.max(1e-3 * m.abs()).powi(2);
        num += w * m;
        den += w;
    }
    Some(num / den).filter(|m| den > 0.0 && m.is_finite())
}

impl Identification {
    /// The JSON of issue 5 (nested objects, fixed keys) with an `uncertainty` object.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::{json, Map, Value};
        let nan = f64::NAN;
        let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
        let v = self.servovalve.as_ref();
        let o = self.oil_column.as_ref();
        let fr = self.friction.as_ref();
        let val = self.validation.as_ref();
        let p = &self.params;
        let mut out = json!({
            "servovalve": {
                "gain": num(v.map(|v| v.gain).unwrap_or(nan)),
                "time_constant_s": num(v.map(|v| v.time_constant_s).unwrap_or(nan)),
                "natural_frequency_hz": num(v.map(|v| v.natural_frequency_hz).unwrap_or(nan)),
                "damping_ratio": num(v.map(|v| v.damping_ratio).unwrap_or(nan)),
                "model": v.map(|v| v.chosen.name()).unwrap_or("unidentified"),
            },
            "table": {
                "mass_kg": num(self.mass_kg.unwrap_or(nan)),
                "mass_random_kg": num(self.mass_random.as_ref().map(|m| m.mass_kg).unwrap_or(nan)),
                "mass_periodic_kg": num(self.mass_periodic.as_ref().map(|m| m.mass_kg).unwrap_or(nan)),
                "stiffness_n_m": num(self.triangles.as_ref().map(|t| t.stiffness_n_m).unwrap_or(nan)),
            },
            "oil_column": {
                "frequency_hz": num(o.map(|o| o.frequency_hz).unwrap_or(nan)),
                "damping_ratio": num(o.map(|o| o.damping_ratio).unwrap_or(nan)),
                "bulk_modulus_pa": num(o.map(|o| o.bulk_modulus_pa).unwrap_or(nan)),
            },
            "friction": {
                "force_n": num(fr.map(|f| f.force_n).unwrap_or(nan)),
                "yield_displacement_m": num(fr.map(|f| f.yield_displacement_m).unwrap_or(nan)),
                "shape": num(fr.map(|f| f.shape).unwrap_or(nan)),
            },
            "validation": {
                "table_tf_error": num(val.map(|v| v.table_tf_error).unwrap_or(nan)),
                "table_tf_error_nonlinear": num(val.map(|v| v.table_tf_error_nonlinear).unwrap_or(nan)),
                "peak_hz": num(val.map(|v| v.peak_hz).unwrap_or(nan)),
                "measured_peak_hz": num(val.and_then(|v| v.measured_figures).map(|f| f.peak_hz).unwrap_or(nan)),
                "test": val.map(|v| v.test.clone()),
            },
            "actuator": { "model": p.actuator.model.name(), "leakage_m3_s_pa": num(o.map(|o| o.leakage_m3_s_pa).unwrap_or(nan)) },
            "missing": self.missing,
            "screening": self.screening,
            "defaults": self.defaults().into_iter().map(|(k, r)| json!({"key": k, "reason": r})).collect::<Vec<_>>(),
        });
        let mut unc = Map::new();
        let mut put = |block: &str, key: &str, x: Option<f64>| {
            if let Some(x) = x.filter(|x| x.is_finite()) {
                let e = unc.entry(block.to_string()).or_insert_with(|| json!({}));
                e[key] = json!(x);
            }
        };
        put(
            "servovalve",
            "natural_frequency_hz",
            v.map(|v| v.sigma_natural_frequency_hz),
        );
        put(
            "servovalve",
            "damping_ratio",
            v.map(|v| v.sigma_damping_ratio),
        );
        put(
            "servovalve",
            "time_constant_s",
            v.map(|v| v.sigma_time_constant_s),
        );
        put(
            "table",
            "mass_random_kg",
            self.mass_random.as_ref().map(|m| m.sigma_mass_kg),
        );
        put(
            "table",
            "mass_periodic_kg",
            self.mass_periodic.as_ref().map(|m| m.sigma_mass_kg),
        );
        put(
            "table",
            "stiffness_n_m",
            self.triangles.as_ref().map(|t| t.sigma_stiffness_n_m),
        );
        put(
            "oil_column",
            "frequency_hz",
            o.map(|o| o.sigma_frequency_hz),
        );
        put(
            "oil_column",
            "damping_ratio",
            o.map(|o| o.sigma_damping_ratio),
        );
        put(
            "oil_column",
            "bulk_modulus_pa",
            o.map(|o| o.sigma_bulk_modulus_pa),
        );
        put("friction", "force_n", fr.map(|f| f.sigma_force_n));
        out["uncertainty"] = Value::Object(unc);
        out
    }

    /// The parameter-file keys that hold a default, not an identified value, and why.
    pub fn defaults(&self) -> Vec<(&'static str, &'static str)> {
        let mut d = Vec::new();
        let mut add = |missing: bool, keys: &[&'static str], why: &'static str| {
            if missing {
                d.extend(keys.iter().map(|k| (*k, why)));
            }
        };
        add(
            self.servovalve.is_none(),
            &[
                "servovalve.gain",
                "servovalve.time_constant_s",
                "servovalve.natural_frequency_hz",
                "servovalve.damping_ratio",
            ],
            "servovalve not identified (see missing)",
        );
        add(
            self.mass_kg.is_none(),
            &["table.mass_kg"],
            "no mass estimate (see missing)",
        );
        add(
            self.triangles.is_none(),
            &["table.stiffness_n_m"],
            "no triangle estimate: zero stiffness assumed",
        );
        add(
            self.friction.is_none(),
            &[
                "friction.force_n",
                "friction.yield_displacement_m",
                "friction.shape",
            ],
            "Bouc-Wen friction not identified (see missing)",
        );
        add(
            self.oil_column.is_none(),
            &["actuator.bulk_modulus_pa", "actuator.leakage_m3_s_pa"],
            "oil column not identified (see missing)",
        );
        d
    }

    /// Oil-column figures of the identified parameters.
    pub fn oil_column_of_params(&self) -> OilColumn {
        OilColumn::of(&self.params)
    }
}

//! A device between actuator and reaction (a damper, a hysteretic specimen) from any test
//! that records displacement and force, of any kind: the Bouc-Wen force of the payload
//! friction (spec section 5; paper eqs. 4.14-4.15) plus a viscous term, a stiffness, an
//! inertia and the load cell's zero,
//! `F = F_mu Z(x) + c v + k x + m a + F_0`,
//! fitted by Levenberg-Marquardt ([`lsq::minimise`]) on one test and checked on every
//! other (force-fit NRMSE and fit %). `m a` is the rod's (or the table's) inertia: the
//! measured acceleration when there is one, else the displacement's second derivative.
//! Velocity and acceleration come from the displacement by a zero-phase spectral
//! derivative, band-limited where the displacement has its content ([`Kinematics`]).

use super::error::IdentifyError;
use super::friction::bouc_wen_path;
use super::lsq::{self, minimise, LsqOptions};
use super::results::{DeviceFit, DeviceTestFit};
use super::select::DeviceRoles;
use super::signals::correlation_factor;
use super::{check_bounds, check_moved, MASS_BOUNDS_KG};
use crate::campaign::{Campaign, Measured, Record};
use nalgebra::{DMatrix, DVector};
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use std::f64::consts::PI;

/// Share of the displacement's power (mean removed) below the pass-band corner: the
/// derivatives keep everything the motion holds and drop the sensor noise above it
/// (white noise differentiated grows with frequency).
pub const DEVICE_POWER_SHARE: f64 = 0.999;
/// Margin from the frequency holding [`DEVICE_POWER_SHARE`] to the corner, and from the
/// corner to the end of the cosine roll-off: a few percent of the power lies above the
/// share's frequency in velocity and acceleration (they weigh it by `w` and `w^2`).
pub const DEVICE_CORNER_MARGIN: f64 = 2.0;
/// Fewest samples for a device fit: seven parameters and a few cycles of motion.
pub const DEVICE_MIN_SAMPLES: usize = 200;
/// Start values of the yield displacement tried, as fractions of the displacement's RMS
/// (the best by linear least squares on the other five parameters starts the fit): a
/// friction slides within a small fraction of the stroke, a soft hysteretic device
/// yields within a good part of it.
pub const DEVICE_YIELD_STARTS: [f64; 5] = [0.003, 0.01, 0.03, 0.1, 0.3];
/// Smallest yield displacement fitted, as a fraction of the RMS displacement step between
/// samples: a hysteresis that closes within a fraction of one sample's motion is not
/// resolved by the record (and would cost the Bouc-Wen path hundreds of sub-steps per
/// sample).
pub const DEVICE_YIELD_RESOLUTION: f64 = 0.2;
/// Bouc-Wen shape constant of the start values (the middle of its range [0, 1)).
const SHAPE_START: f64 = 0.5;
/// Points of a hysteresis loop kept for the report (a window around the peak stroke).
const LOOP_POINTS: usize = 3000;

/// Displacement, velocity and acceleration of one test, band-limited alike, with the
/// measured force.
pub(super) struct Kinematics {
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub f: Vec<f64>,
    pub corner_hz: f64,
    pub measured_acceleration: bool,
}

/// The real spectrum of the even extension `x, reversed x` (no jump at the ends).
fn even_spectrum(x: &[f64]) -> Vec<Complex<f64>> {
    let m = 2 * x.len();
    let fwd = RealFftPlanner::<f64>::new().plan_fft_forward(m);
    let mut ext: Vec<f64> = x.iter().chain(x.iter().rev()).copied().collect();
    let mut spec = fwd.make_output_vec();
    // lengths match the plan: cannot fail
    let _ = fwd.process(&mut ext, &mut spec);
    spec
}

/// The pass-band corner: [`DEVICE_CORNER_MARGIN`] times the frequency below which the
/// displacement holds [`DEVICE_POWER_SHARE`] of its power; `None` for a flat record.
fn corner_hz(spec: &[Complex<f64>], df: f64) -> Option<f64> {
    let total: f64 = spec.iter().skip(1).map(|c| c.norm_sqr()).sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut acc = 0.0;
    let k = spec.iter().skip(1).position(|c| {
        acc += c.norm_sqr();
        acc >= DEVICE_POWER_SHARE * total
    })?;
    Some(DEVICE_CORNER_MARGIN * (k + 1) as f64 * df)
}

/// The derivatives of order 0, 1, 2 of `x` in the frequency domain (zero phase), flat to
/// `corner` and rolled off by a cosine to `DEVICE_CORNER_MARGIN * corner`.
fn band_limited(x: &[f64], fs: f64) -> Option<(f64, [Vec<f64>; 3])> {
    let n = x.len();
    let m = 2 * n;
    let spec = even_spectrum(x);
    let df = fs / m as f64;
    let corner = corner_hz(&spec, df)?.min(0.5 * fs);
    let top = DEVICE_CORNER_MARGIN * corner;
    let inv = RealFftPlanner::<f64>::new().plan_fft_inverse(m);
    let last = spec.len() - 1;
    let derivative = |order: i32| -> Vec<f64> {
        let mut s: Vec<Complex<f64>> = spec
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let f = k as f64 * df;
                let w = match f {
                    f if f <= corner => 1.0,
                    f if f >= top => 0.0,
                    f => 0.5 * (1.0 + (PI * (f - corner) / (top - corner)).cos()),
                };
                // the DC bin of a derivative and the odd derivative at Nyquist vanish
                let zero = order > 0 && (k == 0 || (k == last && order % 2 != 0));
                match zero {
                    true => Complex::new(0.0, 0.0),
                    false => *c * Complex::new(0.0, 2.0 * PI * f).powi(order) * (w / m as f64),
                }
            })
            .collect();
        let mut out = inv.make_output_vec();
        let _ = inv.process(&mut s, &mut out);
        out.truncate(n);
        out
    };
    Some((corner, [derivative(0), derivative(1), derivative(2)]))
}

impl Kinematics {
    /// The kinematics of test `name` (`rec` at `fs`), or the error naming what is missing.
    pub(super) fn of(name: &str, rec: &Record, fs: f64) -> Result<Kinematics, IdentifyError> {
        const WITHOUT: &str = "device force not identified from this test";
        let x = super::signals::channel(name, rec, Measured::Displacement, WITHOUT)?;
        let f = super::signals::channel(name, rec, Measured::Force, WITHOUT)?;
        if x.len() < DEVICE_MIN_SAMPLES {
            return Err(IdentifyError::failed(
                name,
                format!(
                    "{} samples, the device fit needs at least {DEVICE_MIN_SAMPLES}",
                    x.len()
                ),
            ));
        }
        let (corner_hz, [xf, v, a2]) = band_limited(x, fs)
            .ok_or_else(|| IdentifyError::failed(name, "displacement_m does not move"))?;
        let measured = rec.measured(Measured::Acceleration);
        Ok(Kinematics {
            x: xf,
            v,
            a: measured.map_or(a2, <[f64]>::to_vec),
            f: f.to_vec(),
            corner_hz,
            measured_acceleration: measured.is_some(),
        })
    }

    /// The modelled force of parameters `p` = `[F_mu, Y, b, c, k, m, F_0]` (eqs. 4.14-4.15
    /// from rest at the record's start, plus the linear terms).
    pub(super) fn model(&self, p: &[f64]) -> Vec<f64> {
        let z = bouc_wen_path(&self.x, p[1], p[2], 0.0);
        (0..self.x.len())
            .map(|i| p[0] * z[i] + p[3] * self.v[i] + p[4] * self.x[i] + p[5] * self.a[i] + p[6])
            .collect()
    }

    /// Net work of the force on the motion, J: a device from rest to rest dissipates, so
    /// it is positive in the project's convention (force on the device along its motion).
    fn work_j(&self, fs: f64) -> f64 {
        self.f.iter().zip(&self.v).map(|(f, v)| f * v).sum::<f64>() / fs
    }
}

fn rms_about_mean(x: &[f64]) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
    (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// Linear least squares of `[F_mu, c, k, m, F_0]` for a given `Y`, `b`: the start of the
/// nonlinear fit and its cost.
fn linear_start(k: &Kinematics, yield_m: f64) -> Option<(Vec<f64>, f64)> {
    let z = bouc_wen_path(&k.x, yield_m, SHAPE_START, 0.0);
    let n = k.x.len();
    let cols: [&[f64]; 4] = [&z, &k.v, &k.x, &k.a];
    let a = DMatrix::from_fn(n, 5, |i, j| if j < 4 { cols[j][i] } else { 1.0 });
    let b = DVector::from_column_slice(&k.f);
    let (x, _) = lsq::linear(&a, &b)?;
    let cost = (&a * &x - &b).norm_squared();
    Some((
        vec![x[0], yield_m, SHAPE_START, x[1], x[2], x[3], x[4]],
        cost,
    ))
}

/// Force-fit NRMSE of `model` against `k.f`: `RMS(meas - model) / RMS(meas - mean)`.
fn nrmse(k: &Kinematics, model: &[f64]) -> f64 {
    let e: Vec<f64> = k.f.iter().zip(model).map(|(f, m)| f - m).collect();
    let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len().max(1) as f64).sqrt();
    rms / rms_about_mean(&k.f)
}

/// The fit of `p` on test `name`: NRMSE, fit %, and a window of the loop around the
/// peak stroke for the report. With `refit_zero` the load cell's zero is re-estimated
/// (the mean residual): it drifts between runs and is no property of the device.
fn test_fit(name: &str, k: &Kinematics, p: &[f64], refit_zero: bool) -> DeviceTestFit {
    let mut model = k.model(p);
    let mut offset = p[6];
    if refit_zero {
        let shift = k.f.iter().zip(&model).map(|(f, m)| f - m).sum::<f64>() / k.f.len() as f64;
        model.iter_mut().for_each(|m| *m += shift);
        offset += shift;
    }
    let e = nrmse(k, &model);
    let peak = (0..k.x.len())
        .max_by(|&i, &j| k.x[i].abs().total_cmp(&k.x[j].abs()))
        .unwrap_or(0);
    let lo = peak.saturating_sub(LOOP_POINTS / 2);
    let hi = (lo + LOOP_POINTS).min(k.x.len());
    DeviceTestFit {
        test: name.to_string(),
        nrmse: e,
        fit_percent: 100.0 * (1.0 - e),
        offset_n: offset,
        displacement_m: k.x[lo..hi].to_vec(),
        measured_force_n: k.f[lo..hi].to_vec(),
        model_force_n: model[lo..hi].to_vec(),
    }
}

/// The fit's start (the best of [`DEVICE_YIELD_STARTS`] with the linear parameters by
/// least squares), bounds (a dissipating friction and damper, `Y` resolved by the
/// sampling ([`DEVICE_YIELD_RESOLUTION`]), `b` in the parameter file's `[0, 1)`, a mass
/// within [`MASS_BOUNDS_KG`]) and scales, in the order
/// `F_mu, Y, b, c, k, m, F_0`.
#[allow(clippy::type_complexity)]
fn problem(k: &Kinematics) -> Option<(Vec<f64>, [f64; 7], [f64; 7], [f64; 7])> {
    let (f_rms, x_rms) = (rms_about_mean(&k.f), rms_about_mean(&k.x));
    let scaled = |s: f64| {
        if s > 0.0 && s.is_finite() {
            f_rms / s
        } else {
            f_rms
        }
    };
    let steps: Vec<f64> = k.x.windows(2).map(|w| w[1] - w[0]).collect();
    let y_min = (DEVICE_YIELD_RESOLUTION * rms_about_mean(&steps)).max(1e-6);
    let t0 = DEVICE_YIELD_STARTS
        .iter()
        .filter_map(|r| linear_start(k, (r * x_rms).max(y_min)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(t, _)| t)?;
    let lower = [0.0, y_min, 0.0, 0.0, -1e12, 0.0, -1e9];
    let upper = [
        1e9,
        (10.0 * x_rms).max(2.0 * y_min),
        0.999,
        1e9,
        1e12,
        MASS_BOUNDS_KG[1],
        1e9,
    ];
    let t0: Vec<f64> = (0..7).map(|i| t0[i].clamp(lower[i], upper[i])).collect();
    let scale = [
        f_rms,
        t0[1],
        0.5,
        scaled(rms_about_mean(&k.v)),
        scaled(x_rms),
        scaled(rms_about_mean(&k.a)),
        f_rms,
    ];
    Some((t0, lower, upper, scale))
}

/// The device fit on the tests of `roles` ([`super::select::device_roles`]): the model
/// of the module doc fitted on `roles.fit`, checked on `roles.others`.
pub fn fit_device(c: &Campaign, roles: &DeviceRoles) -> Result<DeviceFit, IdentifyError> {
    let fs = c.sample_rate_of(roles.fit);
    let (spec, rec) = (&c.info.tests[roles.fit], &c.records[roles.fit]);
    let name = spec.name.as_str();
    let k = Kinematics::of(name, rec, fs)?;
    check_dissipates(name, &k, fs)?;
    let fit = fit_force(name, &k)?;
    let p = &fit.theta;
    check_bounds(name, "device mass (kg)", p[5], [0.0, MASS_BOUNDS_KG[1]])?;
    let r: Vec<f64> = k.model(p).iter().zip(&k.f).map(|(m, f)| m - f).collect();
    // a tenth of the record at most: the loop's own period stays out of the sum
    let inflate = correlation_factor(&r, r.len() / 10).sqrt();
    let sigma: Vec<f64> = fit.sigma.iter().map(|s| s * inflate).collect();
    let others = roles
        .others
        .iter()
        .map(|&i| {
            let n = c.info.tests[i].name.as_str();
            Kinematics::of(n, &c.records[i], c.sample_rate_of(i))
                .map(|ko| test_fit(n, &ko, p, true))
        })
        .collect::<Vec<_>>();
    Ok(DeviceFit {
        test: name.to_string(),
        force_n: p[0],
        yield_displacement_m: p[1],
        shape: p[2],
        viscous_n_s_m: p[3],
        stiffness_n_m: p[4],
        mass_kg: p[5],
        offset_n: p[6],
        sigma,
        sigma_correlation_factor: inflate * inflate,
        corner_hz: k.corner_hz,
        measured_acceleration: k.measured_acceleration,
        fit: test_fit(name, &k, p, false),
        validation: others
            .iter()
            .filter_map(|r| r.as_ref().ok().cloned())
            .collect(),
        not_validated: others
            .iter()
            .filter_map(|r| r.as_ref().err().map(|e| e.to_string()))
            .collect(),
    })
}

/// `Err` unless the recorded force of test `name` does net negative work on the motion
/// `k` (at `fs`): a device dissipates, so a force doing work has the opposite sign of
/// the project's convention.
fn check_dissipates(name: &str, k: &Kinematics, fs: f64) -> Result<(), IdentifyError> {
    if k.work_j(fs) > 0.0 || k.work_j(fs).is_nan() {
        return Ok(());
    }
    Err(IdentifyError::failed(
        name,
        format!(
            "force_n does net work {:.4e} J on the motion: a device dissipates, so the recorded force has the \
             opposite sign of the project's convention (force on the device along its motion; a negative \
             `scale` in [columns] turns it): device force not identified",
            -k.work_j(fs)
        ),
    ))
}

/// Levenberg-Marquardt of the device model on the force of test `name` (motion `k`)
/// from its linear start ([`problem`]).
fn fit_force(name: &str, k: &Kinematics) -> Result<lsq::LsqFit, IdentifyError> {
    let (t0, lower, upper, scale) =
        problem(k).ok_or_else(|| IdentifyError::failed(name, "device start fit failed"))?;
    let residual = |p: &[f64]| -> Option<Vec<f64>> {
        Some(k.model(p).iter().zip(&k.f).map(|(m, f)| m - f).collect())
    };
    // each Jacobian column is a Bouc-Wen path over the whole record: in parallel
    let opts = LsqOptions {
        parallel: true,
        ..LsqOptions::default()
    };
    let fit = minimise(residual, &t0, &lower, &upper, &scale, opts)
        .ok_or_else(|| IdentifyError::failed(name, "device fit failed"))?;
    check_moved(name, "device fit", &fit, &t0, &scale)?;
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record of displacement `x` and force `f` at `fs`.
    fn record(x: Vec<f64>, f: Vec<f64>, fs: f64) -> Record {
        let n = x.len();
        Record {
            time_s: (0..n).map(|i| i as f64 / fs).collect(),
            ref_displacement_m: x.clone(),
            ref_velocity_m_s: vec![0.0; n],
            ref_acceleration_m_s2: vec![0.0; n],
            displacement_m: Some(x),
            force_n: Some(f),
            ..Record::default()
        }
    }

    /// A campaign of `records` named T0, T1, ... at `fs`.
    fn campaign(records: Vec<Record>, fs: f64) -> Campaign {
        use crate::campaign::{CampaignInfo, ControllerOverride, Geometry, TestSpec};
        let tests = (0..records.len())
            .map(|i| TestSpec::record(format!("T{i}"), format!("T{i}.csv")))
            .collect();
        Campaign {
            dir: Default::default(),
            sources: Default::default(),
            info: CampaignInfo {
                name: "device".into(),
                sample_rate_hz: fs,
                geometry: Geometry::default(),
                controller: ControllerOverride::default(),
                tests,
            },
            records,
        }
    }

    /// A smooth multi-sine stroke from rest (a few mm, 0.5-8 Hz).
    fn stroke(fs: f64, secs: f64) -> Vec<f64> {
        let n = (fs * secs) as usize;
        (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                let env = (PI * t / secs).sin().powi(2);
                env * (4e-3 * (2.0 * PI * 0.7 * t).sin()
                    + 2e-3 * (2.0 * PI * 3.1 * t + 1.0).sin()
                    + 1e-3 * (2.0 * PI * 7.3 * t + 2.0).sin())
            })
            .collect()
    }

    #[test]
    fn recovers_a_bouc_wen_damper_and_checks_it_on_another_stroke() {
        let fs = 1000.0;
        let truth = [800.0, 5e-4, 0.3, 2000.0, 5e4, 3.0, -120.0];
        let make = |secs: f64| {
            let x = stroke(fs, secs);
            let (_, [xf, v, a]) = band_limited(&x, fs).unwrap();
            let k = Kinematics {
                x: xf,
                v,
                a,
                f: vec![0.0; x.len()],
                corner_hz: 0.0,
                measured_acceleration: false,
            };
            let f = k.model(&truth);
            record(x, f, fs)
        };
        let c = campaign(vec![make(20.0), make(13.0)], fs);
        let d = fit_device(
            &c,
            &DeviceRoles {
                fit: 0,
                others: vec![1],
            },
        )
        .unwrap();
        let got = [
            d.force_n,
            d.yield_displacement_m,
            d.shape,
            d.viscous_n_s_m,
            d.stiffness_n_m,
        ];
        for (g, t) in got.iter().zip(&truth) {
            assert!((g / t - 1.0).abs() < 0.02, "{got:?} vs {truth:?}");
        }
        assert!(d.fit.fit_percent > 99.0, "{}", d.fit.fit_percent);
        assert!(
            d.validation[0].fit_percent > 99.0,
            "{}",
            d.validation[0].fit_percent
        );
    }

    #[test]
    fn a_force_of_the_opposite_sign_or_a_still_record_is_named() {
        let fs = 1000.0;
        let x = stroke(fs, 5.0);
        let (_, [_, v, _]) = band_limited(&x, fs).unwrap();
        let f: Vec<f64> = v.iter().map(|v| -1e3 * v).collect();
        let mut c = campaign(vec![record(x, f, fs)], fs);
        let e = fit_device(
            &c,
            &DeviceRoles {
                fit: 0,
                others: vec![],
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("opposite sign"), "{e}");
        c.records[0] = record(vec![0.0; 1000], vec![1.0; 1000], fs);
        let e = fit_device(
            &c,
            &DeviceRoles {
                fit: 0,
                others: vec![],
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("does not move"), "{e}");
    }
}

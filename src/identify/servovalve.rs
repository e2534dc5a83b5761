//! The servovalve from the valve test's command-to-spool FRF (paper 4.1.1, eqs. 4.1-4.2).

use super::error::IdentifyError;
use super::lsq::{minimise, LsqOptions};
use super::results::{FrfData, ServovalveFit};
use super::signals::{channel, spool_channel, welch_for};
use super::{
    check_bounds, check_moved, check_random_length, DAMPING_BOUNDS, FREQUENCY_BOUNDS_HZ,
    VALVE_BAND_HZ,
};
use crate::campaign::{Measured, Record};
use crate::linear::ValveTf;
use crate::params::ServovalveModel;
use num_complex::Complex64;
use std::f64::consts::PI;

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
pub fn fit_servovalve(name: &str, rec: &Record, fs: f64) -> Result<ServovalveFit, IdentifyError> {
    let x = spool_channel(rec).ok_or_else(|| IdentifyError::MissingChannel {
        test: name.to_string(),
        channel: "spool_position",
        consequence: "servovalve not identified",
    })?;
    let u = channel(
        name,
        rec,
        Measured::ValveCommand,
        "servovalve not identified",
    )?;
    check_random_length(name, rec, fs, "servovalve fit")?;
    let w = welch_for(fs, rec.len()).map_err(|e| IdentifyError::failed(name, e))?;
    let e = w.frf(u, x).map_err(|e| IdentifyError::failed(name, e))?;
    let idx = e.band(VALVE_BAND_HZ[0], VALVE_BAND_HZ[1]);
    if idx.len() < 10 {
        return Err(IdentifyError::failed(
            name,
            format!("too few frequency bins in {VALVE_BAND_HZ:?} Hz"),
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
        |p| {
            let valve = ValveTf::first_order(p[0], p[1]);
            Some(resid(&|s| valve.response(s)))
        },
        &t1,
        &[0.05, 1e-4],
        &[20.0, 1.0],
        &s1,
        opts,
    )
    .ok_or_else(|| IdentifyError::failed(name, "first-order valve fit failed"))?;
    check_moved(name, "first-order valve fit", &first, &t1, &s1)?;
    // eq. 4.2: Ks w^2 / (s^2 + 2 xi w s + w^2), from the first-order guess
    let w0 = 1.0 / first.theta[1];
    let t2 = [first.theta[0], 1.5 * w0 / (2.0 * PI), 1.0];
    let second = minimise(
        |p| {
            let valve = ValveTf::second_order(p[0], p[1], p[2]);
            Some(resid(&|s| valve.response(s)))
        },
        &t2,
        &[0.05, 0.5, 0.05],
        &[20.0, 500.0, 5.0],
        &[1.0, 10.0, 1.0],
        opts,
    )
    .ok_or_else(|| IdentifyError::failed(name, "second-order valve fit failed"))?;
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
    let (first_tf, second_tf) = (
        ValveTf::first_order(k1, tau),
        ValveTf::second_order(k2, fv, xi),
    );
    let first_err = err_of(&|s| first_tf.response(s));
    let second_err = err_of(&|s| second_tf.response(s));
    let mut valid_to = f[0];
    for k in 0..f.len() {
        let s = Complex64::new(0.0, 2.0 * PI * f[k]);
        let dp = (first_tf.response(s) / h[k]).arg().to_degrees().abs();
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

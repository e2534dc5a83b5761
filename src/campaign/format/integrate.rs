//! The reference velocity and displacement of an acceleration-controlled test computed
//! from its recorded reference acceleration (campaign-format.md, "What is required").
//!
//! Integrating twice amplifies whatever the sampled acceleration says below the test's
//! band: a reference that steps (a raised-cosine fade starts with a jump in acceleration)
//! integrates with an error of about half a sample times the step, a constant velocity
//! error that drifts the displacement by millimetres over a 30-s test (8 mm end to end,
//! 2.6 mm RMS, on a 5.7-mm RMS reference measured on the paper's R2). A test that starts
//! and ends at rest pins that drift: the displacement is constant over both rest segments
//! and the same at both, so the baseline is corrected by the lowest-order line through
//! them (a constant velocity error over the motion), as strong-motion records are
//! baseline-corrected.

use super::layout::spectral;
use crate::campaign::line_fit;

/// A reference at rest has an acceleration below this share of its peak: a command written
/// by the controller is exactly zero at rest, one recorded through an ADC carries its
/// quantisation and noise, some 1e-4 of full scale.
const REST_SHARE_OF_PEAK: f64 = 1e-3;
/// A rest segment is at least this long, s: long enough to fit its level and slope, and
/// longer than a random reference lingers near zero while moving.
const MIN_REST_S: f64 = 0.1;

/// Velocity and displacement of the acceleration `a` sampled at `fs` Hz: the frequency-
/// domain integrals, baseline-corrected to rest where the record starts and ends at
/// rest; otherwise the plain integrals without their mean (nothing pins their drift).
pub fn velocity_and_displacement(a: &[f64], fs: f64) -> (Vec<f64>, Vec<f64>) {
    let Some((first, last)) = rest_segments(a, fs) else {
        return (spectral(a, fs, -1), spectral(a, fs, -2));
    };
    // the spectral integrals drop the mean acceleration; put its integrals back so that
    // the rest segments keep their true (constant) shape
    let n = a.len();
    let mean = a.iter().sum::<f64>() / n as f64;
    let t: Vec<f64> = (0..n).map(|k| k as f64 / fs).collect();
    let v = spectral(a, fs, -1)
        .into_iter()
        .zip(&t)
        .map(|(v, t)| v + mean * t);
    let x = spectral(a, fs, -2)
        .into_iter()
        .zip(&t)
        .map(|(x, t)| x + 0.5 * mean * t * t);
    let x: Vec<f64> = x.collect();
    let baseline = Baseline::through_rests(&t, &x, first, last);
    let v = v.zip(&t).map(|(v, t)| v - baseline.slope_at(*t)).collect();
    let x = x
        .iter()
        .zip(&t)
        .map(|(x, t)| x - baseline.value_at(*t))
        .collect();
    (v, x)
}

/// The leading and trailing rest segments' sample ranges `[0, first)` and `[last, n)`,
/// when both are at least [`MIN_REST_S`] long.
fn rest_segments(a: &[f64], fs: f64) -> Option<(usize, usize)> {
    let peak = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if peak <= 0.0 || !peak.is_finite() {
        return None;
    }
    let at_rest = |v: &f64| v.abs() <= REST_SHARE_OF_PEAK * peak;
    let first = a.iter().take_while(|v| at_rest(v)).count();
    let last = a.len() - a.iter().rev().take_while(|v| at_rest(v)).count();
    let min = ((MIN_REST_S * fs).ceil() as usize).max(2);
    (first >= min && a.len() - last >= min && first < last).then_some((first, last))
}

/// A piecewise-linear baseline: `(start time, intercept, slope)` pieces in time order.
struct Baseline(Vec<(f64, f64, f64)>);

impl Baseline {
    /// The line fitted to each rest segment there, and the chord joining them over the
    /// motion (a constant velocity error between the two rests).
    fn through_rests(t: &[f64], x: &[f64], first: usize, last: usize) -> Baseline {
        let (c0, s0) = line_fit(&t[..first], &x[..first]);
        let (c1, s1) = line_fit(&t[last..], &x[last..]);
        let (t0, t1) = (t[first - 1], t[last]);
        let (y0, y1) = (c0 + s0 * t0, c1 + s1 * t1);
        Baseline(vec![
            (f64::NEG_INFINITY, c0, s0),
            (t0, y0 - (y1 - y0) / (t1 - t0) * t0, (y1 - y0) / (t1 - t0)),
            (t1, c1, s1),
        ])
    }

    fn piece(&self, t: f64) -> (f64, f64) {
        let p = self.0.iter().rev().find(|p| t >= p.0).unwrap_or(&self.0[0]);
        (p.1, p.2)
    }

    fn value_at(&self, t: f64) -> f64 {
        let (c, s) = self.piece(t);
        c + s * t
    }

    fn slope_at(&self, t: f64) -> f64 {
        self.piece(t).1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A reference from rest to rest whose acceleration steps where its fade starts and
    /// ends (the synthesis' raised-cosine fade of a band-limited signal).
    fn faded(fs: f64) -> (Vec<f64>, Vec<f64>) {
        let (rest, moving) = (1.0, 20.0);
        let fade = 0.5;
        let n = ((2.0 * rest + moving) * fs) as usize;
        let w = |tau: f64| match tau {
            t if t <= 0.0 || t >= moving => (0.0, 0.0, 0.0),
            t if t < fade => {
                let k = PI / fade;
                (
                    (1.0 - (k * t).cos()) / 2.0,
                    k * (k * t).sin() / 2.0,
                    k * k * (k * t).cos() / 2.0,
                )
            }
            t if t > moving - fade => {
                let k = PI / fade;
                let u = moving - t;
                (
                    (1.0 - (k * u).cos()) / 2.0,
                    -k * (k * u).sin() / 2.0,
                    k * k * (k * u).cos() / 2.0,
                )
            }
            _ => (1.0, 0.0, 0.0),
        };
        let s = |t: f64| {
            let (f1, f2) = (2.0 * PI * 0.7, 2.0 * PI * 3.1);
            (
                0.01 * (f1 * t + 0.3).sin() + 0.004 * (f2 * t + 1.0).sin(),
                0.01 * f1 * (f1 * t + 0.3).cos() + 0.004 * f2 * (f2 * t + 1.0).cos(),
                -0.01 * f1 * f1 * (f1 * t + 0.3).sin() - 0.004 * f2 * f2 * (f2 * t + 1.0).sin(),
            )
        };
        let (mut x, mut a) = (vec![0.0; n], vec![0.0; n]);
        for k in 0..n {
            let tau = k as f64 / fs - rest;
            let ((w0, w1, w2), (s0, s1, s2)) = (w(tau), s(tau));
            x[k] = s0 * w0;
            a[k] = s2 * w0 + 2.0 * s1 * w1 + s0 * w2;
        }
        (x, a)
    }

    fn rms(v: &[f64]) -> f64 {
        (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
    }

    #[test]
    fn a_reference_from_rest_to_rest_integrates_without_drift() {
        for fs in [200.0, 512.0, 1000.0] {
            let (x, a) = faded(fs);
            let (_, got) = velocity_and_displacement(&a, fs);
            let err: Vec<f64> = got.iter().zip(&x).map(|(g, x)| g - x).collect();
            // the plain spectral double integral drifts by several % of the RMS here
            let plain = spectral(&a, fs, -2);
            let mean = plain.iter().zip(&x).map(|(p, x)| p - x).sum::<f64>() / x.len() as f64;
            let plain_err: Vec<f64> = plain.iter().zip(&x).map(|(p, x)| p - x - mean).collect();
            eprintln!("{fs} Hz: {:.3e} plain {:.3e}", rms(&err), rms(&plain_err));
            // the steps' half-sample ambiguity leaves a velocity error that is not
            // constant across the fades: a few % of the RMS at 200 Hz, less at higher rates
            assert!(
                rms(&err) < 0.03 * rms(&x) && rms(&err) < 0.1 * rms(&plain_err),
                "{fs} Hz: error {:.3e} of {:.3e} (plain {:.3e})",
                rms(&err),
                rms(&x),
                rms(&plain_err)
            );
            // at rest where the record starts and, within the error, where it ends
            assert!(got[0].abs() < 1e-6 * rms(&x));
            assert!(got[x.len() - 1].abs() < 0.03 * rms(&x));
        }
    }

    #[test]
    fn a_record_not_at_rest_is_integrated_plainly() {
        let fs = 500.0;
        let f = 2.0 * PI * 1.3;
        let x: Vec<f64> = (0..5000)
            .map(|k| 0.01 * (f * k as f64 / fs).sin())
            .collect();
        let a: Vec<f64> = x.iter().map(|x| -f * f * x).collect();
        let (v, got) = velocity_and_displacement(&a, fs);
        assert_eq!(got, spectral(&a, fs, -2));
        assert_eq!(v, spectral(&a, fs, -1));
    }
}

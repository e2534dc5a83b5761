//! How well a table reproduced its target, as labs measure it (e.g. the NCREE practice
//! over 1 209 tests, Chen et al. 2018): the RMS error of the achieved acceleration over the
//! target's RMS, the PGA error, and the share of 5 %-damped spectral-acceleration
//! ordinates from 0.5 to 30 Hz outside +-10 % of the target's.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Damping of the response spectrum's oscillators (the engineering convention).
pub const SPECTRUM_DAMPING: f64 = 0.05;
/// Band of the spectral ordinates, Hz (where specimens on shake tables respond).
pub const SPECTRUM_BAND_HZ: (f64, f64) = (0.5, 30.0);
/// Ordinates over the band, log-spaced (about 60 a decade: finer than any oscillator's
/// 5 %-damped half-power width of 10 %).
pub const SPECTRUM_ORDINATES: usize = 170;
/// An ordinate is outside when it differs from the target's by more than this fraction.
pub const SPECTRUM_TOLERANCE: f64 = 0.10;

/// The three figures of a reproduction, as fractions.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct Metrics {
    pub rms_error: f64,
    /// Signed: achieved PGA over the target's, minus 1.
    pub pga_error: f64,
    pub spectral_outside_fraction: f64,
}

/// Compare `achieved` with `target` (same rate and length, aligned).
pub fn metrics(target: &[f64], achieved: &[f64], rate_hz: f64) -> Metrics {
    let n = target.len().min(achieved.len());
    let (t, a) = (&target[..n], &achieved[..n]);
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (s, c) = v.fold((0.0, 0usize), |(s, c), x| (s + x * x, c + 1));
        (s / c.max(1) as f64).sqrt()
    };
    let err = rms(&mut t.iter().zip(a).map(|(x, y)| y - x));
    let peak = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let st = response_spectrum(t, rate_hz);
    let sa = response_spectrum(a, rate_hz);
    let outside = st
        .iter()
        .zip(&sa)
        .filter(|(x, y)| (*y / *x - 1.0).abs() > SPECTRUM_TOLERANCE)
        .count();
    Metrics {
        rms_error: err / rms(&mut t.iter().copied()),
        pga_error: peak(a) / peak(t) - 1.0,
        spectral_outside_fraction: outside as f64 / st.len() as f64,
    }
}

/// The ordinates' frequencies, Hz.
pub fn spectrum_frequencies_hz() -> Vec<f64> {
    let (lo, hi) = SPECTRUM_BAND_HZ;
    (0..SPECTRUM_ORDINATES)
        .map(|k| lo * (hi / lo).powf(k as f64 / (SPECTRUM_ORDINATES - 1) as f64))
        .collect()
}

/// Pseudo-spectral acceleration `w^2 max|u|` of 5 %-damped oscillators under the base
/// acceleration `a`, at [`spectrum_frequencies_hz`]; exact for an acceleration linear
/// between samples (Nigam and Jennings 1969; written here: no crate computes it).
pub fn response_spectrum(a: &[f64], rate_hz: f64) -> Vec<f64> {
    let dt = 1.0 / rate_hz;
    spectrum_frequencies_hz()
        .iter()
        .map(|f| {
            let w = 2.0 * PI * f;
            let c = NigamJennings::new(w, SPECTRUM_DAMPING, dt);
            let (mut u, mut v, mut umax) = (0.0_f64, 0.0_f64, 0.0_f64);
            for k in 1..a.len() {
                (u, v) = c.step(u, v, a[k - 1], a[k]);
                umax = umax.max(u.abs());
            }
            w * w * umax
        })
        .collect()
}

/// The exact one-step recurrence of `u'' + 2 z w u' + w^2 u = -a(t)` for `a` linear over
/// the step: `[u, v]_{k+1} = A [u, v]_k + B [a_k, a_{k+1}]`.
struct NigamJennings {
    a: [[f64; 2]; 2],
    b: [[f64; 2]; 2],
}

impl NigamJennings {
    fn new(w: f64, z: f64, dt: f64) -> Self {
        let wd = w * (1.0 - z * z).sqrt();
        let e = (-z * w * dt).exp();
        let (s, c) = ((wd * dt).sin(), (wd * dt).cos());
        let zr = z / (1.0 - z * z).sqrt();
        let a11 = e * (zr * s + c);
        let a12 = e * s / wd;
        let a21 = -w / (1.0 - z * z).sqrt() * e * s;
        let a22 = e * (c - zr * s);
        let t1 = (2.0 * z * z - 1.0) / (w * w * dt);
        let t2 = 2.0 * z / (w * w * w * dt);
        let b11 = e * ((t1 + z / w) * s / wd + (t2 + 1.0 / (w * w)) * c) - t2;
        let b12 = -e * (t1 * s / wd + t2 * c) - 1.0 / (w * w) + t2;
        let b21 = e * ((t1 + z / w) * (c - zr * s) - (t2 + 1.0 / (w * w)) * (wd * s + z * w * c))
            + 1.0 / (w * w * dt);
        let b22 = -e * (t1 * (c - zr * s) - t2 * (wd * s + z * w * c)) - 1.0 / (w * w * dt);
        NigamJennings {
            a: [[a11, a12], [a21, a22]],
            b: [[b11, b12], [b21, b22]],
        }
    }

    fn step(&self, u: f64, v: f64, a0: f64, a1: f64) -> (f64, f64) {
        let (a, b) = (&self.a, &self.b);
        (
            a[0][0] * u + a[0][1] * v + b[0][0] * a0 + b[0][1] * a1,
            a[1][0] * u + a[1][1] * v + b[1][0] * a0 + b[1][1] * a1,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resonant_sine_gives_the_textbook_amplification() {
        // a long 5 Hz sine: the 5 Hz oscillator's steady amplitude is 1/(2 z) times the
        // static one, so its Sa is 10 times the input amplitude
        let rate = 1000.0;
        let a: Vec<f64> = (0..60_000)
            .map(|k| (2.0 * PI * 5.0 * k as f64 / rate).sin())
            .collect();
        let freqs = spectrum_frequencies_hz();
        let sa = response_spectrum(&a, rate);
        let (k, _) = freqs
            .iter()
            .enumerate()
            .min_by(|x, y| (x.1 - 5.0).abs().total_cmp(&(y.1 - 5.0).abs()))
            .unwrap();
        let r = freqs[k] / 5.0;
        let expected = 1.0 / ((1.0 - r * r).powi(2) + (2.0 * SPECTRUM_DAMPING * r).powi(2)).sqrt();
        assert!(
            (sa[k] - expected).abs() < 0.02 * expected,
            "{} {expected}",
            sa[k]
        );
        // a stiff oscillator (30 Hz) follows the ground quasi-statically: 1/(1 - r^2), plus
        // the free vibration the sine's sudden start leaves (under 10 %)
        let r: f64 = 5.0 / 30.0;
        let quasi_static = 1.0 / (1.0 - r * r);
        let last = sa[freqs.len() - 1];
        assert!(
            last >= quasi_static * 0.99 && last < quasi_static * 1.1,
            "{last}"
        );
    }

    #[test]
    fn metrics_of_a_scaled_copy() {
        let rate = 200.0;
        let t: Vec<f64> = (0..4000)
            .map(|k| (k as f64 * 0.37).sin() * (k as f64 / 900.0).sin())
            .collect();
        let a: Vec<f64> = t.iter().map(|x| 1.05 * x).collect();
        let m = metrics(&t, &a, rate);
        assert!((m.rms_error - 0.05).abs() < 1e-12);
        assert!((m.pga_error - 0.05).abs() < 1e-12);
        assert_eq!(m.spectral_outside_fraction, 0.0);
        let b: Vec<f64> = t.iter().map(|x| 1.2 * x).collect();
        assert_eq!(metrics(&t, &b, rate).spectral_outside_fraction, 1.0);
    }
}

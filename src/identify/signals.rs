//! Channel access and signal helpers the estimators share.

use super::error::IdentifyError;
use super::frf::{Welch, WelchOptions};
use super::{frf, RESOLUTION_HZ};
use crate::campaign::{Measured, Record};

/// The spool channel of a record, if recorded.
pub(super) fn spool_channel(r: &Record) -> Option<&[f64]> {
    r.spool_position.as_deref()
}

/// Channel `m` of test `name`, or the error naming the test, the channel and what cannot
/// be identified without it.
pub(super) fn channel<'a>(
    name: &str,
    rec: &'a Record,
    m: Measured,
    consequence: &'static str,
) -> Result<&'a [f64], IdentifyError> {
    rec.measured(m)
        .ok_or_else(|| IdentifyError::MissingChannel {
            test: name.to_string(),
            channel: m.name(),
            consequence,
        })
}

pub(super) fn welch_for(fs: f64, n: usize) -> Result<Welch, frf::FrfError> {
    Welch::new(
        fs,
        WelchOptions::for_resolution(fs, RESOLUTION_HZ).fit_to(n, 8),
    )
}

/// White-noise RMS of `x` from its fourth difference: its variance is 70 times the
/// noise's (binomial(8, 4)), while a signal at 14 Hz sampled at 512 Hz is attenuated to
/// 8e-4 of its amplitude, so slow motion and the oil-column chatter do not leak in. NaN
/// for fewer than 16 samples.
pub(crate) fn fourth_difference_rms(x: &[f64]) -> f64 {
    if x.len() < 16 {
        return f64::NAN;
    }
    let d: Vec<f64> = x
        .windows(5)
        .map(|w| w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4])
        .collect();
    centred_rms(&d) / 70f64.sqrt()
}

/// Longest lag of a residual's autocorrelation summed, samples: 2 s at 1 kHz, beyond any
/// correlation a fit's model error leaves (and a bound on the work).
pub(super) const MAX_CORRELATION_LAG: usize = 2000;

/// Integrated autocorrelation of a fit's residual `r`, `1 + 2 sum rho_k` over lags below
/// `lags` (and [`MAX_CORRELATION_LAG`]) until the first one whose correlation is not
/// positive: the residual samples per independent one, by which `s^2 (J^T J)^-1`
/// understates the covariance of a fit to correlated residuals (model error,
/// oversampling). Its square root widens the sigmas; 1 for white or silent residuals.
pub(super) fn correlation_factor(r: &[f64], lags: usize) -> f64 {
    let n = r.len();
    let r0: f64 = r.iter().map(|v| v * v).sum();
    if n < 2 || r0 <= 0.0 {
        return 1.0;
    }
    let mut sum = 0.0;
    for lag in 1..lags.min(MAX_CORRELATION_LAG).min(n - 1) {
        let rho = r.iter().zip(&r[lag..]).map(|(a, b)| a * b).sum::<f64>() / r0;
        if rho <= 0.0 {
            break;
        }
        sum += rho;
    }
    1.0 + 2.0 * sum
}

/// RMS of `x` about its mean (its standard deviation); 0 for no samples.
pub(crate) fn centred_rms(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt()
}

/// The path of `x` with its sensor noise's back-and-forth taken out: between reversals it
/// only moves on (a running maximum while rising, a running minimum while falling), and a
/// reversal counts once `x` has come back by `threshold` from the last extreme. A
/// rate-independent hysteresis (Bouc-Wen, eq. 4.15) driven by a noisy displacement turns
/// at every wiggle: an LVDT noise of 2 % of the yield displacement made the fitted shape
/// `b` 11-16 % high. Hand-written: a hysteresis filter of a few lines (the "turning
/// point" filter of rainflow counting), which no crate offers on its own.
pub(super) fn monotone_path(x: &[f64], threshold: f64) -> Vec<f64> {
    let Some(&first) = x.first() else {
        return Vec::new();
    };
    let (mut level, mut rising) = (first, None::<bool>);
    x.iter()
        .map(|&xi| {
            match rising {
                None if (xi - level).abs() > threshold => {
                    rising = Some(xi > level);
                    level = xi;
                }
                None => {}
                Some(true) if xi > level => level = xi,
                Some(false) if xi < level => level = xi,
                Some(r) if (xi - level).abs() > threshold => {
                    rising = Some(!r);
                    level = xi;
                }
                Some(_) => {}
            }
            level
        })
        .collect()
}

/// Zero-phase smoothing: a centred moving average of `2 h + 1` samples.
pub(super) fn smooth(x: &[f64], h: usize) -> Vec<f64> {
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
pub(super) fn derivative(x: &[f64], fs: f64) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (x[b] - x[a]) * fs / (b - a).max(1) as f64
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slow sine with a noise's wiggles: the path keeps the sine's two reversals a
    /// cycle and drops every wiggle, and stays within the threshold of the sine.
    #[test]
    fn the_monotone_path_keeps_the_reversals_and_drops_the_wiggles() {
        let (n, period) = (80_000, 20_000.0);
        let sine = |k: usize| (std::f64::consts::TAU * k as f64 / period).sin();
        // a deterministic wiggle of 1.5e-3 peak to peak, far above the sine's step
        let x: Vec<f64> = (0..n)
            .map(|k| sine(k) + 1e-3 * if k % 3 == 0 { 1.0 } else { -0.5 })
            .collect();
        let threshold = 5e-3;
        let path = monotone_path(&x, threshold);
        // reversals: sign changes of the steps that move (a hold is no turn)
        let turns = |y: &[f64]| {
            let steps: Vec<f64> = y
                .windows(2)
                .map(|w| w[1] - w[0])
                .filter(|d| *d != 0.0)
                .collect();
            steps.windows(2).filter(|w| w[0] * w[1] < 0.0).count()
        };
        assert!(
            turns(&x) > n / 2,
            "the raw signal turns at nearly every sample"
        );
        // four cycles from a rising zero: a peak and a trough each, the last trough a
        // quarter cycle before the end
        assert_eq!(turns(&path), 8);
        for (k, x) in path.iter().enumerate().take(n) {
            assert!((x - sine(k)).abs() < threshold + 2e-3, "{k}");
        }
    }

    #[test]
    fn the_fourth_difference_reads_white_noise_and_not_slow_motion() {
        // a uniform noise of RMS 1/sqrt(12) from a fixed sequence, on a slow ramp
        let mut state = 12345u64;
        let x: Vec<f64> = (0..20_000)
            .map(|k| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                1e-2 * u + 1e-3 * k as f64
            })
            .collect();
        let rms = fourth_difference_rms(&x);
        let truth = 1e-2 / 12f64.sqrt();
        assert!((rms / truth - 1.0).abs() < 0.03, "{rms} for {truth}");
        assert!(fourth_difference_rms(&x[..10]).is_nan());
    }
}

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

//! A record on a periodic grid, in the frequency domain: filtering, integration and
//! differentiation as gains per frequency, and band-limited resampling. The records here
//! are at rest at both ends (zero-padded), so their periodic extension does not jump.

use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use std::f64::consts::PI;

/// Largest denominator of the ratio of two sample rates that resampling handles exactly
/// (1/0.005 s to 1024 Hz is 128/25; a lab's rates are ratios of small integers).
pub const MAX_RATE_DENOMINATOR: usize = 10_000;

/// How close to a ratio of integers two rates must be: rates from a printed step (1/0.005 s)
/// carry rounding of a few 1e-16; 1e-9 leaves room for that and nothing else.
const RATE_RATIO_TOLERANCE: f64 = 1e-9;

/// The spectrum of a real signal of `n` samples at `rate_hz`.
pub struct Periodic {
    n: usize,
    rate_hz: f64,
    bins: Vec<Complex<f64>>,
}

impl Periodic {
    pub fn new(x: &[f64], rate_hz: f64) -> Self {
        let mut planner = RealFftPlanner::<f64>::new();
        let fwd = planner.plan_fft_forward(x.len());
        let mut input = x.to_vec();
        let mut bins = fwd.make_output_vec();
        // lengths match the plan, so this cannot fail
        let _ = fwd.process(&mut input, &mut bins);
        Periodic {
            n: x.len(),
            rate_hz,
            bins,
        }
    }

    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Each bin multiplied by `gain(frequency_hz)`.
    pub fn filtered(&self, gain: impl Fn(f64) -> Complex<f64>) -> Periodic {
        let df = self.rate_hz / self.n as f64;
        let bins = self
            .bins
            .iter()
            .enumerate()
            .map(|(k, c)| c * gain(k as f64 * df))
            .collect();
        Periodic { bins, ..*self }
    }

    /// The `order`-th time derivative (negative: integral); the mean (0 Hz) is set to
    /// zero, and for odd orders the Nyquist bin too (its derivative is not real).
    pub fn derivative(&self, order: i32) -> Periodic {
        let last = self.bins.len() - 1;
        let even_n = self.n.is_multiple_of(2);
        let mut d = self.filtered(|f| Complex::new(0.0, 2.0 * PI * f).powi(order));
        d.bins[0] = Complex::new(0.0, 0.0);
        if order % 2 != 0 && even_n {
            d.bins[last] = Complex::new(0.0, 0.0);
        }
        d
    }

    /// Back to samples.
    pub fn signal(&self) -> Vec<f64> {
        let mut planner = RealFftPlanner::<f64>::new();
        let inv = planner.plan_fft_inverse(self.n);
        let mut bins = self.bins.clone();
        bins[0].im = 0.0;
        if self.n.is_multiple_of(2) {
            let last = bins.len() - 1;
            bins[last].im = 0.0;
        }
        let mut out = inv.make_output_vec();
        let _ = inv.process(&mut bins, &mut out);
        out.iter().map(|v| v / self.n as f64).collect()
    }
}

/// `x` at `rate_in_hz` resampled to `rate_out_hz` by band-limited (FFT) interpolation
/// over a zero-padded grid; the content above the lower Nyquist frequency is dropped.
/// Errors when the rates are not a ratio of integers up to [`MAX_RATE_DENOMINATOR`].
pub fn resample(x: &[f64], rate_in_hz: f64, rate_out_hz: f64) -> Result<Vec<f64>, String> {
    let ratio = rate_out_hz / rate_in_hz;
    let q = (1..=MAX_RATE_DENOMINATOR)
        .find(|&q| {
            let p = ratio * q as f64;
            (p - p.round()).abs() <= RATE_RATIO_TOLERANCE * p.max(1.0)
        })
        .ok_or_else(|| {
            format!(
                "the rates {rate_in_hz} Hz and {rate_out_hz} Hz are not a ratio of small integers"
            )
        })?;
    let p = (ratio * q as f64).round() as usize;
    let n_in = x.len().div_ceil(q) * q;
    let n_out = n_in / q * p;
    let mut padded = x.to_vec();
    padded.resize(n_in, 0.0);
    let spec = Periodic::new(&padded, rate_in_hz);
    let keep = n_in.min(n_out) / 2; // bins strictly below the lower Nyquist frequency
    let mut bins = vec![Complex::new(0.0, 0.0); n_out / 2 + 1];
    let scale = n_out as f64 / n_in as f64;
    for k in 0..keep.min(bins.len()) {
        bins[k] = spec.bins[k] * scale;
    }
    let out = Periodic {
        n: n_out,
        rate_hz: rate_out_hz,
        bins,
    }
    .signal();
    let len = (x.len() as f64 * ratio).round() as usize;
    Ok(out.into_iter().take(len).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(n: usize, rate: f64, f: f64) -> Vec<f64> {
        (0..n)
            .map(|k| (2.0 * PI * f * k as f64 / rate).sin())
            .collect()
    }

    #[test]
    fn derivatives_of_a_periodic_sine_are_exact() {
        let (rate, f) = (100.0, 2.0);
        let x = sine(500, rate, f); // 10 periods exactly
        let a = Periodic::new(&x, rate).derivative(2).signal();
        let w2 = (2.0 * PI * f).powi(2);
        for k in 0..x.len() {
            assert!((a[k] + w2 * x[k]).abs() < 1e-9 * w2, "{k}");
        }
        let i = Periodic::new(&x, rate).derivative(-1).signal();
        let expected = -(2.0 * PI * f * 3.0 / rate).cos() / (2.0 * PI * f);
        assert!((i[3] - expected).abs() < 1e-12);
    }

    #[test]
    fn resampling_keeps_a_band_limited_signal() {
        // 200 Hz to 1024 Hz (ratio 128/25): a 3 Hz sine stays a 3 Hz sine
        let x = sine(1000, 200.0, 3.0);
        let y = resample(&x, 200.0, 1024.0).unwrap();
        assert_eq!(y.len(), 5120);
        let truth = sine(5120, 1024.0, 3.0);
        let err = y
            .iter()
            .zip(&truth)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-9, "{err}");
        assert!(resample(&x, 200.0, 1024.0 * std::f64::consts::SQRT_2).is_err());
    }
}

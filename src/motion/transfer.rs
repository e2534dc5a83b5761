//! The table's transfer from drive (reference acceleration) to table acceleration on a
//! record's frequency grid: the model's (the closed loop linearised at rest, specimen
//! included) and, as drive/response pairs are measured, the pairs' accumulated spectra,
//! as a lab's online iteration updates it (Welch-like: periodogram products summed over
//! pairs and smoothed over neighbouring frequencies).

use crate::linear::Linearisation;
use crate::params::Params;
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;

/// Width of the frequency smoothing of measured spectra, Hz: about 10 bins of a 45-s
/// record, enough for a coherence estimate, narrower than the specimen's resonance
/// (2 % damping at 2 Hz is 0.08 Hz wide at half power, so peaks are smeared a little).
pub const SMOOTHING_HZ: f64 = 0.25;

/// Tikhonov regularisation of the inverse, relative to the table's unit low-frequency
/// gain: where the table's gain falls below this (above its band, at the specimen's
/// anti-resonance) the drive asks at most 1/(2 eps) times the target instead of chasing a
/// zero.
pub const INVERSE_REGULARISATION: f64 = 0.1;

/// The transfer on the grid of `n` samples at `rate_hz` (bins `0..=n/2`).
#[derive(Debug, Clone)]
pub struct Transfer {
    pub rate_hz: f64,
    pub n: usize,
    pub model: Vec<Complex<f64>>,
    /// Sums over the pairs of `|D|^2`, `conj(D) A`, `|A|^2` per bin.
    pub s_dd: Vec<f64>,
    pub s_da: Vec<Complex<f64>>,
    pub s_aa: Vec<f64>,
    pub pairs: usize,
}

/// Forward real FFT of `x`.
pub fn fft(x: &[f64]) -> Vec<Complex<f64>> {
    let mut planner = RealFftPlanner::<f64>::new();
    let f = planner.plan_fft_forward(x.len());
    let mut input = x.to_vec();
    let mut out = f.make_output_vec();
    let _ = f.process(&mut input, &mut out);
    out
}

/// Inverse real FFT to `n` samples (normalised).
pub fn ifft(bins: &[Complex<f64>], n: usize) -> Vec<f64> {
    let mut planner = RealFftPlanner::<f64>::new();
    let f = planner.plan_fft_inverse(n);
    let mut b = bins.to_vec();
    b[0].im = 0.0;
    if n.is_multiple_of(2) {
        let last = b.len() - 1;
        b[last].im = 0.0;
    }
    let mut out = f.make_output_vec();
    let _ = f.process(&mut b, &mut out);
    out.iter().map(|v| v / n as f64).collect()
}

impl Transfer {
    /// The model's transfer for the table of `p` (unit gain at 0 Hz).
    pub fn from_model(p: &Params, n: usize, rate_hz: f64) -> Transfer {
        let lin = Linearisation::new(p);
        let bins = n / 2 + 1;
        let model = (0..bins)
            .map(|k| match k {
                0 => Complex::new(1.0, 0.0),
                _ => {
                    let h = lin.table_tf(k as f64 * rate_hz / n as f64);
                    if h.re.is_finite() && h.im.is_finite() {
                        h
                    } else {
                        Complex::new(0.0, 0.0)
                    }
                }
            })
            .collect();
        Transfer {
            rate_hz,
            n,
            model,
            s_dd: vec![0.0; bins],
            s_da: vec![Complex::new(0.0, 0.0); bins],
            s_aa: vec![0.0; bins],
            pairs: 0,
        }
    }

    /// Add a measured (or simulated) pair: the drive's acceleration and the table's.
    pub fn add_pair(&mut self, drive: &[f64], response: &[f64]) {
        let (d, a) = (fft(drive), fft(response));
        for k in 0..self.s_dd.len() {
            self.s_dd[k] += d[k].norm_sqr();
            self.s_da[k] += d[k].conj() * a[k];
            self.s_aa[k] += a[k].norm_sqr();
        }
        self.pairs += 1;
    }

    fn smoothed<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>>(
        &self,
        x: &[T],
        zero: T,
    ) -> Vec<T> {
        let half = ((SMOOTHING_HZ / 2.0) / (self.rate_hz / self.n as f64)).round() as usize;
        let mut prefix = Vec::with_capacity(x.len() + 1);
        prefix.push(zero);
        for v in x {
            let last = *prefix.last().unwrap_or(&zero);
            prefix.push(last + *v);
        }
        (0..x.len())
            .map(|k| {
                let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(x.len()));
                (prefix[hi] + prefix[lo] * -1.0) * (1.0 / (hi - lo) as f64)
            })
            .collect()
    }

    /// The coherence of the measured pairs per bin (0 without pairs).
    pub fn coherence(&self) -> Vec<f64> {
        if self.pairs == 0 {
            return vec![0.0; self.model.len()];
        }
        let (dd, aa) = (
            self.smoothed(&self.s_dd, 0.0),
            self.smoothed(&self.s_aa, 0.0),
        );
        let da = self.smoothed(&self.s_da, Complex::new(0.0, 0.0));
        (0..dd.len())
            .map(|k| {
                let den = dd[k] * aa[k];
                if den > 0.0 {
                    (da[k].norm_sqr() / den).min(1.0)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The transfer used: the measured one `S_da / S_dd` where the pairs are coherent, the
    /// model's where they are not (`H_model + coh (H_meas - H_model)`).
    pub fn estimate(&self) -> Vec<Complex<f64>> {
        if self.pairs == 0 {
            return self.model.clone();
        }
        let coh = self.coherence();
        let dd = self.smoothed(&self.s_dd, 0.0);
        let da = self.smoothed(&self.s_da, Complex::new(0.0, 0.0));
        (0..dd.len())
            .map(|k| match dd[k] > 0.0 {
                true => self.model[k] + (da[k] / dd[k] - self.model[k]) * coh[k],
                false => self.model[k],
            })
            .collect()
    }

    /// The regularised inverse of [`Transfer::estimate`], band-limited to `band_hz`
    /// (cosine roll-off over the last [`ROLL_OFF`] of the band).
    pub fn inverse(&self, band_hz: f64) -> Vec<Complex<f64>> {
        let eps2 = INVERSE_REGULARISATION * INVERSE_REGULARISATION;
        let df = self.rate_hz / self.n as f64;
        self.estimate()
            .iter()
            .enumerate()
            .map(|(k, h)| h.conj() / (h.norm_sqr() + eps2) * band_weight(k as f64 * df, band_hz))
            .collect()
    }
}

/// Share of the band over which the inverse rolls off to zero (a hard edge would ring).
pub const ROLL_OFF: f64 = 0.2;

fn band_weight(f: f64, band_hz: f64) -> f64 {
    let start = band_hz * (1.0 - ROLL_OFF);
    if f <= start {
        1.0
    } else if f >= band_hz {
        0.0
    } else {
        0.5 * (1.0 + (std::f64::consts::PI * (f - start) / (band_hz - start)).cos())
    }
}

//! Welch-averaged spectral estimates (paper section 4.1): auto and cross spectra of
//! recorded channels with `realfft`, and the frequency-response estimators built on them:
//! H1 (`S_xy / S_xx`, unbiased by noise on the output), H2 (`S_yy / S_yx`, unbiased by
//! noise on the input), the instrumental-variable estimate (`S_zy / S_zx` with a
//! noise-free instrument `z`, e.g. the valve command), and the ordinary coherence.
//!
//! Choices (stated in every report): Hann window, 50 % overlap, mean removed per
//! segment, one-sided density scaling. The segment length sets the resolution
//! `fs / segment_len`; [`WelchOptions::for_resolution`] picks the power of two that gives
//! at least the requested resolution.

use num_complex::Complex64;
use realfft::RealFftPlanner;
use std::f64::consts::PI;
use std::sync::Arc;

/// Errors of the spectral estimates.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FrfError {
    #[error("channels have different lengths ({0} and {1} samples)")]
    LengthMismatch(usize, usize),
    #[error("{samples} samples are fewer than one segment of {segment} samples")]
    TooShort { samples: usize, segment: usize },
    #[error("segment length {0} must be at least 8")]
    BadSegment(usize),
    #[error("overlap {0} must be in [0, 1)")]
    BadOverlap(f64),
    #[error("non-finite sample at index {0}")]
    NonFinite(usize),
}

/// Welch parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct WelchOptions {
    pub segment_len: usize,
    /// Fraction of a segment shared with the next, in [0, 1).
    pub overlap: f64,
}

impl WelchOptions {
    /// Hann segments of the smallest power of two giving a resolution of at least
    /// `resolution_hz` at `sample_rate_hz`, 50 % overlap.
    pub fn for_resolution(sample_rate_hz: f64, resolution_hz: f64) -> Self {
        let want = (sample_rate_hz / resolution_hz).ceil().max(8.0) as usize;
        WelchOptions {
            segment_len: want.next_power_of_two(),
            overlap: 0.5,
        }
    }

    /// The same, shortened so that a record of `samples` gives at least `min_segments`.
    pub fn fit_to(mut self, samples: usize, min_segments: usize) -> Self {
        while self.segment_len > 64 && self.segments(samples) < min_segments {
            self.segment_len /= 2;
        }
        self
    }

    fn hop(&self) -> usize {
        ((self.segment_len as f64) * (1.0 - self.overlap))
            .round()
            .max(1.0) as usize
    }

    /// Number of segments a record of `samples` gives.
    pub fn segments(&self, samples: usize) -> usize {
        if samples < self.segment_len {
            0
        } else {
            (samples - self.segment_len) / self.hop() + 1
        }
    }
}

/// Segment spectra of a set of channels, from which any auto/cross spectrum follows.
pub struct Welch {
    pub options: WelchOptions,
    pub sample_rate_hz: f64,
    window: Vec<f64>,
    scale: f64,
    fft: Arc<dyn realfft::RealToComplex<f64>>,
}

/// A frequency-response estimate with its coherence.
#[derive(Debug, Clone, Default)]
pub struct FrfEstimate {
    pub frequency_hz: Vec<f64>,
    pub h1: Vec<Complex64>,
    pub h2: Vec<Complex64>,
    pub coherence: Vec<f64>,
    pub segments: usize,
}

impl FrfEstimate {
    /// Indices of the bins within `[lo, hi]` Hz.
    pub fn band(&self, lo: f64, hi: f64) -> Vec<usize> {
        band_indices(&self.frequency_hz, lo, hi)
    }
}

/// Indices of `freqs` within `[lo, hi]`.
pub fn band_indices(freqs: &[f64], lo: f64, hi: f64) -> Vec<usize> {
    (0..freqs.len())
        .filter(|&i| freqs[i] >= lo && freqs[i] <= hi)
        .collect()
}

impl Welch {
    pub fn new(sample_rate_hz: f64, options: WelchOptions) -> Result<Self, FrfError> {
        if options.segment_len < 8 {
            return Err(FrfError::BadSegment(options.segment_len));
        }
        if !(0.0..1.0).contains(&options.overlap) {
            return Err(FrfError::BadOverlap(options.overlap));
        }
        let n = options.segment_len;
        // periodic Hann
        let window: Vec<f64> = (0..n)
            .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos())
            .collect();
        let power: f64 = window.iter().map(|w| w * w).sum();
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        Ok(Welch {
            options,
            sample_rate_hz,
            window,
            scale: 1.0 / (sample_rate_hz * power),
            fft,
        })
    }

    /// Bin frequencies, Hz.
    pub fn frequencies(&self) -> Vec<f64> {
        let n = self.options.segment_len;
        (0..=n / 2)
            .map(|k| k as f64 * self.sample_rate_hz / n as f64)
            .collect()
    }

    /// FFT of every windowed, mean-removed segment of `x`.
    pub fn segment_spectra(&self, x: &[f64]) -> Result<Vec<Vec<Complex64>>, FrfError> {
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(FrfError::NonFinite(i));
        }
        let n = self.options.segment_len;
        let count = self.options.segments(x.len());
        if count == 0 {
            return Err(FrfError::TooShort {
                samples: x.len(),
                segment: n,
            });
        }
        let hop = self.options.hop();
        let mut input = self.fft.make_input_vec();
        let mut scratch = self.fft.make_scratch_vec();
        let mut out = Vec::with_capacity(count);
        for k in 0..count {
            let seg = &x[k * hop..k * hop + n];
            let mean = seg.iter().sum::<f64>() / n as f64;
            for i in 0..n {
                input[i] = (seg[i] - mean) * self.window[i];
            }
            let mut spec = self.fft.make_output_vec();
            // lengths come from the planner itself, so the transform cannot fail
            if self
                .fft
                .process_with_scratch(&mut input, &mut spec, &mut scratch)
                .is_err()
            {
                return Err(FrfError::BadSegment(n));
            }
            out.push(spec);
        }
        Ok(out)
    }

    /// One-sided cross spectral density `S_ab = 2 conj(A) B / (fs sum w^2)`, averaged.
    pub fn cross(&self, a: &[Vec<Complex64>], b: &[Vec<Complex64>]) -> Vec<Complex64> {
        let bins = self.options.segment_len / 2 + 1;
        let mut s = vec![Complex64::new(0.0, 0.0); bins];
        for (sa, sb) in a.iter().zip(b) {
            for k in 0..bins {
                s[k] += sa[k].conj() * sb[k];
            }
        }
        let m = a.len().max(1) as f64;
        for (k, v) in s.iter_mut().enumerate() {
            let one_sided = if k == 0 || k + 1 == bins { 1.0 } else { 2.0 };
            *v *= one_sided * self.scale / m;
        }
        s
    }

    /// Auto spectral density of `x`.
    pub fn auto(&self, a: &[Vec<Complex64>]) -> Vec<f64> {
        self.cross(a, a).iter().map(|z| z.re).collect()
    }

    /// H1, H2 and coherence from input `x` to output `y`.
    pub fn frf(&self, x: &[f64], y: &[f64]) -> Result<FrfEstimate, FrfError> {
        if x.len() != y.len() {
            return Err(FrfError::LengthMismatch(x.len(), y.len()));
        }
        let fx = self.segment_spectra(x)?;
        let fy = self.segment_spectra(y)?;
        Ok(self.frf_from(&fx, &fy))
    }

    /// H1, H2 and coherence from segment spectra.
    pub fn frf_from(&self, fx: &[Vec<Complex64>], fy: &[Vec<Complex64>]) -> FrfEstimate {
        let sxx = self.auto(fx);
        let syy = self.auto(fy);
        let sxy = self.cross(fx, fy);
        let tiny = f64::MIN_POSITIVE;
        FrfEstimate {
            frequency_hz: self.frequencies(),
            h1: sxy.iter().zip(&sxx).map(|(c, a)| c / a.max(tiny)).collect(),
            h2: syy.iter().zip(&sxy).map(|(a, c)| *a / c.conj()).collect(),
            coherence: sxy
                .iter()
                .zip(sxx.iter().zip(&syy))
                .map(|(c, (a, b))| (c.norm_sqr() / (a * b).max(tiny)).min(1.0))
                .collect(),
            segments: fx.len(),
        }
    }

    /// Instrumental-variable estimate `S_zy / S_zx` from input `x` to output `y` with an
    /// instrument `z` correlated with `x` but not with the noise on `x` (paper 4.1.3).
    /// Returned in `h1`; `h2` holds the plain H2 and `coherence` the x-y coherence.
    pub fn frf_instrumental(
        &self,
        z: &[f64],
        x: &[f64],
        y: &[f64],
    ) -> Result<FrfEstimate, FrfError> {
        if x.len() != y.len() {
            return Err(FrfError::LengthMismatch(x.len(), y.len()));
        }
        if z.len() != x.len() {
            return Err(FrfError::LengthMismatch(z.len(), x.len()));
        }
        let fz = self.segment_spectra(z)?;
        let fx = self.segment_spectra(x)?;
        let fy = self.segment_spectra(y)?;
        let mut est = self.frf_from(&fx, &fy);
        let szx = self.cross(&fz, &fx);
        let szy = self.cross(&fz, &fy);
        est.h1 = szy.iter().zip(&szx).map(|(a, b)| a / b).collect();
        Ok(est)
    }
}

/// Auto and cross spectra of an instrument `z`, an input `x` and an output `y`, for the
/// equation-error residual of a parametric fit ([`CrossSpectra::equation_error`]).
#[derive(Debug, Clone)]
pub struct CrossSpectra {
    pub frequency_hz: Vec<f64>,
    pub segments: usize,
    s_zz: Vec<f64>,
    s_zx: Vec<Complex64>,
    s_zy: Vec<Complex64>,
    s_xx: Vec<f64>,
    s_yy: Vec<f64>,
    s_xy: Vec<Complex64>,
}

/// Floor of the residual spectrum `S_ee` as a fraction of `S_yy`: a record without noise
/// leaves only rounding (about 1e-16 of the output) in `e`, so 1e-12 never hides real
/// noise and keeps the residual of a noise-free record finite.
const RESIDUAL_SPECTRUM_FLOOR: f64 = 1e-12;

impl CrossSpectra {
    /// The spectra of `z`, `x` and `y` (equal lengths) with `welch`'s segments. With
    /// `z = x` the residual is that of H1 (a noise-free input).
    pub fn new(welch: &Welch, z: &[f64], x: &[f64], y: &[f64]) -> Result<Self, FrfError> {
        if x.len() != y.len() {
            return Err(FrfError::LengthMismatch(x.len(), y.len()));
        }
        if z.len() != x.len() {
            return Err(FrfError::LengthMismatch(z.len(), x.len()));
        }
        let (fz, fx, fy) = (
            welch.segment_spectra(z)?,
            welch.segment_spectra(x)?,
            welch.segment_spectra(y)?,
        );
        Ok(CrossSpectra {
            frequency_hz: welch.frequencies(),
            segments: fx.len(),
            s_zz: welch.auto(&fz),
            s_zx: welch.cross(&fz, &fx),
            s_zy: welch.cross(&fz, &fy),
            s_xx: welch.auto(&fx),
            s_yy: welch.auto(&fy),
            s_xy: welch.cross(&fx, &fy),
        })
    }

    /// Indices of the bins within `[lo, hi]` Hz.
    pub fn band(&self, lo: f64, hi: f64) -> Vec<usize> {
        band_indices(&self.frequency_hz, lo, hi)
    }

    /// The instrumental-variable equation error of a model response `h` at bin `i`,
    /// `(h S_zx - S_zy) / sigma`, in units of its own standard deviation
    /// `sigma^2 = S_zz S_ee / n_segments`, with `S_ee = S_yy - 2 Re(h S_yx) + |h|^2 S_xx` the
    /// spectrum of `e = y - h x` (Pintelon and Schoukens, System Identification, the
    /// sample maximum-likelihood cost with an instrument). At the true `h`, `e` holds
    /// only the noise of `x` and `y` and the window's leakage, none of it correlated
    /// with `z`, so the error is zero-mean with an expected squared magnitude of one
    /// (overlapping segments aside): the least squares on it
    /// weigh every bin by what it knows. Unlike a residual relative to the measured
    /// ratio `S_zy / S_zx`, no noisy estimate divides it: a bin whose `S_zx` came out
    /// small by chance (a large measured FRF) is not thereby down-weighted, and a bin
    /// the noise dominates does not pull the fit towards zero.
    pub fn equation_error(&self, i: usize, h: Complex64) -> Complex64 {
        let s_ee = self.s_yy[i] - 2.0 * (h * self.s_xy[i].conj()).re + h.norm_sqr() * self.s_xx[i];
        let s_ee = s_ee.max(RESIDUAL_SPECTRUM_FLOOR * self.s_yy[i]);
        let sigma = (self.s_zz[i] * s_ee / self.segments.max(1) as f64).sqrt();
        (h * self.s_zx[i] - self.s_zy[i]) / sigma.max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A known FIR filter `y[k] = x[k] + 0.5 x[k-1]` has `H = 1 + 0.5 e^{-jw/fs}`.
    #[test]
    fn h1_recovers_a_known_filter_and_coherence_is_one() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = Normal::new(0.0, 1.0).unwrap();
        let x: Vec<f64> = (0..1 << 15).map(|_| n.sample(&mut rng)).collect();
        let y: Vec<f64> = (0..x.len())
            .map(|k| x[k] + if k > 0 { 0.5 * x[k - 1] } else { 0.0 })
            .collect();
        let fs = 512.0;
        let w = Welch::new(fs, WelchOptions::for_resolution(fs, 1.0)).unwrap();
        let e = w.frf(&x, &y).unwrap();
        for k in 1..e.frequency_hz.len() - 1 {
            let wk = 2.0 * PI * e.frequency_hz[k] / fs;
            let h = Complex64::new(1.0, 0.0) + 0.5 * Complex64::from_polar(1.0, -wk);
            assert!((e.h1[k] - h).norm() < 0.02, "bin {k}: {} vs {h}", e.h1[k]);
            assert!(e.coherence[k] > 0.99);
        }
    }

    /// Noise on the input biases H1 low by `S_xx/(S_xx + S_nn)`; the instrument does not.
    #[test]
    fn instrument_removes_input_noise_bias() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let n = Normal::new(0.0, 1.0).unwrap();
        let z: Vec<f64> = (0..1 << 16).map(|_| n.sample(&mut rng)).collect();
        let y: Vec<f64> = z.iter().map(|v| 2.0 * v).collect();
        let x: Vec<f64> = z.iter().map(|v| v + n.sample(&mut rng)).collect();
        let w = Welch::new(100.0, WelchOptions::for_resolution(100.0, 1.0)).unwrap();
        let e = w.frf_instrumental(&z, &x, &y).unwrap();
        let h1 = w.frf(&x, &y).unwrap();
        let mid = e.frequency_hz.len() / 2;
        assert!((e.h1[mid].re - 2.0).abs() < 0.1, "{}", e.h1[mid]);
        assert!((h1.h1[mid].re - 1.0).abs() < 0.2, "{}", h1.h1[mid]);
    }

    /// At the true response the equation error of a noisy input has unit variance (it
    /// is in units of its own sigma); the H1-like response of the noisy input does not.
    #[test]
    fn equation_error_is_in_units_of_its_sigma() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = Normal::new(0.0, 1.0).unwrap();
        let z: Vec<f64> = (0..1 << 16).map(|_| n.sample(&mut rng)).collect();
        let x: Vec<f64> = z.iter().map(|v| v + n.sample(&mut rng)).collect();
        let y: Vec<f64> = z
            .iter()
            .map(|v| 2.0 * v + 0.5 * n.sample(&mut rng))
            .collect();
        let w = Welch::new(100.0, WelchOptions::for_resolution(100.0, 1.0)).unwrap();
        let c = CrossSpectra::new(&w, &z, &x, &y).unwrap();
        let bins = c.band(5.0, 45.0);
        let mean_square = |h: f64| {
            bins.iter()
                .map(|&i| c.equation_error(i, Complex64::new(h, 0.0)).norm_sqr())
                .sum::<f64>()
                / bins.len() as f64
        };
        // E|e|^2 = 1 but for the 50 % overlap's correlated segments (up to ~1.2)
        assert!((mean_square(2.0) - 1.0).abs() < 0.3, "{}", mean_square(2.0));
        assert!(mean_square(1.0) > 20.0, "{}", mean_square(1.0));
    }

    #[test]
    fn bad_input_is_an_error() {
        let w = Welch::new(
            100.0,
            WelchOptions {
                segment_len: 64,
                overlap: 0.5,
            },
        )
        .unwrap();
        assert_eq!(
            w.frf(&[0.0; 10], &[0.0; 11]).unwrap_err(),
            FrfError::LengthMismatch(10, 11)
        );
        assert!(matches!(
            w.frf(&[0.0; 10], &[0.0; 10]),
            Err(FrfError::TooShort { .. })
        ));
        let mut x = vec![0.0; 100];
        x[7] = f64::NAN;
        assert_eq!(w.frf(&x, &x).unwrap_err(), FrfError::NonFinite(7));
        assert!(Welch::new(
            100.0,
            WelchOptions {
                segment_len: 64,
                overlap: 1.0
            }
        )
        .is_err());
    }
}

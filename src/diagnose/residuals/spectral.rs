//! Octave bands, the split of a signal into them, and the DCT the whitening uses.

/// Lower edge of the lowest octave band but one, Hz: the bands of [`octave_bands`] halve
/// from the Nyquist frequency down to here, and one band holds everything below.
pub const LOWEST_BAND_HZ: f64 = 1.0;

/// Octave bands `(lo_hz, hi_hz)` from the Nyquist frequency down, the last from 0 Hz.
pub fn octave_bands(sample_rate_hz: f64) -> Vec<(f64, f64)> {
    let nyquist = sample_rate_hz / 2.0;
    let count = ((nyquist / LOWEST_BAND_HZ).log2().floor().max(0.0) as usize) + 1;
    (0..count)
        .map(|b| {
            let hi = nyquist / 2f64.powi(b as i32);
            let lo = if b + 1 == count { 0.0 } else { hi / 2.0 };
            (lo, hi)
        })
        .collect()
}

/// Zero-phase band split by FFT masking of the even extension of `x` (`x` then `x`
/// reversed: its periodic extension has no step at the ends, which would leak into every
/// band; a line through the end points would add their noise as a slow ramp instead).
/// Hand-written over `realfft` because no crate offers a band split.
pub fn band_split(x: &[f64], bands: &[(f64, f64)], sample_rate_hz: f64) -> Vec<Vec<f64>> {
    let half = x.len();
    if half < 2 {
        return bands.iter().map(|_| x.to_vec()).collect();
    }
    let spec = even_spectrum(x);
    let n = 2 * half;
    let inv = with_planner(|p| p.plan_fft_inverse(n));
    let df = sample_rate_hz / n as f64;
    bands
        .iter()
        .enumerate()
        .map(|(j, &(lo, hi))| {
            let mut s = spec.clone();
            for (k, c) in s.iter_mut().enumerate() {
                let f = k as f64 * df;
                // each bin in exactly one band; the top band keeps the Nyquist bin
                let inside = f >= lo && (f < hi || j == 0);
                if !inside {
                    *c = num_complex::Complex64::new(0.0, 0.0);
                }
            }
            // the first and (even n) last bins must be real for the inverse
            s[0].im = 0.0;
            if n.is_multiple_of(2) {
                if let Some(last) = s.last_mut() {
                    last.im = 0.0;
                }
            }
            let mut out = inv.make_output_vec();
            let _ = inv.process(&mut s, &mut out);
            out.truncate(half);
            out.iter_mut().for_each(|v| *v /= n as f64);
            out
        })
        .collect()
}

/// Highest frequency the output-error fits look at, Hz: above it every model's residual is
/// sensor noise (the valve, the oil column, a foundation and chatter all live below), so
/// the fits skip those coefficients, which would only add cost.
pub const FIT_MAX_HZ: f64 = 64.0;

/// Run `f` with this thread's FFT planner: a planner caches its plans, and planning a
/// long transform (twiddle factors) costs as much as running it, so the fits, which
/// transform the same lengths thousands of times, keep one per worker thread.
pub(super) fn with_planner<R>(f: impl FnOnce(&mut realfft::RealFftPlanner<f64>) -> R) -> R {
    thread_local! {
        static PLANNER: std::cell::RefCell<realfft::RealFftPlanner<f64>> =
            std::cell::RefCell::new(realfft::RealFftPlanner::new());
    }
    PLANNER.with(|p| f(&mut p.borrow_mut()))
}

/// The real FFT of `x` followed by `x` reversed (the even extension, length `2 len(x)`):
/// no jump at the ends, so masking its spectrum leaves no edge ripple.
pub(super) fn even_spectrum(x: &[f64]) -> Vec<num_complex::Complex64> {
    let mut buf: Vec<f64> = x.iter().chain(x.iter().rev()).copied().collect();
    let fwd = with_planner(|p| p.plan_fft_forward(buf.len()));
    let mut spec = fwd.make_output_vec();
    // realfft only fails on wrong buffer lengths, which are made here
    let _ = fwd.process(&mut buf, &mut spec);
    spec
}

/// DCT-II of `x` through the FFT of its even extension (the transform that band-splits
/// without end effects, as [`band_split`]): `C_k = sum x_m cos(pi k (m + 1/2) / N)`,
/// frequency `k fs / (2N)`. A white series of variance `s^2` gives `E[C_k^2] = s^2 N / 2`.
pub fn dct(x: &[f64]) -> Vec<f64> {
    dct_first(x, x.len())
}

/// The first `count` coefficients of [`dct`] (all of them when `count >= x.len()`): the
/// fits weigh only those up to [`FIT_MAX_HZ`], and rotating the rest (a sine and a cosine
/// each) cost a tenth of a fit's time.
pub fn dct_first(x: &[f64], count: usize) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let spec = even_spectrum(x);
    (0..count.min(n))
        .map(|k| {
            let phase = -std::f64::consts::PI * k as f64 / (2 * n) as f64;
            (spec[k] * num_complex::Complex64::from_polar(1.0, phase)).re / 2.0
        })
        .collect()
}

//! The band-normalised residual least squares minimises ([`Whitening`]).

use super::channels::{measured, simulated};
use super::noise::NoiseFloor;
use super::prediction::predict;
use super::spectral::{dct, octave_bands, FIT_MAX_HZ};
use super::Part;
use crate::campaign::Campaign;
use crate::params::Params;
use crate::Outputs;

/// Weights that turn a sample-wise residual into the band-normalised one of [`scores`]:
/// per test and channel, one weight per DCT coefficient up to [`FIT_MAX_HZ`], `1 /
/// sqrt(bands * E_b)` with `E_b` the energy a model's predicted spread (and the unfed
/// measurement noise) puts in the coefficient's octave band. The squared sum of the
/// weighted coefficients of a residual is then the mean over bands of residual over
/// predicted power: the fits minimise what the score measures (a Whittle-like,
/// prewhitened least squares), so a baseline refined with them sits at the floor in every
/// band, not only in the bands the loop's noise response dominates.
#[derive(Debug, Clone, Default)]
pub struct Whitening {
    /// Per test of the campaign, per channel (empty when absent or not computed).
    weights: Vec<[Vec<f64>; 5]>,
    part: Option<Part>,
}

impl Whitening {
    /// From `p`'s prediction of `tests` over `part`.
    pub fn new(p: &Params, c: &Campaign, tests: &[usize], noise: &NoiseFloor, part: Part) -> Self {
        use rayon::prelude::*;
        let per: Vec<(usize, [Vec<f64>; 5])> = tests
            .par_iter()
            .map(|&i| {
                // each test's octave bands at its own rate
                let fs = c.sample_rate_of(i);
                let bands = octave_bands(fs);
                let r = &c.records[i];
                let range = part.range(r.len());
                let pred = predict(p, c, i, part.simulated(), noise);
                let mut w: [Vec<f64>; 5] = Default::default();
                let n = range.len();
                if n < 2 {
                    return (i, w);
                }
                let band_of = |k: usize| {
                    let f = k as f64 * fs / (2 * n) as f64;
                    bands
                        .iter()
                        .position(|&(lo, hi)| f >= lo && f < hi)
                        .unwrap_or(0)
                };
                let kmax = ((FIT_MAX_HZ * 2.0 * n as f64 / fs).ceil() as usize).min(n);
                for (ch, wc) in w.iter_mut().enumerate() {
                    if measured(r, ch).is_none() || !noise.of(ch).is_finite() {
                        continue;
                    }
                    let white = white_variance(noise, ch);
                    let mut energy = vec![0.0; bands.len()];
                    let mut count = vec![0usize; bands.len()];
                    for spread in pred.spread(range.clone(), ch) {
                        for (k, v) in dct(&spread).iter().enumerate() {
                            energy[band_of(k)] += v * v / pred.noisy.len() as f64;
                        }
                    }
                    for k in 0..n {
                        count[band_of(k)] += 1;
                    }
                    let nb = bands.len() as f64;
                    *wc = (0..kmax)
                        .map(|k| {
                            let b = band_of(k);
                            let e = energy[b] + white * n as f64 / 2.0 * count[b] as f64;
                            1.0 / (nb * e.max(f64::MIN_POSITIVE)).sqrt()
                        })
                        .collect();
                }
                (i, w)
            })
            .collect();
        let mut weights = vec![Default::default(); c.records.len()];
        for (i, w) in per {
            weights[i] = w;
        }
        Whitening {
            weights,
            part: Some(part),
        }
    }

    /// The weighted DCT coefficients of the residual of `sim` (a run over `part`) on test
    /// `i`, appended to `out`.
    pub fn residuals(&self, c: &Campaign, i: usize, sim: &[Outputs], out: &mut Vec<f64>) {
        let (Some(part), Some(w)) = (self.part, self.weights.get(i)) else {
            return;
        };
        let r = &c.records[i];
        let range = part.range(r.len());
        for (ch, wc) in w.iter().enumerate() {
            let Some(m) = measured(r, ch) else { continue };
            if wc.is_empty() {
                continue;
            }
            let x: Vec<f64> = range
                .clone()
                .map(|k| m[k] - simulated(&sim[k], ch))
                .collect();
            let d = dct(&x);
            out.extend(d.iter().zip(wc).map(|(v, w)| v * w));
        }
    }
}

/// Variance of the noise a prediction does not hold in channel `ch`: the spool's (never
/// fed back) and a tiny floor for the command (recorded without noise).
pub(super) fn white_variance(noise: &NoiseFloor, ch: usize) -> f64 {
    if ch == 3 {
        noise.measurement(ch).powi(2)
    } else {
        1e-6 * noise.of(ch).powi(2)
    }
}

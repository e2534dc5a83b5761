//! The band-normalised residual least squares minimises ([`Whitening`]).

use super::channels::{Channel, PerChannel};
use super::noise::NoiseFloor;
use super::prediction::predict;
use super::spectral::{dct, dct_first, octave_bands, FIT_MAX_HZ};
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
    weights: Vec<PerChannel<Vec<f64>>>,
    part: Option<Part>,
}

impl Whitening {
    /// From `p`'s prediction of `tests` over `part`.
    pub fn new(p: &Params, c: &Campaign, tests: &[usize], noise: &NoiseFloor, part: Part) -> Self {
        use rayon::prelude::*;
        let per: Vec<(usize, PerChannel<Vec<f64>>)> = tests
            .par_iter()
            .map(|&i| (i, test_weights(p, c, i, noise, part)))
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

    /// Whether [`Whitening::residuals`] gives test `i` any coefficient (a recorded channel
    /// with weights).
    pub fn weighs(&self, c: &Campaign, i: usize) -> bool {
        let (Some(_), Some(w)) = (self.part, self.weights.get(i)) else {
            return false;
        };
        w.iter()
            .any(|(ch, wc)| !wc.is_empty() && ch.measured(&c.records[i]).is_some())
    }

    /// The weighted DCT coefficients of the residual of `sim` (a run over `part`) on test
    /// `i`, appended to `out`.
    pub fn residuals(&self, c: &Campaign, i: usize, sim: &[Outputs], out: &mut Vec<f64>) {
        let (Some(part), Some(w)) = (self.part, self.weights.get(i)) else {
            return;
        };
        let r = &c.records[i];
        let range = part.range(r.len());
        for (ch, wc) in w.iter() {
            let Some(m) = ch.measured(r) else { continue };
            if wc.is_empty() {
                continue;
            }
            let x: Vec<f64> = range
                .clone()
                .map(|k| m[k] - ch.simulated(&sim[k]))
                .collect();
            out.extend(weighted(&x, wc));
        }
    }

    /// Per channel of test `i`, the squared sum of the weighted DCT coefficients of the
    /// difference `a - b` of two runs through the whitening's part: the mean over octave
    /// bands of the difference's power over the power a model predicts there (a
    /// difference of 1 is as large as the noise). `None` for channels not weighed.
    pub fn difference(
        &self,
        c: &Campaign,
        i: usize,
        a: &[Outputs],
        b: &[Outputs],
    ) -> PerChannel<Option<f64>> {
        let mut out = PerChannel::filled(None);
        let (Some(part), Some(w)) = (self.part, self.weights.get(i)) else {
            return out;
        };
        let range = part.range(c.records[i].len());
        if range.end > a.len().min(b.len()) {
            return out;
        }
        for (ch, wc) in w.iter() {
            if wc.is_empty() {
                continue;
            }
            let x: Vec<f64> = range
                .clone()
                .map(|k| ch.simulated(&a[k]) - ch.simulated(&b[k]))
                .collect();
            out[ch] = Some(weighted(&x, wc).map(|v| v * v).sum());
        }
        out
    }
}

/// The weights of test `i` per channel (empty where the channel is absent or has no
/// noise estimate, or the part is too short) from `p`'s prediction over `part`.
fn test_weights(
    p: &Params,
    c: &Campaign,
    i: usize,
    noise: &NoiseFloor,
    part: Part,
) -> PerChannel<Vec<f64>> {
    let r = &c.records[i];
    let range = part.range(r.len());
    let pred = predict(p, c, i, part.simulated(), noise);
    let mut w: PerChannel<Vec<f64>> = Default::default();
    if range.len() < 2 {
        return w;
    }
    // each test's octave bands at its own rate
    let coefficients = CoefficientBands::new(c.sample_rate_of(i), range.len());
    for ch in Channel::ALL {
        let (Some(_), Some(s)) = (ch.measured(r), noise.of(ch)) else {
            continue;
        };
        w[ch] = match pred.spread(range.clone(), ch) {
            Some(spreads) => {
                let white = white_variance(noise, ch, s);
                coefficients.weights(&spreads, pred.noisy.len(), white)
            }
            // a run that stopped predicts no spread: every coefficient gets the power
            // floor's weight, the largest there is
            None => coefficients.floor_weights(),
        };
    }
    w
}

/// The DCT coefficients of a part of `n` samples at `fs` and the octave band each falls
/// in; those up to [`FIT_MAX_HZ`] are weighed.
struct CoefficientBands {
    fs: f64,
    n: usize,
    bands: Vec<(f64, f64)>,
    /// Coefficients weighed: those below [`FIT_MAX_HZ`].
    kmax: usize,
}

impl CoefficientBands {
    fn new(fs: f64, n: usize) -> Self {
        let kmax = ((FIT_MAX_HZ * 2.0 * n as f64 / fs).ceil() as usize).min(n);
        CoefficientBands {
            fs,
            n,
            bands: octave_bands(fs),
            kmax,
        }
    }

    /// The octave band of coefficient `k` (frequency `k fs / 2n`).
    fn band_of(&self, k: usize) -> usize {
        let f = k as f64 * self.fs / (2 * self.n) as f64;
        self.bands
            .iter()
            .position(|&(lo, hi)| f >= lo && f < hi)
            .unwrap_or(0)
    }

    /// Every coefficient's weight when nothing is predicted: the power floor's.
    fn floor_weights(&self) -> Vec<f64> {
        let nb = self.bands.len() as f64;
        vec![1.0 / (nb * f64::MIN_POSITIVE).sqrt(); self.kmax]
    }

    /// The weights from the predicted `spreads` (of `realisations` noisy runs) and the
    /// variance `white` of the noise the prediction does not hold: `1 / sqrt(bands *
    /// E_b)`, `E_b` the energy per coefficient in the coefficient's band.
    fn weights(&self, spreads: &[Vec<f64>], realisations: usize, white: f64) -> Vec<f64> {
        let (n, nb) = (self.n, self.bands.len() as f64);
        let mut energy = vec![0.0; self.bands.len()];
        let mut count = vec![0usize; self.bands.len()];
        for spread in spreads {
            for (k, v) in dct(spread).iter().enumerate() {
                energy[self.band_of(k)] += v * v / realisations as f64;
            }
        }
        for k in 0..n {
            count[self.band_of(k)] += 1;
        }
        (0..self.kmax)
            .map(|k| {
                let b = self.band_of(k);
                let e = energy[b] + white * n as f64 / 2.0 * count[b] as f64;
                1.0 / (nb * e.max(f64::MIN_POSITIVE)).sqrt()
            })
            .collect()
    }
}

/// The DCT coefficients of `x` that `weights` weigh, weighted: what the fits' residual
/// and [`Whitening::difference`] are made of.
fn weighted<'a>(x: &[f64], weights: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
    dct_first(x, weights.len())
        .into_iter()
        .zip(weights)
        .map(|(v, w)| v * w)
}

/// Variance of the noise a prediction does not hold in channel `ch`, whose noise floor is
/// `floor`: the spool's (never fed back) and a tiny floor for the others (the command is
/// recorded without noise; the sensors' noise is in the prediction). A spool with a floor
/// has its sensor level too (the floor is the larger of the rest's and the sensor's); none
/// would leave it no white variance.
pub(super) fn white_variance(noise: &NoiseFloor, ch: Channel, floor: f64) -> f64 {
    if ch == Channel::Spool {
        noise.measurement(ch).map_or(0.0, |s| s.powi(2))
    } else {
        TINY_WHITE_VARIANCE * floor.powi(2)
    }
}

/// The white variance [`white_variance`] gives a channel other than the spool, as a share
/// of its floor's square: a thousandth of the floor's RMS, so that no band's variance is
/// zero while the prediction's own spread dominates.
const TINY_WHITE_VARIANCE: f64 = 1e-6;

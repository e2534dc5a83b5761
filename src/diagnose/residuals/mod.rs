//! What the simulation gets wrong, in noise units: the noise floor estimated from the data,
//! the normalised residual per test and channel (the heat map), and the predictive score
//! that ranks candidates.
//!
//! Why a predictive score and not only the sample-wise residual: some effects make the
//! table's response depend on the in-loop sensor noise, not only on the reference. With
//! stick-slip (static friction above kinetic) the friction's falling branch is a negative
//! damping larger than the oil column's, and the loop chatters near the oil-column
//! frequency whenever the table creeps; the bursts grow out of the noise, so their phase
//! is random while their envelope is not. A noise-free simulation, even of the true model,
//! cannot match such a record sample by sample, and a model that predicts the chatter with
//! the wrong phase scores *worse* sample-wise than one that predicts none. So every model
//! is simulated twice, noise-free (`locked`) and with seeded sensor noise at the estimated
//! levels inside the loop (`noisy`), and each window of a record is scored by the Gaussian
//! log score of its residual power under the model's predicted spread (a proper scoring
//! rule): `P_meas/P_pred + ln(P_pred/s^2)` with `P_meas` the mean squared residual to the
//! locked run, `P_pred` the mean squared difference of the noisy run's readings (its
//! feedback noise included, as on the table) to the locked run. Residual and spread are
//! first split into octave bands and every band counts alike ([`scores`]), so an effect
//! that lives away from the oil-column resonance is not drowned by the loop's noise
//! response there.

mod cell;
mod channels;
pub(crate) mod noise;
mod prediction;
mod run;
mod scoring;
mod spectral;
mod unrecorded;
mod whitening;

pub use cell::*;
pub use channels::*;
pub use noise::*;
pub use prediction::*;
pub use run::*;
pub use scoring::*;
pub use spectral::*;
pub use whitening::*;

use super::Part;

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::PI;

    /// Octaves from Nyquist down to 1 Hz plus one from 0, contiguous.
    #[test]
    fn octave_bands_tile_the_spectrum() {
        let b = octave_bands(512.0);
        assert_eq!(b.len(), 9);
        assert_eq!(b[0], (128.0, 256.0));
        assert_eq!(*b.last().unwrap(), (0.0, 1.0));
        for w in b.windows(2) {
            assert_eq!(w[0].0, w[1].1);
        }
    }

    /// Two tones in different octaves land each in its own band with its power, and the
    /// bands sum back to the signal (masking partitions the spectrum).
    #[test]
    fn band_split_separates_tones_and_sums_back() {
        let fs = 512.0;
        let n = 4096;
        let x: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 / fs;
                2.0 * (2.0 * PI * 6.0 * t).sin() + 0.5 * (2.0 * PI * 45.0 * t).sin()
            })
            .collect();
        let bands = octave_bands(fs);
        let parts = band_split(&x, &bands, fs);
        let power =
            |v: &[f64]| v[n / 4..3 * n / 4].iter().map(|a| a * a).sum::<f64>() / (n / 2) as f64;
        let at = |f: f64| {
            bands
                .iter()
                .position(|&(lo, hi)| f >= lo && f < hi)
                .unwrap()
        };
        // a sine of amplitude A has power A^2/2 (away from the ends)
        assert!((power(&parts[at(6.0)]) / 2.0 - 1.0).abs() < 0.02);
        assert!((power(&parts[at(45.0)]) / 0.125 - 1.0).abs() < 0.02);
        // the masks are sharp: what leaks into the other octaves is the tones' slope
        // discontinuity at the record's ends, below 0.1 % of the larger tone's power
        for (b, p) in parts.iter().enumerate() {
            if b != at(6.0) && b != at(45.0) {
                assert!(power(p) < 2e-3, "band {b}: {}", power(p));
            }
        }
        for k in 0..n {
            let s: f64 = parts.iter().map(|p| p[k]).sum();
            assert!((s - x[k]).abs() < 1e-9);
        }
    }

    /// White noise of variance s^2 has E[C_k^2] = s^2 N / 2 (the whitening's scale).
    #[test]
    fn dct_of_white_noise_has_the_stated_energy() {
        let n = 8192;
        let s = 0.3;
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let normal = Normal::new(0.0, s).unwrap();
        let x: Vec<f64> = (0..n).map(|_| normal.sample(&mut rng)).collect();
        let c = dct(&x);
        let mean = c[1..].iter().map(|v| v * v).sum::<f64>() / (n - 1) as f64;
        assert!(
            (mean / (s * s * n as f64 / 2.0) - 1.0).abs() < 0.05,
            "{mean}"
        );
    }
}

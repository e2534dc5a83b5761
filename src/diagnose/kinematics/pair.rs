//! One test's reading of the accelerometer against the LVDT's second derivative
//! ([`super::check`] reads every test): the frequency response between them, read as one
//! gain and one delay, and through a first-order high-pass when one describes the
//! low-frequency lead better (an AC-coupled accelerometer).

use super::{HighPass, PairReading};
use crate::motion::spectrum::Periodic;
use std::f64::consts::PI;

/// Seconds dropped at each end of a test: the double derivative's ringing where the
/// record's periodic extension joins.
const EDGE_S: f64 = 2.0;
/// Frequency resolution of the response, Hz, and the fewest segments averaged.
const RESOLUTION_HZ: f64 = 0.25;
const MIN_SEGMENTS: usize = 8;
/// A bin counts when the two sensors are this coherent there: the noise on either side
/// then biases H1 or H2 by at most 1 %, and their geometric mean by much less.
const MIN_COHERENCE: f64 = 0.99;
/// Coherent bins a test needs: a slope and a level need a few points.
const MIN_BINS: usize = 3;
/// Highest first-order high-pass corner a test's reading tries, Hz: a fifth of the
/// compared band (a piezoelectric accelerometer's charge amplifier or an AC-coupled
/// input sits at 0.05-2 Hz; a corner near the band's top leaves too few bins above it to
/// tell it from a gain).
const MAX_CORNER_HZ: f64 = 5.0;
/// A test reads a high-pass when adding its corner lowers the chi-square by this many
/// times the reading's reduced chi-square (at least 1): a five-sigma improvement for one
/// parameter more, where the misfit's own scatter beyond the coherence's variance is
/// counted against it.
const MIN_CORNER_CHI2_DROP: f64 = 25.0;

/// One coherent bin of [`read_pair`]: its angular frequency, the response's phase and log
/// gain, and the inverse-variance weight its coherence gives.
struct Bin {
    w_rad_s: f64,
    phase_rad: f64,
    log_gain: f64,
    weight: f64,
}

/// One test: the frequency response from the LVDT's second derivative to the
/// accelerometer (Welch, Hann segments), over the bins of `band_hz` where the two are
/// coherent ([`MIN_COHERENCE`]), read as one gain and one delay: the delay from the
/// phase's slope and the gain from the log magnitude, each bin weighted by the inverse
/// variance its coherence gives (`(1 - g^2) / (2 n g^2)` for `n` segments: Bendat &
/// Piersol, Random Data, 4th ed., section 9.2). The magnitude is the geometric mean of H1
/// and H2, which the noise on either side biases in opposite directions. Then the same
/// through a high-pass ([`fit_corner`]), kept when it fits much better. `None` for a test
/// too short or with too few coherent bins.
pub(super) fn read_pair(x: &[f64], a: &[f64], fs: f64, band_hz: [f64; 2]) -> Option<PairReading> {
    use crate::identify::frf::{Welch, WelchOptions};
    let n = x.len().min(a.len());
    let edge = (EDGE_S * fs) as usize;
    if n <= 2 * edge + 64 || !(band_hz[1] > band_hz[0]) {
        return None;
    }
    let xdd = Periodic::new(&detrended(&x[..n]), fs)
        .derivative(2)
        .signal();
    let (xdd, a) = (&xdd[edge..n - edge], &a[edge..n - edge]);
    let options = WelchOptions::for_resolution(fs, RESOLUTION_HZ).fit_to(xdd.len(), MIN_SEGMENTS);
    let est = Welch::new(fs, options).ok()?.frf(xdd, a).ok()?;
    let segments = est.segments as f64;
    let bins: Vec<Bin> = est
        .band(band_hz[0], band_hz[1])
        .into_iter()
        .filter(|&k| est.coherence[k] >= MIN_COHERENCE)
        .map(|k| {
            let g2 = est.coherence[k];
            let weight = 2.0 * segments * g2 / (1.0 - g2).max(1e-12);
            let w = 2.0 * PI * est.frequency_hz[k];
            let log_gain = 0.5 * (est.h1[k].norm() * est.h2[k].norm()).ln();
            Bin {
                w_rad_s: w,
                phase_rad: est.h1[k].arg(),
                log_gain,
                weight,
            }
        })
        .filter(|b| b.w_rad_s > 0.0 && b.phase_rad.is_finite() && b.log_gain.is_finite())
        .collect();
    if bins.len() < MIN_BINS {
        return None;
    }
    let plain = Solved::at(&bins, 0.0);
    let corner = fit_corner(&bins, &plain);
    let fit = corner.as_ref().map_or(&plain, |c| &c.solved);
    let dof = (2 * bins.len()).saturating_sub(2 + usize::from(corner.is_some()));
    Some(PairReading {
        test: String::new(),
        ratio: fit.log_ratio.exp(),
        ratio_sigma: fit.log_ratio.exp() / fit.sw.sqrt(),
        lag_s: fit.lag_s,
        lag_sigma_s: 1.0 / fit.sww.sqrt(),
        bins: bins.len(),
        misfit: fit.chi2 / dof.max(1) as f64,
        high_pass: corner.map(|c| c.high_pass),
    })
}

/// One gain and one delay read over the bins through a first-order high-pass of corner
/// `wc`, `H = g exp(-j w lag) j w / (j w + wc)`: given `wc`, the phase less the corner's
/// lead `atan(wc / w)` is linear in the lag and the log gain plus `ln(1 + wc^2/w^2) / 2`
/// is the log ratio; each by weighted least squares, and the chi-square left.
struct Solved {
    lag_s: f64,
    log_ratio: f64,
    chi2: f64,
    /// `sum weight w^2` and `sum weight`, the lag's and the log ratio's information.
    sww: f64,
    sw: f64,
}

impl Solved {
    fn at(bins: &[Bin], wc: f64) -> Solved {
        let lead = |b: &Bin| (wc / b.w_rad_s).atan();
        let droop = |b: &Bin| 0.5 * (wc / b.w_rad_s).powi(2).ln_1p();
        let sum = |f: &dyn Fn(&Bin) -> f64| bins.iter().map(f).sum::<f64>();
        let (sww, sw) = (
            sum(&|b| b.weight * b.w_rad_s * b.w_rad_s),
            sum(&|b| b.weight),
        );
        let lag_s = -sum(&|b| b.weight * b.w_rad_s * (b.phase_rad - lead(b))) / sww;
        let log_ratio = sum(&|b| b.weight * (b.log_gain + droop(b))) / sw;
        let chi2 = sum(&|b| {
            b.weight
                * ((b.phase_rad - lead(b) + b.w_rad_s * lag_s).powi(2)
                    + (b.log_gain + droop(b) - log_ratio).powi(2))
        });
        Solved {
            lag_s,
            log_ratio,
            chi2,
            sww,
            sw,
        }
    }
}

/// A test's high-pass, and the gain and delay read beside it.
struct Corner {
    high_pass: HighPass,
    solved: Solved,
}

/// The corner of a first-order high-pass over `bins` (Brent's minimisation of the
/// chi-square over 0 to [`MAX_CORNER_HZ`]), when it lowers `plain`'s chi-square by
/// [`MIN_CORNER_CHI2_DROP`] times its reduced chi-square; its standard error from the
/// chi-square's curvature, scaled by the reduced chi-square (the scatter beyond the
/// coherence's variance).
fn fit_corner(bins: &[Bin], plain: &Solved) -> Option<Corner> {
    let max_wc = 2.0 * PI * MAX_CORNER_HZ;
    let (wc, _) = crate::diagnose::simplex::brent(
        |wc| Solved::at(bins, wc).chi2,
        [0.0, max_wc],
        [1e-8, 1e-6],
        200,
    )?;
    let solved = Solved::at(bins, wc);
    let dof = (2 * bins.len()).saturating_sub(3).max(1) as f64;
    let reduced = (solved.chi2 / dof).max(1.0);
    if plain.chi2 - solved.chi2 < MIN_CORNER_CHI2_DROP * reduced {
        return None;
    }
    let h = 1e-3 * wc;
    let curvature = (Solved::at(bins, wc + h).chi2 - 2.0 * solved.chi2
        + Solved::at(bins, wc - h).chi2)
        / (h * h);
    let sigma_wc = (2.0 * reduced / curvature).sqrt();
    (curvature > 0.0).then(|| Corner {
        high_pass: HighPass {
            corner_hz: wc / (2.0 * PI),
            sigma_hz: sigma_wc / (2.0 * PI),
        },
        solved,
    })
}

/// `y` less the line through its ends, so that its periodic extension does not jump
/// (a line has no second derivative).
fn detrended(y: &[f64]) -> Vec<f64> {
    let n = y.len();
    let (y0, y1) = (y[0], y[n - 1]);
    let slope = (y1 - y0) / (n - 1).max(1) as f64;
    y.iter()
        .enumerate()
        .map(|(k, v)| v - y0 - slope * k as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::{BAND_HIGH_HZ, BAND_LOW_HZ};
    use super::*;

    /// A random-phase displacement of 40 lines over 0.7-18 Hz (`order` 0), or its exact
    /// second derivative (`order` 2) through a first-order high-pass of corner
    /// `corner_hz` (each line's gain and phase lead), at time `t`.
    fn motion(t: f64, order: i32, seed: u64, corner_hz: f64) -> f64 {
        (0..40)
            .map(|k| {
                let f = 0.7 + 0.45 * k as f64;
                let phase = ((seed + 7 * k) as f64 * 2.399_963).rem_euclid(2.0 * PI);
                let w = 2.0 * PI * f;
                let x = |lead: f64| (1e-3 / f) * (w * t + phase + lead).sin();
                if order == 2 {
                    let r = corner_hz / f;
                    -w * w * x(r.atan()) / r.hypot(1.0)
                } else {
                    x(0.0)
                }
            })
            .sum()
    }

    /// The reading of 40 s at 512 Hz whose accelerometer reads `gain` times the table's
    /// acceleration `lag_s` late, through a high-pass at `corner_hz` (0: none).
    fn reading_through(lag_s: f64, gain: f64, corner_hz: f64, seed: u64) -> PairReading {
        let fs = 512.0;
        let t: Vec<f64> = (0..40 * 512).map(|k| k as f64 / fs).collect();
        let x: Vec<f64> = t.iter().map(|&t| motion(t, 0, seed, 0.0)).collect();
        let a: Vec<f64> = t
            .iter()
            .map(|&t| gain * motion(t - lag_s, 2, seed, corner_hz))
            .collect();
        read_pair(&x, &a, fs, [BAND_LOW_HZ, BAND_HIGH_HZ]).unwrap()
    }

    fn reading(lag_s: f64, gain: f64, seed: u64) -> PairReading {
        reading_through(lag_s, gain, 0.0, seed)
    }

    #[test]
    fn agreeing_sensors_read_one_and_no_lag() {
        let r = reading(0.0, 1.0, 3);
        assert!((r.ratio - 1.0).abs() < 2e-3, "{r:?}");
        assert!(r.lag_s.abs() < 2e-5, "{r:?}");
        assert_eq!(r.high_pass, None, "{r:?}");
    }

    /// An AC-coupled accelerometer (first-order high-pass at 0.1 to 1 Hz), also scaled and
    /// late: the corner read within 3 % or 0.015 Hz (its lead within 2 degrees at the
    /// band's 0.5-Hz edge; the lag's and the corner's leads trade a little), the gain and
    /// the lag as without it.
    #[test]
    fn an_ac_coupled_accelerometer_reads_its_corner() {
        for (corner_hz, lag_s, gain, seed) in [
            (0.5, 0.0, 1.0, 3),
            (0.1, 0.002, 1.03, 5),
            (1.0, 0.0, 0.97, 7),
        ] {
            let r = reading_through(lag_s, gain, corner_hz, seed);
            let read = r
                .high_pass
                .unwrap_or_else(|| panic!("{corner_hz} Hz: {r:?}"))
                .corner_hz;
            assert!(
                (read - corner_hz).abs() < 0.03 * corner_hz + 0.015,
                "{corner_hz} Hz: {r:?}"
            );
            assert!((r.ratio / gain - 1.0).abs() < 3e-3, "{r:?}");
            assert!((r.lag_s - lag_s).abs() < 5e-5, "{r:?}");
        }
    }

    #[test]
    fn a_late_scaled_accelerometer_is_read_as_such() {
        // 3 ms is a sample and a half at 512 Hz
        let r = reading(0.003, 1.05, 5);
        assert!((r.ratio - 1.05).abs() < 3e-3, "{r:?}");
        assert!((r.lag_s - 0.003).abs() < 5e-5, "{r:?}");
    }
}

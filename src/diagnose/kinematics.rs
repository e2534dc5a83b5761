//! Whether the accelerometer and the LVDT agree, from the recordings alone: the table's
//! acceleration is the second derivative of its displacement, so on every test that
//! recorded both, the accelerometer must read `x''`, with no gain and no time shift
//! between them. A ratio or a skew that holds over the tests is a sensor's sensitivity
//! or an acquisition channel's latency. No model enters: a model refined on the
//! recordings bends to such an error (a 3-ms accelerometer lag moved the refined loop's
//! timing, and the untouched force then seemed to lead it), so the check names the pair
//! that disagrees, not which of the two is wrong.

use crate::campaign::Campaign;
use crate::motion::spectrum::Periodic;
use serde::Serialize;
use std::f64::consts::PI;

/// The band compared, Hz: above the slow drifts a double derivative cannot hold, below
/// where the LVDT's noise, raised by the double derivative as f^4, drowns its `x''`
/// (and at most an eighth of the sample rate).
const BAND_LOW_HZ: f64 = 0.5;
const BAND_HIGH_HZ: f64 = 25.0;
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
/// A test's reading counts when its bins hold one gain and one delay to this reduced
/// chi-square: beyond it the two sensors differ by a dynamics (a foundation under the
/// LVDT's reaction, impacts in free play), which no sensor number describes. Twice the
/// largest seen on sensors that differ by a gain and a delay alone (random and
/// triangle tests, 0.8 to 2.1; overlapping segments correlate neighbouring bins), where
/// free play's impacts and the sines' few harmonic bins gave 11 to 3 300.
const MAX_MISFIT: f64 = 4.0;
/// A ratio is a finding when its mean is this far from 1, and a skew when its mean is
/// at least this, s: a calibration a lab would correct (sensitivities drift by a
/// fraction of 2 %), and a quarter of a 1-kHz sample.
const MIN_RATIO_OFFSET: f64 = 0.02;
const MIN_SKEW_S: f64 = 2.5e-4;
/// ...and each test's value lies within this of the mean (beside four of its own
/// standard errors): one sensitivity and one latency for all tests.
const RATIO_SPREAD: f64 = 0.01;
const SKEW_SPREAD_S: f64 = 2.5e-4;
/// Tests that must agree for a finding: one may be a fluke of its content.
const MIN_TESTS: usize = 2;

/// One test's reading: the accelerometer as `ratio` times `x''`, `lag_s` later
/// (positive: the accelerometer lags the LVDT), with their standard errors, the
/// coherent bins they rest on and how well one gain and one delay hold over them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairReading {
    pub test: String,
    pub ratio: f64,
    pub ratio_sigma: f64,
    pub lag_s: f64,
    pub lag_sigma_s: f64,
    pub bins: usize,
    pub misfit: f64,
}

/// The check over a campaign: every test's reading that counts, their weighted means,
/// and what holds over them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KinematicCheck {
    pub band_hz: [f64; 2],
    /// Tests that recorded both sensors.
    pub tests: usize,
    pub readings: Vec<PairReading>,
    /// Means over the readings (inverse-variance weights), when there are [`MIN_TESTS`].
    pub ratio: Option<f64>,
    pub lag_s: Option<f64>,
    /// What the engineer should check, when a ratio or a skew holds over the tests.
    pub finding: Option<String>,
}

impl KinematicCheck {
    /// Whether a time skew between the two was found (then a model refined on the
    /// recordings has bent its timing to it).
    pub fn skewed(&self) -> bool {
        self.lag_s.is_some_and(|l| skew_holds(&self.readings, l))
    }

    /// The terminal's line: the means and ranges, and the finding.
    pub fn text(&self) -> String {
        let head = format!(
            "sensors: the accelerometer against the LVDT's second derivative, {:.1}-{:.1} Hz",
            self.band_hz[0], self.band_hz[1]
        );
        let (Some(ratio), Some(lag_s)) = (self.ratio, self.lag_s) else {
            return format!(
                "{head}: {} of {} tests read as one gain and one delay (at least {MIN_TESTS} needed)",
                self.readings.len(),
                self.tests
            );
        };
        let range = |f: &dyn Fn(&PairReading) -> f64| {
            let lo = self.readings.iter().map(f).fold(f64::INFINITY, f64::min);
            (
                lo,
                self.readings
                    .iter()
                    .map(f)
                    .fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (r0, r1) = range(&|r| r.ratio);
        let (l0, l1) = range(&|r| 1e3 * r.lag_s);
        let verdict = match &self.finding {
            Some(f) => format!("\nsensor: {f}"),
            None => ": they agree".to_string(),
        };
        format!(
            "{head}: ratio {ratio:.4} ({r0:.4} to {r1:.4}), accelerometer lag {:+.3} ms \
             ({l0:+.3} to {l1:+.3}) on {} of {} tests{verdict}",
            1e3 * lag_s,
            self.readings.len(),
            self.tests
        )
    }
}

/// The check on `c`; `None` when no test recorded both the displacement and the
/// acceleration.
pub fn check(c: &Campaign) -> Option<KinematicCheck> {
    let mut band_hz = [BAND_LOW_HZ, BAND_HIGH_HZ];
    let mut tests = 0;
    let mut readings = Vec::new();
    for (i, r) in c.records.iter().enumerate() {
        let (Some(x), Some(a)) = (r.displacement_m.as_deref(), r.acceleration_m_s2.as_deref())
        else {
            continue;
        };
        tests += 1;
        let fs = c.sample_rate_of(i);
        let high_hz = BAND_HIGH_HZ.min(fs / 8.0);
        band_hz[1] = band_hz[1].min(high_hz);
        let reading = read_pair(x, a, fs, [BAND_LOW_HZ, high_hz]);
        if super::trace_enabled() {
            eprintln!("  kinematics {}: {reading:?}", c.info.tests[i].name);
        }
        if let Some(mut r) = reading.filter(|r| r.misfit <= MAX_MISFIT) {
            r.test = c.info.tests[i].name.clone();
            readings.push(r);
        }
    }
    if tests == 0 {
        return None;
    }
    let enough = readings.len() >= MIN_TESTS;
    let mean = |v: &dyn Fn(&PairReading) -> (f64, f64)| {
        let (num, den) = readings.iter().map(v).fold((0.0, 0.0), |(n, d), (x, s)| {
            (n + x / (s * s), d + 1.0 / (s * s))
        });
        num / den
    };
    let ratio = enough.then(|| mean(&|r| (r.ratio, r.ratio_sigma)));
    let lag_s = enough.then(|| mean(&|r| (r.lag_s, r.lag_sigma_s)));
    let mut out = KinematicCheck {
        band_hz,
        tests,
        readings,
        ratio,
        lag_s,
        finding: None,
    };
    out.finding = describe(&out);
    Some(out)
}

fn skew_holds(readings: &[PairReading], lag_s: f64) -> bool {
    lag_s.abs() >= MIN_SKEW_S
        && readings
            .iter()
            .all(|r| (r.lag_s - lag_s).abs() <= SKEW_SPREAD_S + 4.0 * r.lag_sigma_s)
}

fn ratio_holds(readings: &[PairReading], ratio: f64) -> bool {
    (ratio - 1.0).abs() >= MIN_RATIO_OFFSET
        && readings
            .iter()
            .all(|r| (r.ratio - ratio).abs() <= RATIO_SPREAD * ratio + 4.0 * r.ratio_sigma)
}

/// The finding's message, when a ratio or a skew holds over the readings.
fn describe(k: &KinematicCheck) -> Option<String> {
    let (ratio, lag_s) = (k.ratio?, k.lag_s?);
    let mut parts = Vec::new();
    if ratio_holds(&k.readings, ratio) {
        parts.push(format!(
            "the accelerometer reads {ratio:.4} times the LVDT's second derivative"
        ));
    }
    if skew_holds(&k.readings, lag_s) {
        let who = if lag_s > 0.0 {
            "the accelerometer"
        } else {
            "the LVDT"
        };
        parts.push(format!(
            "{who} runs {:.2} ms behind the other",
            1e3 * lag_s.abs()
        ));
    }
    (!parts.is_empty()).then(|| {
        format!(
            "{} on {} tests ({:.1}-{:.1} Hz): one of the two sensors' sensitivity or \
             acquisition timing is off; check both before the table's physics (a model \
             refined on these recordings bends to the error, and a delay found against it \
             on another channel is then the model's)",
            parts.join(", and "),
            k.readings.len(),
            k.band_hz[0],
            k.band_hz[1]
        )
    })
}

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
/// Piersol, Random Data, 4th ed., section 9.2). The magnitude is the geometric mean of H1 and H2, which the noise on
/// either side biases in opposite directions. `None` for a test too short or with too
/// few coherent bins.
fn read_pair(x: &[f64], a: &[f64], fs: f64, band_hz: [f64; 2]) -> Option<PairReading> {
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
    let sum = |f: &dyn Fn(&Bin) -> f64| bins.iter().map(f).sum::<f64>();
    let (sww, sw) = (
        sum(&|b| b.weight * b.w_rad_s * b.w_rad_s),
        sum(&|b| b.weight),
    );
    let lag_s = -sum(&|b| b.weight * b.w_rad_s * b.phase_rad) / sww;
    let log_ratio = sum(&|b| b.weight * b.log_gain) / sw;
    let chi2 = sum(&|b| {
        b.weight * ((b.phase_rad + b.w_rad_s * lag_s).powi(2) + (b.log_gain - log_ratio).powi(2))
    });
    Some(PairReading {
        test: String::new(),
        ratio: log_ratio.exp(),
        ratio_sigma: log_ratio.exp() / sw.sqrt(),
        lag_s,
        lag_sigma_s: 1.0 / sww.sqrt(),
        bins: bins.len(),
        misfit: chi2 / (2 * bins.len() - 2).max(1) as f64,
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
    use super::*;

    /// A random-phase displacement of 40 lines over 0.7-18 Hz (`order` 0), or its exact
    /// second derivative (`order` 2), at time `t`.
    fn motion(t: f64, order: i32, seed: u64) -> f64 {
        (0..40)
            .map(|k| {
                let f = 0.7 + 0.45 * k as f64;
                let phase = ((seed + 7 * k) as f64 * 2.399_963).rem_euclid(2.0 * PI);
                let w = 2.0 * PI * f;
                let x = (1e-3 / f) * (w * t + phase).sin();
                if order == 2 {
                    -w * w * x
                } else {
                    x
                }
            })
            .sum()
    }

    /// The reading of 40 s at 512 Hz whose accelerometer reads `gain` times the table's
    /// acceleration `lag_s` late.
    fn reading(lag_s: f64, gain: f64, seed: u64) -> PairReading {
        let fs = 512.0;
        let t: Vec<f64> = (0..40 * 512).map(|k| k as f64 / fs).collect();
        let x: Vec<f64> = t.iter().map(|&t| motion(t, 0, seed)).collect();
        let a: Vec<f64> = t
            .iter()
            .map(|&t| gain * motion(t - lag_s, 2, seed))
            .collect();
        read_pair(&x, &a, fs, [BAND_LOW_HZ, BAND_HIGH_HZ]).unwrap()
    }

    fn at(lag_ms: f64, ratio: f64) -> PairReading {
        PairReading {
            test: String::new(),
            ratio,
            ratio_sigma: 1e-4,
            lag_s: 1e-3 * lag_ms,
            lag_sigma_s: 1e-5,
            bins: 30,
            misfit: 1.0,
        }
    }

    fn checked(readings: Vec<PairReading>) -> KinematicCheck {
        let n = readings.len();
        let mut k = KinematicCheck {
            band_hz: [BAND_LOW_HZ, BAND_HIGH_HZ],
            tests: n,
            ratio: (n >= MIN_TESTS)
                .then(|| readings.iter().map(|r| r.ratio).sum::<f64>() / n as f64),
            lag_s: (n >= MIN_TESTS)
                .then(|| readings.iter().map(|r| r.lag_s).sum::<f64>() / n as f64),
            readings,
            finding: None,
        };
        k.finding = describe(&k);
        k
    }

    #[test]
    fn a_finding_needs_one_number_over_two_tests_and_off_its_no_error_value() {
        // one skew over the tests: found, and the accelerometer named as the late one
        let k = checked(vec![at(2.0, 1.0), at(2.1, 1.001), at(1.95, 0.999)]);
        assert!(k.skewed());
        assert!(k.finding.unwrap().contains("accelerometer runs 2.02 ms"));
        // one test is not enough
        assert!(checked(vec![at(2.0, 1.05)]).finding.is_none());
        // skews a sample apart are no one latency, ratios 5 % apart no one sensitivity
        assert!(checked(vec![at(2.0, 1.0), at(4.0, 1.0)]).finding.is_none());
        assert!(checked(vec![at(0.0, 1.05), at(0.0, 1.10)])
            .finding
            .is_none());
        // within the noise of agreeing sensors: nothing to check
        assert!(checked(vec![at(0.05, 1.005), at(-0.05, 0.998)])
            .finding
            .is_none());
        // a negative lag is the LVDT's
        let late_lvdt = checked(vec![at(-1.0, 1.0), at(-1.1, 1.0)]).finding.unwrap();
        assert!(late_lvdt.contains("the LVDT runs"), "{late_lvdt}");
    }

    #[test]
    fn agreeing_sensors_read_one_and_no_lag() {
        let r = reading(0.0, 1.0, 3);
        assert!((r.ratio - 1.0).abs() < 2e-3, "{r:?}");
        assert!(r.lag_s.abs() < 2e-5, "{r:?}");
    }

    #[test]
    fn a_late_scaled_accelerometer_is_read_as_such() {
        // 3 ms is a sample and a half at 512 Hz
        let r = reading(0.003, 1.05, 5);
        assert!((r.ratio - 1.05).abs() < 3e-3, "{r:?}");
        assert!((r.lag_s - 0.003).abs() < 5e-5, "{r:?}");
    }
}

//! Whether the accelerometer and the LVDT agree, from the recordings alone: the table's
//! acceleration is the second derivative of its displacement, so on every test that
//! recorded both, the accelerometer must read `x''`, with no gain and no time shift
//! between them. A ratio or a skew that holds over the tests is a sensor's sensitivity
//! or an acquisition channel's latency; a low-frequency lead that one first-order
//! high-pass describes is an AC-coupled accelerometer's (a piezoelectric sensor's charge
//! amplifier), whose reading below a few hertz is not the table's. No model enters: a
//! model refined on the recordings bends to such an error (a 3-ms accelerometer lag moved
//! the refined loop's timing, and the untouched force then seemed to lead it), so the
//! check names the pair that disagrees, not which of the two is wrong. Each test's
//! reading: [`pair`].

use crate::campaign::Campaign;
use pair::read_pair;
use serde::Serialize;

mod pair;

/// The band compared, Hz: above the slow drifts a double derivative cannot hold, below
/// where the LVDT's noise, raised by the double derivative as f^4, drowns its `x''`
/// (and at most an eighth of the sample rate).
const BAND_LOW_HZ: f64 = 0.5;
const BAND_HIGH_HZ: f64 = 25.0;
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
/// A high-pass is a finding from this corner on, Hz: below it the phase leads the
/// table's acceleration by less than 3 degrees at 1 Hz, and the gain is off by 0.1 %.
const MIN_CORNER_HZ: f64 = 0.05;
/// ...and when each test's corner lies within this fraction of the mean (beside four of
/// its own standard errors): one sensor's coupling for all tests.
const CORNER_SPREAD: f64 = 0.1;
/// Phase lead, degrees, below which frequency the finding says the accelerometer's
/// reading is not the table's: `corner / tan(5 deg)`, 11.4 times the corner.
const CORNER_PHASE_DEG: f64 = 5.0;

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
    /// The first-order high-pass between the two, when the test reads one
    /// (`pair::MIN_CORNER_CHI2_DROP`); `ratio`, `lag_s` and `misfit` are then read
    /// beside it.
    pub high_pass: Option<HighPass>,
}

/// A first-order high-pass read between the two sensors: its corner and the corner's
/// standard error, Hz.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HighPass {
    pub corner_hz: f64,
    pub sigma_hz: f64,
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
    /// Mean corner of the readings that read a high-pass, Hz, when [`MIN_TESTS`] do and
    /// they are at least half of the readings.
    pub high_pass_hz: Option<f64>,
    /// What the engineer should check, when a ratio, a skew or a high-pass holds over the
    /// tests.
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
        let corner = self
            .high_pass_hz
            .map_or(String::new(), |c| format!(", a high-pass at {c:.3} Hz"));
        format!(
            "{head}: ratio {ratio:.4} ({r0:.4} to {r1:.4}), accelerometer lag {:+.3} ms \
             ({l0:+.3} to {l1:+.3}){corner} on {} of {} tests{verdict}",
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
    let ratio = enough.then(|| weighted_mean(readings.iter().map(|r| (r.ratio, r.ratio_sigma))));
    let lag_s = enough.then(|| weighted_mean(readings.iter().map(|r| (r.lag_s, r.lag_sigma_s))));
    let corners: Vec<(f64, f64)> = (readings.iter())
        .filter_map(|r| r.high_pass.map(|h| (h.corner_hz, h.sigma_hz)))
        .collect();
    let high_pass_hz = (corners.len() >= MIN_TESTS && 2 * corners.len() >= readings.len())
        .then(|| weighted_mean(corners.into_iter()));
    let mut out = KinematicCheck {
        band_hz,
        tests,
        readings,
        ratio,
        lag_s,
        high_pass_hz,
        finding: None,
    };
    out.finding = describe(&out);
    Some(out)
}

/// The inverse-variance weighted mean of `(value, standard error)` pairs.
fn weighted_mean(values: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (num, den) = values.fold((0.0, 0.0), |(n, d), (x, s)| {
        (n + x / (s * s), d + 1.0 / (s * s))
    });
    num / den
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

/// Whether one high-pass of at least [`MIN_CORNER_HZ`] holds over the readings that read
/// one ([`CORNER_SPREAD`]).
fn corner_holds(readings: &[PairReading], corner_hz: f64) -> bool {
    corner_hz >= MIN_CORNER_HZ
        && readings.iter().filter_map(|r| r.high_pass).all(|h| {
            (h.corner_hz - corner_hz).abs() <= CORNER_SPREAD * corner_hz + 4.0 * h.sigma_hz
        })
}

/// The finding's message, when a ratio, a skew or a high-pass holds over the readings.
fn describe(k: &KinematicCheck) -> Option<String> {
    let sensitivity_or_timing = describe_gain_and_skew(k);
    let coupling = (k.high_pass_hz)
        .filter(|&c| corner_holds(&k.readings, c))
        .map(|c| describe_high_pass(k, c));
    match (sensitivity_or_timing, coupling) {
        (Some(a), Some(b)) => Some(format!("{b}; and {a}")),
        (a, b) => b.or(a),
    }
}

/// The finding on an AC-coupled accelerometer: its corner, and below which frequency its
/// reading leads the table's acceleration by more than [`CORNER_PHASE_DEG`].
fn describe_high_pass(k: &KinematicCheck, corner_hz: f64) -> String {
    let n = k.readings.iter().filter(|r| r.high_pass.is_some()).count();
    let below_hz = corner_hz / CORNER_PHASE_DEG.to_radians().tan();
    format!(
        "the accelerometer reads the LVDT's second derivative through a first-order \
         high-pass at {corner_hz:.3} Hz on {n} tests ({:.1}-{:.1} Hz): an AC-coupled \
         accelerometer (a piezoelectric sensor's charge amplifier, or the acquisition's AC \
         coupling); below {below_hz:.1} Hz its phase leads the table's acceleration by \
         more than {CORNER_PHASE_DEG:.0} degrees, and what is read off the acceleration there \
         (the oil column's damping, the leakage, a stiffness) bends to it: record it \
         DC-coupled or correct the channel before the table's physics",
        k.band_hz[0], k.band_hz[1]
    )
}

/// The finding's message on a sensitivity or a latency, when a ratio or a skew holds over
/// the readings.
fn describe_gain_and_skew(k: &KinematicCheck) -> Option<String> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn at(lag_ms: f64, ratio: f64) -> PairReading {
        PairReading {
            test: String::new(),
            ratio,
            ratio_sigma: 1e-4,
            lag_s: 1e-3 * lag_ms,
            lag_sigma_s: 1e-5,
            bins: 30,
            misfit: 1.0,
            high_pass: None,
        }
    }

    fn with_corner(corner_hz: f64, r: PairReading) -> PairReading {
        PairReading {
            high_pass: Some(HighPass {
                corner_hz,
                sigma_hz: 1e-3,
            }),
            ..r
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
            high_pass_hz: readings[0].high_pass.map(|h| h.corner_hz),
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
    fn one_high_pass_over_the_tests_is_a_finding() {
        let k = checked(vec![
            with_corner(0.5, at(0.0, 1.0)),
            with_corner(0.51, at(0.0, 1.0)),
        ]);
        let f = k.finding.expect("a finding");
        assert!(f.contains("high-pass at 0.500 Hz on 2 tests"), "{f}");
        assert!(!f.contains("sensitivity or"), "{f}");
        // corners far apart are no one coupling; one too small to matter is none
        let apart = checked(vec![
            with_corner(0.5, at(0.0, 1.0)),
            with_corner(0.9, at(0.0, 1.0)),
        ]);
        assert!(apart.finding.is_none());
        let tiny = checked(vec![
            with_corner(0.01, at(0.0, 1.0)),
            with_corner(0.01, at(0.0, 1.0)),
        ]);
        assert!(tiny.finding.is_none());
        // with a late accelerometer beside it, both are said
        let both = checked(vec![
            with_corner(0.5, at(2.0, 1.0)),
            with_corner(0.5, at(2.0, 1.0)),
        ]);
        let f = both.finding.unwrap();
        assert!(f.contains("high-pass") && f.contains("runs 2.00 ms"), "{f}");
    }
}

//! The model-error response of a cell the final model still misses (issue 17 part 4):
//! the frequency response from the test's input (its reference) to the residual
//! `e = measured - simulated`, with a confidence band. What the extended model lacks
//! shows in its shape: a peak is a missing resonance (a specimen or foundation mode), a
//! slope a missing compliance or dynamics, a broad floor at low coherence a nonlinearity
//! or noise no linear response from the reference explains.
//!
//! The response is the H1 estimate `S_xe / S_xx` (Welch, [`crate::identify::frf`]): the
//! reference is noise-free, so the sensor noise and the loop's response to it, which sit
//! on the residual, leave it unbiased and only lower the coherence. The band is
//! `|H| (1 +- Z eps)` with Bendat & Piersol's normalised random error of a gain factor
//! estimate, `eps = sqrt(1 - coh) / (sqrt(coh) sqrt(2 n_d))` (coh the ordinary coherence
//! `gamma^2`, `n_d` the number of averages; J. S. Bendat, A. G. Piersol, *Random Data:
//! Analysis and Measurement Procedures*, 4th ed., Wiley 2010, section 9.2, Table 9.6);
//! the normal approximation holds for `eps` below about 0.2 and widens honestly beyond.

use super::residuals::{simulate_test, Channel, TestRun, FIT_MAX_HZ};
use super::{Diagnosis, Part};
use crate::campaign::{Campaign, Control, Record};
use crate::identify::frf::{FrfError, Welch, WelchOptions};
use crate::params::Params;
use serde::Serialize;

/// Finest frequency resolution asked for, Hz: the identification's, fine enough to place
/// a mode of a few Hz within a tenth of its frequency.
const FINEST_RESOLUTION_HZ: f64 = 0.25;
/// Coarsest resolution accepted, Hz: coarser, a mode of a few hertz is no longer placed
/// within a fifth of its frequency, and the figure would mislead.
const COARSEST_RESOLUTION_HZ: f64 = 1.0;
/// Averages wanted: the resolution is coarsened (down to [`COARSEST_RESOLUTION_HZ`])
/// until the record gives this many. At coherence 0.5 the gain's random error is then
/// 0.18, a band of about +-36 %: narrow enough to tell a peak from the floor.
const WANTED_AVERAGES: usize = 16;
/// Fewest averages with which a response is given at all: with fewer, the gain's random
/// error exceeds 0.25 even at coherence 0.5 and the band says little.
const MIN_AVERAGES: usize = 8;
/// Equivalent independent averages per Hann segment at 50 % overlap: the overlap
/// correlation of adjacent Hann segments is 0.167 (F. J. Harris, Proc. IEEE 66, 1978,
/// Table I) and enters the variance squared, so K segments average like
/// `K / (1 + 2 * 0.167^2)` independent ones (P. D. Welch, IEEE Trans. AU-15, 1967).
const OVERLAP_EFFICIENCY: f64 = 1.0 / (1.0 + 2.0 * 0.167 * 0.167);
/// Normal quantile of the band: about 95 % two-sided.
pub const BAND_SIGMAS: f64 = 2.0;
/// A bin whose input power is below this fraction of the band's largest is not excited
/// (a fade, a sine test's empty bins): the gain there is the noise over nothing.
const MIN_INPUT_POWER_RATIO: f64 = 1e-4;

/// The model-error response of one test and channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelErrorResponse {
    pub test: String,
    pub channel: Channel,
    /// The input: `ref_displacement_m` or `ref_acceleration_m_s2` (the test's control).
    pub input: &'static str,
    /// Unit of the gain: the channel's unit per the input's.
    pub unit: String,
    pub estimate: ResponseEstimate,
}

/// A gain estimate with its confidence band, one entry per excited bin in the band.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ResponseEstimate {
    pub frequency_hz: Vec<f64>,
    /// `|H1|`, residual per unit input.
    pub gain: Vec<f64>,
    /// `gain (1 - BAND_SIGMAS eps)`, at least 0.
    pub lower: Vec<f64>,
    /// `gain (1 + BAND_SIGMAS eps)` (infinite at zero coherence).
    pub upper: Vec<f64>,
    /// Ordinary coherence input-residual, in [0, 1].
    pub coherence: Vec<f64>,
    /// Welch segments averaged.
    pub averages: usize,
    pub resolution_hz: f64,
}

impl ResponseEstimate {
    /// The largest gain among the bins whose band excludes zero (the gain is there at
    /// the band's confidence): (frequency, gain, coherence); `None` when no bin is.
    pub fn peak(&self) -> Option<(f64, f64, f64)> {
        (0..self.gain.len())
            .filter(|&k| self.lower[k] > 0.0)
            .max_by(|&a, &b| self.gain[a].total_cmp(&self.gain[b]))
            .map(|k| (self.frequency_hz[k], self.gain[k], self.coherence[k]))
    }
}

/// Why a model-error response cannot be given.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum NoResponse {
    #[error("no test {0}")]
    NoTest(String),
    #[error("no channel {0}")]
    NoChannel(String),
    #[error("test {test} did not record the {channel} channel")]
    MissingChannel { test: String, channel: &'static str },
    #[error("the model's run of {test} stopped at {time_s:.2} s ({reason})")]
    Diverged {
        test: String,
        time_s: f64,
        reason: String,
    },
    #[error(
        "{samples} samples give {averages} averages at {resolution_hz} Hz resolution, fewer than {MIN_AVERAGES}"
    )]
    TooShort {
        samples: usize,
        averages: usize,
        resolution_hz: f64,
    },
    #[error("the input {0} has no power in the band {1:?} Hz")]
    NoInput(&'static str, [f64; 2]),
    #[error("spectral estimate: {0}")]
    Spectral(#[from] FrfError),
}

/// The model-error response of channel `ch` of test `i` under the model `p` (the
/// extended model of a diagnosis), over the whole test, up to the test's band's top or
/// [`FIT_MAX_HZ`], whichever is lower.
///
/// The whole test, not the report quarter: the figure decides nothing, and a quarter
/// would give too few averages for a band; a fit of ten parameters over thousands of
/// samples takes up no measurable part of the residual of its first half.
pub fn model_error_response(
    p: &Params,
    c: &Campaign,
    i: usize,
    ch: Channel,
) -> Result<ModelErrorResponse, NoResponse> {
    let (spec, r) = (c.info.tests.get(i), c.records.get(i));
    let (Some(spec), Some(r)) = (spec, r) else {
        return Err(NoResponse::NoTest(i.to_string()));
    };
    let test = spec.name.clone();
    let measured = ch.measured(r).ok_or_else(|| NoResponse::MissingChannel {
        test: test.clone(),
        channel: ch.name(),
    })?;
    let simulated = match simulate_test(p, c, i, Part::Whole) {
        Ok(simulated) => simulated,
        Err(d) => {
            return Err(NoResponse::Diverged {
                test,
                time_s: d.time_s,
                reason: d.reason,
            })
        }
    };
    let residual: Vec<f64> = measured
        .iter()
        .zip(simulated.iter())
        .map(|(m, o)| m - ch.simulated(o))
        .collect();
    let (input_name, input) = reference(spec.control, r);
    let fs = c.sample_rate_of(i);
    let top_hz = spec.band_hz.map_or(FIT_MAX_HZ, |b| b[1]).min(FIT_MAX_HZ);
    let bottom_hz = spec.band_hz.map_or(0.0, |b| b[0]);
    let estimate =
        residual_response(input, &residual, fs, [bottom_hz, top_hz]).map_err(|e| match e {
            NoResponse::NoInput(_, band) => NoResponse::NoInput(input_name, band),
            e => e,
        })?;
    Ok(ModelErrorResponse {
        test,
        channel: ch,
        input: input_name,
        unit: format!(
            "{}/{}",
            quotient_term(channel_unit(ch)),
            quotient_term(input_unit(spec.control))
        ),
        estimate,
    })
}

impl ModelErrorResponse {
    /// The peak of the response ([`ResponseEstimate::peak`]) with what it is of.
    pub fn peak(&self) -> Option<ModelErrorPeak> {
        let (frequency_hz, gain, coherence) = self.estimate.peak()?;
        Some(ModelErrorPeak {
            test: self.test.clone(),
            channel: self.channel.name(),
            input: self.input,
            unit: self.unit.clone(),
            frequency_hz,
            gain,
            coherence,
        })
    }
}

/// Where a model-error response peaks: the diagnosis JSON's `model_error_peak`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelErrorPeak {
    pub test: String,
    pub channel: &'static str,
    pub input: &'static str,
    /// Unit of the gain.
    pub unit: String,
    pub frequency_hz: f64,
    pub gain: f64,
    pub coherence: f64,
}

/// One unexplained cell's model-error response, or why it has none.
#[derive(Debug)]
pub struct CellResponse {
    pub test: String,
    pub channel: String,
    pub response: Result<ModelErrorResponse, NoResponse>,
}

/// The extended model's model-error responses on `d`'s unexplained cells, worst first,
/// until `max` cells have one (none when the data is explained); the cells tried on the
/// way are kept with why they have none.
pub fn unexplained_responses(d: &Diagnosis, c: &Campaign, max: usize) -> Vec<CellResponse> {
    let mut out = Vec::new();
    let mut found = 0;
    for u in d.unexplained.iter().filter(|_| !d.explained) {
        if found >= max {
            break;
        }
        let i = c.info.tests.iter().position(|t| t.name == u.test);
        let response = match (i, Channel::named(&u.channel)) {
            (None, _) => Err(NoResponse::NoTest(u.test.clone())),
            (_, None) => Err(NoResponse::NoChannel(u.channel.clone())),
            (Some(i), Some(ch)) => model_error_response(&d.extended, c, i, ch),
        };
        found += usize::from(response.is_ok());
        out.push(CellResponse {
            test: u.test.clone(),
            channel: u.channel.clone(),
            response,
        });
    }
    out
}

/// The reference the test's controller follows, by its campaign-format name.
fn reference(control: Control, r: &Record) -> (&'static str, &[f64]) {
    match control {
        Control::Displacement => ("ref_displacement_m", &r.ref_displacement_m),
        Control::Acceleration => ("ref_acceleration_m_s2", &r.ref_acceleration_m_s2),
    }
}

/// SI unit of a channel (campaign format: the valve command and spool are normalised).
pub fn channel_unit(ch: Channel) -> &'static str {
    match ch {
        Channel::Displacement => "m",
        Channel::Acceleration => "m/s^2",
        Channel::Force => "N",
        Channel::Spool | Channel::ValveCommand => "1",
    }
}

/// A unit as a term of a quotient: in parentheses when it is a quotient itself.
fn quotient_term(unit: &str) -> String {
    if unit.contains('/') {
        format!("({unit})")
    } else {
        unit.to_string()
    }
}

fn input_unit(control: Control) -> &'static str {
    match control {
        Control::Displacement => "m",
        Control::Acceleration => "m/s^2",
    }
}

/// The gain `|S_xe / S_xx|` from `input` to `residual` sampled at `fs` Hz over the bins
/// in `band_hz` (0 Hz excluded: every segment's mean is removed) that the input excites,
/// with its confidence band (module doc).
pub fn residual_response(
    input: &[f64],
    residual: &[f64],
    fs: f64,
    band_hz: [f64; 2],
) -> Result<ResponseEstimate, NoResponse> {
    let options = welch_options(fs, input.len())?;
    let welch = Welch::new(fs, options)?;
    let est = welch.frf(input, residual)?;
    let input_power = welch.auto(&welch.segment_spectra(input)?);
    let in_band: Vec<usize> = (1..est.frequency_hz.len())
        .filter(|&k| est.frequency_hz[k] >= band_hz[0] && est.frequency_hz[k] <= band_hz[1])
        .collect();
    let largest = in_band.iter().map(|&k| input_power[k]).fold(0.0, f64::max);
    let excited: Vec<usize> = in_band
        .into_iter()
        .filter(|&k| largest > 0.0 && input_power[k] >= MIN_INPUT_POWER_RATIO * largest)
        .collect();
    if excited.is_empty() {
        return Err(NoResponse::NoInput("input", band_hz));
    }
    let n_d = est.segments as f64 * OVERLAP_EFFICIENCY;
    let mut out = ResponseEstimate {
        averages: est.segments,
        resolution_hz: fs / options.segment_len as f64,
        ..ResponseEstimate::default()
    };
    for k in excited {
        let gain = est.h1[k].norm();
        let coherence = est.coherence[k];
        let eps = gain_random_error(coherence, n_d);
        out.frequency_hz.push(est.frequency_hz[k]);
        out.gain.push(gain);
        out.lower.push((gain * (1.0 - BAND_SIGMAS * eps)).max(0.0));
        out.upper.push(gain * (1.0 + BAND_SIGMAS * eps));
        out.coherence.push(coherence);
    }
    Ok(out)
}

/// The residual power of channel `ch` of test `i` in `run` (a model's run of it, at least
/// to the end of `part`) over `part` that is linearly
/// coherent with the test's input, and its whole power, summed over the Welch bins
/// (0 Hz excluded): `(sum gamma^2 S_ee, sum S_ee)`. `None` where no estimate can be made.
///
/// A residual coherent with the reference is deterministic, and a model's predicted
/// spread should not be credited with it; chatter and impacts chaotic in detail are not
/// coherent (the selection rule `spread_credited`).
pub fn coherent_power(
    c: &Campaign,
    i: usize,
    ch: Channel,
    part: Part,
    run: &TestRun,
) -> Option<(f64, f64)> {
    let (spec, r) = (c.info.tests.get(i)?, c.records.get(i)?);
    let measured = ch.measured(r)?;
    let range = part.range(r.len());
    let simulated = run.as_ref().ok()?;
    let residual: Vec<f64> = measured[range.clone()]
        .iter()
        .zip(&simulated[range.clone()])
        .map(|(m, o)| m - ch.simulated(o))
        .collect();
    let (_, input) = reference(spec.control, r);
    let input = &input[range];
    let fs = c.sample_rate_of(i);
    let welch = Welch::new(fs, welch_options(fs, input.len()).ok()?).ok()?;
    let est = welch.frf(input, &residual).ok()?;
    let power = welch.auto(&welch.segment_spectra(&residual).ok()?);
    let coherent = (1..power.len())
        .map(|k| est.coherence[k].clamp(0.0, 1.0) * power[k])
        .filter(|x| x.is_finite())
        .sum();
    Some((coherent, power[1..].iter().sum()))
}

/// Bendat & Piersol's normalised random error of a gain factor estimate from `n_d`
/// averages at ordinary coherence `coherence` (gamma^2): infinite at zero coherence.
pub fn gain_random_error(coherence: f64, n_d: f64) -> f64 {
    let c = coherence.clamp(0.0, 1.0);
    (1.0 - c).sqrt() / (c.sqrt() * (2.0 * n_d).sqrt())
}

/// Welch segments for a record of `samples` at `fs`: the finest resolution down to
/// [`FINEST_RESOLUTION_HZ`] that gives [`WANTED_AVERAGES`], never coarser than
/// [`COARSEST_RESOLUTION_HZ`]; too short when even that gives fewer than
/// [`MIN_AVERAGES`].
fn welch_options(fs: f64, samples: usize) -> Result<WelchOptions, NoResponse> {
    let mut options = WelchOptions::for_resolution(fs, FINEST_RESOLUTION_HZ);
    let coarsest = WelchOptions::for_resolution(fs, COARSEST_RESOLUTION_HZ).segment_len;
    while options.segment_len / 2 >= coarsest && options.segments(samples) < WANTED_AVERAGES {
        options.segment_len /= 2;
    }
    let averages = options.segments(samples);
    if averages < MIN_AVERAGES {
        return Err(NoResponse::TooShort {
            samples,
            averages,
            resolution_hz: fs / options.segment_len as f64,
        });
    }
    Ok(options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::PI;

    const FS: f64 = 512.0;

    /// A lightly damped resonance at `f0` (a digital two-pole filter, gain 1 at 0 Hz)
    /// applied to `x`, and its true gain at `f` Hz.
    fn resonance(x: &[f64], f0: f64, r: f64) -> (Vec<f64>, impl Fn(f64) -> f64) {
        let (a1, a2) = (2.0 * r * (2.0 * PI * f0 / FS).cos(), -r * r);
        let b0 = 1.0 - a1 - a2;
        let mut y = vec![0.0; x.len()];
        for k in 0..x.len() {
            let y1 = if k > 0 { y[k - 1] } else { 0.0 };
            let y2 = if k > 1 { y[k - 2] } else { 0.0 };
            y[k] = b0 * x[k] + a1 * y1 + a2 * y2;
        }
        let truth = move |f: f64| {
            let z = Complex64::from_polar(1.0, -2.0 * PI * f / FS);
            (b0 / (1.0 - a1 * z - a2 * z * z)).norm()
        };
        (y, truth)
    }

    /// A known resonance plus white noise as the "residual": the band covers the true
    /// gain at most bins (95 % nominal), the gain is within 10 % where the coherence is
    /// high, and the peak is the resonance.
    #[test]
    fn the_band_covers_a_known_response_and_the_gain_is_right_where_coherent() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let x: Vec<f64> = (0..20 * 512).map(|_| normal.sample(&mut rng)).collect();
        let (y, truth) = resonance(&x, 5.0, 0.99);
        // noise below the response near the peak, far above it at 64 Hz: the coherence spans 0-1
        let e: Vec<f64> = y
            .iter()
            .map(|v| v + 0.5 * normal.sample(&mut rng))
            .collect();
        let est = residual_response(&x, &e, FS, [0.0, 64.0]).unwrap();
        assert!(est.averages >= WANTED_AVERAGES, "{}", est.averages);
        let n = est.frequency_hz.len();
        let covered = (0..n)
            .filter(|&k| {
                let t = truth(est.frequency_hz[k]);
                est.lower[k] <= t && t <= est.upper[k]
            })
            .count();
        assert!(covered as f64 >= 0.85 * n as f64, "{covered} of {n}");
        let coherent: Vec<usize> = (0..n).filter(|&k| est.coherence[k] > 0.9).collect();
        assert!(coherent.len() >= 3, "{}", coherent.len());
        for k in coherent {
            let t = truth(est.frequency_hz[k]);
            assert!(
                (est.gain[k] / t - 1.0).abs() < 0.1,
                "bin {k}: {} vs {t}",
                est.gain[k]
            );
        }
        // low coherence somewhere: the test exercises the band's width
        assert!(est.coherence.iter().any(|&c| c < 0.3));
        let (f, _, _) = est.peak().unwrap();
        assert!((f - 5.0).abs() <= 0.5, "peak at {f} Hz");
    }

    /// The band widens as the coherence falls and is infinite at none.
    #[test]
    fn the_random_error_follows_the_coherence() {
        assert_eq!(gain_random_error(1.0, 16.0), 0.0);
        let half = gain_random_error(0.5, 16.0);
        assert!((half - 1.0 / 32f64.sqrt()).abs() < 1e-12);
        assert!(gain_random_error(0.1, 16.0) > half);
        assert!(gain_random_error(0.0, 16.0).is_infinite());
    }

    /// No input or too few samples: no response, with the reason.
    #[test]
    fn a_silent_or_short_record_gives_no_response() {
        let zeros = vec![0.0; 20 * 512];
        let noise: Vec<f64> = (0..zeros.len()).map(|k| (k as f64 * 0.37).sin()).collect();
        assert!(matches!(
            residual_response(&zeros, &noise, FS, [0.0, 64.0]),
            Err(NoResponse::NoInput(..))
        ));
        assert!(matches!(
            residual_response(&noise[..2000], &noise[..2000], FS, [0.0, 64.0]),
            Err(NoResponse::TooShort { .. })
        ));
    }
}

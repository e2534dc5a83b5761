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

use super::Part;
use crate::campaign::{Campaign, Record};
use crate::params::Params;
use crate::solver::{simulate_run_with, Checks, DEFAULT_MAX_SUBSTEP_S};
use crate::{Model, Outputs, SensorNoise};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

/// The compared channels.
pub const CHANNELS: [&str; 5] = [
    "displacement",
    "acceleration",
    "force",
    "spool",
    "valve_command",
];

/// Window of the predictive score, samples (0.25 s at 512 Hz: short beside a chatter
/// burst's growth, long enough for a power estimate within about 12 %).
pub const SCORE_WINDOW: usize = 128;

/// Windows over which the predicted spread is averaged (centred; 1.25 s at 512 Hz).
pub const SPREAD_WINDOWS: usize = 5;

/// Noise per channel, estimated from the data (never from a generator's settings).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct NoiseFloor {
    /// The floor, in which residuals are counted: what a noise-free simulation cannot
    /// predict at rest, i.e. the sensor noise plus the loop's response to it (the
    /// oil-column resonance makes the latter several times the former in acceleration
    /// and force). Displacement (LVDT), m.
    pub displacement_m: f64,
    pub acceleration_m_s2: f64,
    pub force_n: f64,
    pub spool: f64,
    /// The command at rest: the controller's response to the feedback noise (the
    /// command itself is recorded without measurement noise).
    pub valve_command: f64,
    /// The sensor noise alone (white), which the noisy runs of [`predict`] feed into the
    /// loop and which bounds every window's predicted spread from below.
    pub sensor: SensorLevels,
    /// How it was estimated.
    pub method: &'static str,
}

/// White sensor-noise RMS of the measured channels.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SensorLevels {
    pub displacement_m: f64,
    pub acceleration_m_s2: f64,
    pub force_n: f64,
    pub spool: f64,
}

impl NoiseFloor {
    /// Noise floor of channel `ch` of [`CHANNELS`] (the residual's unit).
    pub fn of(&self, ch: usize) -> f64 {
        [
            self.displacement_m,
            self.acceleration_m_s2,
            self.force_n,
            self.spool,
            self.valve_command,
        ][ch]
    }

    /// Measurement noise of channel `ch` alone (the command has none: its spread is the
    /// loop's response, which the noisy run predicts).
    pub fn measurement(&self, ch: usize) -> f64 {
        let s = &self.sensor;
        [
            s.displacement_m,
            s.acceleration_m_s2,
            s.force_n,
            s.spool,
            0.0,
        ][ch]
    }

    /// Seeded sensor noise at the sensor levels for a record of `n` samples (the feedback
    /// channels only, as on the table; spec section 2).
    pub fn loop_noise(&self, n: usize, seed: u64) -> Vec<SensorNoise> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let normal = Normal::new(0.0, 1.0).expect("unit normal");
        let s = &self.sensor;
        (0..n)
            .map(|_| SensorNoise {
                displacement_m: s.displacement_m * normal.sample(&mut rng),
                acceleration_m_s2: s.acceleration_m_s2 * normal.sample(&mut rng),
                force_n: s.force_n * normal.sample(&mut rng),
            })
            .collect()
    }
}

fn std_dev(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// White-noise RMS from the fourth difference: its variance is 70 times the noise's
/// (binomial(8, 4)), while a signal at 14 Hz sampled at 512 Hz is attenuated to 8e-4 of
/// its amplitude, so slow motion and the oil-column chatter do not leak in.
fn fourth_difference_rms(x: &[f64]) -> f64 {
    if x.len() < 16 {
        return f64::NAN;
    }
    let d: Vec<f64> = x
        .windows(5)
        .map(|w| w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4])
        .collect();
    std_dev(&d) / 70f64.sqrt()
}

/// Noise of every channel, from the data only. The floor: the rest segments (zero
/// reference) at the start of the tests, median over tests. The sensor noise: the
/// high-frequency content (fourth difference, median over tests), which the loop's
/// response (below 50 Hz) does not reach. Without a rest segment of 64 samples or more
/// in any test, the floor is the sensor noise (and the command's from the gains).
pub fn estimate_noise(c: &Campaign) -> NoiseFloor {
    let mut rest_est: [Vec<f64>; 5] = Default::default();
    let mut hf_est: [Vec<f64>; 4] = Default::default();
    for r in &c.records {
        let rest = (0..r.len())
            .take_while(|&k| {
                r.ref_displacement_m[k] == 0.0
                    && r.ref_velocity_m_s[k] == 0.0
                    && r.ref_acceleration_m_s2[k] == 0.0
            })
            .count();
        for ch in 0..5 {
            if let Some(m) = measured(r, ch) {
                if ch < 4 {
                    hf_est[ch].push(fourth_difference_rms(m));
                }
                if rest >= 64 {
                    rest_est[ch].push(std_dev(&m[..rest]));
                }
            }
        }
    }
    let hf: Vec<f64> = hf_est.iter().map(|v| median(v.clone())).collect();
    let rest: Vec<f64> = rest_est.iter().map(|v| median(v.clone())).collect();
    let have_rest = rest[0].is_finite();
    let method = if have_rest {
        "floor from the rest segments (zero reference) at the start of the tests; sensor noise from the high-frequency content"
    } else {
        "floor and sensor noise from the high-frequency content (fourth difference; no rest segment)"
    };
    // floors so that a noise-free record does not divide by zero
    let lower = [1e-9, 1e-6, 1e-3, 1e-7];
    let sensor: Vec<f64> = (0..4)
        .map(|ch| {
            if hf[ch].is_finite() {
                hf[ch].max(lower[ch])
            } else {
                f64::NAN
            }
        })
        .collect();
    // the floor is never below the sensor noise
    let floor: Vec<f64> = (0..4)
        .map(|ch| {
            if have_rest && rest[ch].is_finite() {
                rest[ch].max(sensor[ch])
            } else {
                sensor[ch]
            }
        })
        .collect();
    let k = &c.info.controller;
    let from_gains =
        ((k.kp * sensor[0]).powi(2) + (k.ka * sensor[1]).powi(2) + (k.kdp * sensor[2]).powi(2))
            .sqrt();
    let su = if have_rest && rest[4].is_finite() {
        rest[4].max(from_gains)
    } else {
        from_gains
    }
    .max(1e-7);
    NoiseFloor {
        displacement_m: floor[0],
        acceleration_m_s2: floor[1],
        force_n: floor[2],
        spool: floor[3],
        valve_command: su,
        sensor: SensorLevels {
            displacement_m: sensor[0],
            acceleration_m_s2: sensor[1],
            force_n: sensor[2],
            spool: sensor[3],
        },
        method,
    }
}

/// Simulate test `i` of the campaign with `p` and the test's controller gains, up to the
/// end of `part`, with optional in-loop sensor noise.
pub fn simulate_test_with(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: Option<&[SensorNoise]>,
) -> Vec<Outputs> {
    let mut q = *p;
    q.controller = c.controller_for(&c.info.tests[i]);
    let inputs = c.records[i].inputs();
    let end = part.range(inputs.len()).end;
    simulate_run_with(
        &Model::new(&q),
        &inputs[..end],
        c.info.sample_rate_hz,
        noise.map(|n| &n[..end.min(n.len())]),
        DIAGNOSIS_SUBSTEP_S,
        Checks::DivergenceOnly,
    )
    .outputs
}

/// Largest RK4 sub-step of the diagnosis' simulations: 1/1536 s, twice the solver's
/// default ([`DEFAULT_MAX_SUBSTEP_S`]). The error grows as h^4, so from the default's
/// 5e-7 of the signal RMS to about 1e-5, a hundredth of the sensor noise (measured: the
/// refined baseline's output-error cost on a clean campaign moves by 1e-5 of itself),
/// and every fit runs twice as fast.
pub const DIAGNOSIS_SUBSTEP_S: f64 = 2.0 * DEFAULT_MAX_SUBSTEP_S;

/// Simulate test `i` of the campaign with `p` and the test's controller gains (noise-free).
pub fn simulate_test(p: &Params, c: &Campaign, i: usize, part: Part) -> Vec<Outputs> {
    simulate_test_with(p, c, i, part, None)
}

/// Channel `ch` of [`CHANNELS`] in a record (None when the record lacks it).
pub fn measured(r: &Record, ch: usize) -> Option<&[f64]> {
    match ch {
        0 => Some(&r.displacement_m),
        1 => Some(&r.acceleration_m_s2),
        2 => Some(&r.force_n),
        3 => r.spool_position.as_deref(),
        _ => Some(&r.valve_command),
    }
}

/// Channel `ch` of [`CHANNELS`] in simulated readings.
pub fn simulated(o: &Outputs, ch: usize) -> f64 {
    match ch {
        0 => o.displacement_m,
        1 => o.acceleration_m_s2,
        2 => o.actuator_force_n,
        3 => o.spool_position,
        _ => o.valve_command,
    }
}

/// Normalised residual RMS per channel over `part` (NaN where the channel is absent): the
/// heat map's "residual / noise RMS".
pub fn ratios(r: &Record, sim: &[Outputs], noise: &NoiseFloor, part: Part) -> [f64; 5] {
    let mut out = [f64::NAN; 5];
    let range = part.range(r.len());
    for (ch, o) in out.iter_mut().enumerate() {
        if let Some(m) = measured(r, ch) {
            let s = noise.of(ch);
            if s.is_finite() && !range.is_empty() {
                let ss: f64 = range
                    .clone()
                    .map(|k| (m[k] - simulated(&sim[k], ch)).powi(2))
                    .sum();
                *o = (ss / range.len() as f64).sqrt() / s;
            }
        }
    }
    out
}

/// A model's prediction of one test: its noise-free run and a run with seeded in-loop
/// noise (the same seed for every model, so that models are compared on one draw).
pub struct Prediction {
    pub locked: Vec<Outputs>,
    /// [`REALISATIONS`] runs with independent noise draws.
    pub noisy: Vec<Vec<Outputs>>,
    /// The noise each noisy run's feedback saw (its readings carry it too).
    pub draws: Vec<Vec<SensorNoise>>,
}

impl Prediction {
    /// The spread of channel `ch` over `range` for each noisy run: its readings plus the
    /// noise its feedback saw, minus the locked run (the coherent spread of [`scores`]).
    pub fn spread(&self, range: std::ops::Range<usize>, ch: usize) -> Vec<Vec<f64>> {
        self.noisy
            .iter()
            .zip(&self.draws)
            .map(|(run, draw)| {
                range
                    .clone()
                    .map(|k| {
                        simulated(&run[k], ch) + fed_back(&draw[k], ch)
                            - simulated(&self.locked[k], ch)
                    })
                    .collect()
            })
            .collect()
    }
}

/// Noisy runs per prediction: noise-driven chatter near its threshold comes in
/// intermittent bursts, and one draw misjudges its expected power.
pub const REALISATIONS: usize = 1;

/// Seed of the `r`-th in-loop noise draw of test `i` in every [`predict`].
fn noise_seed(i: usize, r: usize) -> u64 {
    0x5ead_7ab1e ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ ((r as u64) << 48)
}

/// Simulate test `i` with `p` up to the end of `part`, noise-free and with noise.
pub fn predict(p: &Params, c: &Campaign, i: usize, part: Part, noise: &NoiseFloor) -> Prediction {
    use rayon::prelude::*;
    let n = part.range(c.records[i].len()).end;
    let (locked, noisy) = rayon::join(
        || simulate_test_with(p, c, i, part, None),
        || {
            (0..REALISATIONS)
                .into_par_iter()
                .map(|r| {
                    let draw = noise.loop_noise(n, noise_seed(i, r));
                    (simulate_test_with(p, c, i, part, Some(&draw)), draw)
                })
                .unzip()
        },
    );
    let (noisy, draws) = noisy;
    Prediction {
        locked,
        noisy,
        draws,
    }
}

/// Held-out figures of a model per channel (NaN where the channel is absent, infinite
/// where the run diverged).
#[derive(Debug, Clone, Copy)]
pub struct CellScores {
    /// The predictive score as an equivalent noise ratio: the square root of the mean over
    /// windows of `P_meas/P_pred + ln(P_pred/s^2)` (module doc). It ranks models.
    pub score: [f64; 5],
    /// The standardised residual: the square root of the mean of `P_meas/P_pred`, the
    /// residual in units of the spread the model itself predicts (the noise floor for a
    /// model the noise does not excite, where both equal the ratio of [`ratios`]).
    pub residual: [f64; 5],
}

/// Lower edge of the lowest octave band but one, Hz: the bands of [`octave_bands`] halve
/// from the Nyquist frequency down to here, and one band holds everything below.
pub const LOWEST_BAND_HZ: f64 = 1.0;

/// Degrees of freedom a score window holds in its band (`2 W L / fs`): its length is
/// chosen for it (at least [`SCORE_WINDOW`]), so a narrow low band gets long windows.
const WINDOW_DOF: f64 = 8.0;

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

/// The noise sample of channel `ch` that the feedback saw (none on the spool and command).
fn fed_back(n: &SensorNoise, ch: usize) -> f64 {
    match ch {
        0 => n.displacement_m,
        1 => n.acceleration_m_s2,
        2 => n.force_n,
        _ => 0.0,
    }
}

/// Mean over windows of `P_meas/P_pred` and of `ln(P_pred/reference)` for one band:
/// `meas` the band's residual, `spread` its predicted spread per realisation, `white` the
/// variance of independent measurement noise in the band (added to the prediction).
pub fn band_score(meas: &[f64], spread: &[Vec<f64>], window: usize, white: f64) -> (f64, f64) {
    let n = meas.len();
    let starts: Vec<usize> = (0..n).step_by(window.max(1)).collect();
    let power = |x: &[f64], k0: usize| {
        let end = (k0 + window).min(n);
        (x[k0..end].iter().map(|v| v * v).sum::<f64>(), end - k0)
    };
    let meas_p: Vec<(f64, usize)> = starts.iter().map(|&k0| power(meas, k0)).collect();
    let spread_p: Vec<(f64, usize)> = starts
        .iter()
        .map(|&k0| {
            spread.iter().fold((0.0, 0), |acc, s| {
                let (p, m) = power(s, k0);
                (acc.0 + p, acc.1 + m)
            })
        })
        .collect();
    let half = SPREAD_WINDOWS / 2;
    let (mut ratio, mut log, mut total) = (0.0, 0.0, 0usize);
    for (w, &(pm, m)) in meas_p.iter().enumerate() {
        let lo = w.saturating_sub(half);
        let hi = (w + half + 1).min(spread_p.len());
        let (ps, ns) = spread_p[lo..hi]
            .iter()
            .fold((0.0, 0usize), |a, b| (a.0 + b.0, a.1 + b.1));
        let p_pred = (white + ps / ns.max(1) as f64).max(f64::MIN_POSITIVE);
        ratio += pm / p_pred;
        log += p_pred.ln() * m as f64;
        total += m;
    }
    let t = total.max(1) as f64;
    (ratio / t, log / t)
}

/// [`CellScores`] of a prediction over `part`: per channel, the residual (measured minus
/// the locked run) and the predicted spread (noisy run plus the very noise its feedback
/// saw, minus the locked run: the recorded channels carry the noise the controller saw, so
/// the loop's response and the noise add coherently) are split into octave bands; each
/// band is scored in windows of [`WINDOW_DOF`] degrees of freedom, the predicted power
/// smoothed over [`SPREAD_WINDOWS`] windows; the cell is the mean over bands.
///
/// Why bands: the loop's noise response fills the oil-column octave, and a residual that
/// lives in another octave (a stiff foundation's mode at 30-40 Hz, a hundred times the
/// predicted power there) would vanish in a broadband power that the resonance
/// dominates. Each octave counts alike, as on a Bode plot. Summed over bands with fixed
/// weights, the Gaussian log score stays a proper scoring rule.
pub fn scores(
    r: &Record,
    pred: &Prediction,
    noise: &NoiseFloor,
    part: Part,
    sample_rate_hz: f64,
) -> CellScores {
    let mut out = CellScores {
        score: [f64::NAN; 5],
        residual: [f64::NAN; 5],
    };
    let range = part.range(r.len());
    if range.len() < 2 {
        return out;
    }
    let bands = octave_bands(sample_rate_hz);
    let nyquist = sample_rate_hz / 2.0;
    for ch in 0..CHANNELS.len() {
        let Some(m) = measured(r, ch) else { continue };
        let s = noise.of(ch);
        if !s.is_finite() {
            continue;
        }
        let white = white_variance(noise, ch);
        let locked = |k: usize| simulated(&pred.locked[k], ch);
        let residual: Vec<f64> = range.clone().map(|k| m[k] - locked(k)).collect();
        let spread = pred.spread(range.clone(), ch);
        // a run that diverged ([`crate::solver::simulate_record`] marks it NaN) predicts
        // nothing: an infinite score, never a cell left out as if the channel were absent
        if residual
            .iter()
            .chain(spread.iter().flatten())
            .any(|x| !x.is_finite())
        {
            out.score[ch] = f64::INFINITY;
            out.residual[ch] = f64::INFINITY;
            continue;
        }
        let meas_bands = band_split(&residual, &bands, sample_rate_hz);
        let spread_bands: Vec<Vec<Vec<f64>>> = spread
            .iter()
            .map(|x| band_split(x, &bands, sample_rate_hz))
            .collect();
        let (mut score, mut ratio) = (0.0, 0.0);
        for (b, &(lo, hi)) in bands.iter().enumerate() {
            let width = hi - lo;
            let window =
                ((WINDOW_DOF * sample_rate_hz / (2.0 * width)).ceil() as usize).max(SCORE_WINDOW);
            let share = width / nyquist;
            let sp: Vec<Vec<f64>> = spread_bands.iter().map(|x| x[b].clone()).collect();
            let (q, log) = band_score(&meas_bands[b], &sp, window, white * share);
            // the log term relative to the floor's share of the band, so that a model
            // predicting the floor scores as the ratio alone
            score += q + log - (s * s * share).ln();
            ratio += q;
        }
        let nb = bands.len() as f64;
        out.score[ch] = (score / nb).max(0.0).sqrt();
        out.residual[ch] = (ratio / nb).sqrt();
    }
    out
}

/// Highest frequency the output-error fits look at, Hz: above it every model's residual is
/// sensor noise (the valve, the oil column, a foundation and chatter all live below), so
/// the fits skip those coefficients, which would only add cost.
pub const FIT_MAX_HZ: f64 = 64.0;

/// Run `f` with this thread's FFT planner: a planner caches its plans, and planning a
/// long transform (twiddle factors) costs as much as running it, so the fits, which
/// transform the same lengths thousands of times, keep one per worker thread.
fn with_planner<R>(f: impl FnOnce(&mut realfft::RealFftPlanner<f64>) -> R) -> R {
    thread_local! {
        static PLANNER: std::cell::RefCell<realfft::RealFftPlanner<f64>> =
            std::cell::RefCell::new(realfft::RealFftPlanner::new());
    }
    PLANNER.with(|p| f(&mut p.borrow_mut()))
}

/// The real FFT of `x` followed by `x` reversed (the even extension, length `2 len(x)`):
/// no jump at the ends, so masking its spectrum leaves no edge ripple.
fn even_spectrum(x: &[f64]) -> Vec<num_complex::Complex64> {
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
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let spec = even_spectrum(x);
    (0..n)
        .map(|k| {
            let phase = -std::f64::consts::PI * k as f64 / (2 * n) as f64;
            (spec[k] * num_complex::Complex64::from_polar(1.0, phase)).re / 2.0
        })
        .collect()
}

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
        let fs = c.info.sample_rate_hz;
        let bands = octave_bands(fs);
        let per: Vec<(usize, [Vec<f64>; 5])> = tests
            .par_iter()
            .map(|&i| {
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
fn white_variance(noise: &NoiseFloor, ch: usize) -> f64 {
    if ch == 3 {
        noise.measurement(ch).powi(2)
    } else {
        1e-6 * noise.of(ch).powi(2)
    }
}

/// [`CellScores`] of `p` on test `i` over `part` (one [`predict`] and [`scores`]).
pub fn test_scores(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
) -> CellScores {
    test_scores_held(p, c, i, part, noise, false)
}

/// [`test_scores`] of a trial model held to the operating envelope (spec section 8):
/// where its noise-free run leaves the envelope over `part`, while the measured table did
/// not, the model describes nothing real there and every cell of the test scores
/// infinitely bad. (The fits themselves run with the divergence guards only,
/// [`simulate_test_with`], so an optimiser keeps a finite cost on its way.)
pub fn test_scores_in_envelope(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
) -> CellScores {
    test_scores_held(p, c, i, part, noise, true)
}

fn test_scores_held(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
    to_envelope: bool,
) -> CellScores {
    let pred = predict(p, c, i, part.simulated(), noise);
    let range = part.range(c.records[i].len());
    let locked = &pred.locked[range.start..range.end.min(pred.locked.len())];
    if to_envelope && crate::model::limits::first_exceeded(p, locked).is_some() {
        return CellScores {
            score: [f64::INFINITY; 5],
            residual: [f64::INFINITY; 5],
        };
    }
    scores(&c.records[i], &pred, noise, part, c.info.sample_rate_hz)
}

/// Sum over `tests` and channels of the squared predictive scores over `part`: the
/// objective of the fits that cannot use sample-wise least squares (stick-slip).
pub fn score_sum(p: &Params, c: &Campaign, tests: &[usize], noise: &NoiseFloor, part: Part) -> f64 {
    use rayon::prelude::*;
    if p.validate().is_err() {
        return f64::INFINITY;
    }
    tests
        .par_iter()
        .map(|&i| {
            test_scores(p, c, i, part, noise)
                .score
                .iter()
                .filter(|x| !x.is_nan())
                .map(|x| x * x)
                .sum::<f64>()
        })
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
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

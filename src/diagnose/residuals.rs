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
//! locked run, `P_pred = s_meas^2 + mean (noisy - locked)^2`. For a model whose response
//! the noise does not change, this is exactly the squared sample-wise ratio.

use super::Part;
use crate::campaign::{Campaign, Record};
use crate::params::Params;
use crate::solver::{simulate_record, DEFAULT_MAX_SUBSTEP_S};
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
    simulate_record(
        &Model::new(&q),
        &inputs[..end],
        c.info.sample_rate_hz,
        noise.map(|n| &n[..end.min(n.len())]),
        DEFAULT_MAX_SUBSTEP_S,
    )
}

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
                    simulate_test_with(p, c, i, part, Some(&draw))
                })
                .collect()
        },
    );
    Prediction { locked, noisy }
}

/// Held-out figures of a model per channel (NaN where the channel is absent).
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

/// [`CellScores`] of a prediction over `part`.
pub fn scores(r: &Record, pred: &Prediction, noise: &NoiseFloor, part: Part) -> CellScores {
    let mut out = CellScores {
        score: [f64::NAN; 5],
        residual: [f64::NAN; 5],
    };
    let range = part.range(r.len());
    if range.is_empty() {
        return out;
    }
    for ch in 0..CHANNELS.len() {
        let Some(m) = measured(r, ch) else { continue };
        let s = noise.of(ch);
        if !s.is_finite() {
            continue;
        }
        let s2 = s * s;
        let floor2 = noise.measurement(ch).powi(2).max(1e-6 * s2);
        // per window: measured residual power, and the predicted spread smoothed over
        // SPREAD_WINDOWS windows (the loop's noise response is narrow-band, about the
        // oil-column resonance, so one window holds too few cycles to estimate it)
        let starts: Vec<usize> = range.clone().step_by(SCORE_WINDOW).collect();
        let power = |k0: usize, f: &dyn Fn(usize) -> f64| {
            let end = (k0 + SCORE_WINDOW).min(range.end);
            ((k0..end).map(f).sum::<f64>(), end - k0)
        };
        let meas: Vec<(f64, usize)> = starts
            .iter()
            .map(|&k0| power(k0, &|k| (m[k] - simulated(&pred.locked[k], ch)).powi(2)))
            .collect();
        let spread: Vec<(f64, usize)> = starts
            .iter()
            .map(|&k0| {
                power(k0, &|k| {
                    let l = simulated(&pred.locked[k], ch);
                    pred.noisy
                        .iter()
                        .map(|run| (simulated(&run[k], ch) - l).powi(2))
                        .sum::<f64>()
                        / pred.noisy.len() as f64
                })
            })
            .collect();
        let half = SPREAD_WINDOWS / 2;
        let (mut total, mut calibration, mut windows) = (0.0, 0.0, 0usize);
        for (w, &(pm, n)) in meas.iter().enumerate() {
            let lo = w.saturating_sub(half);
            let hi = (w + half + 1).min(spread.len());
            let (ps, ns) = spread[lo..hi]
                .iter()
                .fold((0.0, 0usize), |a, b| (a.0 + b.0, a.1 + b.1));
            let p_meas = pm / n as f64;
            let p_pred = floor2 + ps / ns as f64;
            total += (p_meas / p_pred + (p_pred / s2).ln()) * n as f64;
            calibration += p_meas / p_pred * n as f64;
            windows += n;
        }
        out.score[ch] = (total / windows as f64).max(0.0).sqrt();
        out.residual[ch] = (calibration / windows as f64).sqrt();
    }
    out
}

/// [`CellScores`] of `p` on test `i` over `part` (one [`predict`] and [`scores`]).
pub fn test_scores(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
) -> CellScores {
    let pred = predict(p, c, i, part.simulated(), noise);
    scores(&c.records[i], &pred, noise, part)
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
                .filter(|x| x.is_finite())
                .map(|x| x * x)
                .sum::<f64>()
        })
        .sum::<f64>()
}

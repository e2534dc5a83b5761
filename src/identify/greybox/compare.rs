//! Measured against simulated (issue 16, part 3): each test simulated as it was run (its
//! reference, its controller override), and per test and motion channel the NRMSE and
//! the fit % as MATLAB's `compare` prints it.
//!
//! Both figures are taken after removing each signal's mean: an LVDT's zero and an
//! accelerometer's bias are the sensors', not the table's, and the model starts at rest
//! at the reference's first value. Then `NRMSE = RMS(measured - simulated) / RMS(measured)`
//! and `fit % = 100 (1 - NRMSE)`.

use crate::campaign::{Campaign, Measured};
use crate::identify::signals::centred_rms;
use crate::model::{Inputs, Outputs};
use crate::params::Params;
use crate::solver::{simulate_run_pair, simulate_run_with, Checks, Run, DEFAULT_MAX_SUBSTEP_S};
use crate::Model;
use rayon::prelude::*;
use serde::Serialize;

/// The channels an output-error fit compares: the table's motion and, where recorded,
/// the actuator force.
pub const COMPARED: [Measured; 3] = [
    Measured::Displacement,
    Measured::Acceleration,
    Measured::Force,
];

/// What a test was used for in the fit whose figures are reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Fitted on: its figures are not a prediction.
    Estimation,
    /// Not used by the fit: its figures are a prediction.
    Validation,
}

/// The fit of one channel of one test.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelFit {
    pub test: String,
    pub channel: &'static str,
    pub role: Role,
    /// `RMS(measured - simulated) / RMS(measured)`, means removed.
    pub nrmse: f64,
    /// `100 (1 - NRMSE)`, as MATLAB's `compare`.
    pub fit_percent: f64,
    /// RMS of the measured channel (mean removed), in its SI unit.
    pub measured_rms: f64,
    /// RMS of the measured channel (mean removed) over the test's rest segment
    /// ([`Campaign::rest_segment`]): the sensor's noise and the loop's response to it,
    /// which no noise-free simulation follows. `None` without a rest segment.
    pub noise_rms: Option<f64>,
    /// The most fit % a noise-free simulation of the true table can reach with the noise
    /// at rest in the channel: `100 (1 - noise_rms / measured_rms)`. In motion the loop's
    /// response to the sensors' noise is larger still (the friction no longer holds the
    /// table: a slow sine's acceleration fits at 1 % under a ceiling of 24 %), so this
    /// bounds the fit from above. Where it is low the channel is mostly noise, and its
    /// fit % says little of the model.
    pub noise_ceiling_percent: Option<f64>,
    /// The ceiling is below [`NOISE_LIMITED_CEILING_PERCENT`]: the channel is mostly noise.
    pub noise_limited: bool,
}

/// The most fit % a noise-free simulation reaches on a channel of RMS `rms` (means
/// removed) that carries a noise of RMS `noise_rms`: `100 (1 - noise_rms / rms)`. `None`
/// for a flat channel.
pub fn noise_ceiling(noise_rms: f64, rms: f64) -> Option<f64> {
    (rms > 0.0).then(|| 100.0 * (1.0 - noise_rms / rms))
}

/// A fit whose noise ceiling is below this, %, is noise-limited: the noise at rest is
/// more than half the channel's RMS (a slow test's acceleration), and its fit % says
/// more of the sensors than of the model.
pub const NOISE_LIMITED_CEILING_PERCENT: f64 = 50.0;

/// Seconds of each test kept for the report's measured-against-simulated figure.
const TRACE_S: f64 = 10.0;
/// Most points of such a figure (the trace is decimated evenly beyond).
const TRACE_POINTS: usize = 4000;

/// Measured against simulated over [`TRACE_S`] of a test from just before it moves, means
/// removed.
#[derive(Debug, Clone, Default)]
pub struct Trace {
    pub test: String,
    pub channel: &'static str,
    pub role: Option<Role>,
    pub time_s: Vec<f64>,
    pub measured: Vec<f64>,
    pub simulated: Vec<f64>,
}

/// The figure starts this long before the measured channel first moves: a laboratory's
/// record often begins with seconds at rest, which would fill the window.
const TRACE_LEAD_S: f64 = 1.0;
/// The channel has moved once it is this fraction of its RMS (mean removed) away from its
/// first sample: far above a sensor's noise at rest, far below any test's motion.
const MOTION_FRACTION: f64 = 0.1;

/// The first sample of the figure: [`TRACE_LEAD_S`] before `meas` first moves.
fn trace_start(meas: &[f64], fs: f64) -> usize {
    let rms = centred_rms(meas);
    let first = meas.first().copied().unwrap_or(0.0);
    let moved = meas
        .iter()
        .position(|v| (v - first).abs() > MOTION_FRACTION * rms)
        .unwrap_or(0);
    moved.saturating_sub((TRACE_LEAD_S * fs) as usize)
}

fn trace(
    test: &str,
    channel: &'static str,
    role: Role,
    fs: f64,
    meas: &[f64],
    sim: &[f64],
) -> Trace {
    let len = meas.len().min(sim.len());
    let start = trace_start(&meas[..len], fs);
    let end = (start + (TRACE_S * fs) as usize).min(len);
    let stride = (end - start).div_ceil(TRACE_POINTS).max(1);
    let (mm, ms) = (mean(meas), mean(sim));
    let idx: Vec<usize> = (start..end).step_by(stride).collect();
    Trace {
        test: test.to_string(),
        channel,
        role: Some(role),
        time_s: idx.iter().map(|&k| k as f64 / fs).collect(),
        measured: idx.iter().map(|&k| meas[k] - mm).collect(),
        simulated: idx.iter().map(|&k| sim[k] - ms).collect(),
    }
}

/// A test's simulation stopped before the test's end: it left the envelope or diverged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{test}: the simulation stopped at {time_s:.3} s: {reason}")]
pub struct SimulationStopped {
    pub test: String,
    /// When it stopped, seconds from the test's first sample.
    pub time_s: f64,
    /// Why ([`crate::solver::Stop::reason`]).
    pub reason: String,
}

/// Test `i` simulated with `p` as it was run: the test's controller override applied to
/// `p`'s gains, the table starting at rest at the reference's first displacement.
/// `Err` with the time and reason when the run left the envelope.
pub fn simulate_test(
    p: &Params,
    c: &Campaign,
    i: usize,
) -> Result<Vec<Outputs>, SimulationStopped> {
    simulate_prefix(p, c, i, c.records[i].len(), Checks::Envelope)
}

/// [`simulate_test`] over the first `samples` samples only, stopping on `checks` (the
/// fit's trial models may pass the envelope on their way to the data, as the
/// diagnosis' do; what is reported is held to it).
pub fn simulate_prefix(
    p: &Params,
    c: &Campaign,
    i: usize,
    samples: usize,
    checks: Checks,
) -> Result<Vec<Outputs>, SimulationStopped> {
    let run = TestRun::new(p, c, i, samples);
    let out = simulate_run_with(
        &run.model,
        &run.inputs,
        c.sample_rate_of(i),
        None,
        DEFAULT_MAX_SUBSTEP_S,
        checks,
    );
    run.outputs(c, out)
}

/// [`simulate_prefix`] of two tests `(test, samples)` at once, advanced together
/// ([`simulate_run_pair`]: the same outputs bit for bit, in less time than one after the
/// other) when they share a sampling rate.
pub fn simulate_prefix_pair(
    p: &Params,
    c: &Campaign,
    [(i, n), (j, m)]: [(usize, usize); 2],
    checks: Checks,
) -> [Result<Vec<Outputs>, SimulationStopped>; 2] {
    let fs = c.sample_rate_of(i);
    if fs != c.sample_rate_of(j) {
        return [
            simulate_prefix(p, c, i, n, checks),
            simulate_prefix(p, c, j, m, checks),
        ];
    }
    let (a, b) = (TestRun::new(p, c, i, n), TestRun::new(p, c, j, m));
    let [ra, rb] = simulate_run_pair(
        (&a.model, &a.inputs),
        (&b.model, &b.inputs),
        fs,
        DEFAULT_MAX_SUBSTEP_S,
        checks,
    );
    [a.outputs(c, ra), b.outputs(c, rb)]
}

/// Test `i` prepared to be simulated as it was run (see [`simulate_test`]).
struct TestRun {
    test: usize,
    /// The model with the test's controller override.
    model: Model,
    /// The first samples, the reference displacement less its first value.
    inputs: Vec<Inputs>,
    /// The reference's first displacement: the table starts at rest there.
    r0_m: f64,
}

impl TestRun {
    fn new(p: &Params, c: &Campaign, i: usize, samples: usize) -> TestRun {
        let spec = &c.info.tests[i];
        let rec = &c.records[i];
        let mut q = *p;
        q.controller = spec.controller.apply(&p.controller);
        let r0_m = rec.ref_displacement_m.first().copied().unwrap_or(0.0);
        let inputs: Vec<Inputs> = rec
            .inputs()
            .into_iter()
            .take(samples)
            .map(|mut u| {
                u.reference.displacement_m -= r0_m;
                u
            })
            .collect();
        TestRun {
            test: i,
            model: Model::new(&q),
            inputs,
            r0_m,
        }
    }

    /// The run's outputs with the displacement back about the reference's first value,
    /// or when and why it stopped.
    fn outputs(&self, c: &Campaign, run: Run) -> Result<Vec<Outputs>, SimulationStopped> {
        if let Some(stop) = run.stop {
            return Err(SimulationStopped {
                test: c.info.tests[self.test].name.clone(),
                time_s: stop.time_s,
                reason: stop.reason,
            });
        }
        let mut out = run.outputs;
        for o in &mut out {
            o.displacement_m += self.r0_m;
        }
        Ok(out)
    }
}

/// The simulated counterpart of measured channel `m`.
pub fn simulated(o: &Outputs, m: Measured) -> f64 {
    match m {
        Measured::Displacement => o.displacement_m,
        Measured::Acceleration => o.acceleration_m_s2,
        Measured::Force => o.actuator_force_n,
        Measured::ValveCommand => o.valve_command,
        Measured::Spool => o.spool_position,
    }
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// NRMSE of `sim` against `meas`, means removed; `None` for a flat or empty channel.
pub fn nrmse(meas: &[f64], sim: &[f64]) -> Option<(f64, f64)> {
    let (mm, ms) = (mean(meas), mean(sim));
    let n = meas.len().min(sim.len());
    let mut e2 = 0.0;
    let mut y2 = 0.0;
    for k in 0..n {
        let y = meas[k] - mm;
        e2 += (y - (sim[k] - ms)).powi(2);
        y2 += y * y;
    }
    let rms = (y2 / n.max(1) as f64).sqrt();
    (n > 0 && y2 > 0.0 && e2.is_finite()).then(|| ((e2 / y2).sqrt(), rms))
}

/// What [`compare`] gives: the fits, the first seconds of each for a figure, and the
/// tests whose simulation stopped (with why).
#[derive(Debug, Clone, Default)]
pub struct Comparison {
    pub fits: Vec<ChannelFit>,
    pub traces: Vec<Trace>,
    pub stopped: Vec<String>,
}

/// Per test of `tests` (with its role) and channel of `channels` it recorded: the fit of
/// `p`. A test whose simulation stopped is reported with the reason.
pub fn compare(
    p: &Params,
    c: &Campaign,
    tests: &[(usize, Role)],
    channels: &[Measured],
) -> Comparison {
    let runs: Vec<(usize, Role, Result<Vec<Outputs>, SimulationStopped>)> = tests
        .par_iter()
        .map(|&(i, role)| (i, role, simulate_test(p, c, i)))
        .collect();
    let mut out = Comparison::default();
    for (i, role, run) in runs {
        let sim = match run {
            Ok(s) => s,
            Err(e) => {
                out.stopped.push(e.to_string());
                continue;
            }
        };
        for &m in channels {
            let Some(meas) = c.records[i].measured(m) else {
                continue;
            };
            let s: Vec<f64> = sim.iter().map(|o| simulated(o, m)).collect();
            if let Some((e, rms)) = nrmse(meas, &s) {
                let test = &c.info.tests[i].name;
                let noise_rms = c.rest_segment(i).map(|r| centred_rms(&meas[r]));
                let ceiling = noise_rms.and_then(|n| noise_ceiling(n, rms));
                out.traces
                    .push(trace(test, m.name(), role, c.sample_rate_of(i), meas, &s));
                out.fits.push(ChannelFit {
                    test: test.clone(),
                    channel: m.name(),
                    role,
                    nrmse: e,
                    fit_percent: 100.0 * (1.0 - e),
                    measured_rms: rms,
                    noise_rms,
                    noise_ceiling_percent: ceiling,
                    noise_limited: ceiling.is_some_and(|c| c < NOISE_LIMITED_CEILING_PERCENT),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::short_campaign;

    /// Points of fit % by which the true table's noise-free simulation may exceed the
    /// noise ceiling: the noise's own draw over a test (its RMS over 8 s is known to a
    /// percent or two).
    const CEILING_SLACK_POINTS: f64 = 2.0;

    /// The true table simulated noise-free fits a test at most as well as its noise at
    /// rest allows, and about that well where the motion dominates (a random test); a
    /// slow sine's acceleration is mostly noise (noise-limited: a low fit that says
    /// nothing against the model), and in motion more so than at rest.
    #[test]
    fn the_true_table_fits_no_better_than_the_noise_at_rest_allows() {
        let truth = Params::trees_lab();
        let c = short_campaign(&truth, &["R1", "S1"], 8.0);
        let tests = [(0, Role::Validation), (1, Role::Validation)];
        let cmp = compare(&truth, &c, &tests, &[Measured::Acceleration]);
        assert_eq!(cmp.fits.len(), 2, "{:?}", cmp.stopped);
        for f in &cmp.fits {
            let ceiling = f
                .noise_ceiling_percent
                .expect("a synthetic test starts at rest");
            assert!(
                f.fit_percent < ceiling + CEILING_SLACK_POINTS,
                "{} fit {:.1} % for a ceiling of {ceiling:.1} %",
                f.test,
                f.fit_percent
            );
        }
        let fit = |name: &str| cmp.fits.iter().find(|f| f.test == name).unwrap();
        let r1 = fit("R1");
        let r1_ceiling = r1.noise_ceiling_percent.unwrap();
        assert!(
            r1.fit_percent > r1_ceiling - CEILING_SLACK_POINTS,
            "R1 {r1:?}"
        );
        assert!(fit("S1").noise_limited && !r1.noise_limited);
    }

    #[test]
    fn the_figure_starts_a_second_before_the_motion() {
        let fs = 100.0;
        // 3 s at rest (with a little noise), then a step and a sine
        let x: Vec<f64> = (0..1000)
            .map(|k| match k < 300 {
                true => 1e-4 * ((k * 7919) % 13) as f64,
                false => 1.0 + (2.0 * (k - 300) as f64 / fs).sin(),
            })
            .collect();
        assert_eq!(trace_start(&x, fs), 200);
        let t = trace("T", "displacement_m", Role::Validation, fs, &x, &x);
        assert_eq!(t.time_s.first(), Some(&2.0));
        // a record that moves from its start is drawn from its start
        assert_eq!(trace_start(&x[300..], fs), 0);
    }

    #[test]
    fn nrmse_is_zero_for_a_perfect_model_and_one_for_a_silent_one() {
        let y: Vec<f64> = (0..100).map(|k| (k as f64 * 0.3).sin() + 5.0).collect();
        let (e, rms) = nrmse(&y, &y).unwrap();
        assert!(e < 1e-12);
        assert!(
            (rms - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.02,
            "{rms}"
        );
        // an offset alone is not an error (the sensor's zero)
        let shifted: Vec<f64> = y.iter().map(|v| v - 3.0).collect();
        assert!(nrmse(&y, &shifted).unwrap().0 < 1e-12);
        let flat = vec![1.0; 100];
        assert!((nrmse(&y, &flat).unwrap().0 - 1.0).abs() < 1e-12);
        // half the amplitude: NRMSE 0.5, fit 50 %
        let half: Vec<f64> = y.iter().map(|v| 0.5 * (v - 5.0)).collect();
        assert!((nrmse(&y, &half).unwrap().0 - 0.5).abs() < 1e-3);
        assert!(
            nrmse(&flat, &y).is_none(),
            "a flat measured channel has no NRMSE"
        );
    }
}

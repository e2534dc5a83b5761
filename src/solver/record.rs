//! Sampled runs of the model: a record's readings at every sample, or where and why the
//! run had to stop ([`Diverged`], typed rather than NaN readings a caller could take for a
//! response). [`Run`] is the same run padded to its length, for the callers that read it
//! sample by sample to the end (the command line, synthesis, the grey-box comparison).

use super::{Checks, Simulator};
use crate::model::{Inputs, Model, Outputs, SensorNoise};

/// A run the guards of [`Simulator::diverged`] stopped: it left the operating envelope
/// or went unstable. It has no readings from the stop on; those before it are kept for a
/// caller that wants the partial run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the run stopped at sample {} (t = {time_s} s): {reason}", .outputs.len())]
pub struct Diverged {
    /// Time of the first sample without a reading, s.
    pub time_s: f64,
    /// Why ([`Simulator::diverged`]'s message).
    pub reason: String,
    /// The readings before the stop, sample `k` at `t_k = k / sample_rate`.
    pub outputs: Vec<Outputs>,
    /// The samples the run was asked for.
    pub samples: usize,
}

impl Diverged {
    /// Index of the first sample without a reading.
    pub fn sample(&self) -> usize {
        self.outputs.len()
    }
}

/// A simulated record: the noise-free readings at every sample, or where it stopped.
pub type Simulated = Result<Vec<Outputs>, Diverged>;

/// A simulated record padded to every sample, and, if the run had to stop, when and why.
#[derive(Debug, Clone)]
pub struct Run {
    /// Noise-free readings at every sample; NaN from the stop on ([`DIVERGED`]).
    pub outputs: Vec<Outputs>,
    /// The stop, if any: the time of the first NaN sample and [`Simulator::diverged`]'s
    /// message.
    pub stop: Option<Stop>,
}

/// Where and why a run stopped.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop {
    pub time_s: f64,
    pub reason: String,
}

/// What a [`Run`] reads for the samples after its stop.
const DIVERGED: Outputs = Outputs {
    valve_command: f64::NAN,
    spool_position: f64::NAN,
    displacement_m: f64::NAN,
    velocity_m_s: f64::NAN,
    acceleration_m_s2: f64::NAN,
    actuator_force_n: f64::NAN,
    pressure_a_pa: f64::NAN,
    pressure_b_pa: f64::NAN,
};

impl From<Simulated> for Run {
    /// Every sample of the run, [`DIVERGED`] from a stop on.
    fn from(run: Simulated) -> Run {
        match run {
            Ok(outputs) => Run {
                outputs,
                stop: None,
            },
            Err(d) => {
                let mut outputs = d.outputs;
                outputs.resize(d.samples, DIVERGED);
                let stop = Stop {
                    time_s: d.time_s,
                    reason: d.reason,
                };
                Run {
                    outputs,
                    stop: Some(stop),
                }
            }
        }
    }
}

/// Simulate a sampled record: `inputs[k]` at `t_k = k / sample_rate`, optional sensor
/// noise per sample (held over the sample interval, inside the loop). Returns the
/// noise-free readings at every sample; `valve_command` is what the controller sent,
/// i.e. computed on the noisy feedback. A run that leaves the envelope or diverges
/// ([`Simulator::diverged`]) stops there: [`Diverged`] says when and why, with the
/// readings before.
pub fn simulate_record(
    model: &Model,
    inputs: &[Inputs],
    sample_rate_hz: f64,
    noise: Option<&[SensorNoise]>,
    max_substep_s: f64,
) -> Simulated {
    simulate_record_with(
        model,
        inputs,
        sample_rate_hz,
        noise,
        max_substep_s,
        Checks::Envelope,
    )
}

/// [`simulate_record`] stopping on `checks` only.
pub fn simulate_record_with(
    model: &Model,
    inputs: &[Inputs],
    sample_rate_hz: f64,
    noise: Option<&[SensorNoise]>,
    max_substep_s: f64,
    checks: Checks,
) -> Simulated {
    let sim = Simulator::new(model.clone(), 0.0, max_substep_s);
    run_observed(sim, inputs, sample_rate_hz, noise, checks, &|_| {})
}

/// [`simulate_record`] padded to every sample ([`Run`]).
pub fn simulate_run(
    model: &Model,
    inputs: &[Inputs],
    sample_rate_hz: f64,
    noise: Option<&[SensorNoise]>,
    max_substep_s: f64,
) -> Run {
    simulate_record(model, inputs, sample_rate_hz, noise, max_substep_s).into()
}

/// [`simulate_record_with`] padded to every sample ([`Run`]).
pub fn simulate_run_with(
    model: &Model,
    inputs: &[Inputs],
    sample_rate_hz: f64,
    noise: Option<&[SensorNoise]>,
    max_substep_s: f64,
    checks: Checks,
) -> Run {
    simulate_record_with(model, inputs, sample_rate_hz, noise, max_substep_s, checks).into()
}

/// Samples between two calls of a run's progress callback.
pub const PROGRESS_EVERY_SAMPLES: usize = 1024;

/// [`simulate_run`] that calls `progress(samples done)` every
/// [`PROGRESS_EVERY_SAMPLES`] samples (a progress bar for long runs).
pub fn simulate_run_observed(
    model: &Model,
    inputs: &[Inputs],
    sample_rate_hz: f64,
    max_substep_s: f64,
    progress: &dyn Fn(usize),
) -> Run {
    let sim = Simulator::new(model.clone(), 0.0, max_substep_s);
    run_observed(
        sim,
        inputs,
        sample_rate_hz,
        None,
        Checks::Envelope,
        progress,
    )
    .into()
}

fn run_observed(
    mut sim: Simulator,
    inputs: &[Inputs],
    sample_rate_hz: f64,
    noise: Option<&[SensorNoise]>,
    checks: Checks,
    progress: &dyn Fn(usize),
) -> Simulated {
    sim.checks = checks;
    let dt = 1.0 / sample_rate_hz;
    let zero = SensorNoise::default();
    let mut out = Vec::with_capacity(inputs.len());
    for k in 0..inputs.len() {
        let nk = noise.map(|n| &n[k]).unwrap_or(&zero);
        out.push(sim.outputs(&inputs[k], nk));
        if k % PROGRESS_EVERY_SAMPLES == 0 {
            progress(k);
        }
        if k + 1 < inputs.len() {
            sim.advance(dt, &inputs[k], &inputs[k + 1], nk);
            // keep sample times exact (no drift from repeated addition)
            sim.time_s = (k + 1) as f64 * dt;
            if let Some(reason) = sim.diverged() {
                return Err(Diverged {
                    time_s: sim.time_s,
                    reason,
                    outputs: out,
                    samples: inputs.len(),
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stopped run keeps its readings before the stop; as a [`Run`] it has every
    /// sample, NaN from the stop on, and the stop's time and reason.
    #[test]
    fn a_diverged_run_pads_to_its_samples_with_nan() {
        let run: Simulated = Err(Diverged {
            time_s: 0.5,
            reason: "runaway".into(),
            outputs: vec![Outputs::default(); 2],
            samples: 4,
        });
        assert_eq!(run.as_ref().unwrap_err().sample(), 2);
        let all = Run::from(run);
        assert_eq!(all.outputs.len(), 4);
        assert_eq!(all.outputs[1], Outputs::default());
        assert!(all.outputs[2].displacement_m.is_nan() && all.outputs[3].valve_command.is_nan());
        let stop = all.stop.expect("stopped");
        assert_eq!((stop.time_s, stop.reason.as_str()), (0.5, "runaway"));
    }
}

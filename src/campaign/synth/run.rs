//! Simulating tests: one test's reference, seeded in-loop noise, simulation and record;
//! any program in parallel; the paper's program.

use super::*;
use crate::campaign::{Campaign, CampaignInfo, ControllerOverride, Geometry, Record, TestSpec};
use crate::model::{Inputs, Model, Outputs, SensorNoise};
use crate::params::Params;
use crate::solver::simulate_run;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

/// One synthesised test with what the file does not hold: the noise-free readings and
/// the noise samples (for tests of the synthesis itself; identification sees `record`).
#[derive(Debug, Clone)]
pub struct SynthTest {
    pub record: Record,
    /// Noise-free readings at every sample (`valve_command` is the one actually sent).
    pub truth: Vec<Outputs>,
    /// Feedback noise at every sample (inside the loop).
    pub noise: Vec<SensorNoise>,
    /// Spool measurement noise at every sample (not fed back).
    pub spool_noise: Vec<f64>,
}

/// Synthesise one test: reference, seeded in-loop noise, simulation, record.
/// `index` is the test's index in its program (it selects the random streams).
pub fn synthesise_test(
    params: &Params,
    spec: &TestSpec,
    index: usize,
    opts: &SynthOptions,
    sample_rate_hz: f64,
) -> Result<SynthTest, SynthError> {
    let fs = sample_rate_hz;
    let r = reference(spec, index, opts.seed, opts.random_duration_s, fs)?;
    let inputs = r.inputs();
    let (noise, spool_noise) = sensor_noise(opts.seed, index, r.len(), &opts.noise);
    let noise_arg = if opts.noise.is_none() {
        None
    } else {
        Some(&noise[..])
    };
    let truth = simulate_test(params, spec, &inputs, fs, noise_arg, opts.max_substep_s)?;
    let readings = Readings {
        truth: &truth,
        noise: &noise,
        spool_noise: &spool_noise,
    };
    let rec = readings.record(r, fs);
    Ok(SynthTest {
        record: rec,
        truth,
        noise,
        spool_noise,
    })
}

/// The test's sensor noise, `n` samples of white noise at the levels `nl`: seeded per
/// test (stream `2 index + 1` of `seed`), drawn in a fixed order per sample (spool,
/// displacement, acceleration, force). Returns the feedback noise and the spool's.
fn sensor_noise(
    seed: u64,
    index: usize,
    n: usize,
    nl: &NoiseLevels,
) -> (Vec<SensorNoise>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(2 * index as u64 + 1);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let mut noise = Vec::with_capacity(n);
    let mut spool_noise = Vec::with_capacity(n);
    for _ in 0..n {
        spool_noise.push(nl.spool * normal.sample(&mut rng));
        noise.push(SensorNoise {
            displacement_m: nl.displacement_m * normal.sample(&mut rng),
            acceleration_m_s2: nl.acceleration_m_s2 * normal.sample(&mut rng),
            force_n: nl.force_n * normal.sample(&mut rng),
        });
    }
    (noise, spool_noise)
}

/// Simulate the table under `spec`'s controller with the feedback noise `noise` (inside
/// the loop, `None` for none); the noise-free readings at every sample, or the test's
/// error if the run stops.
fn simulate_test(
    params: &Params,
    spec: &TestSpec,
    inputs: &[Inputs],
    fs: f64,
    noise: Option<&[SensorNoise]>,
    max_substep_s: f64,
) -> Result<Vec<Outputs>, SynthError> {
    let mut p = *params;
    p.controller = spec.controller.apply(&params.controller);
    let model = Model::new(&p);
    let run = simulate_run(&model, inputs, fs, noise, max_substep_s);
    if let Some(stop) = run.stop {
        return Err(SynthError::BadTest {
            name: spec.name.clone(),
            message: stop.reason,
        });
    }
    Ok(run.outputs)
}

/// A simulated test's readings: the noise-free truth and the noise the sensors added.
struct Readings<'a> {
    truth: &'a [Outputs],
    noise: &'a [SensorNoise],
    spool_noise: &'a [f64],
}

impl Readings<'_> {
    /// The test's record at `fs`: its reference `r`, the measured channels and the
    /// noise-free extras.
    fn record(&self, r: ReferenceSignal, fs: f64) -> Record {
        let truth = self.truth;
        Record {
            time_s: (0..r.len()).map(|k| k as f64 / fs).collect(),
            ref_displacement_m: r.displacement_m,
            ref_velocity_m_s: r.velocity_m_s,
            ref_acceleration_m_s2: r.acceleration_m_s2,
            // the controller's own digital signal: no added noise
            valve_command: Some(truth.iter().map(|o| o.valve_command).collect()),
            // measured channels: the true reading plus the very noise the controller saw
            spool_position: Some(
                truth
                    .iter()
                    .zip(self.spool_noise)
                    .map(|(o, e)| o.spool_position + e)
                    .collect(),
            ),
            displacement_m: Some(self.measured(|o, e| o.displacement_m + e.displacement_m)),
            acceleration_m_s2: Some(
                self.measured(|o, e| o.acceleration_m_s2 + e.acceleration_m_s2),
            ),
            force_n: Some(self.measured(|o, e| o.actuator_force_n + e.force_n)),
            extra: self.extras(),
        }
    }

    /// A measured channel: `reading(true output, its noise)` at every sample.
    fn measured(&self, reading: impl Fn(&Outputs, &SensorNoise) -> f64) -> Vec<f64> {
        self.truth
            .iter()
            .zip(self.noise)
            .map(|(o, e)| reading(o, e))
            .collect()
    }

    /// Extra channels for users (plots, checks): noise-free truths. Identification and
    /// diagnosis do not use them.
    fn extras(&self) -> Vec<(String, Vec<f64>)> {
        let truth = self.truth;
        vec![
            (
                "velocity_m_s".to_string(),
                truth.iter().map(|o| o.velocity_m_s).collect(),
            ),
            (
                "pressure_a_pa".to_string(),
                truth.iter().map(|o| o.pressure_a_pa).collect(),
            ),
            (
                "pressure_b_pa".to_string(),
                truth.iter().map(|o| o.pressure_b_pa).collect(),
            ),
        ]
    }
}

/// Progress callback: `(samples done, samples in total)`, called from worker threads
/// after each test.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// Synthesise any list of tests (`(index, spec)`: index selects the random streams) in
/// parallel, each at its own `sample_rate_hz` if it has one, else at [`SAMPLE_RATE_HZ`]
/// (the campaign's rate; a rate every test shares becomes the campaign's). The campaign's
/// `[controller]` and geometry come from `params`.
pub fn synthesise_program(
    params: &Params,
    program: &[(usize, TestSpec)],
    opts: &SynthOptions,
    progress: Option<Progress>,
) -> Result<Campaign, SynthError> {
    let shared = shared_rate(program);
    let fs = shared.unwrap_or(SAMPLE_RATE_HZ);
    let rate = |s: &TestSpec| s.sample_rate_hz.unwrap_or(fs);
    for (_, s) in program {
        check_spec(s, opts.random_duration_s, rate(s))?;
    }
    let total: u64 = program
        .iter()
        .map(|(_, s)| test_samples(s, opts.random_duration_s, rate(s)) as u64)
        .sum();
    let done = AtomicU64::new(0);
    let records = program
        .par_iter()
        .map(|(i, s)| {
            let t = synthesise_test(params, s, *i, opts, rate(s))?;
            let d =
                done.fetch_add(t.record.len() as u64, Ordering::Relaxed) + t.record.len() as u64;
            if let Some(cb) = progress {
                cb(d, total);
            }
            Ok(t.record)
        })
        .collect::<Result<Vec<Record>, SynthError>>()?;
    let names: Vec<&str> = program.iter().map(|(_, s)| s.name.as_str()).collect();
    Ok(Campaign {
        // made in memory: no file read
        sources: Default::default(),
        dir: PathBuf::new(),
        info: CampaignInfo {
            name: format!(
                "Synthetic campaign ({}; seed {})",
                if names.len() == 18 && opts.tests.is_none() {
                    "paper program".to_string()
                } else {
                    names.join(" ")
                },
                opts.seed
            ),
            sample_rate_hz: fs,
            geometry: Geometry::from_params(params),
            controller: ControllerOverride::known(&params.controller),
            tests: program
                .iter()
                .map(|(_, s)| TestSpec {
                    // a shared rate is said once, as the campaign's
                    sample_rate_hz: s.sample_rate_hz.filter(|_| shared.is_none()),
                    ..s.clone()
                })
                .collect(),
        },
        records,
    })
}

/// The sample rate every test of `program` sets, if they all set the same one.
fn shared_rate(program: &[(usize, TestSpec)]) -> Option<f64> {
    let first = program.first()?.1.sample_rate_hz?;
    program
        .iter()
        .all(|(_, s)| s.sample_rate_hz == Some(first))
        .then_some(first)
}

/// The paper's program (or the subset `opts.tests`) with `(index, spec)` pairs.
pub fn selected_program(opts: &SynthOptions) -> Vec<(usize, TestSpec)> {
    paper_program(opts.random_duration_s)
        .into_iter()
        .enumerate()
        .filter(|(_, s)| match &opts.tests {
            Some(names) => names.iter().any(|n| n == &s.name),
            None => true,
        })
        .collect()
}

/// Synthesise the paper's test program (or the subset `opts.tests`) in memory
/// (`dir` is empty; [`write_synthetic`] or [`synthesise_to_dir`] put it on disk).
///
/// # Panics
/// If `opts.validate()` fails (the command line validates first); use
/// [`synthesise_program`] for a `Result`. `params` must be valid.
pub fn synthesise(params: &Params, opts: &SynthOptions, progress: Option<Progress>) -> Campaign {
    if let Err(e) = opts.validate() {
        panic!("invalid synthesis options: {e}");
    }
    synthesise_program(params, &selected_program(opts), opts, progress)
        .unwrap_or_else(|e| panic!("paper program: {e}"))
}

/// The paper's tests `names` of `truth` at the default seed and noise, their random
/// records `random_duration_s` long: the short campaign a unit test builds.
#[cfg(test)]
pub(crate) fn short_campaign(truth: &Params, names: &[&str], random_duration_s: f64) -> Campaign {
    let opts = SynthOptions {
        random_duration_s,
        tests: Some(names.iter().map(|n| n.to_string()).collect()),
        ..SynthOptions::default()
    };
    synthesise(truth, &opts, None)
}

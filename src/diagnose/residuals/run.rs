//! Simulating a test for diagnosis with the test's gains: the readings at every sample,
//! or where and why the run stopped ([`Diverged`]).

use super::Part;
use crate::campaign::Campaign;
use crate::params::Params;
use crate::solver::{simulate_run_with, Checks, DEFAULT_MAX_SUBSTEP_S, DIVERGED};
use crate::{Model, Outputs, SensorNoise};
use std::borrow::Cow;

/// A diagnosis run of one test: the readings at every sample, or [`Diverged`].
pub type TestRun = Result<Vec<Outputs>, Diverged>;

/// A run the divergence guards stopped (a non-finite state or a runaway speed): it has
/// no readings from the stop on, so whatever it is scored on there scores infinitely bad.
#[derive(Debug, Clone)]
pub struct Diverged {
    /// Time of the first sample without a reading, s.
    pub time_s: f64,
    /// Why the solver stopped ([`crate::solver::Stop`]).
    pub reason: String,
    /// The readings before the stop.
    pub readings: Vec<Outputs>,
    /// The samples the run was asked for.
    pub samples: usize,
}

/// The readings `run` has: every sample's, or those before its stop.
pub fn readings(run: &TestRun) -> &[Outputs] {
    match run {
        Ok(v) => v,
        Err(d) => &d.readings,
    }
}

/// Every sample of `run`, NaN from a stop on (as the solver pads a run): for plots and
/// figures read sample by sample over a whole run.
pub fn padded(run: &TestRun) -> Cow<'_, [Outputs]> {
    match run {
        Ok(v) => Cow::Borrowed(v),
        Err(d) => {
            let mut v = d.readings.clone();
            v.resize(d.samples, DIVERGED);
            Cow::Owned(v)
        }
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
) -> TestRun {
    let q = with_test_gains(p, c, i);
    let inputs = c.records[i].inputs();
    let end = part.range(inputs.len()).end;
    let run = simulate_run_with(
        &Model::new(&q),
        &inputs[..end],
        c.sample_rate_of(i),
        noise.map(|n| &n[..end.min(n.len())]),
        DIAGNOSIS_SUBSTEP_S,
        Checks::DivergenceOnly,
    );
    let Some(stop) = run.stop else {
        return Ok(run.outputs);
    };
    let samples = run.outputs.len();
    let mut readings = run.outputs;
    // the solver writes NaN from the stop on ([`crate::solver::first_divergence`])
    let first_nan = readings.iter().position(|o| o.displacement_m.is_nan());
    readings.truncate(first_nan.unwrap_or(samples));
    Err(Diverged {
        time_s: stop.time_s,
        reason: stop.reason,
        readings,
        samples,
    })
}

/// `p` with test `i`'s controller gains: the ones the campaign gives (the test's own over
/// the campaign's); a gain it does not give is `p`'s, the closed-loop fit's when the
/// campaign left it unknown.
pub fn with_test_gains(p: &Params, c: &Campaign, i: usize) -> Params {
    let mut q = *p;
    q.controller = c.info.tests[i]
        .controller
        .over(&c.info.controller)
        .apply(&p.controller);
    q
}

/// Largest RK4 sub-step of the diagnosis' simulations: 1/1024 s, three times the
/// solver's default ([`DEFAULT_MAX_SUBSTEP_S`]): two sub-steps per sample at 512 Hz and
/// 1 kHz. The error grows as h^4, from the default's 5e-7 of the signal RMS to about
/// 4e-5, still a twentieth of the sensor noise. Measured: the refined baseline's
/// output-error cost on a clean campaign moves by 4e-6 of itself from 1/1536 s (which
/// moved it by 1e-5 from the default), and a campaign with a deadband and a specimen
/// (seed 803) gives the same causes to 1e-5 of their parameters, 22 % faster; the free
/// play's contact (about 190 Hz on the 41-t table) is still resolved, its gap within 2 %.
pub const DIAGNOSIS_SUBSTEP_S: f64 = 3.0 * DEFAULT_MAX_SUBSTEP_S;

/// Simulate test `i` of the campaign with `p` and the test's controller gains (noise-free).
pub fn simulate_test(p: &Params, c: &Campaign, i: usize, part: Part) -> TestRun {
    simulate_test_with(p, c, i, part, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stopped run keeps its readings before the stop; padded, it has every sample.
    #[test]
    fn a_diverged_run_pads_to_its_samples_with_nan() {
        let run: TestRun = Err(Diverged {
            time_s: 0.5,
            reason: "runaway".into(),
            readings: vec![Outputs::default(); 2],
            samples: 4,
        });
        assert_eq!(readings(&run).len(), 2);
        let all = padded(&run);
        assert_eq!(all.len(), 4);
        assert_eq!(all[1], Outputs::default());
        assert!(all[2].displacement_m.is_nan() && all[3].valve_command.is_nan());
    }
}

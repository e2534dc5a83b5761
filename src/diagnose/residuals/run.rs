//! Simulating a test for diagnosis with the test's gains: the readings at every sample,
//! or where and why the run stopped ([`Diverged`]).

use super::Part;
use crate::campaign::Campaign;
use crate::params::Params;
pub use crate::solver::Diverged;
use crate::solver::{simulate_record_with, Checks, Simulated, DEFAULT_MAX_SUBSTEP_S};
use crate::{Model, Outputs, SensorNoise};

/// A diagnosis run of one test: the readings at every sample, or where the solver
/// stopped it ([`Diverged`]: it has no readings from the stop on, so whatever it is scored
/// on there scores infinitely bad).
pub type TestRun = Simulated;

/// The readings `run` has: every sample's, or those before its stop.
pub fn readings(run: &TestRun) -> &[Outputs] {
    match run {
        Ok(v) => v,
        Err(d) => &d.outputs,
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
    simulate_record_with(
        &Model::new(&q),
        &inputs[..end],
        c.sample_rate_of(i),
        noise.map(|n| &n[..end.min(n.len())]),
        DIAGNOSIS_SUBSTEP_S,
        Checks::DivergenceOnly,
    )
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

//! Simulating a test for diagnosis: noise-free and with seeded in-loop sensor noise (the
//! predicted spread), and the normalised residual per channel.

use super::channels::{fed_back, measured, simulated};
use super::noise::NoiseFloor;
use super::Part;
use crate::campaign::{Campaign, Record};
use crate::params::Params;
use crate::solver::{simulate_run_with, Checks, DEFAULT_MAX_SUBSTEP_S};
use crate::{Model, Outputs, SensorNoise};

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
    // the gains the campaign gives (the test's own over the campaign's); a gain it does
    // not give is `p`'s: the closed-loop fit's when the campaign left it unknown
    let spec = &c.info.tests[i];
    q.controller = spec
        .controller
        .over(&c.info.controller)
        .apply(&p.controller);
    let inputs = c.records[i].inputs();
    let end = part.range(inputs.len()).end;
    simulate_run_with(
        &Model::new(&q),
        &inputs[..end],
        c.sample_rate_of(i),
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
pub(super) fn noise_seed(i: usize, r: usize) -> u64 {
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

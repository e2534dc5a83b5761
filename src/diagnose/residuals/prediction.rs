//! A model's prediction of a test for diagnosis: noise-free and with seeded in-loop
//! sensor noise (the predicted spread), and the normalised residual per channel.

use super::cell::{Cell, Cells};
use super::channels::{Channel, PerChannel};
use super::noise::NoiseFloor;
use super::run::{readings, simulate_test_with, TestRun};
use super::Part;
use crate::campaign::{Campaign, Record};
use crate::params::Params;
use crate::{Outputs, SensorNoise};
use std::ops::Range;

/// Normalised residual RMS per channel over `part` ([`Cell::Absent`] where the channel is
/// absent or has no noise estimate, [`Cell::Diverged`] where the run stopped inside
/// `part`): the heat map's "residual / noise RMS".
pub fn ratios(r: &Record, run: &TestRun, noise: &NoiseFloor, part: Part) -> Cells {
    let range = part.range(r.len());
    PerChannel::from_fn(|ch| {
        let (Some(m), Some(s)) = (ch.measured(r), noise.of(ch)) else {
            return Cell::Absent;
        };
        if range.is_empty() {
            return Cell::Absent;
        }
        let Some(sim) = readings(run).get(range.clone()) else {
            return Cell::Diverged;
        };
        let ss: f64 = range
            .clone()
            .zip(sim)
            .map(|(k, o)| (m[k] - ch.simulated(o)).powi(2))
            .sum();
        Cell::Scored((ss / range.len() as f64).sqrt() / s)
    })
}

/// A model's prediction of one test: its noise-free run and a run with seeded in-loop
/// noise (the same seed for every model, so that models are compared on one draw).
pub struct Prediction {
    pub locked: TestRun,
    /// [`REALISATIONS`] runs with independent noise draws.
    pub noisy: Vec<TestRun>,
    /// The noise each noisy run's feedback saw (its readings carry it too).
    pub draws: Vec<Vec<SensorNoise>>,
}

impl Prediction {
    /// The noise-free readings over `range`, `None` when the run stopped before its end.
    pub fn locked_over(&self, range: Range<usize>) -> Option<&[Outputs]> {
        readings(&self.locked).get(range)
    }

    /// The spread of channel `ch` over `range` for each noisy run: its readings plus the
    /// noise its feedback saw, minus the locked run (the coherent spread of [`scores`]);
    /// `None` when a run stopped before the end of `range`.
    ///
    /// [`scores`]: super::scores
    pub fn spread(&self, range: Range<usize>, ch: Channel) -> Option<Vec<Vec<f64>>> {
        let locked = self.locked_over(range.clone())?;
        self.noisy
            .iter()
            .zip(&self.draws)
            .map(|(run, draw)| {
                let run = readings(run).get(range.clone())?;
                let spread = run
                    .iter()
                    .zip(&draw[range.clone()])
                    .zip(locked)
                    .map(|((o, n), l)| ch.simulated(o) + ch.fed_back(n) - ch.simulated(l))
                    .collect();
                Some(spread)
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

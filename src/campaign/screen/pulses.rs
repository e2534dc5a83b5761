//! Short pulses that are the table's response, not glitches: an impact inside a free
//! play's gap, the chatter of a sticking bearing. At 512 Hz an impact on a light table
//! lasts a sample or two (the contact of a 300-kg rod on a 6-t table rings at about
//! 400 Hz), so the spike test of [`super::spikes`] cannot tell it from a corrupted
//! sample by its shape. It can by its timing: a periodic test's response recurs with its
//! reference, and these pulses come a little after each reversal, when the rod has
//! crossed the gap; a glitch falls anywhere.

use super::super::reversals::reversals;
use super::super::{Record, TestKind, TestSpec};

/// Share of the half period after each reversal of the reference in which a response
/// pulse may fall: a free play's impacts came 4-14 % of it after the reversals of the
/// paper's slow sines (0.4 mm, 6-t table, seed 81); a 2-mm gap takes about 0.9 s to
/// cross on the slowest (10 s half period). A glitch falls in these windows by chance
/// with this probability, so three of them all inside with 0.8 %.
const RESPONSE_WINDOW: f64 = 0.2;
/// Fewest distinct reversals the pulses must follow: a response recurs, a glitch or two
/// in the windows by chance does not make one.
const MIN_REVERSALS: usize = 3;
/// A pulse larger than this many times the largest excursion of the rest of the record
/// (from its median) is no response but a corrupted value (an impact reached about 3
/// times a slow sine's noise-dominated excursion; a corrupted sample reads 1e300).
const MAX_PULSE_RATIO: f64 = 100.0;

/// Where a periodic test's response may pulse: the [`RESPONSE_WINDOW`] after each
/// reversal of its reference.
pub(super) struct ResponseWindows {
    reversals: Vec<usize>,
    len: usize,
}

impl ResponseWindows {
    /// The windows of a sine or triangle with a declared frequency; `None` for other
    /// tests (a random test's reference reverses every few samples, so its windows would
    /// cover the record).
    pub(super) fn of(spec: &TestSpec, r: &Record, fs: f64) -> Option<ResponseWindows> {
        if !matches!(spec.kind, TestKind::Sine | TestKind::Triangle) {
            return None;
        }
        let f = spec.frequency_hz.filter(|f| f.is_finite() && *f > 0.0)?;
        let half_period = fs / (2.0 * f);
        let reversals: Vec<usize> = reversals(&r.ref_velocity_m_s, fs)
            .into_iter()
            .map(|(k, _)| k)
            .collect();
        Some(ResponseWindows {
            reversals,
            len: (RESPONSE_WINDOW * half_period) as usize,
        })
    }

    /// The reversal whose window holds sample `i`, if any.
    fn reversal_before(&self, i: usize) -> Option<usize> {
        let k = self.reversals.partition_point(|&r| r <= i);
        let r = *self.reversals.get(k.checked_sub(1)?)?;
        (i - r <= self.len).then_some(r)
    }

    /// Whether the spikes `spikes` of channel `x` (median `median`) are the response:
    /// every one inside a window, after at least [`MIN_REVERSALS`] reversals, and none
    /// beyond [`MAX_PULSE_RATIO`] times the rest of the record's largest excursion.
    pub(super) fn hold(&self, x: &[f64], median: f64, spikes: &[usize]) -> bool {
        let mut after: Vec<usize> = Vec::new();
        for &i in spikes {
            match self.reversal_before(i) {
                Some(r) => after.push(r),
                None => return false,
            }
        }
        after.dedup();
        let excursion = |i: usize| (x[i] - median).abs();
        let rest = (0..x.len())
            .filter(|i| spikes.binary_search(i).is_err())
            .map(excursion)
            .fold(0.0f64, f64::max);
        let largest = spikes.iter().map(|&i| excursion(i)).fold(0.0f64, f64::max);
        after.len() >= MIN_REVERSALS && largest <= MAX_PULSE_RATIO * rest
    }
}

#[cfg(test)]
mod tests {
    use super::super::{screen, Action};
    use super::ResponseWindows;
    use crate::campaign::synth::{synthesise, SynthOptions};
    use crate::params::Params;

    /// A 6-t table (the TREES Lab table scaled, `scripts/dev/table_6t.toml`) with a
    /// 0.4-mm free play and a 300-kg rod, on its slowest sine.
    fn light_table_with_play(seed: u64) -> crate::campaign::Campaign {
        let mut p = Params::trees_lab();
        let r = 6000.0 / p.table.mass_kg;
        p.table.mass_kg = 6000.0;
        p.actuator.piston_area_m2 *= r;
        p.actuator.total_oil_volume_m3 *= r;
        p.actuator.flow_gain_m3_s *= r;
        p.actuator.leakage_m3_s_pa *= r;
        p.friction.force_n *= r;
        p.controller.kdp /= r;
        p.free_play.enabled = true;
        p.free_play.gap_m = 4e-4;
        p.free_play.rod_mass_kg = 300.0;
        let opts = SynthOptions {
            tests: Some(vec!["S1".to_string()]),
            seed,
            ..Default::default()
        };
        synthesise(&p, &opts, None)
    }

    /// The impacts of a free play on a light table pass the spike test, and they are kept
    /// as its response (on three noise seeds); glitches at random rows of the same record
    /// are still repaired, as is a single corrupted sample among the impacts.
    #[test]
    fn impacts_after_the_reversals_are_kept_and_glitches_are_not() {
        for seed in [81, 82, 83] {
            let c = light_table_with_play(seed);
            let s = screen(&c);
            let accel: Vec<_> = s
                .findings
                .iter()
                .filter(|f| f.channel == "acceleration_m_s2")
                .collect();
            assert!(
                accel.len() == 1 && accel[0].action == Action::KeptAsResponse,
                "seed {seed}: {accel:?}"
            );
            let kept = s.campaign.records[0].acceleration_m_s2.as_ref().unwrap();
            assert_eq!(kept, c.records[0].acceleration_m_s2.as_ref().unwrap());

            // mid-stroke, half a window past the end of the second reversal's
            let fs = c.sample_rate_for(&c.info.tests[0]);
            let w = ResponseWindows::of(&c.info.tests[0], &c.records[0], fs).unwrap();
            let mid = w.reversals[1] + 3 * w.len / 2;
            let mut glitched = c.clone();
            let a = glitched.records[0].acceleration_m_s2.as_mut().unwrap();
            a[mid] = 40.0;
            let s = screen(&glitched);
            let repaired = s
                .findings
                .iter()
                .any(|f| f.channel == "acceleration_m_s2" && f.action == Action::Repaired);
            assert!(repaired, "seed {seed}: {:?}", s.findings);
        }
    }
}

//! Short pulses that are the table's response, not glitches: an impact inside a free
//! play's gap, the chatter of a sticking bearing. At 512 Hz an impact on a light table
//! lasts a sample or two (the contact of a 300-kg rod on a 6-t table rings at about
//! 400 Hz), so the spike test of [`super::spikes`] cannot tell it from a corrupted
//! sample by its shape. It can by its timing: a periodic test's response recurs with its
//! reference, and these pulses come a little after each change of its motion (a
//! reversal, the set-off, the stop), when the rod has crossed the gap; a glitch falls
//! anywhere.

use super::super::reversals::motion_changes;
use super::super::{Record, TestKind, TestSpec};

/// Share of the half period after each change of the reference's motion (a reversal, a
/// set-off, a stop: [`motion_changes`]) in which a response pulse may fall: a free play's
/// impacts came 4-14 % of it after the reversals of the paper's slow sines and 0-10 %
/// after the triangles' reversals and stops (0.4 mm, 6-t table, seed 81); a 2-mm gap
/// takes about 0.9 s to cross on the slowest sine (10 s half period). A glitch falls in
/// the windows of a test's six to twelve changes by chance with about this probability,
/// so three of them all inside with about 1 %.
const RESPONSE_WINDOW: f64 = 0.2;
/// Seconds before a change in which a pulse may fall too: a stop decelerates over about
/// 0.1 s, and a triangle's end-of-test impacts began 3 ms after the reference started to
/// slow, 90 ms before it rested.
const LEAD_S: f64 = 0.1;
/// Fewest distinct changes of the motion the pulses must follow: a response recurs, a
/// glitch or two in the windows by chance does not make one.
const MIN_CHANGES: usize = 3;
/// A pulse larger than this many times the largest excursion of the rest of the record
/// (from its median) is no response but a corrupted value (an impact reached about 3
/// times a slow sine's noise-dominated excursion; a corrupted sample reads 1e300).
const MAX_PULSE_RATIO: f64 = 100.0;

/// Where a periodic test's response may pulse: from [`LEAD_S`] before to the
/// [`RESPONSE_WINDOW`] after each change of its reference's motion.
pub(super) struct ResponseWindows {
    changes: Vec<usize>,
    lead: usize,
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
        Some(ResponseWindows {
            changes: motion_changes(&r.ref_velocity_m_s, fs),
            lead: (LEAD_S * fs) as usize,
            len: (RESPONSE_WINDOW * half_period) as usize,
        })
    }

    /// The change whose window holds sample `i`, if any.
    fn change_at(&self, i: usize) -> Option<usize> {
        let k = self.changes.partition_point(|&r| r <= i + self.lead);
        let r = *self.changes.get(k.checked_sub(1)?)?;
        (i + self.lead >= r && i <= r + self.len).then_some(r)
    }

    /// Whether the spikes `spikes` of channel `x` (median `median`) are the response:
    /// every one inside a window, at at least [`MIN_CHANGES`] changes, and none
    /// beyond [`MAX_PULSE_RATIO`] times the rest of the record's largest excursion.
    pub(super) fn hold(&self, x: &[f64], median: f64, spikes: &[usize]) -> bool {
        let mut after: Vec<usize> = Vec::new();
        for &i in spikes {
            match self.change_at(i) {
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
        after.len() >= MIN_CHANGES && largest <= MAX_PULSE_RATIO * rest
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
            tests: Some(vec!["S1".to_string(), "T1".to_string()]),
            seed,
            ..Default::default()
        };
        synthesise(&p, &opts, None)
    }

    /// The impacts of a free play on a light table pass the spike test, and on its slowest
    /// sine and triangle they are kept as its response (on three noise seeds); a glitch
    /// mid-stroke of the same sine is still repaired.
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
            let kept = |t: &str| {
                accel
                    .iter()
                    .any(|f| f.test == t && f.action == Action::KeptAsResponse)
            };
            assert!(
                accel.len() == 2 && kept("S1") && kept("T1"),
                "seed {seed}: {accel:?}"
            );
            for (screened, read) in s.campaign.records.iter().zip(&c.records) {
                assert_eq!(screened.acceleration_m_s2, read.acceleration_m_s2);
            }

            // mid-stroke, half a window past the end of the second change's
            let fs = c.sample_rate_for(&c.info.tests[0]);
            let w = ResponseWindows::of(&c.info.tests[0], &c.records[0], fs).unwrap();
            let mid = w.changes[1] + 3 * w.len / 2;
            let mut glitched = c.clone();
            let a = glitched.records[0].acceleration_m_s2.as_mut().unwrap();
            a[mid] = 40.0;
            let s = screen(&glitched);
            let repaired = s.findings.iter().any(|f| {
                f.test == "S1" && f.channel == "acceleration_m_s2" && f.action == Action::Repaired
            });
            assert!(repaired, "seed {seed}: {:?}", s.findings);
        }
    }
}

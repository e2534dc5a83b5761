//! Informed starts of the asymmetries of the catalogue's second part (spec section 7),
//! read off the periodic tests: the friction ratio from the force balance split by the
//! direction of motion, the flow ratio from velocity against spool split by the spool's
//! sign. (The free play's gap has no start read off the data yet: the LVDT/accelerometer
//! discrepancy at the reversals of the paper's sines is below the accelerometer's noise
//! at 0.05 Hz and not a clean square wave at 0.5 Hz; a grid starts it.)

use crate::campaign::{Campaign, Record, TestKind};
use crate::params::Params;

/// Samples count in a direction only while the speed exceeds this fraction of the test's
/// largest: near a reversal the Bouc-Wen friction is still turning round (pre-sliding)
/// and the velocity's sign says nothing about the friction's; a fifth keeps most of a
/// sine's cycle and drops the turn.
const SLIDING_SPEED_FRACTION: f64 = 0.2;

/// Spool samples count only beyond this fraction of the test's largest spool: near zero
/// the flow is leakage and compressibility more than the valve's gain.
const SPOOL_FRACTION: f64 = 0.2;

/// A ratio start is kept only within this factor of 1 either way: beyond, the direction
/// split is measuring something else (a specimen, a drift), and the caller's grid covers
/// the range anyway.
const RATIO_START_LIMIT: f64 = 5.0;

/// The periodic tests of `kinds` with their frequency, sample rate and record.
fn periodic<'a>(
    c: &'a Campaign,
    kinds: &'a [TestKind],
) -> impl Iterator<Item = (f64, f64, &'a Record)> {
    c.info
        .tests
        .iter()
        .zip(&c.records)
        .filter(|(t, _)| kinds.contains(&t.kind))
        .filter_map(move |(t, r)| Some((t.frequency_hz?, c.sample_rate_for(t), r)))
}

/// Sines and triangles.
const PERIODIC: [TestKind; 2] = [TestKind::Sine, TestKind::Triangle];

/// Central-difference velocity of `x` sampled at `fs`.
fn velocity(x: &[f64], fs: f64) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            if b > a {
                (x[b] - x[a]) * fs / (b - a) as f64
            } else {
                0.0
            }
        })
        .collect()
}

/// A ratio kept only when finite and within [`RATIO_START_LIMIT`].
fn plausible_ratio(r: f64) -> Option<f64> {
    (r.is_finite() && r > 1.0 / RATIO_START_LIMIT && r < RATIO_START_LIMIT).then_some(r)
}

/// `friction_asymmetry.ratio` from the force balance of the periodic tests: while sliding,
/// `F - M a - k_h x` is the friction `F_mu+` (moving positively) or `-F_mu-` (negatively);
/// the ratio is their quotient (the model's factors `2r/(1+r)`, `2/(1+r)`). Needs the
/// force, acceleration and displacement.
pub(super) fn friction_ratio_start(c: &Campaign, base: &Params) -> Option<f64> {
    let (mut pos, mut neg) = ((0.0, 0usize), (0.0, 0usize));
    for (_, fs, r) in periodic(c, &PERIODIC) {
        let (Some(f), Some(a), Some(x)) = (
            r.force_n.as_deref(),
            r.acceleration_m_s2.as_deref(),
            r.displacement_m.as_deref(),
        ) else {
            continue;
        };
        let v = velocity(x, fs);
        let vmax = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for k in 0..v.len().min(f.len()).min(a.len()) {
            let friction = f[k] - base.table.mass_kg * a[k] - base.table.stiffness_n_m * x[k];
            if v[k] > SLIDING_SPEED_FRACTION * vmax {
                pos = (pos.0 + friction, pos.1 + 1);
            } else if v[k] < -SLIDING_SPEED_FRACTION * vmax {
                neg = (neg.0 - friction, neg.1 + 1);
            }
        }
    }
    if pos.1 == 0 || neg.1 == 0 {
        return None;
    }
    plausible_ratio((pos.0 / pos.1 as f64) / (neg.0 / neg.1 as f64))
}

/// `flow_asymmetry.ratio` from the periodic tests: the table's speed over the spool (or
/// the valve command where no spool is recorded), a least-squares slope through zero for
/// each sign of the spool; the ratio is the positive slope over the negative one.
pub(super) fn flow_ratio_start(c: &Campaign) -> Option<f64> {
    // sums of x v and x^2 per sign of the spool
    let (mut pos, mut neg) = ((0.0, 0.0), (0.0, 0.0));
    for (_, fs, r) in periodic(c, &PERIODIC) {
        let (Some(s), Some(x)) = (
            r.spool_position.as_deref().or(r.valve_command.as_deref()),
            r.displacement_m.as_deref(),
        ) else {
            continue;
        };
        let v = velocity(x, fs);
        let smax = s.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (&sk, &vk) in s.iter().zip(&v) {
            if sk > SPOOL_FRACTION * smax {
                pos = (pos.0 + sk * vk, pos.1 + sk * sk);
            } else if sk < -SPOOL_FRACTION * smax {
                neg = (neg.0 + sk * vk, neg.1 + sk * sk);
            }
        }
    }
    if pos.1 <= 0.0 || neg.1 <= 0.0 {
        return None;
    }
    plausible_ratio((pos.0 / pos.1) / (neg.0 / neg.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratios_outside_the_plausible_range_are_no_start() {
        assert_eq!(plausible_ratio(1.3), Some(1.3));
        assert_eq!(plausible_ratio(RATIO_START_LIMIT * 1.01), None);
        assert_eq!(plausible_ratio(f64::NAN), None);
        assert_eq!(plausible_ratio(-1.0), None);
    }
}

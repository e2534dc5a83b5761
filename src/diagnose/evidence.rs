//! Whether a fitted candidate is evidence of its effect (issue 17 part 3): a near-empty
//! candidate (a deadband of 0.0001, a foundation whose damping sits at its bound) fitted
//! to physics outside the catalogue is not a cause, however much it helps.

use super::effect::Effect;
use super::effect_values::EffectBounds;
use std::collections::BTreeMap;

/// A strength parameter is significant when it lies more than this many sigma from its
/// no-effect value: two sigma, the usual 95 % two-sided test for a Gaussian estimate.
pub const EVIDENCE_SIGMAS: f64 = 2.0;

/// A parameter within this fraction of its range's width (or, on a range spanning
/// decades, of its bound's value) from a bound of its fitting range sits at the bound:
/// the optimiser was stopped by the range, not by the data, so its value is not an
/// estimate. One in a thousand is well below any fit's precision here (percents).
const AT_BOUND_FRACTION: f64 = 1e-3;

/// Why the fitted `parameters` (with their one-sigma `sigma`, where the fit gives them;
/// infinite where the data cannot fix one) of `effect` are not evidence of it, fitted
/// within `bounds`, if they are not; `None` when they are.
pub(super) fn not_evidence(
    effect: Effect,
    parameters: &BTreeMap<String, f64>,
    sigma: &BTreeMap<String, f64>,
    bounds: &EffectBounds,
) -> Option<String> {
    for (key, lo, hi) in bounds.iter() {
        let Some(&x) = parameters.get(key) else {
            continue;
        };
        if let Some(bound) = at_bound(x, lo, hi) {
            return Some(format!(
                "{}.{key} = {x:.4e} sits at the {bound} of its fitting range [{lo:.4e}, {hi:.4e}]: the range stopped the fit, not the data",
                effect.name()
            ));
        }
    }
    // every effect's parameter, whether or not it has a no-effect value (a flow limit's
    // is infinite)
    for key in effect.parameters() {
        if sigma.get(key).is_some_and(|s| !s.is_finite()) {
            return Some(format!(
                "{}.{key} is not fixed by the data: it lies along a null direction of the fit (it does not change the residual, or only together with other parameters it frees, e.g. a flow limit that never binds), so its uncertainty is unbounded",
                effect.name()
            ));
        }
    }
    for &(key, none) in effect.no_effect() {
        let (Some(&x), Some(&s)) = (parameters.get(key), sigma.get(key)) else {
            continue;
        };
        if (x - none).abs() <= EVIDENCE_SIGMAS * s {
            return Some(format!(
                "{}.{key} = {x:.4e} +- {s:.2e} (1 sigma) is within {EVIDENCE_SIGMAS} sigma of {none}, where the effect vanishes",
                effect.name()
            ));
        }
    }
    None
}

/// `"lower bound"` or `"upper bound"` when `x` sits at one ([`AT_BOUND_FRACTION`]).
fn at_bound(x: f64, lo: f64, hi: f64) -> Option<&'static str> {
    let width = hi - lo;
    let near = |b: f64| (x - b).abs() <= AT_BOUND_FRACTION * width.min(b.abs().max(width * 1e-6));
    // beyond a bound counts as at it: a fit the range did not hold (a start from a grid
    // past its edge) is no more evidence than one it stopped
    if x <= lo || near(lo) {
        Some("lower bound")
    } else if x >= hi || near(hi) {
        Some("upper bound")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::effect_values::EffectValues;

    fn map(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    /// The fitting range of `effect` from `(key, lower, upper)`.
    fn range(effect: Effect, ranges: &[(&str, f64, f64)]) -> EffectBounds {
        let side = |pick: fn(&(&str, f64, f64)) -> f64| {
            let pairs: Vec<(&str, f64)> = ranges.iter().map(|r| (r.0, pick(r))).collect();
            EffectValues::new(effect, &pairs)
        };
        EffectBounds {
            lower: side(|r| r.1),
            upper: side(|r| r.2),
        }
    }

    #[test]
    fn a_parameter_at_a_bound_is_not_evidence() {
        let b = range(
            Effect::of(&crate::effects::specimen::EFFECT),
            &[
                ("mass_kg", 200.0, 2e5),
                ("frequency_hz", 0.5, 60.0),
                ("damping_ratio", 0.002, 0.5),
            ],
        );
        let fitted = map(&[
            ("mass_kg", 8e3),
            ("frequency_hz", 6.0),
            ("damping_ratio", 0.002),
        ]);
        let why = not_evidence(
            Effect::of(&crate::effects::specimen::EFFECT),
            &fitted,
            &map(&[]),
            &b,
        )
        .unwrap();
        assert!(
            why.contains("damping_ratio") && why.contains("lower bound"),
            "{why}"
        );
        let inside = map(&[
            ("mass_kg", 8e3),
            ("frequency_hz", 6.0),
            ("damping_ratio", 0.03),
        ]);
        assert_eq!(
            not_evidence(
                Effect::of(&crate::effects::specimen::EFFECT),
                &inside,
                &map(&[]),
                &b
            ),
            None
        );
    }

    /// A deadband of 1e-4 +- 1e-4 cannot be told from none; 1e-2 +- 1e-3 can.
    /// A fit the range did not hold (stick-slip's grid once refined past its edge to a
    /// static ratio of 8.5 on a range up to 6) is not evidence either.
    #[test]
    fn a_parameter_beyond_a_bound_is_not_evidence() {
        let b = range(
            Effect::of(&crate::effects::stick_slip::EFFECT),
            &[
                ("static_ratio", 1.0, 6.0),
                ("stribeck_velocity_m_s", 1e-4, 0.05),
            ],
        );
        let beyond = map(&[("static_ratio", 8.5), ("stribeck_velocity_m_s", 0.01)]);
        let why = not_evidence(
            Effect::of(&crate::effects::stick_slip::EFFECT),
            &beyond,
            &map(&[]),
            &b,
        )
        .unwrap();
        assert!(
            why.contains("static_ratio") && why.contains("upper bound"),
            "{why}"
        );
        let inside = map(&[("static_ratio", 2.0), ("stribeck_velocity_m_s", 0.01)]);
        assert_eq!(
            not_evidence(
                Effect::of(&crate::effects::stick_slip::EFFECT),
                &inside,
                &map(&[]),
                &b
            ),
            None
        );
    }

    #[test]
    fn a_strength_within_two_sigma_of_no_effect_is_not_evidence() {
        let b = range(
            Effect::of(&crate::effects::valve_deadband::EFFECT),
            &[("deadband", 0.0, 0.2)],
        );
        let weak = map(&[("deadband", 1e-3)]);
        let why = not_evidence(
            Effect::of(&crate::effects::valve_deadband::EFFECT),
            &weak,
            &map(&[("deadband", 1e-3)]),
            &b,
        );
        assert!(why.unwrap().contains("vanishes"));
        let strong = map(&[("deadband", 1e-2)]);
        assert_eq!(
            not_evidence(
                Effect::of(&crate::effects::valve_deadband::EFFECT),
                &strong,
                &map(&[("deadband", 1e-3)]),
                &b
            ),
            None
        );
        // no sigma (a fit that gives none, as stick-slip's): only the bounds judge
        assert_eq!(
            not_evidence(
                Effect::of(&crate::effects::valve_deadband::EFFECT),
                &weak,
                &map(&[]),
                &b
            ),
            None
        );
        // a parameter the data cannot fix (infinite sigma) is no evidence
        let why = not_evidence(
            Effect::of(&crate::effects::valve_deadband::EFFECT),
            &strong,
            &map(&[("deadband", f64::INFINITY)]),
            &b,
        );
        assert!(why.unwrap().contains("null direction"));
    }
}

//! The reversals of a test's reference: where the commanded motion changes direction.
//! Screening keeps the response that pulses there ([`super::screen`]), and the diagnosis
//! reads the free play's gap across them.

/// A reference that changes sign within this many seconds reverses; a rest (zero speed
/// for longer) between two motions is not a reversal.
const REVERSAL_MAX_S: f64 = 0.1;
/// Reference speeds below this share of the test's largest count as zero: a derived
/// reference velocity wanders about zero at rest.
const REST_SPEED_FRACTION: f64 = 1e-3;

/// The reversals of the reference velocity `v` sampled at `fs`: the first sample of each
/// new direction and that direction (+-1), where the sign changes within
/// [`REVERSAL_MAX_S`].
pub fn reversals(v: &[f64], fs: f64) -> Vec<(usize, f64)> {
    let rest = REST_SPEED_FRACTION * v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut out = Vec::new();
    let mut last: Option<(usize, f64)> = None;
    for (k, &x) in v.iter().enumerate() {
        if x.abs() <= rest {
            continue;
        }
        let s = x.signum();
        if let Some((j, t)) = last {
            if t != s && ((k - j) as f64) < REVERSAL_MAX_S * fs {
                out.push((k, s));
            }
        }
        last = Some((k, s));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reference through zero reverses; one that rests at zero and sets off again the
    /// other way does not.
    #[test]
    fn reversals_are_sign_changes_without_a_rest() {
        let fs = 100.0;
        let mut v: Vec<f64> = (0..200)
            .map(|k| ((k as f64) / 50.0 * std::f64::consts::PI).sin())
            .collect();
        v.extend(std::iter::repeat_n(0.0, 100));
        // the last motion was negative: setting off positive after the rest
        v.extend((0..50).map(|k| (k as f64 + 1.0) / 50.0));
        let r = reversals(&v, fs);
        assert_eq!(r.len(), 3, "{r:?}");
        assert!(r.iter().all(|&(k, _)| k < 200), "{r:?}");
    }
}

//! The reversals of a test's reference: where the commanded motion changes direction.
//! Screening keeps the response that pulses there ([`super::screen`]), and the diagnosis
//! reads the free play's gap across them.

/// A reference that changes sign within this many seconds reverses; a rest (zero speed
/// for longer) between two motions is not a reversal.
const REVERSAL_MAX_S: f64 = 0.1;
/// Reference speeds below this share of the test's largest count as zero: a derived
/// reference velocity wanders about zero at rest.
const REST_SPEED_FRACTION: f64 = 1e-3;

/// The speed below which the reference velocity `v` counts as at rest
/// ([`REST_SPEED_FRACTION`] of its largest).
fn rest_speed(v: &[f64]) -> f64 {
    REST_SPEED_FRACTION * v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The reversals of the reference velocity `v` sampled at `fs`: the first sample of each
/// new direction and that direction (+-1), where the sign changes within
/// [`REVERSAL_MAX_S`].
pub fn reversals(v: &[f64], fs: f64) -> Vec<(usize, f64)> {
    let rest = rest_speed(v);
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

/// Every sample where the reference's motion changes: its reversals, and where it sets off
/// from rest or comes to rest (a rest being a pause of at least [`REVERSAL_MAX_S`], or the
/// record's ends), sorted. A play between rod and table is crossed at each.
pub fn motion_changes(v: &[f64], fs: f64) -> Vec<usize> {
    let rest = rest_speed(v);
    let moving: Vec<usize> = (0..v.len()).filter(|&k| v[k].abs() > rest).collect();
    let (Some(&first), Some(&last)) = (moving.first(), moving.last()) else {
        return Vec::new();
    };
    let mut out = vec![first];
    for w in moving.windows(2) {
        if ((w[1] - w[0]) as f64) >= REVERSAL_MAX_S * fs {
            out.extend([w[0], w[1]]);
        }
    }
    out.push(last);
    out.extend(reversals(v, fs).into_iter().map(|(k, _)| k));
    out.sort_unstable();
    out.dedup();
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
        // and the motion changes there, at the start, before and after the rest, at the end
        let m = motion_changes(&v, fs);
        let expected: Vec<usize> = [1, 199, 300, 349]
            .into_iter()
            .chain(r.iter().map(|&(k, _)| k))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        assert_eq!(m, expected);
    }
}

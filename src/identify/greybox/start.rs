//! Informed starts of the closed-loop fit, read off the measured response of the table
//! to its reference (Welch H1): the loop bandwidth sets the loop gain, the valve's time
//! constant and the band in which the oil column may lie; a resonance peak, when the
//! reference excites one, places the oil column.

use super::super::signals::welch_for;
use crate::campaign::{Campaign, Control};
use crate::params::Params;
use num_complex::Complex64;

/// Phase lag of a first-order loop `K / (s + K)` at its corner: where the measured lag
/// first reaches it, `2 pi f = K` (the loop gain, 1/s).
const CORNER_LAG_RAD: f64 = std::f64::consts::FRAC_PI_4;
/// Coherence below which an FRF bin is not read (the reference did not excite it).
const MIN_COHERENCE: f64 = 0.8;
/// A resonance is read as the oil column when the gain there exceeds the low-frequency
/// gain by this factor (a well-damped oil column of a stiff loop shows none).
const RESONANCE_FACTOR: f64 = 1.3;
/// Oil-column frequencies tried without a visible resonance, as multiples of the loop
/// bandwidth: a servo loop is stable only with the oil column well above its bandwidth
/// (about three times at least); twenty times covers the stiffest small actuators.
pub const OIL_COLUMN_MULTIPLES: [f64; 3] = [3.0, 8.0, 20.0];
/// Valve corner assumed at the start, as a multiple of the loop bandwidth (valves are
/// chosen several times faster than the loop they serve).
const VALVE_MULTIPLE: f64 = 5.0;
/// Oil-column damping ratio of the start: between the lightly damped bare column
/// (0.03-0.1) and a leaky one, so the fit can move either way.
pub const START_DAMPING_RATIO: f64 = 0.2;
/// Fraction of the Nyquist frequency above which no oil-column start is placed: the
/// sampled record cannot show a resonance there.
const NYQUIST_FRACTION: f64 = 0.8;

/// The low-frequency fit of `(K + F s) / (s + K)` uses the coherent bins up to this
/// multiple of the 45-degree frequency: below the valve and the oil column, where the
/// loop is the first-order servo with feed-forward.
const LOW_BAND_MULTIPLE: f64 = 1.0;
/// Feed-forward ratios of the starts read off the 45-degree frequency alone, whose loop
/// gain is `2 pi f45`: none, and a middling one. A servo with a feed-forward above
/// `3 - 2 sqrt 2` never lags 45 degrees, so where the measured lag reaches it the valve
/// and the oil column take part, and the low-band fit is bent by them (a slow valve).
const FEED_FORWARD_STARTS: [f64; 2] = [0.0, 0.5];
/// Fewest bins of that fit.
const MIN_LOW_BINS: usize = 3;

/// What the measured response of a test tells before fitting.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopReading {
    /// Where the measured lag reaches 45 degrees, Hz.
    pub bandwidth_hz: f64,
    /// Loop gains `K` (1/s) and feed-forward ratios `F` of `(K + F s) / (s + K)` to start
    /// from: the fit below the bandwidth (when it gives `0 <= F < 1`), and `K = 2 pi f45`
    /// with each of [`FEED_FORWARD_STARTS`].
    pub loops: Vec<(f64, f64)>,
    /// A resonance above it, Hz, when one shows.
    pub resonance_hz: Option<f64>,
}

/// The loop's bandwidth and resonance read from test `i` (displacement over reference
/// displacement, or acceleration over reference acceleration); `None` when the record
/// is too short for a spectral estimate or no coherent bin reaches the corner.
pub fn read_loop(c: &Campaign, i: usize) -> Option<LoopReading> {
    let rec = &c.records[i];
    let fs = c.sample_rate_of(i);
    let (input, output) = match (&rec.displacement_m, &rec.acceleration_m_s2) {
        (Some(x), _)
            if c.info.tests[i].control == Control::Displacement
                || rec.acceleration_m_s2.is_none() =>
        {
            (&rec.ref_displacement_m, x)
        }
        (_, Some(a)) => (&rec.ref_acceleration_m_s2, a),
        (Some(x), None) => (&rec.ref_displacement_m, x),
        (None, None) => return None,
    };
    let w = welch_for(fs, rec.len()).ok()?;
    let h = w.frf(input, output).ok()?;
    let bins: Vec<usize> = (1..h.frequency_hz.len())
        .filter(|&k| h.coherence[k] >= MIN_COHERENCE && h.h1[k].norm() > 0.0)
        .collect();
    let first = *bins.first()?;
    let low_gain = h.h1[first].norm();
    let corner = bins
        .iter()
        .find(|&&k| lag(h.h1[k]) >= CORNER_LAG_RAD)
        .copied()
        .unwrap_or(*bins.last()?);
    let bandwidth_hz = h.frequency_hz[corner];
    let resonance_hz = bins
        .iter()
        .filter(|&&k| h.frequency_hz[k] > bandwidth_hz)
        .max_by(|&&a, &&b| h.h1[a].norm().total_cmp(&h.h1[b].norm()))
        .filter(|&&k| h.h1[k].norm() > RESONANCE_FACTOR * low_gain)
        .map(|&k| h.frequency_hz[k]);
    let low: Vec<(f64, Complex64)> = bins
        .iter()
        .filter(|&&k| h.frequency_hz[k] <= LOW_BAND_MULTIPLE * bandwidth_hz)
        .map(|&k| (h.frequency_hz[k], h.h1[k]))
        .collect();
    let mut loops: Vec<(f64, f64)> = servo_with_feed_forward(&low).into_iter().collect();
    let w45 = 2.0 * std::f64::consts::PI * bandwidth_hz;
    loops.extend(FEED_FORWARD_STARTS.iter().map(|&f| (w45, f)));
    (bandwidth_hz > 0.0).then_some(LoopReading {
        bandwidth_hz,
        loops,
        resonance_hz,
    })
}

/// `K` and `F` of `H = (K + F s) / (s + K)` by linear least squares on `(f, H)` points:
/// `H s = K (1 - H) + F s`, real and imaginary parts. `None` with too few points or a
/// non-positive `K`.
fn servo_with_feed_forward(points: &[(f64, Complex64)]) -> Option<(f64, f64)> {
    use nalgebra::{DMatrix, DVector};
    if points.len() < MIN_LOW_BINS {
        return None;
    }
    let n = points.len();
    let mut a = DMatrix::zeros(2 * n, 2);
    let mut b = DVector::zeros(2 * n);
    for (k, &(f, h)) in points.iter().enumerate() {
        let s = Complex64::new(0.0, 2.0 * std::f64::consts::PI * f);
        let (lhs, kk, ff) = (h * s, Complex64::new(1.0, 0.0) - h, s);
        a[(2 * k, 0)] = kk.re;
        a[(2 * k, 1)] = ff.re;
        b[2 * k] = lhs.re;
        a[(2 * k + 1, 0)] = kk.im;
        a[(2 * k + 1, 1)] = ff.im;
        b[2 * k + 1] = lhs.im;
    }
    let (x, _) = super::super::lsq::linear(&a, &b)?;
    (x[0] > 0.0 && x[0].is_finite() && (0.0..1.0).contains(&x[1])).then(|| (x[0], x[1]))
}

/// The phase lag of `h`, radians in `(-pi, pi]` (positive for a lag).
fn lag(h: Complex64) -> f64 {
    -h.arg()
}

/// Oil-column frequencies to start from: the resonance if one shows, else multiples of
/// the bandwidth below the Nyquist limit.
pub fn oil_column_starts(r: &LoopReading, sample_rate_hz: f64) -> Vec<f64> {
    if let Some(f) = r.resonance_hz {
        return vec![f];
    }
    let top = NYQUIST_FRACTION * sample_rate_hz / 2.0;
    let mut v: Vec<f64> = OIL_COLUMN_MULTIPLES
        .iter()
        .map(|m| m * r.bandwidth_hz)
        .filter(|&f| f < top)
        .collect();
    if v.is_empty() {
        v.push(top);
    }
    v
}

/// What of the loop the start sets: the free gain and whether the feed-forward and the
/// valve are free.
#[derive(Debug, Clone, Copy)]
pub struct LoopStart {
    /// The loop gain is set through Kp (else through the flow gain Kq).
    pub through_kp: bool,
    pub feed_forward: bool,
    pub valve: bool,
}

/// `p` with loop gain `k` and feed-forward ratio `f` (`K = Kp Ks Kq / A`,
/// `F = Fv Ks Kq / A`) and the valve's time constant [`VALVE_MULTIPLE`] times faster
/// than the bandwidth of `r`.
pub fn with_loop(p: &Params, r: &LoopReading, (k, f): (f64, f64), what: LoopStart) -> Params {
    let mut q = *p;
    let a = q.actuator.piston_area_m2;
    let ks = q.servovalve.gain;
    if what.through_kp {
        q.controller.kp = k * a / (ks * q.actuator.flow_gain_m3_s);
    } else {
        q.actuator.flow_gain_m3_s = k * a / (ks * q.controller.kp.max(f64::MIN_POSITIVE));
    }
    if what.feed_forward {
        q.controller.fv = f * a / (ks * q.actuator.flow_gain_m3_s);
    }
    if what.valve {
        q.servovalve.time_constant_s =
            1.0 / (VALVE_MULTIPLE * 2.0 * std::f64::consts::PI * r.bandwidth_hz);
    }
    q
}

/// Largest oil-column damping ratio a start tries while looking for a stable loop.
const MAX_START_DAMPING_RATIO: f64 = 2.0;

/// `p` with its oil column at `frequency_hz`, damped by [`START_DAMPING_RATIO`] or, if the
/// loop is unstable with it (a loop gain read high for this oil column), doubled until
/// stable: an unstable start leaves the envelope and tells the fit nothing.
pub fn stable_oil_column(p: &Params, frequency_hz: f64) -> Params {
    let mut zeta = START_DAMPING_RATIO;
    loop {
        let q = with_oil_column(p, frequency_hz, zeta);
        let stable = crate::linear::stability_warning(&q).is_none();
        if stable || zeta >= MAX_START_DAMPING_RATIO {
            return q;
        }
        zeta *= 2.0;
    }
}

/// `p` with its oil column at `frequency_hz` and `damping_ratio` (the bulk modulus and
/// leakage that give them with `p`'s geometry and mass; spec section 4).
pub fn with_oil_column(p: &Params, frequency_hz: f64, damping_ratio: f64) -> Params {
    let mut q = *p;
    let a = &mut q.actuator;
    let m = q.table.mass_kg;
    a.bulk_modulus_pa = a.bulk_modulus_for_frequency_pa(frequency_hz, m);
    a.leakage_m3_s_pa = a.leakage_for_damping_ratio_m3_s_pa(m, damping_ratio);
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear::OilColumn;

    #[test]
    fn the_oil_column_set_is_the_one_read_back() {
        let p = with_oil_column(&Params::trees_lab(), 37.0, 0.15);
        let o = OilColumn::of(&p);
        assert!((o.frequency_hz - 37.0).abs() < 1e-9 * 37.0, "{o:?}");
        assert!((o.damping_ratio - 0.15).abs() < 1e-9, "{o:?}");
    }

    #[test]
    fn the_servo_and_its_feed_forward_are_read_back() {
        let (k, f) = (13.0, 0.4);
        let pts: Vec<(f64, Complex64)> = [0.5, 1.0, 2.0, 3.0, 5.0]
            .iter()
            .map(|&hz| {
                let s = Complex64::new(0.0, 2.0 * std::f64::consts::PI * hz);
                (hz, (k + f * s) / (s + k))
            })
            .collect();
        let (k2, f2) = servo_with_feed_forward(&pts).unwrap();
        assert!((k2 - k).abs() < 1e-9 && (f2 - f).abs() < 1e-9, "{k2} {f2}");
    }

    #[test]
    fn starts_stay_below_nyquist() {
        let r = LoopReading {
            bandwidth_hz: 10.0,
            loops: vec![(50.0, 0.0)],
            resonance_hz: None,
        };
        assert_eq!(oil_column_starts(&r, 1000.0), vec![30.0, 80.0, 200.0]);
        assert_eq!(oil_column_starts(&r, 200.0), vec![30.0]);
        let peaked = LoopReading {
            resonance_hz: Some(14.2),
            ..r
        };
        assert_eq!(oil_column_starts(&peaked, 512.0), vec![14.2]);
    }
}

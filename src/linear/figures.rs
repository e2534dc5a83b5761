//! Sampled frequency responses and the figures the paper reads off a table TF (spec
//! section 6): peak, low-frequency gain, phase drop and steepest phase; grids and phase
//! unwrapping.

use super::LOW_FREQUENCY_HZ;
use num_complex::Complex64;
use std::f64::consts::PI;

/// Peak and phase figures of a table transfer function (spec section 6).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TfFigures {
    pub peak_hz: f64,
    pub peak_gain: f64,
    pub low_frequency_gain: f64,
    /// `peak_gain / low_frequency_gain`.
    pub peak_ratio: f64,
    /// Phase at `peak - 1 Hz` minus phase at `peak + 1 Hz`, degrees (unwrapped).
    pub phase_drop_deg: f64,
    /// Where the phase falls fastest within +-1 Hz of the peak, Hz.
    pub steepest_hz: f64,
}

/// A sampled frequency response.
#[derive(Debug, Clone, Default)]
pub struct Frf {
    pub frequency_hz: Vec<f64>,
    pub response: Vec<Complex64>,
}

/// `start, start + step, ... <= stop`.
pub fn linear_grid(start: f64, stop: f64, step: f64) -> Vec<f64> {
    let n = ((stop - start) / step + 1e-9).floor() as usize + 1;
    (0..n).map(|i| start + i as f64 * step).collect()
}

/// `n` points logarithmically spaced from `start` to `stop`.
pub fn log_grid(start: f64, stop: f64, n: usize) -> Vec<f64> {
    let (l0, l1) = (start.ln(), stop.ln());
    (0..n)
        .map(|i| (l0 + (l1 - l0) * i as f64 / (n.max(2) - 1) as f64).exp())
        .collect()
}

/// Unwrapped phase in radians.
pub fn unwrapped_phase(h: &[Complex64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(h.len());
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    for z in h {
        let p = z.arg();
        if let Some(q) = prev {
            let d = p - q;
            if d > PI {
                offset -= 2.0 * PI;
            } else if d < -PI {
                offset += 2.0 * PI;
            }
        }
        prev = Some(p);
        out.push(p + offset);
    }
    out
}

impl TfFigures {
    /// Peak, low-frequency gain and phase figures of a sampled table TF (ascending grid).
    /// The low-frequency gain is read at the first grid point at or above
    /// [`LOW_FREQUENCY_HZ`]. `None` when the grid does not span +-1 Hz around the peak.
    pub fn from_frf(frf: &Frf) -> Option<TfFigures> {
        let f = &frf.frequency_hz;
        let h = &frf.response;
        if f.len() < 5 || h.iter().any(|z| !z.re.is_finite() || !z.im.is_finite()) {
            return None;
        }
        let mag: Vec<f64> = h.iter().map(|z| z.norm()).collect();
        let ip = (0..f.len()).max_by(|&i, &j| mag[i].total_cmp(&mag[j]))?;
        // parabolic refinement of the peak on the grid
        let (peak_hz, peak_gain) = if ip > 0 && ip + 1 < f.len() {
            let (y0, y1, y2) = (mag[ip - 1], mag[ip], mag[ip + 1]);
            let den = y0 - 2.0 * y1 + y2;
            let d = if den.abs() > 0.0 {
                0.5 * (y0 - y2) / den
            } else {
                0.0
            };
            let step = 0.5 * (f[ip + 1] - f[ip - 1]);
            (f[ip] + d * step, y1 - 0.25 * (y0 - y2) * d)
        } else {
            (f[ip], mag[ip])
        };
        let il = f.iter().position(|&x| x >= LOW_FREQUENCY_HZ)?;
        let low = mag[il];
        let phase = unwrapped_phase(h);
        let at = |x: f64| -> Option<f64> {
            let i = f.partition_point(|&g| g < x);
            if i == 0 || i >= f.len() {
                return None;
            }
            let w = (x - f[i - 1]) / (f[i] - f[i - 1]);
            Some(phase[i - 1] + w * (phase[i] - phase[i - 1]))
        };
        let drop = (at(peak_hz - 1.0)? - at(peak_hz + 1.0)?).to_degrees();
        let mut steepest = (f64::NEG_INFINITY, peak_hz);
        for i in 1..f.len() {
            let mid = 0.5 * (f[i] + f[i - 1]);
            if (mid - peak_hz).abs() <= 1.0 {
                let slope = -(phase[i] - phase[i - 1]) / (f[i] - f[i - 1]);
                if slope > steepest.0 {
                    steepest = (slope, mid);
                }
            }
        }
        Some(TfFigures {
            peak_hz,
            peak_gain,
            low_frequency_gain: low,
            peak_ratio: peak_gain / low,
            phase_drop_deg: drop,
            steepest_hz: steepest.1,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phase_unwrap_is_continuous() {
        let h: Vec<Complex64> = (0..200)
            .map(|i| Complex64::from_polar(1.0, -0.1 * i as f64))
            .collect();
        let p = unwrapped_phase(&h);
        assert!((p[199] + 19.9).abs() < 1e-9);
    }
}

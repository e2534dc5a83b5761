//! A ground motion made a table target (`record import`): the mean removed, the ends
//! tapered, quiet pads added, resampled to the controller's rate, high-passed so that the
//! displacement fits the stroke, brought to rest at both ends, scaled to a PGA. Every
//! step is linear and zero-phase, done on one periodic grid (`spectrum`), so the target's
//! acceleration, velocity and displacement are consistent derivatives of each other.

use super::read::GroundMotion;
use super::spectrum::{resample, Periodic};
use super::MotionError;
use crate::params::Params;
use realfft::num_complex::Complex;
use serde::Serialize;
use std::f64::consts::PI;

/// Order of the high-pass Butterworth magnitude; applied zero-phase, it removes the
/// long-period drift that double integration turns into metres, as strong-motion
/// processing does (4th order is the PEER NGA practice).
pub const HIGHPASS_ORDER: i32 = 4;

/// Lowest corner tried when the corner is chosen automatically, Hz: below 0.1 Hz a
/// table's 0.5-m stroke holds no useful motion of a scaled earthquake.
pub const DEFAULT_MIN_HIGHPASS_HZ: f64 = 0.1;

/// Highest corner the automatic choice goes to, Hz: above 1 Hz the filter would remove
/// the earthquake itself; a target that needs more must be scaled down instead.
pub const MAX_AUTO_HIGHPASS_HZ: f64 = 1.0;

/// Factor between successive corners tried (about 12 steps per decade).
const CORNER_STEP: f64 = 1.2;

/// Share of the stroke and of the velocity limit a target may use: the rest is the
/// table's tracking error and the specimen's pull (spec section 8 stops at the limits).
pub const ENVELOPE_BUDGET: f64 = 0.8;

/// Quiet time added at each end, s: the table starts and ends at rest, and the lead-in
/// gives the online iteration its measure of noise.
pub const DEFAULT_PAD_S: f64 = 3.0;

/// Cosine taper of the record's own ends, s (at most 5 % of the record): a record cut off
/// mid-motion would otherwise start with a step.
const END_TAPER_S: f64 = 1.0;

/// How to prepare a target.
#[derive(Debug, Clone)]
pub struct PrepareOptions {
    pub rate_hz: f64,
    /// The high-pass corner; `None`: the lowest from [`DEFAULT_MIN_HIGHPASS_HZ`] up that
    /// keeps the target within [`ENVELOPE_BUDGET`] of the stroke and velocity limits.
    pub highpass_hz: Option<f64>,
    pub pga_m_s2: Option<f64>,
    pub pad_s: f64,
}

/// A table target: uniform samples at `rate_hz`, at rest at both ends.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    pub rate_hz: f64,
    pub acceleration_m_s2: Vec<f64>,
    pub velocity_m_s: Vec<f64>,
    pub displacement_m: Vec<f64>,
}

/// What the preparation did, for the user and `--json`.
#[derive(Debug, Clone, Serialize)]
pub struct PrepareSummary {
    pub source: String,
    pub source_step_s: f64,
    pub source_samples: usize,
    pub mean_removed_m_s2: f64,
    pub rate_hz: f64,
    pub pad_s: f64,
    pub duration_s: f64,
    pub highpass_hz: f64,
    pub highpass_order: i32,
    pub highpass_chosen_by: String,
    /// RMS of what the high-pass and the rest at the ends removed, over the RMS of the
    /// resampled record (both before scaling).
    pub removed_rms_fraction: f64,
    pub source_pga_m_s2: f64,
    pub scale_factor: f64,
    pub pga_m_s2: f64,
    pub peak_velocity_m_s: f64,
    pub peak_displacement_m: f64,
}

/// Prepare `motion` as a target for the table of `params` (its `[limits]` bound the
/// automatic high-pass corner).
pub fn prepare(
    motion: &GroundMotion,
    params: &Params,
    options: &PrepareOptions,
) -> Result<(Target, PrepareSummary), MotionError> {
    let source_rate = 1.0 / motion.step_s;
    let samples = &motion.acceleration_m_s2;
    let mean = samples.iter().sum::<f64>() / samples.len() as f64;
    let mut a: Vec<f64> = samples.iter().map(|v| v - mean).collect();
    let source_pga = peak(&a);
    if source_pga == 0.0 {
        return Err(MotionError::Read {
            file: motion.source.clone(),
            message: "the record has no motion (every sample equals its mean)".into(),
        });
    }
    taper_ends(&mut a, source_rate);
    let pad_in = (options.pad_s * source_rate).round() as usize;
    let mut padded = vec![0.0; pad_in];
    padded.extend_from_slice(&a);
    padded.resize(padded.len() + pad_in, 0.0);
    let x =
        resample(&padded, source_rate, options.rate_hz).map_err(|message| MotionError::Option {
            option: "--rate-hz".into(),
            message,
        })?;
    let pad = (options.pad_s * options.rate_hz).round() as usize;
    let spectrum = Periodic::new(&x, options.rate_hz);
    let (corner, chosen_by, shape) = match options.highpass_hz {
        Some(fc) => (
            fc,
            "given (--highpass-hz)".to_string(),
            at_corner(&spectrum, fc, pad),
        ),
        None => auto_corner(&spectrum, pad, params, options)?,
    };
    let removed: Vec<f64> = x
        .iter()
        .zip(&shape.acceleration_m_s2)
        .map(|(a, b)| a - b)
        .collect();
    let factor = options
        .pga_m_s2
        .map_or(1.0, |pga| pga / peak(&shape.acceleration_m_s2));
    let target = shape.scaled(factor);
    let summary = PrepareSummary {
        source: motion.source.clone(),
        source_step_s: motion.step_s,
        source_samples: samples.len(),
        mean_removed_m_s2: mean,
        rate_hz: options.rate_hz,
        pad_s: pad as f64 / options.rate_hz,
        duration_s: x.len() as f64 / options.rate_hz,
        highpass_hz: corner,
        highpass_order: HIGHPASS_ORDER,
        highpass_chosen_by: chosen_by,
        removed_rms_fraction: rms(&removed) / rms(&x),
        source_pga_m_s2: source_pga,
        scale_factor: factor,
        pga_m_s2: peak(&target.acceleration_m_s2),
        peak_velocity_m_s: peak(&target.velocity_m_s),
        peak_displacement_m: peak(&target.displacement_m),
    };
    Ok((target, summary))
}

impl Target {
    fn scaled(&self, factor: f64) -> Target {
        let s = |v: &[f64]| v.iter().map(|x| x * factor).collect();
        Target {
            rate_hz: self.rate_hz,
            acceleration_m_s2: s(&self.acceleration_m_s2),
            velocity_m_s: s(&self.velocity_m_s),
            displacement_m: s(&self.displacement_m),
        }
    }

    /// The model's inputs with this motion as the reference (no external force).
    pub fn inputs(&self) -> Vec<crate::model::Inputs> {
        (0..self.acceleration_m_s2.len())
            .map(|k| crate::model::Inputs {
                reference: crate::model::Reference {
                    displacement_m: self.displacement_m[k],
                    velocity_m_s: self.velocity_m_s[k],
                    acceleration_m_s2: self.acceleration_m_s2[k],
                },
                external_force_n: 0.0,
            })
            .collect()
    }

    /// Seconds from the first sample to the last.
    pub fn duration_s(&self) -> f64 {
        self.acceleration_m_s2.len().saturating_sub(1) as f64 / self.rate_hz
    }
}

/// The lowest corner (from the minimum, in steps of [`CORNER_STEP`]) whose target, at the
/// requested PGA, stays within [`ENVELOPE_BUDGET`] of the stroke and the velocity limit.
fn auto_corner(
    spectrum: &Periodic,
    pad: usize,
    params: &Params,
    options: &PrepareOptions,
) -> Result<(f64, String, Target), MotionError> {
    let stroke = ENVELOPE_BUDGET * params.limits.stroke_m;
    let velocity = ENVELOPE_BUDGET * params.limits.velocity_m_s;
    let mut fc = DEFAULT_MIN_HIGHPASS_HZ;
    let mut last = (0.0, 0.0);
    while fc <= MAX_AUTO_HIGHPASS_HZ * (1.0 + 1e-9) {
        let shape = at_corner(spectrum, fc, pad);
        let f = options
            .pga_m_s2
            .map_or(1.0, |pga| pga / peak(&shape.acceleration_m_s2));
        let (d, v) = (
            f * peak(&shape.displacement_m),
            f * peak(&shape.velocity_m_s),
        );
        if d <= stroke && v <= velocity {
            let why = format!(
                "the lowest corner from {DEFAULT_MIN_HIGHPASS_HZ} Hz that keeps the peak \
                 displacement ({d:.3} m) and velocity ({v:.3} m/s) within {:.0} % of the \
                 stroke ({} m) and velocity limit ({} m/s)",
                100.0 * ENVELOPE_BUDGET,
                params.limits.stroke_m,
                params.limits.velocity_m_s
            );
            return Ok((fc, why, shape));
        }
        last = (d, v);
        fc *= CORNER_STEP;
    }
    Err(MotionError::Option {
        option: "--scale-pga".into(),
        message: format!(
            "even high-passed at {MAX_AUTO_HIGHPASS_HZ} Hz the target needs {:.3} m of \
             stroke and {:.3} m/s (budget {stroke:.3} m, {velocity:.3} m/s: {:.0} % of \
             [limits]): scale it down, or give --highpass-hz to filter harder",
            last.0,
            last.1,
            100.0 * ENVELOPE_BUDGET
        ),
    })
}

/// The unscaled target high-passed at `fc_hz`: the displacement (the acceleration
/// integrated twice in the frequency domain) windowed to rest over the `pad` samples at
/// each end, and its derivatives.
fn at_corner(spectrum: &Periodic, fc_hz: f64, pad: usize) -> Target {
    let highpass = |f: f64| {
        let g = if f <= 0.0 {
            0.0
        } else {
            1.0 / (1.0 + (fc_hz / f).powi(2 * HIGHPASS_ORDER)).sqrt()
        };
        Complex::new(g, 0.0)
    };
    let mut d = spectrum.filtered(highpass).derivative(-2).signal();
    rest_at_ends(&mut d, pad);
    let rate_hz = spectrum.rate_hz();
    let d_spec = Periodic::new(&d, rate_hz);
    Target {
        rate_hz,
        acceleration_m_s2: d_spec.derivative(2).signal(),
        velocity_m_s: d_spec.derivative(1).signal(),
        displacement_m: d,
    }
}

/// Multiply the first and last `pad` samples by a window rising from 0 to 1 with zero
/// first and second derivatives at both of its ends (`s - sin(2 pi s)/(2 pi)`), so the
/// displacement, velocity and acceleration all start and end at zero.
pub(super) fn rest_at_ends(d: &mut [f64], pad: usize) {
    let n = d.len();
    let pad = pad.min(n / 2);
    for k in 0..pad {
        let s = k as f64 / pad as f64;
        let w = s - (2.0 * PI * s).sin() / (2.0 * PI);
        d[k] *= w;
        d[n - 1 - k] *= w;
    }
}

/// A cosine taper over the first and last [`END_TAPER_S`] (at most 5 % of the record).
fn taper_ends(a: &mut [f64], rate_hz: f64) {
    let n = a.len();
    // rounded, not truncated: a rate read off a time column (99.99999999999999 Hz for
    // times printed to 0.01 s) must give the taper of its rate, not one sample less
    let m = ((END_TAPER_S * rate_hz).round() as usize)
        .min(n / 20)
        .max(1);
    for k in 0..m {
        let w = 0.5 * (1.0 - (PI * k as f64 / m as f64).cos());
        a[k] *= w;
        a[n - 1 - k] *= w;
    }
}

pub(super) fn peak(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pulse-like record: a decaying 2 Hz oscillation plus a 0.05 Hz drift.
    fn record(step_s: f64, seconds: f64) -> GroundMotion {
        let n = (seconds / step_s) as usize;
        let acceleration_m_s2 = (0..n)
            .map(|k| {
                let t = k as f64 * step_s;
                3.0 * (-(t - 5.0).powi(2) / 8.0).exp() * (2.0 * PI * 2.0 * t).sin()
                    + 0.2 * (2.0 * PI * 0.05 * t).sin()
            })
            .collect();
        GroundMotion {
            step_s,
            acceleration_m_s2,
            source: "test".into(),
        }
    }

    fn options(pga: Option<f64>) -> PrepareOptions {
        PrepareOptions {
            rate_hz: 1024.0,
            highpass_hz: None,
            pga_m_s2: pga,
            pad_s: DEFAULT_PAD_S,
        }
    }

    #[test]
    fn a_target_is_at_rest_at_both_ends_with_the_pga_asked() {
        let p = Params::trees_lab();
        let (t, s) = prepare(&record(0.01, 20.0), &p, &options(Some(2.0))).unwrap();
        assert!((peak(&t.acceleration_m_s2) - 2.0).abs() < 1e-9);
        assert_eq!(t.acceleration_m_s2.len(), (26.0 * 1024.0) as usize);
        for v in [&t.acceleration_m_s2, &t.velocity_m_s, &t.displacement_m] {
            assert!(v[0].abs() < 1e-3 * peak(v) && v[v.len() - 1].abs() < 1e-3 * peak(v));
        }
        assert!(s.peak_displacement_m <= ENVELOPE_BUDGET * p.limits.stroke_m);
        // the 2 Hz content survives: the high-pass removes the drift and little else
        assert!(s.removed_rms_fraction < 0.2, "{}", s.removed_rms_fraction);
        assert!(s.highpass_hz >= DEFAULT_MIN_HIGHPASS_HZ && s.highpass_hz < 0.5);
    }

    #[test]
    fn the_derivatives_are_consistent() {
        let p = Params::trees_lab();
        let (t, _) = prepare(&record(0.005, 15.0), &p, &options(None)).unwrap();
        let dt = 1.0 / t.rate_hz;
        let mut v = 0.0;
        let mut worst = 0.0_f64;
        for k in 1..t.acceleration_m_s2.len() {
            v += 0.5 * dt * (t.acceleration_m_s2[k - 1] + t.acceleration_m_s2[k]);
            worst = worst.max((v - t.velocity_m_s[k]).abs());
        }
        assert!(worst < 1e-3 * peak(&t.velocity_m_s), "{worst}");
    }

    #[test]
    fn a_stronger_target_needs_a_higher_corner_or_is_refused() {
        let p = Params::trees_lab();
        let (_, weak) = prepare(&record(0.01, 20.0), &p, &options(Some(1.0))).unwrap();
        let (_, strong) = prepare(&record(0.01, 20.0), &p, &options(Some(8.0))).unwrap();
        assert!(strong.highpass_hz > weak.highpass_hz);
        let e = prepare(&record(0.01, 20.0), &p, &options(Some(400.0))).unwrap_err();
        assert!(e.to_string().contains("scale it down"), "{e}");
    }
}

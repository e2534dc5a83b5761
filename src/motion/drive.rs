//! Drive iteration (issue 19, part 2): the reference to play so that the table's
//! acceleration reproduces a target. Offline, from the model alone: the regularised
//! inverse of the model's table transfer applied to the target, refined by iterating on the
//! simulated table (nonlinearities included). Online, from the previous drive and the
//! table's measured response: the response aligned to the drive (trigger delay), the
//! transfer updated from the measured drive/response pairs (a correction through the
//! model alone diverges when the model is wrong), and the error corrected where it stands
//! above the noise the quiet lead-in shows (a correction that chases noise gets worse).

use super::metrics::{metrics, Metrics};
use super::prepare::{peak, Target};
use super::transfer::{fft, ifft, Transfer};
use super::MotionError;
use crate::model::{Model, Outputs};
use crate::params::Params;
use crate::solver::{simulate_run, DEFAULT_MAX_SUBSTEP_S};
use realfft::num_complex::Complex;
use std::f64::consts::PI;

/// Most offline refinements on the simulated table: each costs one simulation; the
/// error stops falling after three or four on the TREES model with a specimen.
pub const OFFLINE_ITERATIONS: usize = 6;
/// An offline refinement must cut the RMS error by this share to go on.
const MIN_IMPROVEMENT: f64 = 0.02;
/// Longest trigger delay searched when aligning a measured response, s.
pub const MAX_TRIGGER_DELAY_S: f64 = 2.0;
/// Band the trigger delay is measured in, Hz: well below the oil column and a specimen's
/// first mode, where the table follows its reference and only the delay shifts the phase.
const ALIGN_BAND_HZ: f64 = 2.0;
/// Shortest quiet lead-in that gives a noise estimate, s.
const MIN_LEAD_IN_S: f64 = 0.25;
/// The lead-in ends where the target first exceeds this share of its peak.
const LEAD_IN_THRESHOLD: f64 = 1e-3;
/// Half-width of the frequency smoothing of the lead-in's periodogram, Hz: the loop shapes
/// its noise smoothly, and a short lead-in needs many bins for a steady estimate.
const NOISE_SMOOTHING_HZ: f64 = 1.0;
/// The error counts at a frequency only where its power exceeds the noise's by this factor
/// (about twice the scatter of the smoothed estimates), so no iteration chases noise.
const NOISE_MARGIN: f64 = 2.0;

/// How to iterate.
#[derive(Debug, Clone, Copy)]
pub struct DriveOptions {
    /// Share of the correction applied per online iteration.
    pub gain: f64,
    /// Highest frequency the drive corrects, Hz (the table's useful band).
    pub band_hz: f64,
}

/// A drive: the reference displacement and its derivatives, at the target's rate.
pub type Drive = Target;

/// What an iteration gives.
#[derive(Debug, Clone)]
pub struct DriveResult {
    pub drive: Drive,
    /// The model's response to the drive.
    pub predicted: Vec<Outputs>,
    pub predicted_metrics: Metrics,
    pub transfer: Transfer,
    /// Offline: the naive drive's (the target itself as reference) predicted metrics.
    pub naive_metrics: Option<Metrics>,
    /// Online: the measured run's metrics, its alignment shift (s, positive: the response
    /// came late) and whether a noise estimate weighted the correction.
    pub measured_metrics: Option<Metrics>,
    /// Online: the measured table acceleration, aligned to the drive.
    pub measured_response: Option<Vec<f64>>,
    pub trigger_delay_s: Option<f64>,
    pub noise_weighted: bool,
    /// Offline refinements made on the simulated table.
    pub refinements: usize,
}

/// A drive from its acceleration: displacement by double integration in the frequency
/// domain with `dc_m` as its mean, windowed to rest over `pad` samples at each end.
fn drive_from_displacement(mut x: Vec<f64>, rate_hz: f64, pad: usize) -> Drive {
    super::prepare::rest_at_ends(&mut x, pad);
    let n = x.len();
    let spec = fft(&x);
    let deriv = |order: i32| {
        let bins: Vec<Complex<f64>> = spec
            .iter()
            .enumerate()
            .map(|(k, c)| {
                c * Complex::new(0.0, 2.0 * PI * k as f64 * rate_hz / n as f64).powi(order)
            })
            .collect();
        ifft(&bins, n)
    };
    Drive {
        rate_hz,
        velocity_m_s: deriv(1),
        acceleration_m_s2: deriv(2),
        displacement_m: x,
    }
}

/// `x + delta`, where `delta` is the displacement of the acceleration correction `da`
/// (bins; no mean).
fn add_acceleration(x: &[f64], da: &[Complex<f64>], rate_hz: f64) -> Vec<f64> {
    let n = x.len();
    let bins: Vec<Complex<f64>> = da
        .iter()
        .enumerate()
        .map(|(k, c)| match k {
            0 => Complex::new(0.0, 0.0),
            _ => c / -(2.0 * PI * k as f64 * rate_hz / n as f64).powi(2),
        })
        .collect();
    ifft(&bins, n).iter().zip(x).map(|(d, x)| x + d).collect()
}

/// Samples at rest before the target starts.
fn lead_in(target: &Target) -> usize {
    let threshold = LEAD_IN_THRESHOLD * peak(&target.acceleration_m_s2);
    target
        .acceleration_m_s2
        .iter()
        .position(|a| a.abs() > threshold)
        .unwrap_or(0)
}

/// The model's response to `drive`; an error naming the time and the limit if the run
/// leaves the operating envelope.
pub fn play(model: &Model, drive: &Drive) -> Result<Vec<Outputs>, MotionError> {
    let run = simulate_run(
        model,
        &drive.inputs(),
        drive.rate_hz,
        None,
        DEFAULT_MAX_SUBSTEP_S,
    );
    match run.stop {
        Some(stop) => Err(MotionError::Option {
            option: "drive".into(),
            message: format!(
                "the model's table leaves its envelope on this drive at {:.3} s: {}; \
                 the drive is refused (scale the target down or check the parameters)",
                stop.time_s, stop.reason
            ),
        }),
        None => Ok(run.outputs),
    }
}

fn accelerations(o: &[Outputs]) -> Vec<f64> {
    o.iter().map(|o| o.acceleration_m_s2).collect()
}

/// The offline drive for `target` on the table of `p`.
pub fn offline(
    p: &Params,
    target: &Target,
    options: &DriveOptions,
) -> Result<DriveResult, MotionError> {
    let n = target.acceleration_m_s2.len();
    let model = Model::new(p);
    let pad = lead_in(target);
    let mut transfer = Transfer::from_model(p, n, target.rate_hz);
    let naive = play(&model, target)?;
    let naive_metrics = metrics(
        &target.acceleration_m_s2,
        &accelerations(&naive),
        target.rate_hz,
    );
    let inverse = transfer.inverse(options.band_hz);
    let t = fft(&target.acceleration_m_s2);
    // the target's displacement plus what the inverse adds to its acceleration, so the
    // drive keeps the target's mean position (the inverse's gain at 0 Hz is 1)
    let first: Vec<Complex<f64>> = t.iter().zip(&inverse).map(|(t, h)| t * (h - 1.0)).collect();
    let mut drive = drive_from_displacement(
        add_acceleration(&target.displacement_m, &first, target.rate_hz),
        target.rate_hz,
        pad,
    );
    let mut best: Option<(Drive, Vec<Outputs>, Metrics)> = None;
    let mut refinements = 0_usize;
    for _ in 0..=OFFLINE_ITERATIONS {
        let response = play(&model, &drive)?;
        let a = accelerations(&response);
        let m = metrics(&target.acceleration_m_s2, &a, target.rate_hz);
        let better = best
            .as_ref()
            .is_none_or(|(_, _, b)| m.rms_error < b.rms_error * (1.0 - MIN_IMPROVEMENT));
        if !better {
            break;
        }
        transfer.add_pair(&drive.acceleration_m_s2, &a);
        let next = correct(
            &drive,
            target,
            &a,
            &transfer,
            None,
            1.0,
            options.band_hz,
            pad,
        );
        best = Some((drive, response, m));
        drive = next;
        refinements += 1;
    }
    let (drive, predicted, predicted_metrics) = best.expect("the first drive is always kept");
    Ok(DriveResult {
        drive,
        predicted,
        predicted_metrics,
        transfer: Transfer::from_model(p, n, target.rate_hz),
        naive_metrics: Some(naive_metrics),
        measured_metrics: None,
        measured_response: None,
        trigger_delay_s: None,
        noise_weighted: false,
        refinements: refinements.saturating_sub(1),
    })
}

/// The next drive: `drive + gain W H^-1 (target - response)` with `W` the Wiener weight
/// of the error over the noise (1 without a noise estimate).
#[allow(clippy::too_many_arguments)]
fn correct(
    drive: &Drive,
    target: &Target,
    response: &[f64],
    transfer: &Transfer,
    noise_per_bin: Option<&[f64]>,
    gain: f64,
    band_hz: f64,
    pad: usize,
) -> Drive {
    let error: Vec<f64> = target
        .acceleration_m_s2
        .iter()
        .zip(response)
        .map(|(t, a)| t - a)
        .collect();
    let e = fft(&error);
    let weight = match noise_per_bin {
        Some(noise) => wiener_weight(&e, noise, transfer),
        None => vec![1.0; e.len()],
    };
    let inverse = transfer.inverse(band_hz);
    let da: Vec<Complex<f64>> = (0..e.len())
        .map(|k| e[k] * inverse[k] * (gain * weight[k]))
        .collect();
    drive_from_displacement(
        add_acceleration(&drive.displacement_m, &da, target.rate_hz),
        target.rate_hz,
        pad,
    )
}

/// `max(0, 1 - NOISE_MARGIN noise / |E|^2)` per bin, the error's power smoothed over the
/// transfer's smoothing width.
fn wiener_weight(e: &[Complex<f64>], noise: &[f64], transfer: &Transfer) -> Vec<f64> {
    let power: Vec<f64> = e.iter().map(|c| c.norm_sqr()).collect();
    let half = ((super::transfer::SMOOTHING_HZ / 2.0) / (transfer.rate_hz / transfer.n as f64))
        .round() as usize;
    let smooth = moving_average(&power, half);
    (0..e.len())
        .map(|k| match smooth[k] > 0.0 {
            true => (1.0 - NOISE_MARGIN * noise[k] / smooth[k]).max(0.0),
            false => 0.0,
        })
        .collect()
}

/// The expected `|E_k|^2` of the noise in an `n`-sample record, per bin, from the quiet
/// lead-in `quiet`: its periodogram smoothed over +-[`NOISE_SMOOTHING_HZ`] (a 3-s lead-in
/// gives about 12 degrees of freedom per Hz of smoothing) and scaled to `n` samples.
fn noise_per_bin(quiet: &[f64], n: usize, rate_hz: f64) -> Option<Vec<f64>> {
    let m = quiet.len();
    if (m as f64) < MIN_LEAD_IN_S * rate_hz {
        return None;
    }
    let mean = quiet.iter().sum::<f64>() / m as f64;
    let centred: Vec<f64> = quiet.iter().map(|v| v - mean).collect();
    let power: Vec<f64> = fft(&centred)
        .iter()
        .map(|b| b.norm_sqr() / m as f64)
        .collect();
    let half = (NOISE_SMOOTHING_HZ / (rate_hz / m as f64)).round() as usize;
    let smooth = moving_average(&power, half);
    // E|X_k|^2 of white noise of variance s^2 is n s^2: scale the per-sample level to n
    Some(
        (0..n / 2 + 1)
            .map(|k| {
                let f = k as f64 * rate_hz / n as f64;
                let j = ((f / (rate_hz / m as f64)).round() as usize).min(smooth.len() - 1);
                smooth[j] * n as f64
            })
            .collect(),
    )
}

/// The mean of `x` over `k - half ..= k + half` (clipped at the ends).
fn moving_average(x: &[f64], half: usize) -> Vec<f64> {
    let mut prefix = vec![0.0];
    for v in x {
        prefix.push(prefix[prefix.len() - 1] + v);
    }
    (0..x.len())
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(x.len()));
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// `x` low-passed at [`ALIGN_BAND_HZ`] (Butterworth magnitude of order 4, zero phase).
fn low_passed(x: &[f64], rate_hz: f64) -> Vec<f64> {
    let n = x.len();
    let bins: Vec<Complex<f64>> = fft(x)
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let f = k as f64 * rate_hz / n as f64;
            c / (1.0 + (f / ALIGN_BAND_HZ).powi(8)).sqrt()
        })
        .collect();
    ifft(&bins, n)
}

/// The shift (samples; positive: `measured` lags) that best aligns `measured` with
/// `expected`, by FFT cross-correlation within +-`max_lag`.
pub fn align(expected: &[f64], measured: &[f64], max_lag: usize) -> isize {
    let n = expected.len().max(measured.len()) * 2;
    let mut a = expected.to_vec();
    a.resize(n, 0.0);
    let mut b = measured.to_vec();
    b.resize(n, 0.0);
    let (fa, fb) = (fft(&a), fft(&b));
    let cross: Vec<Complex<f64>> = fa.iter().zip(&fb).map(|(x, y)| x.conj() * y).collect();
    let c = ifft(&cross, n);
    let lag_value = |lag: isize| c[lag.rem_euclid(n as isize) as usize];
    let m = max_lag as isize;
    (-m..=m)
        .max_by(|x, y| lag_value(*x).total_cmp(&lag_value(*y)))
        .unwrap_or(0)
}

/// `x` shifted earlier by `lag` samples (later if negative), zero-filled.
fn shifted(x: &[f64], lag: isize, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| {
            let j = k as isize + lag;
            if j >= 0 && (j as usize) < x.len() {
                x[j as usize]
            } else {
                0.0
            }
        })
        .collect()
}

/// The previous iteration as read back: its drive and accumulated transfer.
pub struct Previous {
    pub drive: Drive,
    pub transfer: Transfer,
    pub iteration: usize,
}

/// One online iteration: the next drive from the previous one and the measured table
/// acceleration `measured` (at the drive's rate).
pub fn online(
    p: &Params,
    target: &Target,
    previous: Previous,
    measured: &[f64],
    options: &DriveOptions,
) -> Result<DriveResult, MotionError> {
    let n = target.acceleration_m_s2.len();
    let model = Model::new(p);
    let rate = target.rate_hz;
    // aligned below ALIGN_BAND_HZ, on the model's prediction: there the table follows its
    // reference whatever the model gets wrong about the specimen or the oil column, and
    // the prediction carries the loop's own lag
    let expected = accelerations(&play(&model, &previous.drive)?);
    let max_lag = (MAX_TRIGGER_DELAY_S * rate) as usize;
    let lag = align(
        &low_passed(&expected, rate),
        &low_passed(measured, rate),
        max_lag,
    );
    let response = shifted(measured, lag, n);
    let pad = lead_in(target);
    let quiet_end = (pad as isize - lag.abs()).max(0) as usize;
    let noise = noise_per_bin(&response[..quiet_end.min(n)], n, rate);
    let mut transfer = previous.transfer;
    transfer.add_pair(&previous.drive.acceleration_m_s2, &response);
    let measured_metrics = metrics(&target.acceleration_m_s2, &response, rate);
    let drive = correct(
        &previous.drive,
        target,
        &response,
        &transfer,
        noise.as_deref(),
        options.gain,
        options.band_hz,
        pad,
    );
    let predicted = play(&model, &drive)?;
    let predicted_metrics = metrics(&target.acceleration_m_s2, &accelerations(&predicted), rate);
    Ok(DriveResult {
        drive,
        predicted,
        predicted_metrics,
        transfer,
        naive_metrics: None,
        measured_metrics: Some(measured_metrics),
        measured_response: Some(response),
        trigger_delay_s: Some(lag as f64 / rate),
        noise_weighted: noise.is_some(),
        refinements: 0,
    })
}

/// Refuse a drive before the lab plays it if the model's table on it leaves the envelope
/// (stroke, velocity, spool opening, pressure: [`super::envelope`]) or the drive itself
/// asks for more than the stroke.
pub fn check_drive(p: &Params, r: &DriveResult) -> Result<(), MotionError> {
    let series = |f: fn(&Outputs) -> f64| r.predicted.iter().map(f).collect::<Vec<_>>();
    let motion = Target {
        rate_hz: r.drive.rate_hz,
        acceleration_m_s2: series(|o| o.acceleration_m_s2),
        velocity_m_s: series(|o| o.velocity_m_s),
        displacement_m: series(|o| o.displacement_m),
    };
    let c = super::envelope::check_target(p, &motion);
    let mut over = c.exceeded();
    let stroke = peak(&r.drive.displacement_m);
    if stroke > p.limits.stroke_m {
        over.push(format!(
            "the drive's displacement {stroke:.3} m beyond the {} m stroke",
            p.limits.stroke_m
        ));
    }
    match over.is_empty() {
        true => Ok(()),
        false => Err(MotionError::Option {
            option: "drive".into(),
            message: format!("refused before the lab plays it: {}", over.join("; ")),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn align_finds_a_trigger_delay() {
        let x: Vec<f64> = (0..2000)
            .map(|k| ((k as f64) * 0.05).sin() * (-((k as f64 - 800.0) / 200.0).powi(2)).exp())
            .collect();
        let late = shifted(&x, -37, 2000);
        assert_eq!(align(&x, &late, 100), 37);
        assert_eq!(shifted(&late, 37, 2000)[800], x[800]);
    }
}

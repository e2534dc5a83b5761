//! What one number of the sensor's, rather than the table's physics, would remove from an
//! unexplained cell (issue 17 part 4): a scale factor and offset on the channel (a wrong
//! sensitivity, a unit or gravity slip in a lab's conversion, a zero) or a time shift (an
//! anti-alias filter's group delay, a data-acquisition channel's skew). Real recordings
//! carry such errors often; no catalogue effect describes them, and a cell whose residual
//! one of them removes points the engineer at the sensor before the table.

use serde::Serialize;

/// Largest time shift tried, s: anti-alias filters and acquisition skews are a few
/// milliseconds; a lag beyond 20 ms is a dynamics mismatch (a loop's phase), not latency.
pub const MAX_DELAY_S: f64 = 0.02;

/// The channel read as `factor` times the model's plus `offset`, and the RMS residual
/// (noise units) that leaves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scaled {
    pub factor: f64,
    pub offset: f64,
    pub residual: f64,
}

/// The channel read as the model's `delay_s` later (positive: the sensor lags the model),
/// its mean offset removed, and the RMS residual (noise units) that leaves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Delayed {
    pub delay_s: f64,
    pub residual: f64,
}

/// A cell's sample-wise RMS residual (noise units) as it is and with both means removed
/// (a zero: `centred`), and what a [`Scaled`] or a [`Delayed`] channel would leave of it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RemovedBy {
    pub residual: f64,
    pub centred: f64,
    pub scale: Option<Scaled>,
    pub delay: Option<Delayed>,
}

impl RemovedBy {
    /// One line: the sample-wise residual and what a scale or a delay leaves of it.
    pub fn describe(&self) -> String {
        let mut text = format!(
            "sample-wise {:.2} ({:.2} centred)",
            self.residual, self.centred
        );
        if let Some(s) = self.scale {
            text += &format!(
                ", read x{:.4} {:+.3e}: {:.2}",
                s.factor, s.offset, s.residual
            );
        }
        if let Some(d) = self.delay {
            text += &format!(", read {:+.2} ms late: {:.2}", 1e3 * d.delay_s, d.residual);
        }
        text
    }
}

/// [`RemovedBy`] for the `measured` and `simulated` channel over one stretch sampled at
/// `sample_rate_hz`, in units of the channel's `noise` RMS. `None` when a signal is not
/// finite (a run that stopped) or the stretch is too short to measure.
pub fn removed_by(
    measured: &[f64],
    simulated: &[f64],
    sample_rate_hz: f64,
    noise: f64,
) -> Option<RemovedBy> {
    let n = measured.len().min(simulated.len());
    let (m, s) = (&measured[..n], &simulated[..n]);
    let lag_samples = (MAX_DELAY_S * sample_rate_hz).floor() as usize;
    let finite = m.iter().chain(s).all(|x| x.is_finite());
    if !finite || n <= 4 * lag_samples.max(1) || !(noise > 0.0) {
        return None;
    }
    let rms = |r: &mut dyn Iterator<Item = f64>| {
        let (sum, k) = r.fold((0.0, 0usize), |(a, k), x| (a + x * x, k + 1));
        (sum / k as f64).sqrt() / noise
    };
    let residual = rms(&mut m.iter().zip(s).map(|(a, b)| a - b));
    let (mm, ms) = (mean(m), mean(s));
    let centred = rms(&mut m.iter().zip(s).map(|(a, b)| (a - mm) - (b - ms)));
    Some(RemovedBy {
        residual,
        centred,
        scale: scaled(m, s).map(|(factor, offset)| Scaled {
            factor,
            offset,
            residual: rms(&mut m.iter().zip(s).map(|(a, b)| a - factor * b - offset)),
        }),
        delay: delayed(m, s, lag_samples).map(|(lag, r)| Delayed {
            delay_s: lag / sample_rate_hz,
            residual: r / noise,
        }),
    })
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// Least squares `m ~ k s + b`: `(k, b)`, `None` when `s` does not vary.
fn scaled(m: &[f64], s: &[f64]) -> Option<(f64, f64)> {
    let (mm, ms) = (mean(m), mean(s));
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in m.iter().zip(s) {
        sxy += (a - mm) * (b - ms);
        sxx += (b - ms) * (b - ms);
    }
    (sxx > 0.0).then(|| {
        let k = sxy / sxx;
        (k, mm - k * ms)
    })
}

/// The shift of `s` (samples, fractional) within `max_lag` that best matches `m`, means
/// removed, and the RMS residual it leaves: whole samples first, then a golden-section
/// search between the best one's neighbours. Only the samples every shift covers count.
fn delayed(m: &[f64], s: &[f64], max_lag: usize) -> Option<(f64, f64)> {
    let cost = |lag: f64| shifted_rms(m, s, lag, max_lag);
    let lags = -(max_lag as i64)..=max_lag as i64;
    let (best, c0) = lags
        .map(|l| (l, cost(l as f64)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let (mut lo, mut hi) = (
        (best as f64 - 1.0).max(-(max_lag as f64)),
        (best as f64 + 1.0).min(max_lag as f64),
    );
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
    let (mut ca, mut cb) = (cost(a), cost(b));
    for _ in 0..GOLDEN_STEPS {
        // the inner point kept is the next step's other inner point
        if ca < cb {
            (hi, b, cb) = (b, a, ca);
            a = hi - ratio * (hi - lo);
            ca = cost(a);
        } else {
            (lo, a, ca) = (a, b, cb);
            b = lo + ratio * (hi - lo);
            cb = cost(b);
        }
    }
    let lag = 0.5 * (lo + hi);
    let c = cost(lag);
    Some(if c < c0 { (lag, c) } else { (best as f64, c0) })
}

/// Golden-section steps of [`delayed`]: two samples shrink to 1e-6 of a sample.
const GOLDEN_STEPS: usize = 30;

/// RMS of `m(k) - s(k - lag)` (linear interpolation of `s`) with both means removed,
/// over the samples `max_lag + 1 .. len - max_lag - 1`.
fn shifted_rms(m: &[f64], s: &[f64], lag: f64, max_lag: usize) -> f64 {
    let range = (max_lag + 1)..(m.len() - max_lag - 1);
    let at = |k: usize| {
        let x = k as f64 - lag;
        let j = x.floor();
        let w = x - j;
        let j = j as usize;
        s[j] * (1.0 - w) + s[j + 1] * w
    };
    let n = range.len() as f64;
    let mm = range.clone().map(|k| m[k]).sum::<f64>() / n;
    let ms = range.clone().map(at).sum::<f64>() / n;
    let ss: f64 = range
        .map(|k| {
            let r = (m[k] - mm) - (at(k) - ms);
            r * r
        })
        .sum();
    (ss / n).sqrt()
}

/// A channel whose unexplained cells one sensor number removes, consistently: what the
/// engineer should check before the table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensorFinding {
    pub channel: String,
    pub kind: SensorNumber,
    /// The median over the cells.
    pub value: f64,
    /// The smallest and largest over the cells.
    pub range: [f64; 2],
    /// The cells of the channel it holds on, of the unexplained cells listed.
    pub cells: usize,
    /// Median sample-wise RMS residual of those cells (noise units) with the means removed
    /// (a sensor's zero is no finding), and as read with the fitted number.
    pub residual: f64,
    pub residual_after: f64,
    /// Median over the cells of the share of the residual above the noise that the
    /// number leaves ([`excess`]).
    pub share_left: f64,
}

/// The one number of a [`SensorFinding`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorNumber {
    /// A sensitivity, unit or zero: the finding's value is the factor.
    Scale,
    /// A latency: the value in s, positive when the sensor lags the model.
    Delay,
}

/// What one cell says of a [`SensorNumber`]: its fitted value, its centred residual and
/// the residual the number leaves (noise units).
#[derive(Debug, Clone, Copy)]
struct CellNumber {
    value: f64,
    centred: f64,
    after: f64,
}

/// Largest median share of a channel's residual above the noise ([`excess`]) that the
/// fitted number may leave for a finding: a half removes three quarters of its power,
/// which a table's physics does not do by a gain or a shift on every cell, while an 8 %
/// accelerometer left about 0.3 and a 3 % LVDT 0.05.
pub const FINDING_SHARE_LEFT: f64 = 0.5;

/// Cells of a channel a finding needs: one cell may be a fluke of its test.
pub const FINDING_MIN_CELLS: usize = 2;

/// Least median centred residual of a finding's cells, noise RMS: below it the channel
/// reads the model sample by sample within about its noise (at 1.5 the excess over the
/// noise is 1.1 noise RMS; the diagnosis's own line for a missed cell), and the cell is
/// missed by its band power alone, which no sensor number explains. A 0.5-mm free play's
/// valve command (seed 459, full length) at 1.01-1.03 took a factor of 0.99975 that
/// left a fifth of that sliver: named as a sensor to check. The 8 % accelerometer's
/// cells read 1.45 to 22.6 (median 3.6), the 3 % LVDT's 104.
pub const FINDING_MIN_RESIDUAL: f64 = 1.5;

/// How far a cell's scale factor may lie from the median, relative: a sensor's
/// calibration is one number for every test (an 8 % accelerometer gave 1.061 to 1.081
/// across twelve cells, the random tests' bent baseline taking a little of it).
pub const FINDING_FACTOR_SPREAD: f64 = 0.05;

/// How far a cell's delay may lie from the median, in samples at the cell's rate.
pub const FINDING_DELAY_SPREAD_SAMPLES: f64 = 1.0;

/// The [`SensorFinding`]s of the unexplained `cells` (channel name, its [`RemovedBy`],
/// sampling rate), per channel, each measured against the cells' centred residual: a
/// scale where every cell of the channel has a factor
/// within [`FINDING_FACTOR_SPREAD`] of the median and the median share left is at most
/// [`FINDING_SHARE_LEFT`]; else a delay by the same rule (no shift of zero).
pub fn sensor_findings(cells: &[(&str, RemovedBy, f64)]) -> Vec<SensorFinding> {
    let mut channels: Vec<&str> = cells.iter().map(|c| c.0).collect();
    channels.sort();
    channels.dedup();
    let mut found = Vec::new();
    for ch in channels {
        let of: Vec<&(&str, RemovedBy, f64)> = cells.iter().filter(|c| c.0 == ch).collect();
        if of.len() < FINDING_MIN_CELLS {
            continue;
        }
        let scales: Option<Vec<CellNumber>> = of
            .iter()
            .map(|(_, r, _)| {
                r.scale.map(|s| CellNumber {
                    value: s.factor,
                    centred: r.centred,
                    after: s.residual,
                })
            })
            .collect();
        let scale = scales.and_then(|v| {
            let m = median(v.iter().map(|x| x.value));
            let tight = v
                .iter()
                .all(|x| (x.value - m).abs() <= FINDING_FACTOR_SPREAD * m.abs());
            tight.then(|| finding(ch, SensorNumber::Scale, &v))
        });
        let delay = || {
            let delays: Vec<(CellNumber, f64)> = of
                .iter()
                .map(|(_, r, rate_hz)| {
                    r.delay.map(|d| {
                        let n = CellNumber {
                            value: d.delay_s,
                            centred: r.centred,
                            after: d.residual,
                        };
                        (n, *rate_hz)
                    })
                })
                .collect::<Option<_>>()?;
            let m = median(delays.iter().map(|x| x.0.value));
            let tight = delays
                .iter()
                .all(|(x, rate_hz)| (x.value - m).abs() * rate_hz <= FINDING_DELAY_SPREAD_SAMPLES);
            let moved = delays.iter().all(|x| x.0.value != 0.0);
            let numbers: Vec<CellNumber> = delays.into_iter().map(|x| x.0).collect();
            (tight && moved).then(|| finding(ch, SensorNumber::Delay, &numbers))
        };
        if let Some(f) = scale.filter(holds).or_else(|| delay().filter(holds)) {
            found.push(f);
        }
    }
    found
}

/// Whether `f` leaves at most [`FINDING_SHARE_LEFT`] of a residual of at least
/// [`FINDING_MIN_RESIDUAL`].
fn holds(f: &SensorFinding) -> bool {
    f.share_left <= FINDING_SHARE_LEFT && f.residual >= FINDING_MIN_RESIDUAL
}

/// The RMS residual above the noise of a residual `r` in noise units: the sensor's own
/// noise (1) is in every cell, and no number removes it.
fn excess(r: f64) -> f64 {
    (r * r - 1.0).max(0.0).sqrt()
}

/// A finding of `kind` on `channel` from what its cells say of it.
fn finding(channel: &str, kind: SensorNumber, cells: &[CellNumber]) -> SensorFinding {
    let values = || cells.iter().map(|x| x.value);
    let shares = cells
        .iter()
        .filter(|x| excess(x.centred) > 0.0)
        .map(|x| excess(x.after) / excess(x.centred));
    SensorFinding {
        channel: channel.to_string(),
        kind,
        value: median(values()),
        range: [
            values().fold(f64::INFINITY, f64::min),
            values().fold(f64::NEG_INFINITY, f64::max),
        ],
        cells: cells.len(),
        residual: median(cells.iter().map(|x| x.centred)),
        residual_after: median(cells.iter().map(|x| x.after)),
        // no cell above the noise (a NaN median): nothing for a number to remove
        share_left: median(shares).min(f64::INFINITY),
    }
}

/// The median of `x` (the mean of the middle two for an even count); NaN when empty. Not
/// [`super::residuals::median`], whose upper middle would give a finding of two cells
/// the value of one of them.
fn median(x: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = x.collect();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

impl SensorFinding {
    /// One line for the terminal and the report.
    pub fn describe(&self) -> String {
        let what = match self.kind {
            SensorNumber::Scale => format!(
                "reads {:.4} times the model (from {:.4} to {:.4})",
                self.value, self.range[0], self.range[1]
            ),
            SensorNumber::Delay => format!(
                "lags the model by {:.2} ms (from {:.2} to {:.2})",
                1e3 * self.value,
                1e3 * self.range[0],
                1e3 * self.range[1]
            ),
        };
        format!(
            "the {} channel {what} on {} unexplained cells, which leaves {:.2} of their \
             residual {:.2} (median, noise units): check the sensor's calibration and \
             acquisition before the table's physics (a cause named beside it was fitted to \
             the channel as recorded, and may be the model bending to its error)",
            self.channel, self.cells, self.residual_after, self.residual
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A multi-sine at 512 Hz: what a table's channel looks like to these fits.
    fn signal(n: usize, fs: f64, shift_s: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 / fs - shift_s;
                (std::f64::consts::TAU * 1.3 * t).sin()
                    + 0.4 * (std::f64::consts::TAU * 7.1 * t).sin()
                    + 0.2 * (std::f64::consts::TAU * 23.0 * t).cos()
            })
            .collect()
    }

    #[test]
    fn a_miscalibrated_channel_is_removed_by_its_factor_and_offset() {
        let fs = 512.0;
        let model = signal(4096, fs, 0.0);
        let measured: Vec<f64> = model.iter().map(|x| 0.97 * x + 0.01).collect();
        let r = removed_by(&measured, &model, fs, 1e-3).unwrap();
        let s = r.scale.unwrap();
        assert!((s.factor - 0.97).abs() < 1e-9 && (s.offset - 0.01).abs() < 1e-9);
        assert!(s.residual < 1e-6 * r.residual, "{r:?}");
        // a gain error is no latency: a shift leaves most of it
        assert!(r.delay.unwrap().residual > 0.5 * r.residual, "{r:?}");
    }

    #[test]
    fn a_late_channel_is_removed_by_its_delay() {
        let fs = 512.0;
        // 3.3 ms: between samples, as a filter's group delay is
        let (model, measured) = (signal(4096, fs, 0.0), signal(4096, fs, 0.0033));
        let r = removed_by(&measured, &model, fs, 1e-3).unwrap();
        let d = r.delay.unwrap();
        assert!((d.delay_s - 0.0033).abs() < 0.1 / fs, "{d:?}");
        assert!(d.residual < 0.05 * r.residual, "{r:?}");
        assert!(r.scale.unwrap().residual > 0.5 * r.residual, "{r:?}");
    }

    /// A cell of `before` residual that a scale `factor` leaves at `after`, and a delay
    /// of `delay_s` leaves at `delayed`.
    fn cell(before: f64, factor: f64, after: f64, delay_s: f64, delayed: f64) -> RemovedBy {
        RemovedBy {
            residual: before,
            centred: before,
            scale: Some(Scaled {
                factor,
                offset: 0.0,
                residual: after,
            }),
            delay: Some(Delayed {
                delay_s,
                residual: delayed,
            }),
        }
    }

    #[test]
    fn one_factor_on_every_cell_of_a_channel_is_a_finding_and_scattered_ones_are_not() {
        let fs = 512.0;
        let acc = [
            cell(3.6, 1.080, 1.13, 0.0004, 3.6),
            cell(22.6, 1.066, 7.3, 0.0, 22.6),
            cell(1.45, 1.081, 1.17, 0.0005, 1.45),
        ];
        // a drag: the best factor differs from test to test and leaves most of it
        let force = [
            cell(13.0, 1.3, 9.0, 0.0, 12.0),
            cell(8.0, 0.9, 7.5, 0.0, 8.0),
        ];
        let cells: Vec<(&str, RemovedBy, f64)> = acc
            .iter()
            .map(|&r| ("acceleration", r, fs))
            .chain(force.iter().map(|&r| ("force", r, fs)))
            .collect();
        let found = sensor_findings(&cells);
        assert_eq!(found.len(), 1, "{found:?}");
        let f = &found[0];
        assert_eq!(
            (f.channel.as_str(), f.kind, f.cells),
            ("acceleration", SensorNumber::Scale, 3)
        );
        assert_eq!((f.value, f.range), (1.080, [1.066, 1.081]));
        // the noise is not the sensor's error: 1.45 -> 1.17 leaves 0.65 of the excess
        assert!(f.share_left > 0.3 && f.share_left < 0.5, "{f:?}");
        // one cell is no finding
        assert!(sensor_findings(&cells[..1]).is_empty());
        // cells within about their noise sample by sample (missed by their band power):
        // a factor that removes the sliver left is no sensor's (a free play's valve
        // command, seed 459)
        let sliver: Vec<(&str, RemovedBy, f64)> = [(1.025, 1.0001), (1.002, 1.0)]
            .iter()
            .map(|&(r, left)| ("valve_command", cell(r, 0.99975, left, 0.0, r), fs))
            .collect();
        assert!(sensor_findings(&sliver).is_empty());
    }

    #[test]
    fn one_delay_on_every_cell_of_a_channel_is_a_finding() {
        let fs = 1000.0;
        let cells: Vec<(&str, RemovedBy, f64)> = [(40.0, 0.0031, 2.0), (12.0, 0.0036, 1.5)]
            .iter()
            .map(|&(r, d, left)| ("displacement", cell(r, 0.99, 0.9 * r, d, left), fs))
            .collect();
        let found = sensor_findings(&cells);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].kind, SensorNumber::Delay);
        assert!((found[0].value - 0.00335).abs() < 1e-12, "{found:?}");
        // delays 3 samples apart are no one latency
        let apart: Vec<(&str, RemovedBy, f64)> = [(40.0, 0.001, 2.0), (12.0, 0.004, 1.5)]
            .iter()
            .map(|&(r, d, left)| ("displacement", cell(r, 0.99, 0.9 * r, d, left), fs))
            .collect();
        assert!(sensor_findings(&apart).is_empty());
    }

    #[test]
    fn a_stopped_run_or_a_short_stretch_has_no_figure() {
        let fs = 512.0;
        let model = signal(4096, fs, 0.0);
        let mut stopped = model.clone();
        stopped[100] = f64::NAN;
        assert!(removed_by(&model, &stopped, fs, 1e-3).is_none());
        assert!(removed_by(&model[..20], &model[..20], fs, 1e-3).is_none());
    }
}

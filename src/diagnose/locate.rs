//! Where the residual the final model leaves lies (issue 17 part 4): the report cells it
//! still misses, worst first, each with the octave band that holds most of its residual
//! and what the residual depends on (direction of motion, amplitude, speed, load
//! pressure), and what a sensor's scale, offset or latency would remove of it
//! ([`super::calibration`]). This is what an engineer needs to look for physics no
//! catalogue row describes.

use super::calibration::{removed_by, sensor_findings, RemovedBy, SensorFinding};
use super::output::{PartRows, UnexplainedCell};
use super::part::Part;
use super::residuals::{
    channel_bands, predict_draws, readings, CellBands, Channel, NoiseFloor, PerChannel, Prediction,
    HELDOUT_REALISATIONS,
};
use super::EXPLAINED_RATIO;
use crate::campaign::Campaign;
use crate::params::Params;
use crate::Outputs;
use serde::Serialize;

/// Cells listed at most: the worst ones locate the physics; a long tail repeats them.
pub const MAX_UNEXPLAINED_CELLS: usize = 12;

/// RMS residual of a cell (noise RMS units) split by a condition of the motion: while it
/// holds and while it does not. `None` where a side has too few samples to measure.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Split {
    pub when: Option<f64>,
    pub otherwise: Option<f64>,
}

/// What a cell's residual depends on, read off the model's own run.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Dependence {
    /// While the table moves in the positive direction (velocity > 0) against negative.
    pub moving_positive: Split,
    /// While the displacement is beyond half its largest excursion against within it.
    pub large_displacement: Split,
    /// While the speed is beyond half its largest value against within it: a residual
    /// that grows with speed (a drag, a velocity-dependent friction or damper) shows here,
    /// one that grows with excursion (a spring) in `large_displacement`.
    pub fast_motion: Split,
    /// While the load pressure is beyond half its largest value against within it.
    pub high_load_pressure: Split,
}

/// Fewer samples than this on a side of a split give no figure: a tenth of a second at
/// 512 Hz, a few cycles of the oil column, enough for an RMS within about 10 %.
const MIN_SPLIT_SAMPLES: usize = 50;

/// The report cells (of `tests`, campaign order) the baseline missed (`baseline_missed`)
/// that `p`, whose report rows are `rows`, still misses (residual above
/// [`EXPLAINED_RATIO`]), worst first, at most [`MAX_UNEXPLAINED_CELLS`].
pub(super) fn unexplained_cells(
    p: &Params,
    c: &Campaign,
    rows: &PartRows,
    baseline_missed: &[PerChannel<bool>],
    noise: &NoiseFloor,
) -> Vec<UnexplainedCell> {
    let mut worst: Vec<(usize, Channel, f64)> = rows
        .residual
        .iter()
        .zip(baseline_missed)
        .enumerate()
        .flat_map(|(i, (r, m))| {
            r.iter().filter_map(move |(ch, x)| {
                let x = x.figure()?;
                (m[ch] && !(x <= EXPLAINED_RATIO)).then_some((i, ch, x))
            })
        })
        .collect();
    worst.sort_by(|a, b| b.2.total_cmp(&a.2));
    worst.truncate(MAX_UNEXPLAINED_CELLS);
    // one prediction per test, shared by its cells (several channels of a test are often
    // listed), one test at a time (a prediction holds every run of its test)
    let mut tests: Vec<usize> = worst.iter().map(|w| w.0).collect();
    tests.sort_unstable();
    tests.dedup();
    let mut located: Vec<(usize, UnexplainedCell)> = Vec::new();
    for i in tests {
        // the report cell's bands with the draws its residual was measured with
        let pred = predict_draws(p, c, i, Part::Whole, noise, HELDOUT_REALISATIONS);
        for (k, &(_, ch, residual)) in worst.iter().enumerate().filter(|(_, w)| w.0 == i) {
            located.extend(locate(&pred, c, i, ch, residual, noise).map(|u| (k, u)));
        }
    }
    located.sort_by_key(|(k, _)| *k);
    located.into_iter().map(|(_, u)| u).collect()
}

/// The [`SensorFinding`]s of the located `cells` ([`sensor_findings`]).
pub(super) fn findings(c: &Campaign, cells: &[UnexplainedCell]) -> Vec<SensorFinding> {
    let rated: Vec<(&str, RemovedBy, f64)> = cells
        .iter()
        .filter_map(|u| {
            let i = c.info.tests.iter().position(|t| t.name == u.test)?;
            Some((u.channel.as_str(), u.removed_by?, c.sample_rate_of(i)))
        })
        .collect();
    sensor_findings(&rated)
}

/// One cell of test `i` located from the model's prediction `pred` of it: its worst band
/// and its dependences.
fn locate(
    pred: &Prediction,
    c: &Campaign,
    i: usize,
    ch: Channel,
    residual: f64,
    noise: &NoiseFloor,
) -> Option<UnexplainedCell> {
    let r = &c.records[i];
    let worst = match channel_bands(c, i, pred, noise, Part::Report, ch) {
        CellBands::Absent => return None,
        // a diverged run has no band to name
        CellBands::Diverged => None,
        CellBands::Scored(bands) => bands.into_iter().max_by(|a, b| a.ratio.total_cmp(&b.ratio)),
    };
    let (band_hz, band_residual) = match worst {
        Some(b) => ([b.band_hz.0, b.band_hz.1], b.ratio.sqrt()),
        None => ([0.0, c.sample_rate_of(i) / 2.0], f64::INFINITY),
    };
    let range = Part::Report.range(r.len());
    let m = ch.measured(r)?;
    let s = noise.of(ch)?;
    let run = PartRun::of(readings(&pred.locked), range.clone());
    let residual_units: Vec<f64> = range
        .clone()
        .zip(run.readings)
        .map(|(k, o)| (m[k] - ch.simulated(o)) / s)
        .collect();
    let depends_on = Dependence {
        moving_positive: split(&residual_units, &run, |o| o.velocity_m_s > 0.0),
        large_displacement: split_at_half(&residual_units, &run, |o| o.displacement_m.abs()),
        fast_motion: split_at_half(&residual_units, &run, |o| o.velocity_m_s.abs()),
        high_load_pressure: split_at_half(&residual_units, &run, |o| {
            (o.pressure_a_pa - o.pressure_b_pa).abs()
        }),
    };
    // a run that stopped inside the part leaves no whole residual to correct
    let removed_by = (run.missing == 0).then(|| {
        let simulated: Vec<f64> = run.readings.iter().map(|o| ch.simulated(o)).collect();
        removed_by(&m[range], &simulated, c.sample_rate_of(i), s)
    });
    Some(UnexplainedCell {
        test: c.info.tests[i].name.clone(),
        channel: ch.name().to_string(),
        band_hz,
        residual,
        band_residual,
        depends_on,
        removed_by: removed_by.flatten(),
    })
}

/// The model's run over a part of a test: the part's samples it has readings for, and how
/// many later ones it has none for (it stopped inside the part).
struct PartRun<'a> {
    readings: &'a [Outputs],
    missing: usize,
}

impl<'a> PartRun<'a> {
    /// The readings of `run` (those before a stop) over `range`.
    fn of(run: &'a [Outputs], range: std::ops::Range<usize>) -> Self {
        let end = range.end.min(run.len()).max(range.start);
        PartRun {
            readings: run.get(range.start..end).unwrap_or(&[]),
            missing: range.end - end,
        }
    }
}

/// [`split`] at half the largest value of `of` over the run's readings.
fn split_at_half(residual: &[f64], run: &PartRun, of: impl Fn(&Outputs) -> f64) -> Split {
    let largest = run.readings.iter().map(&of).fold(0.0, f64::max);
    split(residual, run, |o| of(o) > 0.5 * largest)
}

/// RMS of `residual` where `when` holds on the model's run, and where it does not. The
/// samples after a stop have no reading, so no condition holds there: they fall on the
/// `otherwise` side, which then has no RMS (NaN, [`MISSING_RESIDUAL`]).
fn split(residual: &[f64], run: &PartRun, when: impl Fn(&Outputs) -> bool) -> Split {
    let (mut on, mut off) = ((0.0, 0usize), (0.0, 0usize));
    for (x, o) in residual.iter().zip(run.readings) {
        let side = if when(o) { &mut on } else { &mut off };
        side.0 += x * x;
        side.1 += 1;
    }
    if run.missing > 0 {
        off = (MISSING_RESIDUAL, off.1 + run.missing);
    }
    let rms = |(sum, n): (f64, usize)| (n >= MIN_SPLIT_SAMPLES).then(|| (sum / n as f64).sqrt());
    Split {
        when: rms(on),
        otherwise: rms(off),
    }
}

/// The sum of squares of a side holding samples without a reading: not a number (the
/// report prints it as NaN, the JSON as null).
const MISSING_RESIDUAL: f64 = f64::NAN;

#[cfg(test)]
mod tests {
    use super::*;

    fn outputs(velocity_m_s: f64, displacement_m: f64) -> Outputs {
        Outputs {
            valve_command: 0.0,
            spool_position: 0.0,
            displacement_m,
            velocity_m_s,
            acceleration_m_s2: 0.0,
            actuator_force_n: 0.0,
            pressure_a_pa: 0.0,
            pressure_b_pa: 0.0,
        }
    }

    /// A residual that lives only while the table moves up shows on that side alone.
    #[test]
    fn a_direction_dependent_residual_shows_on_its_side() {
        let n = 400;
        let run: Vec<Outputs> = (0..n)
            .map(|k| {
                let phase = k as f64 / 50.0;
                outputs(phase.cos(), phase.sin())
            })
            .collect();
        let residual: Vec<f64> = run
            .iter()
            .map(|o| if o.velocity_m_s > 0.0 { 3.0 } else { 0.0 })
            .collect();
        let whole = PartRun::of(&run, 0..n);
        let s = split(&residual, &whole, |o| o.velocity_m_s > 0.0);
        assert_eq!(s.when, Some(3.0));
        assert_eq!(s.otherwise, Some(0.0));
        // too few samples on a side: no figure
        let s = split(&residual[..60], &PartRun::of(&run, 0..60), |o| {
            o.velocity_m_s > 0.0
        });
        assert!(s.otherwise.is_none());
        // a run that stopped at sample 300: the side without readings has no RMS
        let stopped = PartRun::of(&run[..300], 100..n);
        assert_eq!((stopped.readings.len(), stopped.missing), (200, 100));
        let s = split(&residual[100..300], &stopped, |o| o.velocity_m_s > 0.0);
        assert!(s.when.is_some_and(|x| x == 3.0) && s.otherwise.is_some_and(f64::is_nan));
    }
}

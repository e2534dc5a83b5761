//! The predictive score per test and channel: octave bands, windows, the Gaussian log
//! score of the residual power under the predicted spread.

use super::cell::{Cell, Cells};
use super::channels::Channel;
use super::noise::NoiseFloor;
use super::prediction::{predict_draws, Prediction, HELDOUT_REALISATIONS, REALISATIONS};
use super::run::{readings, simulate_test};
use super::spectral::{band_split, octave_bands};
use super::whitening::white_variance;
use super::Part;
use crate::campaign::{Campaign, Record};
use crate::params::Params;
use crate::Outputs;
use rayon::prelude::*;

/// Window of the predictive score, samples (0.25 s at 512 Hz: short beside a chatter
/// burst's growth, long enough for a power estimate within about 12 %).
pub const SCORE_WINDOW: usize = 128;

/// Windows over which the predicted spread is averaged (centred; 1.25 s at 512 Hz).
pub const SPREAD_WINDOWS: usize = 5;

/// Held-out figures of a model per channel ([`Cells`]).
#[derive(Debug, Clone, Copy)]
pub struct CellScores {
    /// The predictive score as an equivalent noise ratio: the square root of the mean over
    /// windows of `P_meas/P_pred + ln(P_pred/s^2)` (module doc). It ranks models.
    pub score: Cells,
    /// The standardised residual: the square root of the mean of `P_meas/P_pred`, the
    /// residual in units of the spread the model itself predicts (the noise floor for a
    /// model the noise does not excite, where both equal the ratio of [`ratios`]).
    pub residual: Cells,
    /// The sample-wise residual: the RMS of measured minus the noise-free run over the
    /// noise floor ([`ratios`], the heat map's units). It does not credit a model with the
    /// spread it predicts.
    ///
    /// [`ratios`]: super::ratios
    pub deviation: Cells,
}

/// Degrees of freedom a score window holds in its band (`2 W L / fs`): its length is
/// chosen for it (at least [`SCORE_WINDOW`]), so a narrow low band gets long windows.
pub const WINDOW_DOF: f64 = 8.0;

/// Mean over windows of `P_meas/P_pred` and of `ln(P_pred/reference)` for one band:
/// `meas` the band's residual, `spread` its predicted spread per realisation, `white` the
/// variance of independent measurement noise in the band (added to the prediction).
pub fn band_score(meas: &[f64], spread: &[Vec<f64>], window: usize, white: f64) -> (f64, f64) {
    let n = meas.len();
    let starts: Vec<usize> = (0..n).step_by(window.max(1)).collect();
    let power = |x: &[f64], k0: usize| {
        let end = (k0 + window).min(n);
        (x[k0..end].iter().map(|v| v * v).sum::<f64>(), end - k0)
    };
    let meas_p: Vec<(f64, usize)> = starts.iter().map(|&k0| power(meas, k0)).collect();
    let spread_p: Vec<(f64, usize)> = starts
        .iter()
        .map(|&k0| {
            spread.iter().fold((0.0, 0), |acc, s| {
                let (p, m) = power(s, k0);
                (acc.0 + p, acc.1 + m)
            })
        })
        .collect();
    let half = SPREAD_WINDOWS / 2;
    let (mut ratio, mut log, mut total) = (0.0, 0.0, 0usize);
    for (w, &(pm, m)) in meas_p.iter().enumerate() {
        let lo = w.saturating_sub(half);
        let hi = (w + half + 1).min(spread_p.len());
        let (ps, ns) = spread_p[lo..hi]
            .iter()
            .fold((0.0, 0usize), |a, b| (a.0 + b.0, a.1 + b.1));
        let p_pred = (white + ps / ns.max(1) as f64).max(f64::MIN_POSITIVE);
        ratio += pm / p_pred;
        log += p_pred.ln() * m as f64;
        total += m;
    }
    let t = total.max(1) as f64;
    (ratio / t, log / t)
}

/// [`CellScores`] of a prediction over `part`: per channel, the residual (measured minus
/// the locked run) and the predicted spread (noisy run plus the very noise its feedback
/// saw, minus the locked run: the recorded channels carry the noise the controller saw, so
/// the loop's response and the noise add coherently) are split into octave bands; each
/// band is scored in windows of [`WINDOW_DOF`] degrees of freedom, the predicted power
/// smoothed over [`SPREAD_WINDOWS`] windows; the cell is the mean over bands.
///
/// Why bands: the loop's noise response fills the oil-column octave, and a residual that
/// lives in another octave (a stiff foundation's mode at 30-40 Hz, a hundred times the
/// predicted power there) would vanish in a broadband power that the resonance
/// dominates. Each octave counts alike, as on a Bode plot. Summed over bands with fixed
/// weights, the Gaussian log score stays a proper scoring rule.
pub fn scores(
    c: &Campaign,
    i: usize,
    pred: &Prediction,
    noise: &NoiseFloor,
    part: Part,
) -> CellScores {
    let r = &c.records[i];
    let mut out = CellScores {
        score: Cells::default(),
        residual: Cells::default(),
        deviation: super::ratios(r, &pred.locked, noise, part),
    };
    // the channels side by side: a search's last polishes score few tests, and the band
    // splits would otherwise leave a core idle
    let banded: Vec<CellBands> = Channel::ALL
        .par_iter()
        .map(|&ch| channel_bands(c, i, pred, noise, part, ch))
        .collect();
    for (ch, bands) in Channel::ALL.into_iter().zip(banded) {
        match bands {
            CellBands::Absent => {}
            CellBands::Diverged => {
                out.score[ch] = Cell::Diverged;
                out.residual[ch] = Cell::Diverged;
            }
            CellBands::Scored(bands) => {
                let nb = bands.len() as f64;
                let score: f64 = bands.iter().map(|b| b.score_term).sum();
                let ratio: f64 = bands.iter().map(|b| b.ratio).sum();
                out.score[ch] = Cell::Scored((score / nb).max(0.0).sqrt());
                out.residual[ch] = Cell::Scored((ratio / nb).sqrt());
            }
        }
    }
    out
}

/// One octave band of a cell: its edges, the mean of `P_meas/P_pred` over its windows
/// and its term of the score.
#[derive(Debug, Clone, Copy)]
pub struct BandScore {
    pub band_hz: (f64, f64),
    pub ratio: f64,
    pub score_term: f64,
}

/// The octave bands of one cell ([`channel_bands`]), or why it has none.
#[derive(Debug, Clone)]
pub enum CellBands {
    /// Nothing to score ([`Cell::Absent`]): the channel is absent, has no noise estimate,
    /// or the part is too short.
    Absent,
    /// The run predicts nothing over the part ([`Cell::Diverged`]): it stopped before the
    /// part's end, or its residual or spread is not finite (or the rate leaves the channel
    /// no band to score, below 4 Hz).
    Diverged,
    /// Every scored band, from Nyquist down.
    Scored(Vec<BandScore>),
}

/// The octave bands of channel `ch` of a prediction of test `i` over `part` (see
/// [`scores`]; the bands of [`scored_bands`]).
pub fn channel_bands(
    c: &Campaign,
    i: usize,
    pred: &Prediction,
    noise: &NoiseFloor,
    part: Part,
    ch: Channel,
) -> CellBands {
    let r = &c.records[i];
    let range = part.range(r.len());
    let (Some(m), Some(s)) = (ch.measured(r), noise.of(ch)) else {
        return CellBands::Absent;
    };
    if range.len() < 2 {
        return CellBands::Absent;
    }
    let bands = scored_bands(c, i, ch);
    let Some((residual, spread)) = cell_signals(pred, m, range, ch) else {
        return CellBands::Diverged;
    };
    if bands.is_empty() {
        return CellBands::Diverged;
    }
    let cell = BandedCell {
        sample_rate_hz: c.sample_rate_of(i),
        white: white_variance(noise, ch, s),
        floor: s,
    };
    CellBands::Scored(cell.band_scores(&residual, &spread, &bands))
}

/// The residual of a cell over `range` (measured minus the locked run) and its predicted
/// spread per noisy run ([`Prediction::spread`]); `None` when the run predicts nothing
/// there (it stopped inside the range, or a sample is not finite).
fn cell_signals(
    pred: &Prediction,
    m: &[f64],
    range: std::ops::Range<usize>,
    ch: Channel,
) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let locked = pred.locked_over(range.clone())?;
    let spread = pred.spread(range.clone(), ch)?;
    let residual: Vec<f64> = range
        .zip(locked)
        .map(|(k, o)| m[k] - ch.simulated(o))
        .collect();
    let finite = residual
        .iter()
        .chain(spread.iter().flatten())
        .all(|x| x.is_finite());
    finite.then_some((residual, spread))
}

/// What scoring a cell band by band needs besides its signals: the test's rate, the
/// variance of independent measurement noise over the whole spectrum
/// ([`white_variance`]) and the channel's noise floor (its RMS).
struct BandedCell {
    sample_rate_hz: f64,
    white: f64,
    floor: f64,
}

impl BandedCell {
    /// The [`BandScore`] of every band of `bands`: the residual and each spread split
    /// into the bands, each band scored in windows of [`WINDOW_DOF`] degrees of freedom
    /// ([`band_score`]) with its share of the white noise.
    fn band_scores(
        &self,
        residual: &[f64],
        spread: &[Vec<f64>],
        bands: &[(f64, f64)],
    ) -> Vec<BandScore> {
        let fs = self.sample_rate_hz;
        let nyquist = fs / 2.0;
        let meas_bands = band_split(residual, bands, fs);
        let spread_bands: Vec<Vec<Vec<f64>>> =
            spread.iter().map(|x| band_split(x, bands, fs)).collect();
        bands
            .iter()
            .enumerate()
            .map(|(b, &(lo, hi))| {
                let width = hi - lo;
                let window = ((WINDOW_DOF * fs / (2.0 * width)).ceil() as usize).max(SCORE_WINDOW);
                let share = width / nyquist;
                let sp: Vec<Vec<f64>> = spread_bands.iter().map(|x| x[b].clone()).collect();
                let (q, log) = band_score(&meas_bands[b], &sp, window, self.white * share);
                // the log term relative to the floor's share of the band, so that a model
                // predicting the floor scores as the ratio alone
                BandScore {
                    band_hz: (lo, hi),
                    ratio: q,
                    score_term: q + log - (self.floor * self.floor * share).ln(),
                }
            })
            .collect()
    }
}

/// The octave bands of test `i`'s rate scored on its channel `ch`: all of them, except
/// the lowest on the displacement of a test whose reference displacement was integrated
/// here from its recorded acceleration (campaign-format.md, "What is required").
///
/// Why: the double integral's error lives there, and no recording bounds it. The
/// acceleration says nothing of a constant velocity, and a sampled acceleration that
/// steps (a fade's start) integrates with an error of half a sample times the step at
/// each step; the correction to rest removes their sum, not the ramps between them. On a
/// clean emulated 1-kHz campaign that left 0.05 mm of ramp in the reference, 2.5 times
/// the LVDT noise, below 2 Hz of the acceleration-controlled tests' displacement: a
/// residual that neither the table model nor any effect has, since the table followed the
/// reference the controller integrated, not ours. The table's own low-frequency motion
/// stays scored on its other channels and on every test driven in displacement.
pub fn scored_bands(c: &Campaign, i: usize, ch: Channel) -> Vec<(f64, f64)> {
    let mut bands = octave_bands(c.sample_rate_of(i));
    let integrated = c
        .info
        .tests
        .get(i)
        .is_some_and(|t| c.computed_here(&t.name, "ref_displacement_m"));
    if ch == Channel::Displacement && integrated {
        // the bands run from Nyquist down; the last starts at 0
        bands.pop();
    }
    bands
}

/// [`CellScores`] of `p` on test `i` over `part` (one [`predict`] and [`scores`]).
pub fn test_scores(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
) -> CellScores {
    test_scores_held(p, c, i, part, noise, false)
}

/// [`test_scores`] of a trial model held to the operating envelope (spec section 8):
/// where its noise-free run leaves the envelope over `part`, while the measured table did
/// not, the model describes nothing real there and every cell of the test scores
/// infinitely bad. (The fits themselves run with the divergence guards only,
/// [`simulate_test_with`], so an optimiser keeps a finite cost on its way.)
pub fn test_scores_in_envelope(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
) -> CellScores {
    test_scores_held(p, c, i, part, noise, true)
}

pub(super) fn test_scores_held(
    p: &Params,
    c: &Campaign,
    i: usize,
    part: Part,
    noise: &NoiseFloor,
    to_envelope: bool,
) -> CellScores {
    test_scores_of_parts(p, c, i, &[part], noise, &[to_envelope])[0].0
}

/// [`CellScores`] of `p` on test `i` over each of `parts`, from one [`predict`] over the
/// whole test, with whether its noise-free run left the envelope over each part where
/// the measured table did not; held to the envelope over the parts where `hold` says so
/// (see [`test_scores_in_envelope`]).
pub fn test_scores_of_parts(
    p: &Params,
    c: &Campaign,
    i: usize,
    parts: &[Part],
    noise: &NoiseFloor,
    hold: &[bool],
) -> Vec<(CellScores, bool)> {
    let simulated = if parts.iter().all(|&q| q == Part::Fit) {
        Part::Fit
    } else {
        Part::Whole
    };
    let heldout = parts
        .iter()
        .any(|&q| matches!(q, Part::Select | Part::Report));
    let draws = if heldout {
        HELDOUT_REALISATIONS
    } else {
        REALISATIONS
    };
    let pred = predict_draws(p, c, i, simulated, noise, draws);
    parts
        .iter()
        .zip(hold)
        .map(|(&part, &held)| {
            let range = part.range(c.records[i].len());
            let left = left_envelope(p, c, i, pred.locked_over(range.clone()), range);
            if held && left {
                let inf = CellScores {
                    score: Cells::filled(Cell::Diverged),
                    residual: Cells::filled(Cell::Diverged),
                    deviation: Cells::filled(Cell::Diverged),
                };
                return (inf, left);
            }
            (scores(c, i, &pred, noise, part), left)
        })
        .collect()
}

/// Whether a model's noise-free readings `locked` of test `i` over `range` leave the
/// envelope where the measured table does not ([`measured_beyond_envelope`]); a run that
/// stopped inside `range` (`locked` None) has left it there.
fn left_envelope(
    p: &Params,
    c: &Campaign,
    i: usize,
    locked: Option<&[Outputs]>,
    range: std::ops::Range<usize>,
) -> bool {
    !range.is_empty()
        && locked.is_none_or(|locked| crate::model::limits::first_exceeded(p, locked).is_some())
        && !measured_beyond_envelope(p, &c.records[i], range)
}

/// Whether `p`'s noise-free whole runs of `tests` stay inside the envelope wherever the
/// measured table does ([`left_envelope`] over each whole record).
pub fn stays_inside(p: &Params, c: &Campaign, tests: &[usize]) -> bool {
    use rayon::prelude::*;
    tests.par_iter().all(|&i| {
        let run = simulate_test(p, c, i, Part::Whole);
        let range = Part::Whole.range(c.records[i].len());
        !left_envelope(p, c, i, readings(&run).get(range.clone()), range)
    })
}

/// Whether the measured table itself left the envelope over `range`, as far as its
/// channels show: the LVDT beyond the stroke limit, or the force channel beyond the load
/// the pressure limit allows (`P_L A`). Then a model that leaves it too is not penalised:
/// it follows the table (a heavily saturated table drives its load pressure to the
/// relief as the true one does).
fn measured_beyond_envelope(p: &Params, r: &Record, range: std::ops::Range<usize>) -> bool {
    use crate::model::limits::{PRESSURE_HIGH_FACTOR, STROKE_FACTOR};
    let stroke_m = STROKE_FACTOR * p.limits.stroke_m;
    let force_n = PRESSURE_HIGH_FACTOR * p.actuator.supply_pressure_pa * p.actuator.piston_area_m2;
    let beyond = |x: Option<&Vec<f64>>, limit: f64| {
        x.is_some_and(|x| {
            x[range.start.min(x.len())..range.end.min(x.len())]
                .iter()
                .any(|v| v.abs() > limit)
        })
    };
    beyond(r.displacement_m.as_ref(), stroke_m) || beyond(r.force_n.as_ref(), force_n)
}

/// Noisy runs per prediction in [`score_sum`], the objective of noise-driven effects'
/// fits: with one draw the predicted spread of chatter or impacts is one realisation, and
/// the score ranks models wrongly. Measured (stop 55, 6-t table, stick-slip ratio 2.5,
/// its fitting halves): one draw scored the truth 533, the fitted model 261 and the truth's
/// baseline with the fitted stick-slip 178 (whose worst held-out cell is 4.6 against the
/// truth's 1.5); two draws 93, 207 and 122, three and four the same order.
pub const FIT_SCORE_REALISATIONS: usize = 2;

/// Sum over `tests` and channels of the squared predictive scores over `part`, with
/// [`FIT_SCORE_REALISATIONS`] noise draws: the objective of the fits that cannot use
/// sample-wise least squares (stick-slip, free play).
pub fn score_sum(p: &Params, c: &Campaign, tests: &[usize], noise: &NoiseFloor, part: Part) -> f64 {
    if p.validate().is_err() {
        return f64::INFINITY;
    }
    tests
        .par_iter()
        .map(|&i| {
            let pred = predict_draws(p, c, i, part.simulated(), noise, FIT_SCORE_REALISATIONS);
            scores(c, i, &pred, noise, part)
                .score
                .values()
                .filter_map(|cell| cell.figure())
                .map(|x| x * x)
                .sum::<f64>()
        })
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    fn noise(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let d = Normal::new(0.0, sigma).unwrap();
        (0..n).map(|_| d.sample(&mut rng)).collect()
    }

    /// A residual with the power the model predicts scores a ratio of 1 (within the
    /// estimate's spread: 20 000 samples give about 1 %), one with four times the power
    /// scores 4, and the log term is the predicted power's.
    #[test]
    fn the_ratio_is_the_measured_over_the_predicted_power() {
        let n = 20_000;
        let spread: Vec<Vec<f64>> = (0..4).map(|k| noise(n, 1.0, 10 + k)).collect();
        let (q, log) = band_score(&noise(n, 1.0, 1), &spread, SCORE_WINDOW, 0.0);
        assert!((q - 1.0).abs() < 0.05, "{q}");
        assert!(log.abs() < 0.05, "{log}");
        let (q4, _) = band_score(&noise(n, 2.0, 2), &spread, SCORE_WINDOW, 0.0);
        assert!((q4 / 4.0 - 1.0).abs() < 0.05, "{q4}");
        // white measurement noise adds to the prediction: 1 + 1 predicted for 2 measured
        let (qw, logw) = band_score(&noise(n, 2f64.sqrt(), 3), &spread, SCORE_WINDOW, 1.0);
        assert!((qw - 1.0).abs() < 0.05, "{qw}");
        assert!((logw - 2f64.ln()).abs() < 0.05, "{logw}");
    }

    /// A model predicting no power where the data has some is infinitely bad, never NaN
    /// (the power floor keeps 0/0 out); data without power under such a model scores 0.
    #[test]
    fn a_prediction_of_nothing_is_infinitely_bad_never_nan() {
        let spread = vec![vec![0.0; 1000]];
        let (q, log) = band_score(&noise(1000, 1.0, 4), &spread, SCORE_WINDOW, 0.0);
        assert_eq!(q, f64::INFINITY);
        assert!(log.is_finite(), "{log}");
        let (q0, _) = band_score(&[0.0; 1000], &spread, SCORE_WINDOW, 0.0);
        assert_eq!(q0, 0.0);
    }
}

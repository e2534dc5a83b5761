//! Stick-slip: from the friction-velocity curve of the slow tests, polished on the
//! predictive score (its chatter has no reproducible phase).

use super::baseline::refine_output_error;
use super::candidates::{FitContext, FitTrace, ScoreFit};
use super::effect::Effect;
use super::effect_values::{EffectBounds, EffectValues};
use super::part::Part;
use super::residuals::{self, NoiseFloor};
use super::simplex;
use super::stribeck::{self, CurveFit};
use crate::campaign::Campaign;
use crate::params::Params;
use rayon::prelude::*;

/// A point of stick-slip's fit: the effect's static ratio and Stribeck velocity, and the
/// baseline's friction amplitude (which absorbed part of the static friction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StickSlipPoint {
    pub static_ratio: f64,
    pub stribeck_velocity_m_s: f64,
    pub friction_n: f64,
}

/// Stick-slip models on one base, scored on the predictive score over the fitting halves
/// of the signature tests.
pub(super) struct StickSlipScore<'a> {
    base: Params,
    c: &'a Campaign,
    sig: &'a [usize],
    noise: &'a NoiseFloor,
}

impl StickSlipScore<'_> {
    /// The score, the effect's values and the model at `x`.
    pub(super) fn eval(&self, x: StickSlipPoint) -> ScoreFit {
        let mut p = self.base;
        let values = EffectValues::new(
            Effect::of(&crate::effects::stick_slip::EFFECT),
            &[
                ("static_ratio", x.static_ratio),
                ("stribeck_velocity_m_s", x.stribeck_velocity_m_s),
            ],
        );
        values.apply(&mut p);
        p.friction.force_n = x.friction_n;
        ScoreFit {
            score: residuals::score_sum(&p, self.c, self.sig, self.noise, Part::Fit),
            values,
            params: p,
        }
    }
}

/// The point of the fit `f` with the friction amplitude `friction_n`.
fn point_of(f: &ScoreFit, friction_n: f64) -> StickSlipPoint {
    StickSlipPoint {
        static_ratio: f.values.get("static_ratio"),
        stribeck_velocity_m_s: f.values.get("stribeck_velocity_m_s"),
        friction_n,
    }
}

/// Stick-slip on the predictive score (see [`residuals`]): its chatter grows out of the
/// sensor noise, so finite-difference gradients of a sample-wise residual are noise,
/// while the score's window powers change smoothly with the parameters. The score's
/// valley is narrow (a static ratio 0.2 off doubles it) and bends with the friction
/// amplitude, so the fit starts from the friction-velocity curve read off the slow tests
/// ([`stribeck`]; a grid when they never slide slowly), polishes `(r_s, v_s, F_mu)` by
/// Nelder-Mead, then, when that clearly beats the baseline without stick-slip
/// ([`UNBEND_BELOW_BARE_SHARE`]), unbends the baseline by output error with that
/// stick-slip in place (the refinement had raised the friction and shrunk its yield
/// displacement to absorb the static peaks) and polishes again while the score improves.
/// `None`, not fitted, when the curve is read and has no static peak
/// ([`NEGLIGIBLE_STATIC_EXCESS`]).
pub(super) fn fit_stick_slip(
    base: &Params,
    sig: &[usize],
    ctx: &FitContext,
    trace: &FitTrace,
) -> Option<ScoreFit> {
    let c = ctx.c;
    let score_on = |base: Params| StickSlipScore {
        base,
        c,
        sig,
        noise: ctx.noise,
    };
    let eval = score_on(*base);
    let bounds = Effect::of(&crate::effects::stick_slip::EFFECT).bounds(base);
    let start = match stribeck::fit_curve(&stribeck::measured_curve(c, base, sig)) {
        Some(curve) if curve.static_ratio < 1.0 + NEGLIGIBLE_STATIC_EXCESS => {
            // the data show no static peak: a polish from one would walk the ratio down
            // to 1 over a few dozen scores (12-20 s on the paper's campaign) and end as
            // a candidate that is no stick-slip. The curve read 1.000-1.023 on paper
            // campaigns with a specimen, foundation, deadband, flow asymmetry or free
            // play, and 1.195, 1.283, 1.480, 2.087 for true ratios 1.2, 1.3, 1.5, 2.5
            // (1.499 for 1.5 beside a 15-t specimen, 2.028 for 2.5 on a 6-t table)
            trace.say(&format!(
                "no static peak in the friction-velocity curve (ratio {:.3}): not fitted",
                curve.static_ratio
            ));
            return None;
        }
        Some(curve) => curve_start(curve),
        None => grid_stick_slip(&eval, base.friction.force_n, &bounds)?,
    };
    let mut best = polish_stick_slip(&eval, start, &bounds)?;
    if best.values.get("static_ratio") < 1.0 + NEGLIGIBLE_STATIC_EXCESS {
        // no static peak: nothing bent the baseline
        return Some(best);
    }
    let bare = residuals::score_sum(base, c, sig, ctx.noise, Part::Fit);
    if best.score >= UNBEND_BELOW_BARE_SHARE * bare {
        // hardly better than no stick-slip on this baseline: the unbending would refit
        // the baseline, not build on a stick-slip
        return Some(best);
    }
    for _ in 0..UNBENDING_ROUNDS {
        let Some(unbent) = refine_output_error(
            c,
            &best.params,
            std::slice::from_ref(&best.values),
            base,
            ctx.fit_idx,
            ctx.whitening,
            UNBENDING_ITERATIONS,
        ) else {
            break;
        };
        let unbent = unbent.params;
        let next = polish_stick_slip(
            &score_on(unbent),
            point_of(&best, unbent.friction.force_n),
            &bounds,
        )?;
        if next.score >= best.score {
            break;
        }
        best = next;
    }
    Some(best)
}

/// The baseline is unbent under the polished stick-slip only when that scores below this
/// share of the baseline without it ("bare"): true stick-slips polished to 1/7.5 to 1/60
/// of the bare score (seeds 454, 460, 482, both searches), while on a baseline bent by
/// another effect the polish scored 1.03 (a 0.03 deadband, seeds 456 and 462) and 0.998 (a
/// 1.25 flow asymmetry, seed 458) times it, and the unbending that followed refitted the
/// baseline for 20-26 s (a stick-slip that saves 5 % of its signature's score is not one
/// the selection would credit).
const UNBEND_BELOW_BARE_SHARE: f64 = 0.95;

/// A static ratio below `1 +` this is no stick-slip: a 5 % static peak changes no channel
/// by more than its noise (the issue measured 2 noise RMS for a 1.3 ratio).
pub(super) const NEGLIGIBLE_STATIC_EXCESS: f64 = 0.05;

/// The polish's start from the curve's fit, the ratio and the velocity kept within
/// [`CURVE_START_RATIO`] and [`CURVE_START_STRIBECK_M_S`].
fn curve_start(curve: CurveFit) -> StickSlipPoint {
    StickSlipPoint {
        static_ratio: curve
            .static_ratio
            .clamp(CURVE_START_RATIO[0], CURVE_START_RATIO[1]),
        stribeck_velocity_m_s: curve
            .stribeck_velocity_m_s
            .clamp(CURVE_START_STRIBECK_M_S[0], CURVE_START_STRIBECK_M_S[1]),
        friction_n: curve.kinetic_n,
    }
}

/// Where the curve's static ratio may start the polish: at least a 5 % static excess (the
/// simplex works on `ln(r_s - 1)`, which has no value at `r_s = 1`, the bare table's
/// curve), at most the effect's upper fitting bound.
const CURVE_START_RATIO: [f64; 2] = [1.05, 6.0];

/// Where the curve's Stribeck velocity may start the polish, m/s: from the grid's slowest
/// ([`GRID_STRIBECK_M_S`]) to 30 mm/s, a little beyond the grid's fastest (20 mm/s) and
/// well inside the effect's fitting bounds (0.1-50 mm/s).
const CURVE_START_STRIBECK_M_S: [f64; 2] = [3e-4, 0.03];

/// The grid of [`grid_stick_slip`]: six static excesses `r_s - 1` from 0.1 in steps of
/// this factor (0.1 to 4.3: ratios 1.1-5.3).
const GRID_EXCESS_STEP: f64 = 2.12;
/// The grid's smallest static excess `r_s - 1`: 10 %, twice [`NEGLIGIBLE_STATIC_EXCESS`].
const GRID_SMALLEST_EXCESS: f64 = 0.1;
/// Six Stribeck velocities from [`GRID_STRIBECK_M_S`] in steps of this factor (0.3 to
/// 20 mm/s, the plausible knees of the curve: [`stribeck`]'s bins).
const GRID_STRIBECK_STEP: f64 = 2.32;
/// The grid's slowest Stribeck velocity, m/s.
const GRID_STRIBECK_M_S: f64 = 3e-4;
/// Points per axis of the coarse grid.
const GRID_POINTS: i32 = 6;
/// The refinements of the grid around its best point, as fractions of its geometric step
/// (half, then quarter steps).
const GRID_REFINEMENTS: [f64; 2] = [0.5, 0.25];
/// The friction amplitudes tried at the grid's best point, as multiples of the
/// baseline's: the baseline absorbed part of the static friction into its amplitude, so
/// the kinetic one lies at or a little below it.
const GRID_FRICTION_FACTORS: [f64; 5] = [0.7, 0.8, 0.9, 1.0, 1.1];

/// The polish's initial simplex steps in `(ln(r_s - 1), ln v_s, ln F_mu)`: a fifth of the
/// static excess, a quarter of the Stribeck velocity, 3 % of the friction amplitude (the
/// score's valley is about that wide in each).
const POLISH_STEPS: [f64; 3] = [0.2, 0.25, 0.03];
/// The polish stops when the simplex's costs spread by less than this share of the
/// start's score.
const POLISH_SPREAD_TOLERANCE: f64 = 1e-3;
/// Nelder-Mead iterations of one polish: three parameters settle in a few dozen
/// evaluations, and each costs a full score (every signature test simulated).
const POLISH_ITERATIONS: u64 = 25;

/// Output-error iterations of one unbending round: a few steps take the baseline's
/// bends out; the effect it holds keeps it from converging anyway.
pub(super) const UNBENDING_ITERATIONS: usize = 4;

/// Rounds of baseline unbending in [`fit_stick_slip`] (each about 5 s on the paper's
/// campaign; the second rarely moves the score by a percent).
pub(super) const UNBENDING_ROUNDS: usize = 2;

/// The point from a grid over (static ratio, Stribeck velocity) with geometric steps,
/// refined twice around the best point (kept within the fitting `bounds`: a refinement
/// step past the coarse grid's edge once landed at a static ratio of 8.5), then five
/// friction amplitudes.
fn grid_stick_slip(
    eval: &StickSlipScore,
    f0: f64,
    bounds: &EffectBounds,
) -> Option<StickSlipPoint> {
    let best_of = |pts: Vec<StickSlipPoint>| {
        pts.par_iter()
            .map(|&x| eval.eval(x))
            .min_by(|a, b| a.score.total_cmp(&b.score))
    };
    let at = |static_ratio, stribeck_velocity_m_s, friction_n| StickSlipPoint {
        static_ratio,
        stribeck_velocity_m_s,
        friction_n,
    };
    // ratios 1.1-5 and Stribeck velocities 0.3-20 mm/s, geometric steps, then two finer
    // 3 x 3 grids (half and quarter steps) around the best point
    let (sr, sv) = (GRID_EXCESS_STEP, GRID_STRIBECK_STEP);
    let ratios: Vec<f64> = (0..GRID_POINTS)
        .map(|k| 1.0 + GRID_SMALLEST_EXCESS * sr.powi(k))
        .collect();
    let speeds: Vec<f64> = (0..GRID_POINTS)
        .map(|k| GRID_STRIBECK_M_S * sv.powi(k))
        .collect();
    let coarse: Vec<StickSlipPoint> = ratios
        .iter()
        .flat_map(|&r| speeds.iter().map(move |&v| at(r, v, f0)))
        .collect();
    let mut t = best_of(coarse)?.values;
    let (ratio, speed) = ("static_ratio", "stribeck_velocity_m_s");
    let (lower, upper) = (&bounds.lower, &bounds.upper);
    for refinement in GRID_REFINEMENTS {
        let (r0, v0) = (t.get(ratio) - 1.0, t.get(speed));
        let mut fine = Vec::new();
        for i in -1..=1 {
            for j in -1..=1 {
                fine.push(at(
                    (1.0 + r0 * sr.powf(refinement * i as f64))
                        .clamp(lower.get(ratio), upper.get(ratio)),
                    (v0 * sv.powf(refinement * j as f64)).clamp(lower.get(speed), upper.get(speed)),
                    f0,
                ));
            }
        }
        t = best_of(fine)?.values;
    }
    // the friction amplitude: the baseline's absorbed part of the static friction
    let best = best_of(
        GRID_FRICTION_FACTORS
            .iter()
            .map(|k| at(t.get(ratio), t.get(speed), k * f0))
            .collect(),
    )?;
    Some(point_of(&best, best.params.friction.force_n))
}

/// Nelder-Mead (argmin) over `(ln(r_s - 1), ln v_s, ln F_mu)` from `start`: the score is
/// smooth but its finite-difference gradient is not trustworthy at chatter onset, and
/// three parameters need no more than a few dozen evaluations. Returns the best point
/// seen (the start itself when nothing beats it). `bounds` are the effect's fitting
/// bounds.
fn polish_stick_slip(
    eval: &StickSlipScore,
    start: StickSlipPoint,
    bounds: &EffectBounds,
) -> Option<ScoreFit> {
    let cost = |x: &[f64]| score_within(eval, bounds, point(x));
    let first = eval.eval(start);
    let x0 = coordinates(start).to_vec();
    let best = nelder_mead(cost, x0, &POLISH_STEPS, first.score, POLISH_ITERATIONS)
        .map(|x| eval.eval(point(&x)));
    match best {
        Some(b) if b.score < first.score => Some(b),
        _ => Some(first),
    }
}

/// The point at the polish's simplex coordinates `x`: `(ln(r_s - 1), ln v_s, ln F_mu)`
/// first.
fn point(x: &[f64]) -> StickSlipPoint {
    StickSlipPoint {
        static_ratio: 1.0 + x[0].exp(),
        stribeck_velocity_m_s: x[1].exp(),
        friction_n: x[2].exp(),
    }
}

/// The simplex coordinates of `at` (the inverse of [`point`]).
fn coordinates(at: StickSlipPoint) -> [f64; 3] {
    [
        (at.static_ratio - 1.0).ln(),
        at.stribeck_velocity_m_s.ln(),
        at.friction_n.ln(),
    ]
}

/// The score of `at` under `eval`, infinite when its static ratio or Stribeck velocity
/// lies outside the effect's fitting `bounds`.
fn score_within(eval: &StickSlipScore, bounds: &EffectBounds, at: StickSlipPoint) -> f64 {
    let (lower, upper) = (&bounds.lower, &bounds.upper);
    let (ratio, speed) = ("static_ratio", "stribeck_velocity_m_s");
    if (lower.get(ratio)..=upper.get(ratio)).contains(&at.static_ratio)
        && (lower.get(speed)..=upper.get(speed)).contains(&at.stribeck_velocity_m_s)
    {
        eval.eval(at).score
    } else {
        f64::INFINITY
    }
}

/// [`simplex::nelder_mead`] on `cost` from `x0`, stopping when the simplex's costs spread
/// by less than [`POLISH_SPREAD_TOLERANCE`] of `start_score`: the best point seen.
fn nelder_mead(
    cost: impl Fn(&[f64]) -> f64,
    x0: Vec<f64>,
    steps: &[f64],
    start_score: f64,
    iterations: u64,
) -> Option<Vec<f64>> {
    let tolerance = POLISH_SPREAD_TOLERANCE * start_score;
    simplex::nelder_mead(cost, &x0, steps, tolerance, iterations).map(|(x, _)| x)
}

/// The wide polish's initial simplex step of the friction shape: 0.05 of its 0-1 range.
const SHAPE_STEP: f64 = 0.05;
/// Nelder-Mead iterations of the wide polish: four coordinates settle in a few dozen.
const WIDE_ITERATIONS: u64 = 60;

/// Stick-slip polished on the score together with the friction shape, the baseline
/// parameter its output-error unbending bends most. The chatter has no reproducible
/// phase, so an output-error fit of the baseline beside it is biased (seed 454: the
/// unbending left the shape at 0.39 for 0.5, which the fitting halves barely see but the
/// stop at the end of each slow triangle does, at 3-4 noise RMS in the force); the score
/// is not. The table mass, which the unbending bent by 0.14 %, stays: the slow signature
/// tests barely see it (freed, it walked 0.3 % further off and the fast sines' force
/// missed by 7 noise RMS). `fit` is the stick-slip fit to polish, on its signature
/// tests `sig`.
pub(super) fn polish_wide(
    fit: &Params,
    sig: &[usize],
    c: &Campaign,
    noise: &NoiseFloor,
) -> Option<ScoreFit> {
    let bounds = Effect::of(&crate::effects::stick_slip::EFFECT).bounds(fit);
    let shaped = |x: &[f64]| {
        let mut base = *fit;
        base.friction.shape = x[3];
        StickSlipScore {
            base,
            c,
            sig,
            noise,
        }
    };
    let cost = |x: &[f64]| score_within(&shaped(x), &bounds, point(x));
    let start = StickSlipPoint {
        static_ratio: fit.stick_slip.static_ratio,
        stribeck_velocity_m_s: fit.stick_slip.stribeck_velocity_m_s,
        friction_n: fit.friction.force_n,
    };
    let x0: Vec<f64> = coordinates(start)
        .into_iter()
        .chain([fit.friction.shape])
        .collect();
    let steps = [
        POLISH_STEPS[0],
        POLISH_STEPS[1],
        POLISH_STEPS[2],
        SHAPE_STEP,
    ];
    let first = cost(&x0);
    let x = nelder_mead(cost, x0, &steps, first, WIDE_ITERATIONS)?;
    let best = shaped(&x).eval(point(&x));
    (best.score < first).then_some(best)
}

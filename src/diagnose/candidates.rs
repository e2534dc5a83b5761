//! Fitting one candidate effect: the tests it is fitted on, its fit (on the predictive
//! score, or by output-error least squares with the baseline's refined parameters free:
//! [`super::candidate_fit`]), and its held-out scores.

use super::baseline::from_motion;
use super::candidate_fit::CandidateFit;
use super::effect::Effect;
use super::effect_table::FitKind;
use super::effect_values::{EffectBounds, EffectValues};
use super::effort::Effort;
use super::evidence::not_evidence;
use super::free_play_fit::fit_free_play;
use super::output::{Candidate, PartRows};
use super::part::Part;
use super::residuals::{CellScores, Cells, NoiseFloor, Whitening};
use super::starts::informed_start;
use super::stick_slip::{fit_stick_slip, polish_wide};
use super::{residuals, trace_enabled};
use crate::campaign::Campaign;
use crate::params::Params;
use rayon::prelude::*;

/// The figures of `p` ([`PartRows`]) on the selection and report quarters of every test
/// of `tests`, per test and channel, from one prediction per test.
///
/// A candidate is held to the operating envelope (`hold`: the rows of the model it
/// extends; [`residuals::test_scores_in_envelope`]) on each test and quarter where that
/// model stayed inside it: there, a candidate that leaves the envelope where the
/// measured table did not describes nothing real. Where the model it extends left it
/// too, the breach comes from physics neither has (a second effect still missing), and
/// the candidate is scored on its residual like that model. The baseline (`hold` None)
/// is not held, so a baseline that passes the relief pressure where the table did not
/// still gives the finite residual that measures the gain.
pub(super) fn heldout_scores(
    p: &Params,
    c: &Campaign,
    tests: &[usize],
    noise: &NoiseFloor,
    hold: Option<&Hold>,
) -> (PartRows, PartRows) {
    let cells: Vec<Vec<(CellScores, bool)>> = tests
        .par_iter()
        .enumerate()
        .map(|(k, &i)| {
            let held = hold.map_or([false; 2], |h| {
                [!h.select.left_envelope[k], !h.report.left_envelope[k]]
            });
            residuals::test_scores_of_parts(p, c, i, &[Part::Select, Part::Report], noise, &held)
        })
        .collect();
    let rows = |k: usize| PartRows {
        score: cells.iter().map(|s| s[k].0.score).collect(),
        residual: cells.iter().map(|s| s[k].0.residual).collect(),
        deviation: cells.iter().map(|s| s[k].0.deviation).collect(),
        left_envelope: cells.iter().map(|s| s[k].1).collect(),
    };
    (rows(0), rows(1))
}

/// The rows of the model a candidate extends, on the selection and report quarters: where
/// it stayed inside the envelope, the candidate is held to it ([`heldout_scores`]).
pub(super) struct Hold<'a> {
    pub select: &'a PartRows,
    pub report: &'a PartRows,
}

/// What a candidate's fit works on besides the effect and its bases: the campaign, the
/// tests whose fitting halves it fits (`fit_idx`) and whose held-out quarters score it
/// (`heldout_idx`), the noise, the effort, the whitening of the output error, and the rows
/// of the model it extends ([`Hold`]).
pub(super) struct FitContext<'a> {
    pub c: &'a Campaign,
    pub fit_idx: &'a [usize],
    pub heldout_idx: &'a [usize],
    pub noise: &'a NoiseFloor,
    pub effort: Effort,
    pub whitening: &'a Whitening,
    pub hold: &'a Hold<'a>,
}

/// The trace lines of one candidate's fit (`SHAKETABLE_TRACE`): the effect, what, and
/// the seconds since the fit began.
pub(super) struct FitTrace {
    effect: Effect,
    t0: std::time::Instant,
}

impl FitTrace {
    fn begin(effect: Effect) -> FitTrace {
        FitTrace {
            effect,
            t0: std::time::Instant::now(),
        }
    }

    pub(super) fn say(&self, what: &str) {
        if trace_enabled() {
            eprintln!(
                "  {} {what} after {:.1} s",
                self.effect.name(),
                self.t0.elapsed().as_secs_f64()
            );
        }
    }
}

/// The tests `e` is fitted on: the fitting tests where its signature lives, or every
/// fitting test when none does or when it is a resonance and the baseline was fitted to
/// the motion; `None` without any.
fn fitted_tests(e: Effect, c: &Campaign, table: &Params, fit_idx: &[usize]) -> Option<Vec<usize>> {
    let sig: Vec<usize> = e
        .signature_tests(c, table)
        .into_iter()
        .filter(|i| fit_idx.contains(i))
        .collect();
    // a resonance moves a baseline fitted to the motion far (the identified mass holds a
    // specimen's, the oil column a foundation's): it is refitted on every test
    // ([`from_motion`]); the other effects perturb it locally and keep their signature's
    let moves_far = e.valley_frequency().is_some() && from_motion(c);
    let sig = if sig.is_empty() || moves_far {
        fit_idx.to_vec()
    } else {
        sig
    };
    (!sig.is_empty()).then_some(sig)
}

/// Effect `e` fitted on `bases` (the refined baseline, then section 4's) over the fitting
/// halves of its tests ([`fitted_tests`]), and scored on the held-out quarters: on the
/// predictive score for the effects fitted on it ([`fit_on_score`]), by output-error
/// least squares with the baseline's refined parameters free for the others
/// ([`CandidateFit`]). `None` when it has no test or no fit converged.
pub(super) fn fit_candidate(e: Effect, bases: &[Params], ctx: &FitContext) -> Option<Candidate> {
    let sig = fitted_tests(e, ctx.c, &bases[0], ctx.fit_idx)?;
    let trace = FitTrace::begin(e);
    match e.row().fit {
        FitKind::OutputError => CandidateFit::new(e, bases, &sig, ctx, &trace).fit(),
        FitKind::StickSlip | FitKind::FreePlay => fit_on_score(e, bases, &sig, ctx, &trace),
    }
}

/// The effects fitted on the predictive score ([`Effect::fitted_on_score`]): stick-slip
/// ([`fit_stick_slip`]) and the free play ([`fit_free_play`]), scored on the held-out
/// quarters.
fn fit_on_score(
    e: Effect,
    bases: &[Params],
    sig: &[usize],
    ctx: &FitContext,
    trace: &FitTrace,
) -> Option<Candidate> {
    let fit = match e.row().fit {
        FitKind::StickSlip => fit_stick_slip(&bases[0], sig, ctx, trace)?,
        _ => {
            // without a gap read off the reversals there is no play to fit: its impacts
            // are chaotic, and a fit from a guess lands wherever the bounces misfit least
            let Some(start) = informed_start(e, ctx.c, &bases[1]) else {
                trace.say("no gap read off the reversals: not fitted");
                return None;
            };
            fit_free_play(bases, sig, &start, ctx, trace)?
        }
    };
    trace.say(&format!(
        "fitted: score {:.1}, {:?}",
        fit.score,
        fit.values.layout()
    ));
    Some(scored_candidate(
        e,
        ctx.c,
        Fitted {
            values: &fit.values,
            sigma: None,
            bounds: &e.bounds(&bases[0]),
            fit_residual: fit.score.sqrt(),
            params: fit.params,
        },
        ctx.heldout_idx,
        ctx.noise,
        ctx.hold,
    ))
}

/// A stick-slip candidate `cand` polished on the predictive score with the friction
/// shape its output-error unbending bent ([`polish_wide`]), on its
/// signature tests under the table `table`, scored on the held-out quarters; `None` for
/// the other effects and when the polish gains nothing on the fit's score.
pub(super) fn polish_on_score(
    cand: &Candidate,
    table: &Params,
    ctx: &FitContext,
) -> Option<Candidate> {
    let e = cand.effect;
    if e.row().fit != FitKind::StickSlip {
        return None;
    }
    let sig = fitted_tests(e, ctx.c, table, ctx.fit_idx)?;
    let fit = polish_wide(&cand.params, &sig, ctx.c, ctx.noise)?;
    Some(scored_candidate(
        e,
        ctx.c,
        Fitted {
            values: &fit.values,
            sigma: None,
            bounds: &e.bounds(table),
            fit_residual: fit.score.sqrt(),
            params: fit.params,
        },
        ctx.heldout_idx,
        ctx.noise,
        ctx.hold,
    ))
}

/// Share of its selection score a candidate pays per parameter in the ranking: of two
/// candidates that explain about as much, the one with fewer parameters ranks first (a
/// parameter more can always absorb a little of chance); 1 % each stays small beside the
/// [`super::REQUIRED_GAIN`] a cause must show.
pub(super) const PENALTY_PER_PARAMETER: f64 = 0.01;

impl Candidate {
    /// Its selection residual, deviation and score over the cells `select_mask` keeps (the
    /// cells the model it extends misses), the score with a penalty of [`PENALTY_PER_PARAMETER`] per parameter,
    /// and its report residual over the cells `report_mask` keeps (the baseline's missed
    /// ones).
    pub(super) fn summarise(
        &mut self,
        select_mask: &dyn Fn(&[Cells]) -> f64,
        report_mask: &dyn Fn(&[Cells]) -> f64,
    ) {
        self.select_residual = select_mask(&self.select.residual);
        self.select_deviation = select_mask(&self.select.deviation);
        self.score = select_mask(&self.select.score)
            * (1.0 + PENALTY_PER_PARAMETER * self.parameters.len() as f64);
        self.report_residual = report_mask(&self.report.residual);
    }
}

/// A fit on the predictive score ([`fit_on_score`]): the score, the effect's values and
/// the model.
pub(super) struct ScoreFit {
    pub score: f64,
    pub values: EffectValues,
    pub params: Params,
}

/// What a fit gives a candidate: the effect's parameters and their one-sigma
/// uncertainties (`None` when the fit gives none), the fit's RMS residual, the model.
pub(super) struct Fitted<'a> {
    pub values: &'a EffectValues,
    pub sigma: Option<&'a EffectValues>,
    /// The fitting range it was fitted in.
    pub bounds: &'a EffectBounds,
    pub fit_residual: f64,
    pub params: Params,
}

/// A fitted candidate with its held-out rows (summarised by [`Candidate::summarise`]) and
/// whether it is evidence of its effect ([`not_evidence`], within its fitting bounds).
pub(super) fn scored_candidate(
    e: Effect,
    c: &Campaign,
    fitted: Fitted,
    heldout_idx: &[usize],
    noise: &NoiseFloor,
    hold: &Hold,
) -> Candidate {
    let p = fitted.params;
    let (select, report) = heldout_scores(&p, c, heldout_idx, noise, Some(hold));
    let parameters = fitted.values.finite_map();
    let sigma = fitted.sigma.map(EffectValues::map).unwrap_or_default();
    let why = not_evidence(e, &parameters, &sigma, fitted.bounds);
    Candidate {
        effect: e,
        parameters,
        sigma,
        select_residual: f64::NAN,
        select_deviation: f64::NAN,
        score: f64::NAN,
        report_residual: f64::NAN,
        fit_residual: fitted.fit_residual,
        not_evidence: why,
        params: p,
        select,
        report,
        fewer_modes: None,
        refitted_sigma: Vec::new(),
    }
}

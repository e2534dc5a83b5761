//! Polishing: a candidate refined like the baseline with the causes accepted before
//! refitted beside it ([`Diagnoser::polish`]), the search's best polished until it
//! explains the selection quarter or stops improving ([`Diagnoser::polish_best`]), and an
//! accepted cause settled before a further search ([`Diagnoser::settle`]).

use super::Diagnoser;
use crate::diagnose::baseline::{refine_output_error, with_actuator, FreedFit, Refined};
use crate::diagnose::candidates::{polish_on_score, scored_candidate, Fitted, Hold};
use crate::diagnose::effect::Effect;
use crate::diagnose::effect_values::{EffectBounds, EffectValues};
use crate::diagnose::missed::Missed;
use crate::diagnose::output::Candidate;
use crate::diagnose::{trace_enabled, EXPLAINED_RATIO};
use crate::params::{ActuatorModel, Params};

/// A further polish round is taken only when the previous one cut the score by at least
/// this factor's complement (5 %): the rounds exist for heavily saturated tables (seed
/// 404), whose baseline is bent by tens of percent, not to chase the last digits.
const POLISH_MIN_IMPROVEMENT: f64 = 0.95;

/// A candidate explains the selection quarter when its residual there is within
/// [`EXPLAINED_RATIO`] (polishing stops there).
pub(super) fn explains(c: &Candidate) -> bool {
    c.select_residual <= EXPLAINED_RATIO
}

/// The causes accepted before `from`, read off the switches in `p0` ([`Effect::present_in`];
/// the identified table switches none on), with their values: each is refitted with
/// `from`. Each was fitted without the effects found after it, and a cause fitted on a
/// model that lacks one is bent by it (a deadband fitted before the specimen was 0.26 %
/// narrow, which alone left the slow tests' displacement twice the floor, seed 803 at full
/// length). Those fitted on the score stay held in `p0`, as the refinement holds them.
fn accepted_before(from: &Candidate, p0: &Params) -> Vec<EffectValues> {
    Effect::present_in(p0)
        .into_iter()
        .filter(|e| e.name() != from.effect.name() && !e.fitted_on_score())
        .map(|e| EffectValues::read(e, p0))
        .collect()
}

/// The polished effect's own uncertainties and fitting bounds (`None` when the polish
/// held it), and the refitted uncertainties of the causes accepted before, from a
/// refinement `r` of `effect` and those causes.
struct SplitSigma {
    own: Option<FreedFit>,
    refitted_sigma: Vec<EffectValues>,
}

impl SplitSigma {
    /// The refinement lists the freed effects in the order given, this one first; an
    /// effect fitted on the score is held and listed nowhere.
    fn of(r: Refined, effect: Effect, accepted: &[EffectValues]) -> Self {
        let mut freed = r.effects.into_iter();
        let own = if effect.fitted_on_score() {
            None
        } else {
            freed.next()
        };
        let refitted_sigma: Vec<EffectValues> = freed.map(|f| f.sigma).collect();
        debug_assert_eq!(refitted_sigma.len(), accepted.len());
        SplitSigma {
            own,
            refitted_sigma,
        }
    }
}

/// The polished candidate's uncertainties: the refinement's `own_sigma`, or, when the
/// polish held the effect (fitted on the score), the fit's own from `from` (none: the
/// score's fit gives none).
fn polished_sigma(from: &Candidate, own_sigma: Option<EffectValues>) -> Option<EffectValues> {
    if own_sigma.is_none() && from.sigma.is_empty() {
        None
    } else if own_sigma.is_none() {
        let pairs: Vec<(&str, f64)> = from
            .effect
            .parameters()
            .into_iter()
            .map(|k| (k, from.sigma.get(k).copied().unwrap_or(f64::NAN)))
            .collect();
        Some(EffectValues::new(from.effect, &pairs))
    } else {
        own_sigma
    }
}

impl Diagnoser<'_> {
    /// `from` refined like the baseline (every fitting test, the friction shape and valve
    /// dynamics free too) with the actuator variant `model`, scored. The causes accepted
    /// before ([`accepted_before`]) are refitted with it, their uncertainties kept in
    /// [`Candidate::refitted_sigma`].
    pub(super) fn polish(
        &self,
        from: &Candidate,
        model: ActuatorModel,
        missed: &Missed,
        hold: &Hold,
    ) -> Option<Candidate> {
        let pairs: Vec<(&str, f64)> = from
            .effect
            .parameters()
            .into_iter()
            .map(|n| (n, from.parameters[n]))
            .collect();
        let own = EffectValues::new(from.effect, &pairs);
        let p0 = with_actuator(&from.params, model);
        let accepted = accepted_before(from, &p0);
        let effects: Vec<EffectValues> = std::iter::once(own)
            .chain(accepted.iter().cloned())
            .collect();
        let r = refine_output_error(
            self.c,
            &p0,
            &effects,
            &self.table,
            &self.tests,
            &self.whitening,
            self.effort.polish_iterations(),
        )?;
        let values = EffectValues::read(from.effect, &r.params);
        let (cost, params) = (r.cost, r.params);
        let split = SplitSigma::of(r, from.effect, &accepted);
        let mut polished = self.polished(from, (cost, params), &values, split, missed, hold);
        polished.fewer_modes = from.fewer_modes.clone();
        Some(polished)
    }

    /// The candidate of `from`'s effect at the refinement of cost `cost` and model
    /// `params` (its values `values`), scored and summarised on the cells `missed`, with
    /// the refitted uncertainties of the causes before it.
    fn polished(
        &self,
        from: &Candidate,
        (cost, params): (f64, Params),
        values: &EffectValues,
        split: SplitSigma,
        missed: &Missed,
        hold: &Hold,
    ) -> Candidate {
        let (own_sigma, bounds): (Option<EffectValues>, EffectBounds) = match split.own {
            Some(own) => (Some(own.sigma), own.bounds),
            None => (None, from.effect.bounds(&self.table)),
        };
        let sigma = polished_sigma(from, own_sigma);
        let mut polished = scored_candidate(
            from.effect,
            self.c,
            Fitted {
                values,
                sigma: sigma.as_ref(),
                bounds: &bounds,
                fit_residual: cost.sqrt(),
                params,
            },
            &self.tests,
            &self.noise,
            hold,
        );
        self.summarise(&mut polished, missed);
        polished.refitted_sigma = split.refitted_sigma;
        polished
    }

    /// The best candidate polished: its own fit only freed what interacts with the
    /// effect, and the rest may still hold the baseline's bends. The baseline's variant
    /// first; while that leaves the selection quarter unexplained the other variant too
    /// (a missing effect can tip the baseline's choice: a deadband on the ideal actuator
    /// fits better as a nonlinear one), then further rounds while unexplained and
    /// improving (a heavily saturated table bends the baseline by tens of percent); last,
    /// a stick-slip candidate polished on the score with the friction shape
    /// ([`polish_on_score`]). Every decision here reads the selection quarter only.
    pub(super) fn polish_best(&self, cand: &Candidate, missed: &Missed, hold: &Hold) -> Candidate {
        let better = |a: Option<Candidate>, b: &Candidate| a.filter(|a| a.score < b.score);
        let own = cand.params.actuator.model;
        let mut best =
            better(self.polish(cand, own, missed, hold), cand).unwrap_or_else(|| cand.clone());
        if !explains(&best) {
            if let Some(other) = ActuatorModel::ALL.into_iter().find(|&m| m != own) {
                if let Some(p) = better(self.polish(cand, other, missed, hold), &best) {
                    best = p;
                }
            }
        }
        for _ in 1..self.effort.polish_rounds() {
            if explains(&best) {
                break;
            }
            match better(
                self.polish(&best, best.params.actuator.model, missed, hold),
                &best,
            ) {
                Some(p) if p.score < POLISH_MIN_IMPROVEMENT * best.score => best = p,
                Some(p) => {
                    best = p;
                    break;
                }
                None => break,
            }
        }
        // stick-slip's own parameters with the baseline's that the output error bends
        // beside its chatter, on the score
        if let Some(p) = better(self.polish_on_score(&best, missed, hold), &best) {
            best = p;
        }
        best
    }

    /// [`polish_on_score`] of `cand` (stick-slip only), summarised on the cells `missed`.
    fn polish_on_score(&self, cand: &Candidate, missed: &Missed, hold: &Hold) -> Option<Candidate> {
        let mut polished = polish_on_score(cand, &self.table, &self.context(hold))?;
        self.summarise(&mut polished, missed);
        if trace_enabled() {
            eprintln!(
                "  {} polished on the score with the friction shape: score {:.4} (was {:.4}), \
                 {:?}, shape {:.4}",
                cand.effect.name(),
                polished.score,
                cand.score,
                polished.parameters,
                polished.params.friction.shape
            );
        }
        Some(polished)
    }

    /// An accepted cause polished until a round gains less than [`POLISH_MIN_IMPROVEMENT`]
    /// (at most the effort's polish rounds), before a further search: [`Self::polish_best`] stops as soon as the
    /// selection quarter is explained, but a further search runs because some cell is
    /// not, and each of its candidates refits the baseline parameters too; an unsettled
    /// model would credit them with that refit (a deadband of zero scored five times
    /// better than the accepted flow saturation it extended).
    pub(super) fn settle(&self, mut best: Candidate, missed: &Missed, hold: &Hold) -> Candidate {
        for _ in 0..self.effort.polish_rounds() {
            match self.polish(&best, best.params.actuator.model, missed, hold) {
                Some(p) if p.score < POLISH_MIN_IMPROVEMENT * best.score => best = p,
                Some(p) if p.score < best.score => return p,
                _ => break,
            }
        }
        best
    }
}

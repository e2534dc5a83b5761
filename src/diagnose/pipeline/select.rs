//! Selection: the candidate a search judges ([`best_candidate`]) and the rules that make
//! it a cause ([`Rule`], [`verdict`]), with the two measurements they may need: what
//! chance moves a score by ([`Diagnoser::chance_factor`]) and how much of the residual is
//! deterministic ([`Diagnoser::credited_to_spread`]).

use super::{Current, Diagnoser};
use crate::diagnose::candidates::heldout_scores;
use crate::diagnose::missed::Missed;
use crate::diagnose::output::Candidate;
use crate::diagnose::{trace_enabled, unphysical, REQUIRED_GAIN};
use crate::params::Params;
use rayon::prelude::*;

/// Relative change of the table mass within what a campaign resolves (section 4's
/// periodic mass has a standard error of about 0.2 %): a smooth model's score moves by
/// about as much (0.05 % on seed 13's baseline); a rough one's, whose free play bounces
/// differently after every small change, by far more (13 % with seed 13's play in it; the
/// move grows as the square root of the change: 0.15 % at 1e-6, 3.6 % at 1e-4).
pub(in crate::diagnose) const UNRESOLVED_CHANGE: f64 = 1e-3;

/// A residual mostly coherent with the reference: more than this share of its power. Half:
/// the deterministic part is then the larger, and it is what the candidate must explain.
pub(in crate::diagnose) const COHERENT_MAJORITY: f64 = 0.5;
/// A cause removes at least this share of a mostly coherent residual's coherent power. A
/// tenth: the true effects seen remove 47 % (a weak deadband beside a specimen) to all of
/// it; the UTFSM damper's stick-slip, explaining by chatter, removed 1 %.
pub(in crate::diagnose) const MIN_COHERENT_REMOVED: f64 = 0.1;
/// A cause's noise-free run leaves at most this many times the current model's *whole*
/// residual power as coherent (deterministic) error on the cells it is credited with:
/// far more would be an error it adds, which only its predicted spread can hide (a
/// deadband "explaining" a sign-flipped valve command left 95 times it). Ten, an order of
/// magnitude: true causes seen leave 0.00005 (a foundation) to 1.34 (a 0.87-mm free play,
/// seed 7232; seed 703's 1.5-mm play 1.03), whose impacts at the reversals fall where the
/// measured ones do not.
pub(in crate::diagnose) const MAX_COHERENT_LEFT: f64 = 10.0;

/// The candidate a search polishes and judges: the best-scoring one that is physical and
/// evidence of its effect, else the best-scoring one (then a partial explanation at
/// most). A candidate whose effect sits at its no-effect value (a deadband of zero) still
/// scores better than the model it extends, by refitting that model's own parameters: it
/// must not hide a weaker-scoring candidate that is evidence of a real second effect.
pub(super) fn best_candidate(candidates: &[Candidate], table_mass_kg: f64) -> Option<usize> {
    let by_score = |a: &usize, b: &usize| candidates[*a].score.total_cmp(&candidates[*b].score);
    let evidence = (0..candidates.len())
        .filter(|&i| {
            candidates[i].not_evidence.is_none()
                && unphysical(&candidates[i], table_mass_kg).is_none()
        })
        .min_by(by_score);
    evidence.or_else(|| (0..candidates.len()).min_by(by_score))
}

/// The selection cells' residual power that is coherent with the reference, under the
/// model a candidate extends and under the candidate, and the former's whole power.
#[derive(Debug, Clone, Copy)]
pub(super) struct CoherentSplit {
    pub current_coherent: f64,
    pub current_total: f64,
    pub candidate_coherent: f64,
}

/// Why a candidate is credited only with the spread it predicts, if it is: the residual
/// it is credited with is mostly coherent with the reference (deterministic: no predicted
/// spread holds it), and its noise-free run removes too little of that coherent part; or
/// its noise-free run leaves more than [`MAX_COHERENT_LEFT`] times the current model's
/// whole residual as coherent error, whatever that residual's share. Chatter and impacts, whose
/// phase is their own, are not coherent (3 % on a true stick-slip, 12 % on a true free
/// play), and the score may credit their spread.
pub(super) fn spread_credited(split: &CoherentSplit) -> Option<String> {
    let left = split.candidate_coherent / split.current_total;
    if left > MAX_COHERENT_LEFT {
        return Some(format!(
            "its noise-free run leaves a residual coherent with the reference \
             (deterministic) of {left:.1} times the whole residual power of the model it \
             extends: it adds a deterministic error and is credited only by the spread \
             it predicts"
        ));
    }
    let share = split.current_coherent / split.current_total;
    let removed = 1.0 - split.candidate_coherent / split.current_coherent;
    (share > COHERENT_MAJORITY && !(removed >= MIN_COHERENT_REMOVED)).then(|| {
        format!(
            "{:.0} % of the residual it is credited with is coherent with the reference \
             (deterministic), and its noise-free run removes {:.1} % of that part, less \
             than {:.0} %: it explains the residual by the spread it predicts, which cannot \
             hold a deterministic error",
            100.0 * share,
            100.0 * removed,
            100.0 * MIN_COHERENT_REMOVED
        )
    })
}

/// What one search concluded about its best candidate.
#[derive(Debug)]
pub(super) enum Verdict {
    Cause,
    /// It helps on the selection quarter but is not a cause (why).
    Partial(String),
    /// It does not help enough to count.
    NoGain,
}

/// The rules a search's best candidate must pass to be a cause, checked in
/// [`Rule::ORDER`]; the first it fails gives the [`Verdict`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Rule {
    /// It divides the current model's score on the selection quarter's missed cells by at
    /// least [`REQUIRED_GAIN`]: a candidate refits the baseline's parameters too and
    /// always gains a little; below the bar it is no explanation at all ([`Verdict::NoGain`]).
    Gain,
    /// The gain beats [`REQUIRED_GAIN`] times the factor chance moves that score by
    /// ([`Diagnoser::chance_factor`]): in a rough model (free play's impacts) any change
    /// draws other bounces, and a candidate can gain by a luckier draw (seed 13's friction
    /// asymmetry on top of the play). Measured only here, past the plain gain: two runs.
    Chance,
    /// Its parameters are physical ([`unphysical`]): a fit absorbing garbage can gain by
    /// an added mass of a hundred tables.
    Physical,
    /// It is evidence of its effect ([`crate::diagnose::evidence`]): no parameter at a
    /// bound, its strength significant; an effect at its no-effect value gains only by
    /// refitting the model it extends.
    Evidence,
    /// Its gain is not a predicted spread credited with a deterministic residual
    /// ([`spread_credited`]): the UTFSM damper's stick-slip explained a coherent error by
    /// its chatter. Measured last, only for an otherwise accepted cause: two more runs.
    Spread,
}

/// What the rules read: the candidate, its gain, and the two measurements, each taken on
/// its rule's first need (at most once: each rule appears once in [`Rule::ORDER`]).
struct Facts<'a, C, S> {
    best: &'a Candidate,
    gain: f64,
    table_mass_kg: f64,
    chance: Option<C>,
    spread: Option<S>,
}

impl Rule {
    /// The order the rules are checked in: the cheap ones first, each measurement only
    /// once the rules before it pass.
    pub(super) const ORDER: [Rule; 5] = [
        Rule::Gain,
        Rule::Chance,
        Rule::Physical,
        Rule::Evidence,
        Rule::Spread,
    ];

    /// The verdict when the candidate of `facts` fails this rule, `None` when it passes.
    fn failed<C, S>(self, facts: &mut Facts<C, S>) -> Option<Verdict>
    where
        C: FnOnce() -> f64,
        S: FnOnce() -> Option<String>,
    {
        let gain = facts.gain;
        match self {
            Rule::Gain => (!(gain >= REQUIRED_GAIN)).then_some(Verdict::NoGain),
            Rule::Chance => {
                let chance = facts.chance.take().map_or(1.0, |measure| measure());
                (!(gain >= REQUIRED_GAIN * chance)).then(|| {
                    Verdict::Partial(format!(
                        "it divides the selection score by {gain:.3}, below {REQUIRED_GAIN} \
                         times the factor {chance:.3} by which chance moves that score (the \
                         model it extends is rough: a {} % change of the table mass moves \
                         its score by that factor)",
                        100.0 * UNRESOLVED_CHANGE
                    ))
                })
            }
            Rule::Physical => unphysical(facts.best, facts.table_mass_kg).map(Verdict::Partial),
            Rule::Evidence => facts.best.not_evidence.clone().map(Verdict::Partial),
            Rule::Spread => facts
                .spread
                .take()
                .and_then(|measure| measure())
                .map(Verdict::Partial),
        }
    }
}

/// The verdict on `best` against the model it extends, scored `current_score` on the
/// selection quarter's missed cells: a cause when it passes every [`Rule`] in order.
/// `chance` measures what chance moves that score by ([`Rule::Chance`]); `spread` says why
/// the gain is a spread credited with a deterministic residual, if it is ([`Rule::Spread`]).
/// Each is called only when its rule is reached.
pub(super) fn verdict(
    best: &Candidate,
    current_score: f64,
    chance: impl FnOnce() -> f64,
    spread: impl FnOnce() -> Option<String>,
    table_mass_kg: f64,
) -> Verdict {
    let mut facts = Facts {
        best,
        gain: current_score / best.score,
        table_mass_kg,
        chance: Some(chance),
        spread: Some(spread),
    };
    Rule::ORDER
        .into_iter()
        .find_map(|rule| rule.failed(&mut facts))
        .unwrap_or(Verdict::Cause)
}

impl Diagnoser<'_> {
    /// The factor by which chance alone moves `current`'s selection score on the cells
    /// `missed`: the score's largest ratio under a change of the table mass by
    /// [`UNRESOLVED_CHANGE`] either way; about 1 for a smooth model. In a rough one (free
    /// play's impacts) every parameter change draws another realisation of the bounces,
    /// and a candidate can gain by drawing a luckier one (seed 13: a friction asymmetry
    /// of 0.96 on top of the play passed the selection quarter's 1.25 and gained 1.20 on
    /// the report quarter).
    pub(super) fn chance_factor(&self, current: &Current, missed: &Missed) -> f64 {
        let score = missed.rms(&current.select.score);
        [1.0 - UNRESOLVED_CHANGE, 1.0 + UNRESOLVED_CHANGE]
            .into_par_iter()
            .map(|factor| {
                let mut p = current.params;
                p.table.mass_kg *= factor;
                let (select, _) =
                    heldout_scores(&p, self.c, &self.tests, &self.noise, Some(&current.hold()));
                let moved = missed.rms(&select.score);
                (moved / score).max(score / moved)
            })
            // a change that leaves the envelope where the model stayed inside (an infinite
            // score) or a score of zero says nothing of chance: not counted
            .filter(|ratio| ratio.is_finite())
            .reduce(|| 1.0, f64::max)
    }

    /// How much of the missed selection cells' residual is coherent with the reference
    /// under `current` and under `best` ([`crate::diagnose::model_error::coherent_power`]
    /// over the selection quarter, in noise-floor units); cells with no estimate (a test
    /// too short for its averages) do not count.
    fn coherence(&self, current: &Params, best: &Candidate, missed: &Missed) -> CoherentSplit {
        use crate::diagnose::model_error::coherent_power;
        use crate::diagnose::residuals::simulate_test;
        use crate::diagnose::Part;
        let mut sums = [[0.0; 2]; 2];
        for (k, &i) in self.tests.iter().enumerate() {
            if !missed.cells[k].values().any(|&m| m) {
                continue;
            }
            // each model's run of the test once, for all its missed channels
            let runs = [current, &best.params].map(|p| simulate_test(p, self.c, i, Part::Select));
            for (ch, &is_missed) in missed.cells[k].iter() {
                let Some(s) = self.noise.of(ch).filter(|_| is_missed) else {
                    continue;
                };
                let [Some(a), Some(b)] = [&runs[0], &runs[1]]
                    .map(|run| coherent_power(self.c, i, ch, Part::Select, run))
                else {
                    continue;
                };
                for (m, (coherent, total)) in [a, b].into_iter().enumerate() {
                    sums[m][0] += coherent / (s * s);
                    sums[m][1] += total / (s * s);
                }
            }
        }
        CoherentSplit {
            current_coherent: sums[0][0],
            current_total: sums[0][1],
            candidate_coherent: sums[1][0],
        }
    }

    /// Why `best` is credited with a residual its predicted spread cannot hold
    /// ([`spread_credited`] on [`Diagnoser::coherence`]), if it is.
    pub(super) fn credited_to_spread(
        &self,
        current: &Current,
        best: &Candidate,
        missed: &Missed,
        round: usize,
    ) -> Option<String> {
        let split = self.coherence(&current.params, best, missed);
        if trace_enabled() {
            eprintln!("  search {}: {} {split:?}", round + 1, best.effect.name());
        }
        spread_credited(&split)
    }
}

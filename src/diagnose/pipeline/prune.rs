//! The backward step after the searches: a cause the others make unneeded is taken out
//! again. A search names the best candidate on the model it extends, and an effect can
//! stand in for one found later (seed 12: a static friction ratio of 5.4 took the first
//! search in place of a 0.30-mm free play, whose bounces at every reversal look like a
//! static friction bump; the play was named in the second).

use super::{Current, Diagnoser, REQUIRED_GAIN};
use crate::diagnose::candidates::heldout_scores;
use crate::diagnose::missed::Missed;
use crate::diagnose::output::{Cause, Partial};
use crate::diagnose::trace_enabled;
use rayon::prelude::*;

/// The model without cause `k` and how far the model with it divides that model's
/// selection score, on the cells the model without it misses (the forward rule's test,
/// taken from the other side).
struct Without {
    k: usize,
    model: Current,
    gain: f64,
    chance: f64,
}

impl Without {
    /// How far the cause clears its bar: the gain over what chance moves the score by (the
    /// least is the one the others make most nearly unneeded).
    fn margin(&self) -> f64 {
        self.gain / self.chance
    }

    /// Whether the model with the cause passes the forward rule on top of the model
    /// without it: divides its score by [`REQUIRED_GAIN`] times what chance moves it by.
    fn needed(&self) -> bool {
        self.gain >= REQUIRED_GAIN * self.chance
    }

    /// Why the cause is not needed once the `others` are in the model.
    fn why_not_needed(&self, others: &[&str]) -> String {
        format!(
            "not needed once {} {} in the model: taking it out of the final model \
             raises the selection score by a factor {:.3} only, below \
             {REQUIRED_GAIN} times the factor {:.3} by which chance moves it",
            others.join(" and "),
            if others.len() == 1 { "is" } else { "are" },
            self.gain,
            self.chance
        )
    }
}

impl Diagnoser<'_> {
    /// While two causes or more are named: each taken out of the final model `current` in
    /// turn (the others and every refined parameter kept); the one whose removal raises
    /// the selection score least against its bar is dropped, and listed in `partial`, when
    /// the model with it would not pass the forward rule on top of the model without it
    /// (divide its score by [`REQUIRED_GAIN`] times what chance moves it by). Selection
    /// quarter only. After a drop, each remaining cause's gain is measured again on the
    /// final parameters ([`Self::regain`]; `baseline_report` is the baseline's report
    /// residual on its missed cells).
    pub(super) fn prune(
        &self,
        causes: &mut Vec<Cause>,
        partial: &mut Vec<Partial>,
        current: &mut Current,
        baseline_report: f64,
    ) {
        let mut dropped = false;
        while causes.len() >= 2 {
            // a removal whose score is not finite (a run that left the envelope or
            // diverged without the cause) is no case for dropping it
            let weakest = (0..causes.len())
                .into_par_iter()
                .map(|k| self.without(causes, k, current))
                .filter(|w| w.gain.is_finite())
                .min_by(|a, b| a.margin().total_cmp(&b.margin()));
            let Some(w) = weakest else { break };
            if trace_enabled() {
                eprintln!(
                    "  without {}: the causes divide its score by {:.3} (chance {:.4})",
                    causes[w.k].effect.name(),
                    w.gain,
                    w.chance
                );
            }
            if w.needed() {
                break;
            }
            let cause = causes.remove(w.k);
            let others: Vec<&str> = causes.iter().map(|c| c.effect.name()).collect();
            partial.push(Partial {
                effect: cause.effect,
                parameters: cause.parameters,
                selection_gain: w.gain,
                why_not_a_cause: w.why_not_needed(&others),
            });
            *current = w.model;
            dropped = true;
        }
        if dropped {
            self.regain(causes, current, baseline_report);
        }
    }

    /// `current` without cause `k`, scored, and the forward rule's figures for it.
    fn without(&self, causes: &[Cause], k: usize, current: &Current) -> Without {
        let (mut params, mut section4) = (current.params, current.section4);
        let effect = causes[k].effect.catalogue();
        effect.set_enabled(&mut params, false);
        effect.set_enabled(&mut section4, false);
        let (select, report) = heldout_scores(&params, self.c, &self.tests, &self.noise, None);
        let model = Current {
            params,
            section4,
            select,
            report,
        };
        let missed = Missed::of(&model.select.residual);
        let gain = missed.rms(&model.select.score) / missed.rms(&current.select.score);
        let chance = self.chance_factor(&model, &missed);
        Without {
            k,
            model,
            gain,
            chance,
        }
    }

    /// Each cause's report gain on the final parameters of `current`: the report residual
    /// (on the baseline's missed cells) with the causes before it over that with it too;
    /// the first cause's against the baseline's `baseline_report`, so the gains multiply
    /// out to the diagnosis' gain, as [`Diagnoser::accept`]'s do.
    fn regain(&self, causes: &mut [Cause], current: &Current, baseline_report: f64) {
        let n = causes.len();
        let report_with_first = |m: usize| {
            if m == 0 {
                return baseline_report;
            }
            if m == n {
                return self.report_missed.rms(&current.report.residual);
            }
            let mut p = current.params;
            for c in &causes[m..] {
                c.effect.catalogue().set_enabled(&mut p, false);
            }
            let (_, report) = heldout_scores(&p, self.c, &self.tests, &self.noise, None);
            self.report_missed.rms(&report.residual)
        };
        let residuals: Vec<f64> = (0..=n).into_par_iter().map(report_with_first).collect();
        for (k, cause) in causes.iter_mut().enumerate() {
            cause.gain = residuals[k] / residuals[k + 1];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::output::PartRows;
    use crate::params::Params;

    fn without(gain: f64, chance: f64) -> Without {
        let model = Current {
            params: Params::default(),
            section4: Params::default(),
            select: PartRows::default(),
            report: PartRows::default(),
        };
        Without {
            k: 0,
            model,
            gain,
            chance,
        }
    }

    /// A cause stays when taking it out raises the score past the forward rule's bar,
    /// chance included; the weakest is the one with the least margin over chance.
    #[test]
    fn a_cause_is_needed_past_the_forward_rule() {
        assert!(without(REQUIRED_GAIN, 1.0).needed());
        assert!(!without(REQUIRED_GAIN * 0.99, 1.0).needed());
        assert!(!without(1.3 * REQUIRED_GAIN * 0.99, 1.3).needed());
        assert!(without(2.0, 1.5).margin() < without(1.5, 1.0).margin());
    }

    /// The reason names the causes that make it unneeded, with the verb they agree with.
    #[test]
    fn the_reason_names_the_other_causes() {
        let w = without(1.1, 1.02);
        let one = w.why_not_needed(&["specimen"]);
        assert!(
            one.starts_with("not needed once specimen is in the model"),
            "{one}"
        );
        assert!(one.contains("by a factor 1.100 only"), "{one}");
        let two = w.why_not_needed(&["specimen", "free_play"]);
        assert!(
            two.starts_with("not needed once specimen and free_play are"),
            "{two}"
        );
    }
}

//! The diagnosis from an identified baseline (steps 1-5 of the module doc), as a
//! [`Diagnoser`] holding what every step shares: the campaign, its noise, the whitening
//! of the fitting halves and the tests on each side of the split.

use super::baseline::{refine_output_error, BASELINE_ITERATIONS};
use super::candidates::{fit_candidate, heldout_scores, scored_candidate, POLISH_ROUNDS};
use super::effect::{Effect, EFFECTS};
use super::output::{Candidate, Diagnosis};
use super::part::Part;
use super::residuals::{estimate_noise, ratios, simulate_test, NoiseFloor, Whitening};
use super::{trace_enabled, unphysical, Progress, EXPLAINED_RATIO, MISS_RATIO, REQUIRED_GAIN};
use crate::campaign::{Campaign, Record};
use crate::identify::lsq::LsqOptions;
use crate::identify::spool::refine_servovalve;
use crate::identify::Identification;
use crate::params::{ActuatorModel, Params};
use rayon::prelude::*;

/// Steps of the progress bar: identification, refinement, the five candidates, the
/// best candidate's polish, done.
const PROGRESS_STEPS: usize = 9;

/// Output-error iterations of one polish of the best candidate.
const POLISH_ITERATIONS: usize = 6;

/// A further polish round is taken only when the previous one cut the score by at least
/// this factor's complement (5 %): the rounds exist for heavily saturated tables (seed
/// 404), whose baseline is bent by tens of percent, not to chase the last digits.
const POLISH_MIN_IMPROVEMENT: f64 = 0.95;

/// The least-squares settings of the candidates' fits: 12 iterations bring an effect's
/// parameters from an informed start to its valley; the tolerances are relative.
const CANDIDATE_LSQ: LsqOptions = LsqOptions {
    max_iterations: 12,
    tolerance: 1e-4,
    step: 1e-4,
    parallel: false,
};

/// The held-out cells the baseline misses ([`MISS_RATIO`]); candidates are scored on
/// them, so an effect that lives in a few tests is not diluted by the many it does not
/// touch.
struct Missed {
    cells: Vec<[bool; 5]>,
    any: bool,
}

impl Missed {
    fn of(baseline_heldout_rows: &[[f64; 5]]) -> Missed {
        let cells: Vec<[bool; 5]> = baseline_heldout_rows
            .iter()
            .map(|r| r.map(|x| !x.is_nan() && x > MISS_RATIO))
            .collect();
        let any = cells.iter().flatten().any(|&m| m);
        Missed { cells, any }
    }

    /// RMS over the missed cells (over every cell when none is missed).
    fn rms(&self, rows: &[[f64; 5]]) -> f64 {
        let v: Vec<f64> = rows
            .iter()
            .zip(&self.cells)
            .flat_map(|(r, m)| {
                r.iter()
                    .zip(m)
                    .filter(|(_, &m)| m || !self.any)
                    .map(|(x, _)| *x)
            })
            // NaN: the channel is absent; a diverged run's cells are infinite and count
            .filter(|x| !x.is_nan())
            .collect();
        (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
    }
}

/// A candidate explains the data when its held-out residual is within [`EXPLAINED_RATIO`].
fn explains(c: &Candidate) -> bool {
    c.heldout_residual <= EXPLAINED_RATIO
}

/// What every step of one diagnosis shares.
struct Diagnoser<'a> {
    c: &'a Campaign,
    noise: NoiseFloor,
    whitening: Whitening,
    /// Every test: fitted on its first half, scored on its second.
    fit_idx: Vec<usize>,
    heldout_idx: Vec<usize>,
    progress: Option<Progress<'a>>,
}

impl Diagnoser<'_> {
    fn tick(&self, i: usize, what: &str) {
        if let Some(p) = self.progress {
            p(i, PROGRESS_STEPS, what);
        }
    }

    /// The baseline `p0` refined by output error on the fitting halves; its cost.
    fn refine(&self, p0: &Params) -> (f64, Params) {
        let refined = refine_output_error(
            self.c,
            p0,
            None,
            &self.fit_idx,
            &self.whitening,
            BASELINE_ITERATIONS,
        );
        match refined {
            Some((cost, p, n)) => {
                if trace_enabled() {
                    eprintln!(
                        "  refinement ({:?}): {n} iterations, cost {cost:.4}",
                        p0.actuator.model
                    );
                }
                (cost, p)
            }
            None => (f64::INFINITY, *p0),
        }
    }

    /// Step 1: the baseline refined with both actuator variants; the better fit is the
    /// baseline's structure. Returns it and the two costs (ideal, nonlinear).
    fn refine_both_variants(&self, base: Params) -> (Params, [f64; 2]) {
        let variant = |model: ActuatorModel| {
            let mut p = base;
            p.actuator.model = model;
            p
        };
        let (ideal, nonlinear) = rayon::join(
            || self.refine(&variant(ActuatorModel::Ideal)),
            || self.refine(&variant(ActuatorModel::Nonlinear)),
        );
        let costs = [ideal.0, nonlinear.0];
        let best = if nonlinear.0 < ideal.0 {
            nonlinear.1
        } else {
            ideal.1
        };
        (best, costs)
    }

    /// Step 2: the baseline's residuals over every test, in noise units (the heat map).
    fn baseline_rows(&self, base: &Params) -> Vec<(String, [f64; 5])> {
        let c = self.c;
        (0..c.records.len())
            .into_par_iter()
            .map(|i| {
                (
                    c.info.tests[i].name.clone(),
                    ratios(
                        &c.records[i],
                        &simulate_test(base, c, i, Part::Whole),
                        &self.noise,
                        Part::Whole,
                    ),
                )
            })
            .collect()
    }

    /// Step 3: every catalogue effect fitted from both bases, summarised on the missed
    /// cells.
    fn fit_candidates(&self, bases: [Params; 2], missed: &Missed) -> Vec<Candidate> {
        let done = std::sync::atomic::AtomicUsize::new(2);
        let mut candidates: Vec<Candidate> = EFFECTS
            .par_iter()
            .filter_map(|&e| {
                let cand = fit_candidate(
                    e,
                    self.c,
                    &bases,
                    &self.fit_idx,
                    &self.heldout_idx,
                    &self.noise,
                    CANDIDATE_LSQ,
                    &self.whitening,
                );
                let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                self.tick(n + 1, e.name());
                cand
            })
            .collect();
        for cand in &mut candidates {
            cand.summarise(&|rows| missed.rms(rows));
        }
        candidates
    }

    /// `from` refined like the baseline (every fitting test, the friction shape and valve
    /// dynamics free too) with the actuator variant `model`, scored.
    fn polish(&self, from: &Candidate, model: ActuatorModel, missed: &Missed) -> Option<Candidate> {
        let theta: Vec<f64> = from
            .effect
            .parameters()
            .iter()
            .map(|n| from.parameters[*n])
            .collect();
        let mut p0 = from.params;
        p0.actuator.model = model;
        let effect: (Effect, &[f64]) = (from.effect, &theta);
        let (cost, p, _) = refine_output_error(
            self.c,
            &p0,
            Some(effect),
            &self.fit_idx,
            &self.whitening,
            POLISH_ITERATIONS,
        )?;
        let theta = from.effect.read(&p);
        let mut polished = scored_candidate(
            from.effect,
            self.c,
            &theta,
            cost.sqrt(),
            p,
            &self.heldout_idx,
            &self.noise,
        );
        polished.summarise(&|rows| missed.rms(rows));
        Some(polished)
    }

    /// Step 4: the best candidate polished: its own fit only freed what interacts with
    /// the effect, and the rest may still hold the baseline's bends. The baseline's
    /// variant first; while that leaves the data unexplained the other variant too (a
    /// missing effect can tip the baseline's choice: a deadband on the ideal actuator
    /// fits better as a nonlinear one), then further rounds while unexplained and
    /// improving (a heavily saturated table bends the baseline by tens of percent).
    fn polish_best(&self, cand: &Candidate, missed: &Missed) -> Candidate {
        let better = |a: Option<Candidate>, b: &Candidate| a.filter(|a| a.score < b.score);
        let own = cand.params.actuator.model;
        let mut best = better(self.polish(cand, own, missed), cand).unwrap_or_else(|| cand.clone());
        if !explains(&best) {
            if let Some(other) = ActuatorModel::ALL.into_iter().find(|&m| m != own) {
                if let Some(p) = better(self.polish(cand, other, missed), &best) {
                    best = p;
                }
            }
        }
        for _ in 1..POLISH_ROUNDS {
            if explains(&best) {
                break;
            }
            match better(
                self.polish(&best, best.params.actuator.model, missed),
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
        best
    }
}

/// Diagnose the screened campaign `c` from its baseline identification `id`.
pub(super) fn diagnose_with(
    c: &Campaign,
    id: Identification,
    progress: Option<Progress>,
) -> Diagnosis {
    if let Some(p) = progress {
        p(0, PROGRESS_STEPS, "identifying the baseline");
    }
    let noise = estimate_noise(c);
    let mut base = id.params;
    // the valve by output error on the spool channel (fitting halves)
    let rated: Vec<(&Record, f64)> = (0..c.records.len())
        .map(|i| (&c.records[i], c.sample_rate_of(i)))
        .collect();
    if let Some(v) = refine_servovalve(&base.servovalve, &rated, |n| Part::Fit.range(n)) {
        base.servovalve = v;
    }
    let spool_valve = base.servovalve;
    let fit_idx: Vec<usize> = (0..c.info.tests.len()).collect();
    let whitening = Whitening::new(&base, c, &fit_idx, &noise, Part::Fit);
    let d = Diagnoser {
        c,
        noise,
        whitening,
        heldout_idx: fit_idx.clone(),
        fit_idx,
        progress,
    };
    d.tick(1, "refining the baseline by output error");
    let (base, actuator_costs) = d.refine_both_variants(base);
    let baseline_rows = d.baseline_rows(&base);
    let (baseline_score_rows, baseline_heldout_rows) =
        heldout_scores(&base, c, &d.heldout_idx, &d.noise, false);
    let missed = Missed::of(&baseline_heldout_rows);
    let baseline_heldout = missed.rms(&baseline_heldout_rows);
    let baseline_score = missed.rms(&baseline_score_rows);
    // candidates start from the section-4 estimates too (the output-error baseline has
    // bent its parameters to absorb the missing effect) with the chosen actuator and the
    // valve fitted on the spool (the refinement may have bent its dynamics too)
    let mut candidate_base = id.params;
    candidate_base.actuator.model = base.actuator.model;
    candidate_base.servovalve = spool_valve;
    let mut candidates = d.fit_candidates([base, candidate_base], &missed);
    let best_index =
        (0..candidates.len()).min_by(|&a, &b| candidates[a].score.total_cmp(&candidates[b].score));
    if let Some(k) = best_index.filter(|_| missed.any) {
        d.tick(8, "refining the best candidate");
        candidates[k] = d.polish_best(&candidates[k], &missed);
    }
    // step 5: the cause, when it divides the baseline's score by REQUIRED_GAIN and is
    // physical
    let best = candidates
        .iter()
        .min_by(|a, b| a.score.total_cmp(&b.score))
        .cloned();
    let rejected = best
        .as_ref()
        .and_then(|b| unphysical(b, base.table.mass_kg));
    let (cause, extended, ext_resid) = match &best {
        Some(b)
            if missed.any && baseline_score / b.score >= REQUIRED_GAIN && rejected.is_none() =>
        {
            (Some(b.effect), b.params, b.heldout_residual)
        }
        _ => (None, base, baseline_heldout),
    };
    let names = |idx: &[usize]| idx.iter().map(|&i| c.info.tests[i].name.clone()).collect();
    Diagnosis {
        baseline: base,
        baseline_rows,
        baseline_heldout,
        baseline_heldout_rows,
        baseline_score,
        candidates,
        cause,
        cause_rejected: rejected,
        explained: ext_resid <= EXPLAINED_RATIO,
        gain: baseline_heldout / ext_resid,
        extended,
        fit_tests: names(&d.fit_idx),
        heldout_tests: names(&d.heldout_idx),
        valve_model: id.params.servovalve.model,
        actuator_model: base.actuator.model,
        actuator_costs,
        noise: d.noise,
        identification: id,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAN: f64 = f64::NAN;

    #[test]
    fn a_missed_cell_is_one_above_the_miss_ratio_and_absent_cells_never_are() {
        let rows = [
            [1.0, MISS_RATIO, MISS_RATIO * 1.01, NAN, 0.5],
            [0.2, 0.3, NAN, NAN, 1.4],
        ];
        let m = Missed::of(&rows);
        assert!(m.any);
        assert_eq!(m.cells[0], [false, false, true, false, false]);
        assert_eq!(m.cells[1], [false; 5]);
        // candidates are scored on that cell alone
        let trial = [[9.0, 9.0, 3.0, NAN, 9.0], [9.0, 9.0, NAN, NAN, 9.0]];
        assert_eq!(m.rms(&trial), 3.0);
    }

    #[test]
    fn with_nothing_missed_every_present_cell_counts_and_a_divergence_is_not_hidden() {
        let rows = [[1.0, 1.2, NAN, 0.9, 1.1]];
        let m = Missed::of(&rows);
        assert!(!m.any);
        let trial = [[2.0, 2.0, NAN, 2.0, 2.0]];
        assert_eq!(m.rms(&trial), 2.0);
        // a diverged run scores infinite cells: they count, they do not vanish like NaN
        let diverged = [[2.0, f64::INFINITY, NAN, 2.0, 2.0]];
        assert_eq!(m.rms(&diverged), f64::INFINITY);
    }

    #[test]
    fn a_candidate_explains_the_data_up_to_the_explained_ratio() {
        let mut c = Candidate {
            effect: Effect::Specimen,
            parameters: Default::default(),
            heldout_residual: EXPLAINED_RATIO,
            score: 1.0,
            fit_residual: 1.0,
            params: Params::default(),
            heldout_rows: Vec::new(),
            score_rows: Vec::new(),
        };
        assert!(explains(&c));
        c.heldout_residual = EXPLAINED_RATIO * 1.001;
        assert!(!explains(&c));
    }
}

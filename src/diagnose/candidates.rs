//! Fitting one candidate effect: starts, output-error least squares with the baseline's
//! refined parameters free, and its held-out scores.

use super::baseline::{
    candidate_range, copy_baseline, from_motion, refined_for, residual_vector, spool_recorded,
    valve_dynamics, BaselineParameter, Range,
};
use super::effect::Effect;
use super::effort::Effort;
use super::evidence::not_evidence;
use super::free_play_fit::fit_free_play;
use super::output::{Candidate, PartRows};
use super::part::Part;
use super::residuals::{CellScores, Cells, NoiseFloor, Whitening};
use super::starts::{informed_start, keep_each_frequency, starts};
use super::stick_slip::fit_stick_slip;
use super::{residuals, trace_enabled};
use crate::campaign::Campaign;
use crate::identify::lsq::minimise;
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

/// Smallest share of the identified table mass a specimen's start leaves to the table
/// when it takes its own mass out: the identified mass holds the specimen's, but a start
/// mass far above the table's would leave a table lighter than any that carries one (a
/// specimen is at most a few times the table's mass; the fit moves on from there).
const MIN_TABLE_MASS_SHARE: f64 = 0.3;

/// A foundation's start stiffens the oil column only when its spring is this many times
/// stiffer than the identified (series) column: closer, `k_f / (k_f - k_id)` grows without
/// bound, and the identified column then is mostly the foundation's, not the oil's.
const FOUNDATION_SERIES_MARGIN: f64 = 1.5;

/// A start of a candidate's fit: the effect's and the free baseline parameters, and the
/// parameters the other baseline parameters are taken from.
pub(super) type Start = (Vec<f64>, Params);

/// The baseline parameters a candidate's fit frees with the effect:
/// [`super::baseline::refined_for`] (the table's parameters, without the mass where it is
/// only a scale, with the gains nobody gave), and the valve's dynamics when no test
/// recorded the spool. Then the valve comes from the
/// closed-loop fit of the table's motion, which bent it to absorb the missing effect (a
/// 20-t specimen fitted on the bent valve scored worse than the baseline it extends).
fn candidate_free(c: &Campaign, base: &Params) -> Vec<BaselineParameter> {
    let valve: &[BaselineParameter] = if spool_recorded(c) {
        &[]
    } else {
        valve_dynamics(base)
    };
    refined_for(c).iter().chain(valve).copied().collect()
}

#[allow(clippy::too_many_arguments)]
pub(super) fn fit_candidate(
    e: Effect,
    c: &Campaign,
    bases: &[Params],
    fit_idx: &[usize],
    heldout_idx: &[usize],
    noise: &NoiseFloor,
    effort: Effort,
    whitening: &Whitening,
    hold: &Hold,
) -> Option<Candidate> {
    let opts = effort.candidate_lsq();
    let sig: Vec<usize> = e
        .signature_tests(c, &bases[0])
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
    if sig.is_empty() {
        return None;
    }
    let t0 = std::time::Instant::now();
    let trace = |what: &str| {
        if trace_enabled() {
            eprintln!(
                "  {} {what} after {:.1} s",
                e.name(),
                t0.elapsed().as_secs_f64()
            );
        }
    };
    // the effects fitted on the predictive score ([`Effect::fitted_on_score`])
    let on_score = match e {
        Effect::StickSlip => Some(fit_stick_slip(
            c, &bases[0], &sig, noise, fit_idx, whitening,
        )?),
        Effect::FreePlay => {
            // without a gap read off the reversals there is no play to fit: its impacts
            // are chaotic, and a fit from a guess lands wherever the bounces misfit least
            let Some(start) = informed_start(e, c, &bases[1]) else {
                trace("no gap read off the reversals: not fitted");
                return None;
            };
            Some(fit_free_play(
                c,
                bases,
                &sig,
                noise,
                &start,
                (fit_idx, whitening),
            )?)
        }
        _ => None,
    };
    if let Some((score, theta, p)) = on_score {
        trace(&format!("fitted: score {score:.1}, {theta:?}"));
        return Some(scored_candidate(
            e,
            c,
            Fitted {
                theta: &theta,
                sigma: &[],
                bounds: &e.bounds(&bases[0]),
                fit_residual: score.sqrt(),
                params: p,
            },
            heldout_idx,
            noise,
            hold,
        ));
    }
    let ne = e.parameters().len();
    let free = candidate_free(c, &bases[0]);
    let (elo, ehi) = e.bounds(&bases[0]);
    let ranges: Vec<Range> = free.iter().map(|&w| candidate_range(bases, w)).collect();
    let base = &bases[0];
    // the effect's parameters, then the free baseline ones; the other baseline
    // parameters from `fixed`
    let assemble = |t: &[f64], fixed: &Params| {
        let mut p = *base;
        e.apply(&mut p, &t[..ne]);
        copy_baseline(fixed, &mut p);
        for (k, which) in free.iter().enumerate() {
            which.set(&mut p, t[ne + k]);
        }
        p
    };
    let lo: Vec<f64> = elo
        .iter()
        .copied()
        .chain(ranges.iter().map(|r| r.lower))
        .collect();
    let hi: Vec<f64> = ehi
        .iter()
        .copied()
        .chain(ranges.iter().map(|r| r.upper))
        .collect();
    // a start of the effect on a baseline: (effect and free baseline parameters, the rest)
    let start_on = |b: &Params, s: &[f64]| -> Start {
        let mut fixed = *b;
        // the valve as fitted on the spool, whichever base the start comes from (the
        // friction's yield and shape stay the base's own: the refined ones may have
        // bent to absorb the effect, the section-4 ones have not)
        for which in BaselineParameter::VALVE {
            which.set(&mut fixed, which.get(&bases[1]));
        }
        if let Some(n) = e.specimen_modes() {
            // the identified mass holds the specimen's (newest mode's) mass at low frequency
            let m = fixed.table.mass_kg;
            fixed.table.mass_kg = (m - s[3 * (n - 1)]).max(MIN_TABLE_MASS_SHARE * m);
        }
        if e == Effect::Foundation {
            // the identified oil column is the oil and the foundation springs in
            // series: 1/k_id = 1/k_oil + 1/k_f, so the oil alone is stiffer
            let k_id = b.actuator.oil_column_stiffness_n_m();
            let k_f = s[0] * (2.0 * std::f64::consts::PI * s[1]).powi(2);
            if k_f > FOUNDATION_SERIES_MARGIN * k_id {
                fixed.actuator.bulk_modulus_pa *= k_f / (k_f - k_id);
            }
        }
        let t0: Vec<f64> = s
            .iter()
            .copied()
            .chain(free.iter().map(|w| w.get(&fixed)))
            .collect();
        (t0, fixed)
    };
    // the start read off the data (its frequency also seeds the screened spread)
    let informed = informed_start(e, c, &bases[1]);
    // every start of the effect on every baseline, screened by one evaluation each
    let mut all: Vec<Start> = Vec::new();
    for b in bases {
        for s in starts(e, c, b, informed.as_deref()) {
            all.push(start_on(b, &s));
        }
    }
    if all.len() > effort.screened_starts() {
        let cost_of = |(t, b): &Start| {
            residual_vector(&assemble(t, b), c, &sig, whitening)
                .map(|r| r.iter().map(|x| x * x).sum::<f64>())
                .unwrap_or(f64::INFINITY)
        };
        let mut scored: Vec<(f64, Start)> = all.into_iter().map(|s| (cost_of(&s), s)).collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        trace(&format!(
            "screened starts: {:?}",
            scored
                .iter()
                .map(|s| (s.0, &s.1 .0[..ne]))
                .collect::<Vec<_>>()
        ));
        all = match e.valley_frequency() {
            // a resonance: the best start at each of its frequencies too
            Some(k) => keep_each_frequency(scored, effort.screened_starts(), |s| s.0[k]),
            None => scored
                .into_iter()
                .take(effort.screened_starts())
                .map(|x| x.1)
                .collect(),
        };
    }
    // a start read off the data itself is fitted whatever its screening: a lightly damped
    // foundation mode a few percent off misfits more than none until the baseline has
    // unbent (the section-4 one, which bent least)
    if let Some(s) = informed {
        trace(&format!("start from the data: {s:?}"));
        all.push(start_on(&bases[1], &s));
    }
    let mut best: Option<(f64, Vec<f64>, Vec<f64>, Params)> = None;
    for (t0, fixed) in all {
        let scale: Vec<f64> = t0[..ne]
            .iter()
            .map(|x| x.abs().max(1e-4))
            .chain(ranges.iter().map(|r| r.scale))
            .collect();
        // stage 1: the free baseline parameters with the effect held at its start (the
        // baseline has bent to absorb the effect; unbent, the joint fit starts downhill)
        let t0 = {
            let eff = t0[..ne].to_vec();
            let aligned = minimise(
                |tb| {
                    let t: Vec<f64> = eff.iter().chain(tb).copied().collect();
                    residual_vector(&assemble(&t, &fixed), c, &sig, whitening)
                },
                &t0[ne..],
                &lo[ne..],
                &hi[ne..],
                &scale[ne..],
                opts,
            );
            match aligned {
                Some(f) => {
                    trace(&format!("stage 1: {} iterations", f.iterations));
                    eff.into_iter().chain(f.theta).collect()
                }
                None => {
                    trace("stage 1 failed");
                    t0
                }
            }
        };
        // stage 2: everything together
        if let Some(f) = minimise(
            |t| residual_vector(&assemble(t, &fixed), c, &sig, whitening),
            &t0,
            &lo,
            &hi,
            &scale,
            opts,
        ) {
            trace(&format!(
                "stage 2: {} iterations, cost {:.4}",
                f.iterations, f.cost
            ));
            if best.as_ref().map(|b| f.cost < b.0).unwrap_or(true) {
                best = Some((f.cost, f.theta, f.sigma, fixed));
            }
        }
    }
    let (cost, theta, sigma, fixed) = best?;
    let p = assemble(&theta, &fixed);
    Some(scored_candidate(
        e,
        c,
        Fitted {
            theta: &theta[..ne],
            sigma: &sigma[..ne],
            bounds: &(elo.clone(), ehi.clone()),
            fit_residual: cost.sqrt(),
            params: p,
        },
        heldout_idx,
        noise,
        hold,
    ))
}

impl Candidate {
    /// Its selection residual, deviation and score over the cells `select_mask` keeps (the
    /// cells the model it extends misses), the score with a penalty of 1 % per parameter,
    /// and its report residual over the cells `report_mask` keeps (the baseline's missed
    /// ones).
    pub(super) fn summarise(
        &mut self,
        select_mask: &dyn Fn(&[Cells]) -> f64,
        report_mask: &dyn Fn(&[Cells]) -> f64,
    ) {
        self.select_residual = select_mask(&self.select.residual);
        self.select_deviation = select_mask(&self.select.deviation);
        self.score = select_mask(&self.select.score) * (1.0 + 0.01 * self.parameters.len() as f64);
        self.report_residual = report_mask(&self.report.residual);
    }
}

/// What a fit gives a candidate: the effect's parameters and their one-sigma
/// uncertainties (empty when the fit gives none), the fit's RMS residual, the model.
pub(super) struct Fitted<'a> {
    pub theta: &'a [f64],
    pub sigma: &'a [f64],
    /// The fitting range it was fitted in: lower and upper bounds, one per parameter.
    pub bounds: &'a (Vec<f64>, Vec<f64>),
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
    let parameters = e.keyed(fitted.theta);
    let sigma = e.sigma_map(fitted.sigma);
    let (lower, upper) = fitted.bounds;
    let why = not_evidence(e, &parameters, &sigma, lower, upper);
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

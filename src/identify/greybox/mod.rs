//! Grey-box identification of the closed loop by output error (issue 16, part 3), as
//! MATLAB's `nlgreyest` does: the measured reference drives the project's own model
//! (spec sections 2-5, the same simulator as everywhere), and the parameters nobody
//! wrote down and no section-4 estimator could give are fitted so that the simulated
//! displacement, acceleration and (where recorded) force follow the measured ones.
//!
//! - What is freed and what is held by convention: [`structure`].
//! - Starts read off the measured response: [`start`]; several oil-column starts when no
//!   resonance shows, each refined on the first seconds of the tests ([`EXCERPT_S`]
//!   each, less when there are many), the best
//!   refined on everything.
//! - Estimation and validation tests: [`split`]; the figures of a test the fit did not
//!   see are predictions ([`compare`]).
//! - The uncertainty: the Levenberg-Marquardt covariance, widened for the residuals'
//!   correlation; the combinations the motion determines and the pairs it cannot
//!   separate: [`combinations`].

mod combinations;
pub mod compare;
mod parameters;
mod split;
mod start;
mod structure;

pub use combinations::{Combination, INSEPARABLE_CORRELATION};
pub use compare::{ChannelFit, Comparison, Role, Trace};
pub use parameters::{GreyParameter, FEED_FORWARD_RATIO_BOUND};
pub use structure::{mass_separable, Convention, Known};

use super::error::IdentifyError;
use super::lsq::{minimise, LsqFit, LsqOptions};
use super::signals::{correlation_factor, MAX_CORRELATION_LAG};
use crate::campaign::{Campaign, Measured};
use crate::params::Params;
use crate::solver::Checks;
use compare::{simulate_prefix, simulate_prefix_pair, simulated, COMPARED};
use parameters::with_search;
use rayon::prelude::*;
use serde::Serialize;
use structure::Structure;

/// Seconds of each estimation test the starts are compared on: several loop time
/// constants and many cycles of any oil column, at a fraction of the full fit's cost.
pub const EXCERPT_S: f64 = 20.0;
/// Seconds of all estimation tests together the starts are compared on, shared among
/// them down to [`MIN_EXCERPT_S`] each: the starts are refined on several tests' first
/// seconds, which cost as much as a full fit's iterations once a campaign has more than
/// two (the starts were over half of `identify` on the four UTFSM estimation tests).
const EXCERPT_TOTAL_S: f64 = 40.0;
/// Fewest seconds of a test in the excerpt: still over a hundred time constants of a
/// loop at 16 1/s and hundreds of cycles of an oil column.
const MIN_EXCERPT_S: f64 = 10.0;
/// Iterations of each start's refinement on the excerpt.
const START_ITERATIONS: usize = 12;
/// Iterations of the final fit.
const FINAL_ITERATIONS: usize = 40;
/// At most this many residual samples per test and channel: the residual is decimated
/// (the simulation is not) so that the Jacobian of a week of recordings fits in memory;
/// 50 000 samples still resolve every dynamic below the Nyquist frequency of 1 kHz data
/// over 50 s, and longer records are sampled evenly.
const MAX_RESIDUALS_PER_CHANNEL: usize = 50_000;
/// Relative cost decrease of a step below which the fit stops. 1e-5 of the cost moves
/// every NRMSE by 5e-6 of itself (a fit % by under 0.001 points), and is seventy times
/// below the smallest drop the valve order's information criterion counts (ln N / N,
/// 7e-4 at 14 000 effective samples); the steps a tighter stop bought were a fifth of the
/// full fits' iterations on the 388-s UTFSM campaign (25 to 20, 12 to 6) for 2e-5 of
/// its cost.
const TOLERANCE: f64 = 1e-5;

/// A freed parameter's estimate.
#[derive(Debug, Clone, Serialize)]
pub struct FreeEstimate {
    /// The parameter estimated (the JSON names it by its key).
    #[serde(skip)]
    pub parameter: GreyParameter,
    pub key: &'static str,
    pub value: f64,
    /// One sigma, widened for the residuals' correlation; `None` when the covariance is
    /// singular (the parameter is not determined).
    pub sigma: Option<f64>,
    /// The estimate sits on a bound of its search range: not an estimate of the table.
    pub at_bound: bool,
}

/// The closed-loop fit.
#[derive(Debug, Clone, Serialize)]
pub struct ClosedLoopFit {
    pub estimation_tests: Vec<String>,
    pub validation_tests: Vec<String>,
    pub channels: Vec<&'static str>,
    pub estimates: Vec<FreeEstimate>,
    pub conventions: Vec<Convention>,
    pub combinations: Vec<Combination>,
    pub inseparable: Vec<String>,
    /// Per test and channel, the fitted model against the measurement.
    pub fits: Vec<ChannelFit>,
    /// Tests whose simulation stopped (the envelope), with why.
    pub stopped: Vec<String>,
    /// The first seconds of each test and channel, for the report.
    #[serde(skip)]
    pub traces: Vec<Trace>,
    pub starts_tried: usize,
    pub iterations: usize,
    /// Factor by which the residuals' correlation widened the covariance.
    pub correlation_factor: f64,
    /// The valve's order, when the fit chose it (no spool recorded).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub valve_order: Option<ValveOrder>,
    #[serde(skip)]
    pub params: Params,
}

/// One measured channel of one estimation test, prepared for the residual.
struct Target {
    test: usize,
    channel: Measured,
    /// Mean-removed measured samples at the kept indices.
    measured: Vec<f64>,
    stride: usize,
    /// Samples simulated (the whole test or its excerpt).
    samples: usize,
    weight: f64,
}

/// Fit the closed loop of `c` on its usable `tests` (those with a reference and the
/// displacement or acceleration), from `p` (the campaign's keys and the section-4
/// estimates applied) with what `known` says is already identified; a free valve's order
/// is the data's ([`ValveOrder`]).
pub fn fit_closed_loop(
    c: &Campaign,
    tests: &[usize],
    p: &Params,
    known: Known,
) -> Result<ClosedLoopFit, IdentifyError> {
    let (estimation, validation) = split::split(c, tests);
    if estimation.is_empty() {
        return Err(IdentifyError::not_usable(
            "closed loop not identified: no test recorded a reference and the displacement or the acceleration",
        ));
    }
    let mut p0 = *p;
    let s = structure::choose(&mut p0, c, &estimation, known);
    if s.free.is_empty() {
        return Err(IdentifyError::not_usable(
            "closed loop: every parameter is known or identified, nothing to fit",
        ));
    }
    let share = (EXCERPT_TOTAL_S / estimation.len() as f64).clamp(MIN_EXCERPT_S, EXCERPT_S);
    let excerpt = targets(c, &estimation, &s, Some(share));
    let starts = starting_points(&p0, c, &estimation, &s);
    let mut best: Option<(Params, f64)> = None;
    for q in &starts {
        if let Some(f) = run_lsq(q, c, &excerpt, &s.free, START_ITERATIONS) {
            let fitted = with_search(q, &s.free, &f.theta);
            if best.as_ref().is_none_or(|(_, cost)| f.cost < *cost) {
                best = Some((fitted, f.cost));
            }
        }
    }
    let (q, _) = best.ok_or_else(|| {
        IdentifyError::not_usable(format!(
            "closed loop not identified: no start ({}) could be simulated; the first: {}",
            starts.len(),
            why_not(&starts[0], c, &estimation)
        ))
    })?;
    let full = targets(c, &estimation, &s, None);
    let fit = run_lsq(&q, c, &full, &s.free, FINAL_ITERATIONS).ok_or_else(|| {
        IdentifyError::not_usable(
            "closed loop not identified: the fit's simulation left the operating envelope",
        )
    })?;
    let (s, q, fit, valve_order) = valve_order(c, &full, s, q, fit);
    let mut out = finish(c, &s, &q, &fit, &full, estimation, validation, starts.len());
    out.valve_order = valve_order;
    Ok(out)
}

/// Which valve order the data chose when the valve is free: the first-order fit, then
/// the second-order one started from it, kept when the Bayesian information criterion
/// prefers it on the effective number of residual samples (the samples over their
/// correlation length, as the covariance's widening counts them). The cost is summed
/// over channels the noise dominates as well (a slow sine's acceleration), so a plain
/// share of it would drown a several-fold better fit of the loop's channels; the
/// criterion asks only that the drop exceed what one more parameter wins from noise.
#[derive(Debug, Clone, Serialize)]
pub struct ValveOrder {
    pub chosen: &'static str,
    pub first_order_cost: f64,
    /// `None` when the second-order fit could not be simulated.
    pub second_order_cost: Option<f64>,
    /// Residual samples over their correlation length.
    pub effective_samples: f64,
    pub rule: &'static str,
}

/// The fit with the valve order the data choose (see [`ValveOrder`]); unchanged, with
/// no choice reported, when the valve is not free.
fn valve_order(
    c: &Campaign,
    full: &[Target],
    s: Structure,
    q: Params,
    fit: LsqFit,
) -> (Structure, Params, LsqFit, Option<ValveOrder>) {
    let fitted = with_search(&q, &s.free, &fit.theta);
    let mut q2 = fitted;
    let Some(s2) = s.with_second_order_valve(&mut q2) else {
        return (s, q, fit, None);
    };
    let fit2 = run_lsq(&q2, c, full, &s2.free, FINAL_ITERATIONS);
    let r = residuals(&fitted, c, full).unwrap_or_default();
    let n = r.len() as f64 / correlation_factor(&r, MAX_CORRELATION_LAG);
    let mut order = ValveOrder {
        chosen: "first_order",
        first_order_cost: fit.cost,
        second_order_cost: fit2.as_ref().map(|f| f.cost),
        effective_samples: n,
        rule: "the second-order valve (natural frequency and damping free, one parameter more) is kept when the information criterion prefers it, N ln(cost_1 / cost_2) > ln N (N the effective residual samples: samples over their correlation length; cost the sum of squared NRMSEs over the estimation tests), and neither its frequency nor its damping sits on a bound of its range, nor its fastest pole within a tenth of the fastest the solver integrates at the record's rate (16 times the rate in rad/s)",
    };
    let rate_hz = slowest_rate_hz(c, full);
    let inside =
        |f: &LsqFit| !valve_at_bound(&with_search(&q2, &s2.free, &f.theta), &s2.free, rate_hz);
    match fit2 {
        Some(f2) if n > 1.0 && n * (fit.cost / f2.cost).ln() > n.ln() && inside(&f2) => {
            order.chosen = "second_order";
            (s2, q2, f2, Some(order))
        }
        _ => (s, q, fit, Some(order)),
    }
}

/// Assemble the result from the final fit.
#[allow(clippy::too_many_arguments)]
fn finish(
    c: &Campaign,
    s: &Structure,
    from: &Params,
    fit: &LsqFit,
    targets: &[Target],
    estimation: Vec<usize>,
    validation: Vec<usize>,
    starts_tried: usize,
) -> ClosedLoopFit {
    let params = with_search(from, &s.free, &fit.theta);
    let factor = residuals(&params, c, targets)
        .map(|r| correlation_factor(&r, MAX_CORRELATION_LAG))
        .unwrap_or(1.0);
    let cov = fit.covariance.as_ref().map(|m| m * factor);
    let estimates = free_estimates(&s.free, &params, cov.as_ref());
    let roles: Vec<(usize, Role)> = estimation
        .iter()
        .map(|&i| (i, Role::Estimation))
        .chain(validation.iter().map(|&i| (i, Role::Validation)))
        .collect();
    let channels: Vec<Measured> = COMPARED
        .into_iter()
        .filter(|&m| m != Measured::Force || s.with_force)
        .collect();
    let compared = compare::compare(&params, c, &roles, &channels);
    let name = |i: &usize| c.info.tests[*i].name.clone();
    ClosedLoopFit {
        estimation_tests: estimation.iter().map(name).collect(),
        validation_tests: validation.iter().map(name).collect(),
        channels: channels.iter().map(|m| m.name()).collect(),
        estimates,
        conventions: s.conventions.clone(),
        combinations: combinations::combinations(&params, &s.free, cov.as_ref()),
        inseparable: cov
            .as_ref()
            .map(|m| combinations::inseparable(&s.free, m))
            .unwrap_or_default(),
        fits: compared.fits,
        stopped: compared.stopped,
        traces: compared.traces,
        starts_tried,
        iterations: fit.iterations,
        correlation_factor: factor,
        valve_order: None,
        params,
    }
}

/// Each free parameter's value in `params`, with its sigma from the covariance `cov` of
/// the search coordinates (scaled back for a logarithmic one) and whether it sits at a
/// bound (within a millionth of its range or value).
fn free_estimates(
    free: &[GreyParameter],
    params: &Params,
    cov: Option<&nalgebra::DMatrix<f64>>,
) -> Vec<FreeEstimate> {
    free.iter()
        .enumerate()
        .map(|(j, g)| {
            let value = g.get(params);
            let [lo, hi] = g.bounds(params);
            let tol = 1e-6 * (hi - lo).abs().min(value.abs().max(1e-300));
            FreeEstimate {
                parameter: *g,
                key: g.key(),
                value,
                sigma: cov.and_then(|m| {
                    let sd = m[(j, j)].sqrt();
                    let sd = if g.logarithmic() { sd * value } else { sd };
                    sd.is_finite().then_some(sd)
                }),
                at_bound: (value - lo).abs() <= tol || (hi - value).abs() <= tol,
            }
        })
        .collect()
}

/// The starts: the loop gain and valve from the measured bandwidth, and one start per
/// oil-column frequency of [`start::oil_column_starts`] when the oil column is free.
fn starting_points(p: &Params, c: &Campaign, estimation: &[usize], s: &Structure) -> Vec<Params> {
    use GreyParameter::*;
    let Some(reading) = estimation.iter().find_map(|&i| start::read_loop(c, i)) else {
        return vec![*p];
    };
    let what = start::LoopStart {
        through_kp: s.free.contains(&DisplacementGain),
        feed_forward: s.free.contains(&VelocityFeedForward),
        valve: s.free.contains(&ValveTimeConstant),
    };
    let loop_free = what.through_kp || s.free.contains(&FlowGain);
    let bases: Vec<Params> = match loop_free {
        true => reading
            .loops
            .iter()
            .map(|&l| start::with_loop(p, &reading, l, what))
            .collect(),
        false => vec![*p],
    };
    if !s.free.contains(&BulkModulus) {
        return bases;
    }
    let rate = estimation
        .first()
        .map_or(c.info.sample_rate_hz, |&i| c.sample_rate_of(i));
    let oil = start::oil_column_starts(&reading, rate);
    bases
        .iter()
        .flat_map(|b| oil.iter().map(|&f| start::stable_oil_column(b, f)))
        .collect()
}

/// The residual targets of the estimation tests: every compared channel they recorded
/// (the force only when the structure uses it), over `excerpt_s` seconds or the whole.
fn targets(c: &Campaign, tests: &[usize], s: &Structure, excerpt_s: Option<f64>) -> Vec<Target> {
    let mut out = Vec::new();
    for &i in tests {
        let rec = &c.records[i];
        let fs = c.sample_rate_of(i);
        let samples = excerpt_s.map_or(rec.len(), |t| ((t * fs) as usize).clamp(2, rec.len()));
        for m in COMPARED {
            if m == Measured::Force && !s.with_force {
                continue;
            }
            let Some(y) = rec.measured(m) else { continue };
            let y = &y[..samples];
            let mean = y.iter().sum::<f64>() / samples as f64;
            let rms = (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / samples as f64).sqrt();
            if !(rms > 0.0) {
                continue;
            }
            let stride = samples.div_ceil(MAX_RESIDUALS_PER_CHANNEL).max(1);
            let measured: Vec<f64> = y.iter().step_by(stride).map(|v| v - mean).collect();
            let weight = 1.0 / (rms * (measured.len() as f64).sqrt());
            out.push(Target {
                test: i,
                channel: m,
                measured,
                stride,
                samples,
                weight,
            });
        }
    }
    out
}

/// The weighted residual of `p` on `targets` (per test and channel, its squared sum is
/// that channel's NRMSE squared); `None` when `p` breaks a parameter rule or a run left
/// the envelope.
fn residuals(p: &Params, c: &Campaign, targets: &[Target]) -> Option<Vec<f64>> {
    p.validate().ok()?;
    // a second-order valve the sub-steps cannot integrate faithfully is no candidate: its
    // damping frees a fast pole the data cannot place, which the fit would put at the
    // integrator's edge of stability (a first-order valve's one pole is what the data
    // ask for; one they want faster than any sub-step ends at that edge too, a known
    // limit)
    let second_order = p.servovalve.model == crate::params::ServovalveModel::SecondOrder;
    let rate_hz = slowest_rate_hz(c, targets);
    if second_order && !crate::solver::within_pole_reach(&crate::model::Model::new(p), rate_hz) {
        return None;
    }
    let mut tests: Vec<(usize, usize)> = targets.iter().map(|t| (t.test, t.samples)).collect();
    tests.dedup();
    let runs = simulate_tests(p, c, tests)?;
    let mut r = Vec::new();
    for t in targets {
        let sim = &runs.iter().find(|(i, _)| *i == t.test)?.1;
        let mean = sim.iter().map(|o| simulated(o, t.channel)).sum::<f64>() / sim.len() as f64;
        let kept = sim.iter().step_by(t.stride);
        r.extend(
            kept.zip(&t.measured)
                .map(|(o, y)| (simulated(o, t.channel) - mean - y) * t.weight),
        );
    }
    r.iter().all(|v| v.is_finite()).then_some(r)
}

/// The slowest sample rate of the tests `targets` compare.
fn slowest_rate_hz(c: &Campaign, targets: &[Target]) -> f64 {
    targets
        .iter()
        .map(|t| c.sample_rate_of(t.test))
        .fold(f64::INFINITY, f64::min)
}

/// The runs of `p` on `tests` (test, samples), two at a time ([`simulate_prefix_pair`],
/// the longest together) and the pairs in parallel; `None` when a run stopped.
fn simulate_tests(
    p: &Params,
    c: &Campaign,
    mut tests: Vec<(usize, usize)>,
) -> Option<Vec<(usize, Vec<crate::model::Outputs>)>> {
    tests.sort_by_key(|&(_, samples)| std::cmp::Reverse(samples));
    let checks = Checks::DivergenceOnly;
    let runs: Vec<Vec<(usize, Vec<crate::model::Outputs>)>> = tests
        .par_chunks(2)
        .map(|pair| match *pair {
            [a, b] => {
                let [ra, rb] = simulate_prefix_pair(p, c, [a, b], checks);
                Some(vec![(a.0, ra.ok()?), (b.0, rb.ok()?)])
            }
            _ => pair
                .iter()
                .map(|&(i, n)| simulate_prefix(p, c, i, n, checks).ok().map(|o| (i, o)))
                .collect(),
        })
        .collect::<Option<_>>()?;
    Some(runs.into_iter().flatten().collect())
}

/// Why `p` cannot be simulated on `tests`: the parameter rule it breaks or the first run
/// that left the envelope.
fn why_not(p: &Params, c: &Campaign, tests: &[usize]) -> String {
    if let Err(e) = p.validate() {
        return e.to_string();
    }
    tests
        .iter()
        .find_map(|&i| compare::simulate_test(p, c, i).err())
        .map(|e| e.to_string())
        .unwrap_or_else(|| "a residual was not finite".to_string())
}

/// Levenberg-Marquardt on the search coordinates of `free`, from `p`.
fn run_lsq(
    p: &Params,
    c: &Campaign,
    targets: &[Target],
    free: &[GreyParameter],
    iterations: usize,
) -> Option<LsqFit> {
    let theta0: Vec<f64> = free.iter().map(|g| g.to_search(g.get(p))).collect();
    let (lower, upper): (Vec<f64>, Vec<f64>) = free
        .iter()
        .map(|g| {
            let [lo, hi] = g.bounds(p);
            (g.to_search(lo), g.to_search(hi))
        })
        .unzip();
    let scale: Vec<f64> = free.iter().map(|g| g.search_scale(p)).collect();
    let opts = LsqOptions {
        max_iterations: iterations,
        tolerance: TOLERANCE,
        step: 1e-4,
        parallel: true,
    };
    minimise(
        |theta| residuals(&with_search(p, free, theta), c, targets),
        &theta0,
        &lower,
        &upper,
        &scale,
        opts,
    )
}

/// The fastest pole of a fitted valve counts as pushed against the solver's reach
/// ([`crate::solver::pole_reach_rad_s`]) beyond this share of it: the fit stops a few
/// steps short of a limit it pushes against.
const VALVE_REACH_SHARE: f64 = 0.9;

/// Whether `p`'s fitted second-order valve sits on a bound, so that the range stopped the
/// fit, not the data, and the valve is not an estimate of the table's: a frequency or
/// damping on a bound of its search range, or a closed loop whose fastest pole presses on
/// what the sub-steps integrate at the slowest rate `rate_hz` of the fitted tests (an
/// overdamped valve's fast pole, which the data cannot place).
fn valve_at_bound(p: &Params, free: &[GreyParameter], rate_hz: f64) -> bool {
    use GreyParameter::*;
    let reach = crate::solver::pole_reach_rad_s(rate_hz) * VALVE_REACH_SHARE;
    let pressing = !crate::solver::within_pole_reach_of(&crate::model::Model::new(p), reach);
    pressing
        || free
            .iter()
            .filter(|g| matches!(g, ValveNaturalFrequency | ValveDamping))
            .any(|g| {
                let (v, [lo, hi]) = (g.get(p), g.bounds(p));
                v <= lo * (1.0 + VALVE_BOUND_MARGIN) || v >= hi * (1.0 - VALVE_BOUND_MARGIN)
            })
}

/// Relative distance from a bound within which a fitted valve parameter counts as on it:
/// Levenberg-Marquardt stops a step short of a bound it pushes against.
const VALVE_BOUND_MARGIN: f64 = 0.01;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_residuals_are_not_widened_and_smooth_ones_are() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let white: Vec<f64> = (0..20_000).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let f = correlation_factor(&white, MAX_CORRELATION_LAG);
        assert!(f < 1.2, "{f}");
        // a moving average over 10 samples: about 10 samples per independent one
        let smooth: Vec<f64> = (0..white.len() - 10)
            .map(|k| white[k..k + 10].iter().sum::<f64>())
            .collect();
        let f = correlation_factor(&smooth, MAX_CORRELATION_LAG);
        assert!((7.0..13.0).contains(&f), "{f}");
    }
}

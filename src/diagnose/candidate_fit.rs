//! The output-error fit of one candidate effect with the baseline's refined parameters
//! free: its starts on each baseline, screened by one evaluation each, then each fitted
//! in two stages (the baseline unbent with the effect held, then everything together).

use super::baseline::{
    candidate_range, copy_baseline, refined_for, residual_vector, spool_recorded, valve_dynamics,
    BaselineParameter, Range,
};
use super::candidates::{scored_candidate, FitContext, FitTrace, Fitted};
use super::effect::Effect;
use super::effect_table::TakesOut;
use super::effect_values::{EffectBounds, EffectValues};
use super::output::Candidate;
use super::starts::{informed_start, keep_each_frequency, starts};
use crate::campaign::Campaign;
use crate::identify::lsq::{minimise, LsqFit};
use crate::params::Params;
use rayon::prelude::*;

/// Smallest share of the identified table mass a specimen's start leaves to the table
/// when it takes its own mass out: the identified mass holds the specimen's, but a start
/// mass far above the table's would leave a table lighter than any that carries one (a
/// specimen is at most a few times the table's mass; the fit moves on from there).
const MIN_TABLE_MASS_SHARE: f64 = 0.3;

/// A foundation's start stiffens the oil column only when its spring is this many times
/// stiffer than the identified (series) column: closer, `k_f / (k_f - k_id)` grows without
/// bound, and the identified column then is mostly the foundation's, not the oil's.
const FOUNDATION_SERIES_MARGIN: f64 = 1.5;

/// Smallest scale of an effect's parameter in the least squares: a start at zero (no
/// deadband, no asymmetry) still gets a finite step.
const MIN_EFFECT_SCALE: f64 = 1e-4;

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

/// [`candidate_range`] of the baseline parameter `which` under the effect `e`: a
/// specimen's extends the table mass down by the share its start may take out
/// ([`MIN_TABLE_MASS_SHARE`], [`CandidateFit::start_on`]): the identified mass holds a
/// specimen's, and a 33.5-t specimen on a 15-t table (identified 48.5 t) left the
/// candidate's table at the plain range's bound, 24 t, and a foundation was named.
fn effect_range(e: Effect, bases: &[Params], which: BaselineParameter) -> Range {
    let mut r = candidate_range(bases, which);
    let specimen = matches!(e.row().takes_out, TakesOut::NewestModeMass);
    if specimen && which == BaselineParameter::TableMass {
        r.lower *= MIN_TABLE_MASS_SHARE;
    }
    r
}

/// The layout of a candidate fit's free vector, the one place that knows it: the
/// effect's parameters in their declaration order ([`EffectValues::layout`]), then the
/// free baseline parameters ([`candidate_free`]) in theirs, each with its range.
struct FreeLayout {
    effect: Effect,
    baseline: Vec<BaselineParameter>,
    ranges: Vec<Range>,
}

impl FreeLayout {
    fn new(e: Effect, c: &Campaign, bases: &[Params]) -> FreeLayout {
        let baseline = candidate_free(c, &bases[0]);
        let ranges = baseline
            .iter()
            .map(|&w| effect_range(e, bases, w))
            .collect();
        FreeLayout {
            effect: e,
            baseline,
            ranges,
        }
    }

    /// The effect's part and the free baseline part of `t`.
    fn split<'t>(&self, t: &'t [f64]) -> (&'t [f64], &'t [f64]) {
        t.split_at(self.effect.parameters().len())
    }

    /// The effect's values in `t`.
    fn effect_of(&self, t: &[f64]) -> EffectValues {
        EffectValues::from_layout(self.effect, self.split(t).0)
    }

    /// The free vector of the effect's values `effect` and the free baseline values
    /// `baseline`.
    fn join(&self, effect: &EffectValues, baseline: &[f64]) -> Vec<f64> {
        self.join_raw(effect.layout(), baseline)
    }

    /// [`FreeLayout::join`] of a vector laid out like the effect's values (its bounds,
    /// its scales).
    fn join_raw(&self, effect: &[f64], baseline: &[f64]) -> Vec<f64> {
        effect.iter().chain(baseline).copied().collect()
    }

    /// The free baseline values of `p`.
    fn baseline_of(&self, p: &Params) -> Vec<f64> {
        self.baseline.iter().map(|w| w.get(p)).collect()
    }

    /// Set the free baseline parameters of `p` to `values`.
    fn set_baseline(&self, p: &mut Params, values: &[f64]) {
        for (which, &x) in self.baseline.iter().zip(values) {
            which.set(p, x);
        }
    }

    /// The lower bounds: the effect's `effect_lower`, then the baseline's ranges'.
    fn lower(&self, effect_lower: &EffectValues) -> Vec<f64> {
        let baseline: Vec<f64> = self.ranges.iter().map(|r| r.lower).collect();
        self.join(effect_lower, &baseline)
    }

    /// The upper bounds: the effect's `effect_upper`, then the baseline's ranges'.
    fn upper(&self, effect_upper: &EffectValues) -> Vec<f64> {
        let baseline: Vec<f64> = self.ranges.iter().map(|r| r.upper).collect();
        self.join(effect_upper, &baseline)
    }

    /// The scales from the start `t0`: the effect's start values' magnitudes (at least
    /// [`MIN_EFFECT_SCALE`]), then the baseline's ranges'.
    fn scale(&self, t0: &[f64]) -> Vec<f64> {
        let effect: Vec<f64> = self
            .split(t0)
            .0
            .iter()
            .map(|x| x.abs().max(MIN_EFFECT_SCALE))
            .collect();
        let baseline: Vec<f64> = self.ranges.iter().map(|r| r.scale).collect();
        self.join_raw(&effect, &baseline)
    }
}

/// A start of a candidate's fit: the effect's values, the free vector ([`FreeLayout`]:
/// the effect's and the free baseline parameters), and the parameters the other baseline
/// parameters are taken from.
struct Start {
    effect: EffectValues,
    free: Vec<f64>,
    fixed: Params,
}

/// The table's mass under a specimen's start: the identified mass `table_mass_kg` holds
/// the specimen's (newest mode's) mass at low frequency, which the start takes out,
/// leaving the table at least [`MIN_TABLE_MASS_SHARE`] of it.
fn table_mass_under_specimen(table_mass_kg: f64, newest_mode_mass_kg: f64) -> f64 {
    (table_mass_kg - newest_mode_mass_kg).max(MIN_TABLE_MASS_SHARE * table_mass_kg)
}

/// The factor on the bulk modulus under a foundation's start of `mass_kg` at
/// `frequency_hz` on a base whose identified oil column is `k_id_n_m`: that column is the
/// oil and the foundation springs in series, `1/k_id = 1/k_oil + 1/k_f`, so the oil alone
/// is stiffer by `k_f / (k_f - k_id)`; `None` unless the foundation's spring is
/// [`FOUNDATION_SERIES_MARGIN`] times the column's.
fn oil_column_factor_under_foundation(
    k_id_n_m: f64,
    mass_kg: f64,
    frequency_hz: f64,
) -> Option<f64> {
    let k_f = mass_kg * (2.0 * std::f64::consts::PI * frequency_hz).powi(2);
    (k_f > FOUNDATION_SERIES_MARGIN * k_id_n_m).then(|| k_f / (k_f - k_id_n_m))
}

/// One candidate effect's output-error fit on its signature tests: the effect, its
/// bases (the refined baseline, then section 4's), the free vector's layout and bounds.
pub(super) struct CandidateFit<'a> {
    e: Effect,
    bases: &'a [Params],
    sig: &'a [usize],
    ctx: &'a FitContext<'a>,
    trace: &'a FitTrace,
    layout: FreeLayout,
    /// The effect's own fitting bounds, which judge it as evidence.
    effect_bounds: EffectBounds,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl<'a> CandidateFit<'a> {
    pub(super) fn new(
        e: Effect,
        bases: &'a [Params],
        sig: &'a [usize],
        ctx: &'a FitContext<'a>,
        trace: &'a FitTrace,
    ) -> CandidateFit<'a> {
        let layout = FreeLayout::new(e, ctx.c, bases);
        let effect_bounds = e.bounds(&bases[0]);
        let lower = layout.lower(&effect_bounds.lower);
        let upper = layout.upper(&effect_bounds.upper);
        CandidateFit {
            e,
            bases,
            sig,
            ctx,
            trace,
            layout,
            effect_bounds,
            lower,
            upper,
        }
    }

    /// The model of the free vector `t`: the effect's parameters on the refined
    /// baseline, the other baseline parameters from `fixed`, then the free ones.
    fn assemble(&self, t: &[f64], fixed: &Params) -> Params {
        let baseline = self.layout.split(t).1;
        let mut p = self.bases[0];
        self.layout.effect_of(t).apply(&mut p);
        copy_baseline(fixed, &mut p);
        self.layout.set_baseline(&mut p, baseline);
        p
    }

    /// The whitened residuals of the model of `t` on the signature tests.
    fn residuals(&self, t: &[f64], fixed: &Params) -> Option<Vec<f64>> {
        residual_vector(
            &self.assemble(t, fixed),
            self.ctx.c,
            self.sig,
            self.ctx.whitening,
        )
    }

    /// The start `s` of the effect on the baseline `b`: the valve as fitted on the spool,
    /// whichever base the start comes from (the friction's yield and shape stay the
    /// base's own: the refined ones may have bent to absorb the effect, the section-4
    /// ones have not), and what the identified baseline holds of the effect taken out (a
    /// specimen's mass out of the table's; section 4 fits the oil column behind the
    /// measured apparent mass, the specimen's resonance in it, so the column stays).
    fn start_on(&self, b: &Params, s: &EffectValues) -> Start {
        let mut fixed = *b;
        for which in BaselineParameter::VALVE {
            which.set(&mut fixed, which.get(&self.bases[1]));
        }
        let e = self.e;
        match e.row().takes_out {
            TakesOut::Nothing => {}
            TakesOut::NewestModeMass => {
                if let Some(m_kg) = e.newest_mode_mass().and_then(|k| s.try_get(k)) {
                    fixed.table.mass_kg = table_mass_under_specimen(fixed.table.mass_kg, m_kg);
                }
            }
            TakesOut::FoundationSpring => {
                let k_id = b.actuator.oil_column_stiffness_n_m();
                let (mass_kg, frequency_hz) = (s.try_get("mass_kg"), s.try_get("frequency_hz"));
                if let Some(factor) = mass_kg
                    .zip(frequency_hz)
                    .and_then(|(m, f)| oil_column_factor_under_foundation(k_id, m, f))
                {
                    fixed.actuator.bulk_modulus_pa *= factor;
                }
            }
        }
        Start {
            effect: s.clone(),
            free: self.layout.join(s, &self.layout.baseline_of(&fixed)),
            fixed,
        }
    }

    /// Every start of the effect on every baseline, screened by one evaluation each
    /// when there are more than the effort fits (a resonance keeps the best start at each
    /// of its frequencies too); `informed` (read off the data) seeds the spread.
    fn screened_starts(&self, informed: Option<&EffectValues>) -> Vec<Start> {
        let mut all: Vec<Start> = Vec::new();
        for b in self.bases {
            for s in starts(self.e, self.ctx.c, b, informed) {
                all.push(self.start_on(b, &s));
            }
        }
        let keep = self.ctx.effort.screened_starts();
        if all.len() <= keep {
            return all;
        }
        let cost_of = |s: &Start| {
            self.residuals(&s.free, &s.fixed)
                .map(|r| r.iter().map(|x| x * x).sum::<f64>())
                .unwrap_or(f64::INFINITY)
        };
        let costs: Vec<f64> = all.par_iter().map(cost_of).collect();
        let mut scored: Vec<(f64, Start)> = costs.into_iter().zip(all).collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.trace.say(&format!(
            "screened starts: {:?}",
            scored
                .iter()
                .map(|s| (s.0, s.1.effect.layout()))
                .collect::<Vec<_>>()
        ));
        match self.e.valley_frequency() {
            Some(key) => keep_each_frequency(scored, keep, |s| s.effect.get(key)),
            None => scored.into_iter().take(keep).map(|x| x.1).collect(),
        }
    }

    /// Stage 1 from `start`: the free baseline parameters with the effect held at its
    /// start (the baseline has bent to absorb the effect; unbent, the joint fit starts
    /// downhill). The free vector unbent, or the start's when the fit fails.
    fn unbent(&self, start: &Start, scale: &[f64]) -> Vec<f64> {
        let baseline = self.layout.split(&start.free).1;
        let effect = &start.effect;
        let aligned = minimise(
            |tb| self.residuals(&self.layout.join(effect, tb), &start.fixed),
            baseline,
            self.layout.split(&self.lower).1,
            self.layout.split(&self.upper).1,
            self.layout.split(scale).1,
            self.ctx.effort.candidate_lsq(),
        );
        match aligned {
            Some(f) => {
                self.trace
                    .say(&format!("stage 1: {} iterations", f.iterations));
                self.layout.join(effect, &f.theta)
            }
            None => {
                self.trace.say("stage 1 failed");
                start.free.clone()
            }
        }
    }

    /// The fit from `start`: stage 1 ([`CandidateFit::unbent`]), then stage 2,
    /// everything together.
    fn fit_start(&self, start: &Start) -> Option<LsqFit> {
        let scale = self.layout.scale(&start.free);
        let t0 = self.unbent(start, &scale);
        let f = minimise(
            |t| self.residuals(t, &start.fixed),
            &t0,
            &self.lower,
            &self.upper,
            &scale,
            self.ctx.effort.candidate_lsq(),
        )?;
        self.trace.say(&format!(
            "stage 2: {} iterations, cost {:.4}",
            f.iterations, f.cost
        ));
        Some(f)
    }

    /// The best fit over the screened starts and the start read off the data, which is
    /// fitted whatever its screening: a lightly damped foundation mode a few percent off
    /// misfits more than none until the baseline has unbent (the section-4 one, which
    /// bent least). Scored on the held-out quarters.
    pub(super) fn fit(&self) -> Option<Candidate> {
        // the start read off the data (its frequency also seeds the screened spread)
        let informed = informed_start(self.e, self.ctx.c, &self.bases[1]);
        let mut all = self.screened_starts(informed.as_ref());
        if let Some(s) = informed {
            self.trace
                .say(&format!("start from the data: {:?}", s.layout()));
            all.push(self.start_on(&self.bases[1], &s));
        }
        // the starts fitted side by side (the cores a search's other effects leave idle
        // at its end), then judged in their order: the same fit whatever the threads
        let fits: Vec<Option<LsqFit>> = all.par_iter().map(|s| self.fit_start(s)).collect();
        let mut best: Option<(LsqFit, Params)> = None;
        for (start, f) in all.into_iter().zip(fits) {
            if let Some(f) = f {
                if best.as_ref().map(|b| f.cost < b.0.cost).unwrap_or(true) {
                    best = Some((f, start.fixed));
                }
            }
        }
        let (f, fixed) = best?;
        let p = self.assemble(&f.theta, &fixed);
        let ctx = self.ctx;
        Some(scored_candidate(
            self.e,
            ctx.c,
            Fitted {
                values: &self.layout.effect_of(&f.theta),
                sigma: Some(&self.layout.effect_of(&f.sigma)),
                bounds: &self.effect_bounds,
                fit_residual: f.cost.sqrt(),
                params: p,
            },
            ctx.heldout_idx,
            ctx.noise,
            ctx.hold,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The start adjustments read the effects' parameters by name: the specimen's newest
    /// mode's mass and the foundation's mass and frequency are where the catalogue puts
    /// them.
    #[test]
    fn the_start_adjustments_find_their_parameters() {
        for (e, n) in [
            (Effect::of(&crate::effects::specimen::EFFECT), 1),
            (Effect::specimen(2).unwrap(), 2),
            (Effect::specimen(3).unwrap(), 3),
        ] {
            let layout: Vec<f64> = (0..e.parameters().len()).map(|k| k as f64).collect();
            let s = EffectValues::from_layout(e, &layout);
            let key = e.newest_mode_mass().unwrap();
            assert_eq!(s.try_get(key), Some(layout[3 * (n - 1)]));
        }
        let f = Effect::of(&crate::effects::foundation::EFFECT);
        let s = EffectValues::from_layout(f, &[2e5, 12.0, 0.05]);
        assert_eq!(s.try_get("mass_kg"), Some(2e5));
        assert_eq!(s.try_get("frequency_hz"), Some(12.0));
        let deadband = Effect::of(&crate::effects::valve_deadband::EFFECT);
        assert_eq!(deadband.newest_mode_mass(), None);
    }

    /// A specimen's start leaves the table at least its share; a soft foundation leaves
    /// the oil column as identified.
    #[test]
    fn the_start_adjustments_are_bounded() {
        assert_eq!(table_mass_under_specimen(40e3, 10e3), 30e3);
        assert_eq!(
            table_mass_under_specimen(40e3, 100e3),
            MIN_TABLE_MASS_SHARE * 40e3
        );
        assert_eq!(oil_column_factor_under_foundation(1e9, 1e3, 1.0), None);
        let factor = oil_column_factor_under_foundation(1e8, 1e6, 100.0).unwrap();
        assert!(factor > 1.0 && factor < 1.01);
    }

    /// A specimen's fit may move the table mass down as far as its start may take it; the
    /// column and the other effects keep the plain range.
    #[test]
    fn a_specimen_widens_the_table_mass_range_down() {
        let bases = [Params::trees_lab()];
        let specimen = Effect::of(&crate::effects::specimen::EFFECT);
        let foundation = Effect::of(&crate::effects::foundation::EFFECT);
        for which in [BaselineParameter::TableMass, BaselineParameter::BulkModulus] {
            let plain = candidate_range(&bases, which);
            assert_eq!(effect_range(foundation, &bases, which), plain);
            let widened = effect_range(specimen, &bases, which);
            let share = if which == BaselineParameter::TableMass {
                MIN_TABLE_MASS_SHARE
            } else {
                1.0
            };
            assert_eq!(widened.lower, share * plain.lower);
            assert_eq!(widened.upper, plain.upper);
        }
        let leakage = BaselineParameter::Leakage;
        assert_eq!(
            effect_range(specimen, &bases, leakage),
            candidate_range(&bases, leakage)
        );
    }
}

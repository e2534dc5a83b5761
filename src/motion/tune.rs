//! `tune` (issue 19, part 4): TVC gains (kp, kv, ka, fv, fa, kdp; spec section 2) that make
//! the table's transfer with its specimen as flat as possible over the useful band, every
//! closed-loop pole kept damped.
//!
//! Objective: the RMS over [`TUNE_POINTS`] log-spaced frequencies in the band of the
//! gain in dB, `20 log10 |H(f)|`, of the linearised closed loop (reference acceleration to
//! table acceleration, [`Linearisation::table_tf`]). Margin: no pole's damping ratio below
//! [`MIN_POLE_DAMPING`], or below the least-damped pole of the gains given if that is
//! lower already (a specimen's own mode at 2 % is not the controller's to damp).
//! Search: Nelder-Mead (argmin) over the gains' logarithms (kp, fv, kdp: positive) and
//! scaled values (kv, ka, fa: non-negative feedback, feed-forward of either sign).

use crate::linear::Linearisation;
use crate::params::{Controller, Params};
use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;
use serde::Serialize;

/// Frequencies of the flatness objective.
pub const TUNE_POINTS: usize = 80;
/// Least damping ratio a tuned closed-loop pole may have: 5 % keeps the oil column from
/// ringing on the transients of a record and leaves room for the model's error.
pub const MIN_POLE_DAMPING: f64 = 0.05;
/// Poles below this frequency are the linearisation's zero pole, not a mode, Hz.
const ZERO_POLE_HZ: f64 = 1e-6;
/// Nelder-Mead iterations: six parameters converge in a few hundred.
const MAX_ITERATIONS: u64 = 600;

/// What tuning found.
#[derive(Debug, Clone, Serialize)]
pub struct Tuning {
    pub before: Controller,
    pub after: Controller,
    pub band_hz: (f64, f64),
    /// RMS of the gain in dB over the band, before and after.
    pub flatness_db_before: f64,
    pub flatness_db_after: f64,
    pub min_damping_before: f64,
    pub min_damping_after: f64,
    pub damping_margin: f64,
}

/// The gain's RMS in dB over the band, and the least pole damping, of `p`.
pub fn flatness(p: &Params, band_hz: (f64, f64)) -> (f64, f64) {
    let lin = Linearisation::new(p);
    let (lo, hi) = band_hz;
    let mut sum = 0.0;
    for k in 0..TUNE_POINTS {
        let f = lo * (hi / lo).powf(k as f64 / (TUNE_POINTS - 1) as f64);
        let db = 20.0 * lin.table_tf(f).norm().log10();
        sum += if db.is_finite() {
            db * db
        } else {
            f64::INFINITY
        };
    }
    // poles that cannot be computed are no margin at all
    let Some(poles) = lin.upper_poles() else {
        return ((sum / TUNE_POINTS as f64).sqrt(), f64::NEG_INFINITY);
    };
    let damping = poles
        .iter()
        // the zero pole of the linearised Bouc-Wen state (see `frf`) has no damping to keep
        .filter(|q| q.frequency_hz > ZERO_POLE_HZ)
        .map(|q| q.damping_ratio)
        .fold(f64::INFINITY, f64::min);
    ((sum / TUNE_POINTS as f64).sqrt(), damping)
}

/// The gains of the search point `x` around `start`.
fn gains(start: &Controller, scale: f64, x: &[f64]) -> Controller {
    Controller {
        kp: start.kp * x[0].exp(),
        fv: start.fv * x[1].exp(),
        kdp: start.kdp * x[2].exp(),
        kv: x[3] * start.fv,
        ka: x[4] * start.fv / scale,
        fa: x[5] * start.fv / scale,
    }
}

struct Objective<'a> {
    params: &'a Params,
    band_hz: (f64, f64),
    margin: f64,
    scale: f64,
}

impl CostFunction for Objective<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        if x[3] < 0.0 || x[4] < 0.0 || x.iter().any(|v| !v.is_finite() || v.abs() > 20.0) {
            return Ok(f64::INFINITY);
        }
        let mut p = *self.params;
        p.controller = gains(&self.params.controller, self.scale, x);
        let (db, damping) = flatness(&p, self.band_hz);
        Ok(if damping >= self.margin {
            db
        } else {
            f64::INFINITY
        })
    }
}

/// Tune the gains of `p` over `band_hz`; `None` if the start is unusable (a gain that is
/// zero where the search scales it: kp, fv, kdp).
pub fn tune(p: &Params, band_hz: (f64, f64)) -> Result<Tuning, String> {
    let c = p.controller;
    if !(c.kp > 0.0 && c.fv > 0.0 && c.kdp > 0.0) {
        return Err(
            "tuning searches around the given kp, fv and kdp: each must be positive".into(),
        );
    }
    let (db0, damping0) = flatness(p, band_hz);
    if damping0 <= 0.0 {
        return Err(format!("the given loop is unstable (least pole damping {damping0:.4}): start from a stable one"));
    }
    let margin = MIN_POLE_DAMPING.min(damping0);
    // ka and fa scaled by the oil column's time scale, so each coordinate moves the
    // response by similar amounts
    let scale = 2.0 * std::f64::consts::PI * crate::linear::OilColumn::of(p).frequency_hz;
    let x0 = vec![
        0.0,
        0.0,
        0.0,
        c.kv / c.fv,
        c.ka * scale / c.fv,
        c.fa * scale / c.fv,
    ];
    let mut simplex = vec![x0.clone()];
    for k in 0..x0.len() {
        let mut x = x0.clone();
        x[k] += 0.3;
        simplex.push(x);
    }
    let objective = Objective {
        params: p,
        band_hz,
        margin,
        scale,
    };
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-6)
        .map_err(|e| e.to_string())?;
    let best = Executor::new(objective, solver)
        .configure(|s| s.max_iters(MAX_ITERATIONS))
        .run()
        .map_err(|e| e.to_string())?
        .state
        .best_param
        .unwrap_or(x0);
    let mut tuned = *p;
    tuned.controller = gains(&c, scale, &best);
    let (db1, damping1) = flatness(&tuned, band_hz);
    let (after, db1, damping1) = match db1 < db0 && damping1 >= margin {
        true => (tuned.controller, db1, damping1),
        false => (c, db0, damping0),
    };
    Ok(Tuning {
        before: c,
        after,
        band_hz,
        flatness_db_before: db0,
        flatness_db_after: db1,
        min_damping_before: damping0,
        min_damping_after: damping1,
        damping_margin: margin,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuning_flattens_the_trees_table_with_a_specimen_and_keeps_it_damped() {
        let mut p = Params::trees_lab();
        p.specimen.enabled = true;
        p.specimen.mass_kg = 20_000.0;
        p.specimen.frequency_hz = 4.0;
        let t = tune(&p, (0.5, 20.0)).unwrap();
        assert!(t.flatness_db_after < 0.7 * t.flatness_db_before, "{t:?}");
        assert!(t.min_damping_after >= t.damping_margin);
        let mut q = p;
        q.controller = t.after;
        let (db, damping) = flatness(&q, (0.5, 20.0));
        assert_eq!(db, t.flatness_db_after);
        assert!(damping >= MIN_POLE_DAMPING.min(t.min_damping_before));
    }
}

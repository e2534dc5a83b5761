//! `record check`: what a target asks of the table with its specimen, against the
//! envelope (spec section 8: stroke and velocity; the servovalve's flow and the supply
//! pressure, spec section 4), before anything is run. The demands are those of a table
//! that follows the target exactly: the actuator force is the table mass times the
//! target acceleration, plus the specimen's reaction (its modal oscillator driven by the
//! target, in the frequency domain), the sliding friction and the horizontal stiffness.

use super::prepare::{peak, Target};
use super::spectrum::Periodic;
use crate::params::{ActuatorModel, Params};
use realfft::num_complex::Complex;
use serde::Serialize;
use std::f64::consts::PI;

/// One demand of the target against its limit.
#[derive(Debug, Clone, Serialize)]
pub struct Demand {
    /// `stroke`, `velocity`, `flow`, `pressure`.
    pub name: &'static str,
    pub unit: &'static str,
    pub peak: f64,
    pub at_time_s: f64,
    pub limit: f64,
    /// `peak / limit`; above 1 the target leaves the envelope.
    pub fraction: f64,
    /// What the limit is.
    pub limit_is: String,
}

/// Every demand, and the largest fraction.
#[derive(Debug, Clone, Serialize)]
pub struct EnvelopeCheck {
    pub demands: Vec<Demand>,
    pub within: bool,
    /// Peak actuator force, N (the specimen's reaction included).
    pub peak_force_n: f64,
    pub specimen: bool,
}

/// Check `target` against the table of `p`.
pub fn check_target(p: &Params, target: &Target) -> EnvelopeCheck {
    let a = &target.acceleration_m_s2;
    let v = &target.velocity_m_s;
    let x = &target.displacement_m;
    let force = actuator_force(p, target);
    let area = p.actuator.piston_area_m2;
    let load: Vec<f64> = force.iter().map(|f| f / area).collect();
    let load_rate = Periodic::new(&load, target.rate_hz).derivative(1).signal();
    let compliance = p.actuator.total_oil_volume_m3 / (4.0 * p.actuator.bulk_modulus_pa);
    let flow: Vec<f64> = (0..a.len())
        .map(|k| area * v[k] + p.actuator.leakage_m3_s_pa * load[k] + compliance * load_rate[k])
        .collect();
    let opening: Vec<f64> = (0..a.len())
        .map(|k| spool_opening(p, flow[k], load[k]))
        .collect();
    let ps = p.actuator.supply_pressure_pa;
    let demands = vec![
        demand(
            "stroke",
            "m",
            x,
            p.limits.stroke_m,
            "[limits] stroke_m".into(),
            target,
        ),
        demand(
            "velocity",
            "m/s",
            v,
            p.limits.velocity_m_s,
            "[limits] velocity_m_s".into(),
            target,
        ),
        demand(
            "valve opening",
            "of full spool",
            &opening,
            1.0,
            valve_limit_text(p),
            target,
        ),
        demand(
            "load pressure",
            "Pa",
            &load,
            ps,
            "the supply pressure P_s".into(),
            target,
        ),
    ];
    EnvelopeCheck {
        within: demands.iter().all(|d| d.fraction <= 1.0),
        demands,
        peak_force_n: peak(&force),
        specimen: p.specimen.enabled,
    }
}

impl EnvelopeCheck {
    /// Each demand beyond its limit, as "`name` N % of its limit at T s".
    pub fn exceeded(&self) -> Vec<String> {
        self.demands
            .iter()
            .filter(|d| d.fraction > 1.0)
            .map(|d| {
                format!(
                    "{} {:.0} % of its limit at {:.2} s",
                    d.name,
                    100.0 * d.fraction,
                    d.at_time_s
                )
            })
            .collect()
    }
}

fn valve_limit_text(p: &Params) -> String {
    let mut s = String::from("the spool fully open");
    if p.actuator.model == ActuatorModel::Nonlinear {
        s.push_str(", flow reduced by the load (orifice law)");
    }
    if p.flow_saturation.enabled {
        s.push_str(", flow bounded by flow_saturation.max_flow_m3_s");
    }
    if p.valve_deadband.enabled {
        s.push_str(", plus the deadband");
    }
    s
}

fn demand(
    name: &'static str,
    unit: &'static str,
    series: &[f64],
    limit: f64,
    limit_is: String,
    target: &Target,
) -> Demand {
    let (k, peak) = series
        .iter()
        .enumerate()
        .fold((0, 0.0_f64), |(bk, bv), (k, v)| {
            if v.abs() > bv {
                (k, v.abs())
            } else {
                (bk, bv)
            }
        });
    Demand {
        name,
        unit,
        peak,
        at_time_s: k as f64 / target.rate_hz,
        limit,
        fraction: peak / limit,
        limit_is,
    }
}

/// The spool opening that delivers `flow` at load pressure `load_pa`: `Q / Kq` for the
/// ideal actuator; with the nonlinear one the orifice loses flow with the load
/// (`Q = Kq x_v sqrt(1 - sign(Q) P_L / P_s)`, spec section 4 with symmetric chambers);
/// a saturated flow or a load at the supply pressure needs more than a full spool (inf).
fn spool_opening(p: &Params, flow: f64, load_pa: f64) -> f64 {
    if p.flow_saturation.enabled && flow.abs() > p.flow_saturation.max_flow_m3_s {
        return f64::INFINITY;
    }
    let mut kq = p.actuator.flow_gain_m3_s;
    if p.actuator.model == ActuatorModel::Nonlinear {
        let left = 1.0 - flow.signum() * load_pa / p.actuator.supply_pressure_pa;
        if left <= 0.0 {
            return f64::INFINITY;
        }
        kq *= left.sqrt();
    }
    let deadband = if p.valve_deadband.enabled {
        p.valve_deadband.deadband
    } else {
        0.0
    };
    flow.abs() / kq + if flow != 0.0 { deadband } else { 0.0 }
}

/// The actuator force of a table that follows `target`: `M a + F_specimen + F_mu sign(v)
/// plus k_h x` (spec section 5; friction at its sliding amplitude, or its static peak
/// with stick-slip).
fn actuator_force(p: &Params, target: &Target) -> Vec<f64> {
    let specimen = specimen_reaction(p, target);
    let friction_peak = if p.stick_slip.enabled {
        p.friction.force_n * p.stick_slip.static_ratio.max(1.0)
    } else {
        p.friction.force_n
    };
    (0..target.acceleration_m_s2.len())
        .map(|k| {
            let v = target.velocity_m_s[k];
            p.table.mass_kg * target.acceleration_m_s2[k]
                + specimen[k]
                + friction_peak * v.signum() * (v != 0.0) as i32 as f64
                + p.table.stiffness_n_m * target.displacement_m[k]
        })
        .collect()
}

/// The force the specimen asks of the table, `m_s (a + x_rel'')`, with the relative
/// motion of its oscillator under the base acceleration `a`:
/// `x_rel = -a / (w_s^2 - w^2 + 2 i zeta_s w_s w)` (spec section 7, `specimen`).
fn specimen_reaction(p: &Params, target: &Target) -> Vec<f64> {
    let n = target.acceleration_m_s2.len();
    if !p.specimen.enabled {
        return vec![0.0; n];
    }
    let s = &p.specimen;
    let ws = 2.0 * PI * s.frequency_hz;
    // total acceleration of the specimen over the base's: 1 + (-w^2) x_rel / a
    let transmissibility = |f: f64| {
        let w = 2.0 * PI * f;
        let den = Complex::new(ws * ws - w * w, 2.0 * s.damping_ratio * ws * w);
        Complex::new(1.0, 0.0) + Complex::new(w * w, 0.0) / den
    };
    Periodic::new(&target.acceleration_m_s2, target.rate_hz)
        .filtered(transmissibility)
        .signal()
        .iter()
        .map(|a_s| s.mass_kg * a_s)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine_target(f_hz: f64, amplitude_m: f64, seconds: f64) -> Target {
        let rate_hz = 256.0;
        let n = (seconds * rate_hz) as usize;
        let w = 2.0 * PI * f_hz;
        let t = |k: usize| k as f64 / rate_hz;
        Target {
            rate_hz,
            displacement_m: (0..n).map(|k| amplitude_m * (w * t(k)).sin()).collect(),
            velocity_m_s: (0..n).map(|k| amplitude_m * w * (w * t(k)).cos()).collect(),
            acceleration_m_s2: (0..n)
                .map(|k| -amplitude_m * w * w * (w * t(k)).sin())
                .collect(),
        }
    }

    #[test]
    fn a_bare_table_sine_needs_what_the_hand_calculation_says() {
        let p = Params::trees_lab();
        let t = sine_target(2.0, 0.05, 4.0); // whole periods: periodic
        let c = check_target(&p, &t);
        let w = 2.0 * PI * 2.0;
        assert!((c.demands[0].peak - 0.05).abs() < 1e-4);
        assert!((c.demands[1].peak - 0.05 * w).abs() < 1e-3);
        let force = p.table.mass_kg * 0.05 * w * w;
        assert!((c.peak_force_n - force).abs() < 0.01 * force + p.friction.force_n);
        // flow ~ A v: opening ~ A v / Kq
        let opening = p.actuator.piston_area_m2 * 0.05 * w / p.actuator.flow_gain_m3_s;
        assert!(
            (c.demands[2].peak - opening).abs() < 0.05 * opening,
            "{}",
            c.demands[2].peak
        );
        assert!(c.within);
    }

    #[test]
    fn a_specimen_at_resonance_multiplies_the_force() {
        let mut p = Params::trees_lab();
        let bare = check_target(&p, &sine_target(4.0, 0.005, 4.0)).peak_force_n;
        p.specimen.enabled = true;
        p.specimen.mass_kg = 20_000.0;
        p.specimen.frequency_hz = 4.0;
        p.specimen.damping_ratio = 0.02;
        let with = check_target(&p, &sine_target(4.0, 0.005, 4.0)).peak_force_n;
        // at resonance the specimen's acceleration is (1 - i/(2 zeta)) times the base's
        let a = 0.005 * (2.0 * PI * 4.0_f64).powi(2);
        let t = Complex::new(1.0, -1.0 / (2.0 * 0.02));
        let total: Complex<f64> = Complex::new(p.table.mass_kg, 0.0) + t * 20_000.0;
        let expected = a * total.norm();
        assert!(with > 4.0 * bare, "{with} {bare}");
        assert!(
            (with - expected).abs() < 0.02 * expected + p.friction.force_n,
            "{with} {expected}"
        );
    }

    #[test]
    fn a_large_sine_leaves_the_stroke_and_the_valve() {
        let p = Params::trees_lab();
        let c = check_target(&p, &sine_target(1.0, 0.6, 4.0));
        assert!(!c.within);
        assert!(c.demands[0].fraction > 1.1);
        assert!(c.demands[2].fraction > 1.0, "{}", c.demands[2].fraction);
    }
}

//! The combinations of parameters the recorded motion determines, with their uncertainty
//! from the fit's covariance (first-order propagation), and the pairs of free parameters
//! the data cannot separate.

use super::parameters::{with_search, GreyParameter};
use crate::linear::OilColumn;
use crate::params::Params;
use nalgebra::DMatrix;
use serde::Serialize;
use std::f64::consts::PI;

/// An identifiable combination: value and one-sigma uncertainty.
#[derive(Debug, Clone, Serialize)]
pub struct Combination {
    pub name: &'static str,
    pub unit: &'static str,
    pub value: f64,
    pub sigma: Option<f64>,
    pub meaning: &'static str,
}

/// Correlation above which two free parameters are reported as not separable: their
/// estimates then move together along a valley of the cost, and only a combination is
/// determined.
pub const INSEPARABLE_CORRELATION: f64 = 0.95;

type Formula = fn(&Params) -> f64;

/// One identifiable combination of the catalogue.
struct Entry {
    name: &'static str,
    unit: &'static str,
    meaning: &'static str,
    formula: Formula,
    /// The free parameters it involves (reported only when the fit freed one of them).
    needs: &'static [GreyParameter],
}

/// Every combination.
const CATALOGUE: [Entry; 8] = {
    use GreyParameter::*;
    [
        Entry {
            name: "loop_gain_1_s",
            unit: "1/s",
            meaning:
                "Kp Ks Kq / A: the displacement loop's gain (its bandwidth is loop_gain / 2 pi)",
            formula: |p| {
                p.controller.kp * p.servovalve.gain * p.actuator.flow_gain_m3_s
                    / p.actuator.piston_area_m2
            },
            needs: &[DisplacementGain, FlowGain],
        },
        Entry {
            name: "feed_forward_ratio",
            unit: "1",
            meaning: "Fv Ks Kq / A: the share of the reference velocity fed forward to the valve",
            formula: |p| {
                p.controller.fv * p.servovalve.gain * p.actuator.flow_gain_m3_s
                    / p.actuator.piston_area_m2
            },
            needs: &[VelocityFeedForward, FlowGain],
        },
        Entry {
            name: "oil_column_frequency_hz",
            unit: "Hz",
            meaning: "sqrt(4 beta A^2 / (V_t M)) / 2 pi (spec section 4)",
            formula: |p| OilColumn::of(p).frequency_hz,
            needs: &[BulkModulus, TableMass],
        },
        Entry {
            name: "oil_column_damping_ratio",
            unit: "1",
            meaning: "(C_l / A) sqrt(beta M / V_t) (spec section 4)",
            formula: |p| OilColumn::of(p).damping_ratio,
            needs: &[BulkModulus, Leakage, TableMass],
        },
        Entry {
            name: "valve_bandwidth_hz",
            unit: "Hz",
            meaning: "1 / (2 pi tau) of the first-order valve",
            formula: |p| 1.0 / (2.0 * PI * p.servovalve.time_constant_s),
            needs: &[ValveTimeConstant],
        },
        Entry {
            name: "valve_natural_frequency_hz",
            unit: "Hz",
            meaning: "natural frequency of the second-order valve (paper eq. 4.2)",
            formula: |p| p.servovalve.natural_frequency_hz,
            needs: &[ValveNaturalFrequency],
        },
        Entry {
            name: "valve_damping_ratio",
            unit: "1",
            meaning: "damping ratio of the second-order valve (paper eq. 4.2)",
            formula: |p| p.servovalve.damping_ratio,
            needs: &[ValveDamping],
        },
        Entry {
            name: "friction_per_mass_m_s2",
            unit: "m/s^2",
            meaning: "F_mu / M: the friction's deceleration of the moving mass",
            formula: |p| p.friction.force_n / p.table.mass_kg,
            needs: &[FrictionForce],
        },
    ]
};

/// The combinations that involve a free parameter, at `p` (the fitted parameters), with
/// their sigma from the covariance `cov` of the search coordinates (`None` when the fit
/// gave none).
pub fn combinations(
    p: &Params,
    free: &[GreyParameter],
    cov: Option<&DMatrix<f64>>,
) -> Vec<Combination> {
    let theta: Vec<f64> = free.iter().map(|g| g.to_search(g.get(p))).collect();
    CATALOGUE
        .iter()
        .filter(|e| e.needs.iter().any(|n| free.contains(n)))
        .map(|e| Combination {
            name: e.name,
            unit: e.unit,
            value: (e.formula)(p),
            sigma: cov
                .and_then(|c| propagate(|t| (e.formula)(&with_search(p, free, t)), &theta, c)),
            meaning: e.meaning,
        })
        .collect()
}

/// Relative step of the numerical gradient in the search coordinates.
const GRADIENT_STEP: f64 = 1e-6;

/// One-sigma of `f(theta)` by first-order propagation of covariance `cov`.
pub fn propagate(f: impl Fn(&[f64]) -> f64, theta: &[f64], cov: &DMatrix<f64>) -> Option<f64> {
    let n = theta.len();
    let f0 = f(theta);
    let grad: Vec<f64> = (0..n)
        .map(|j| {
            let h = GRADIENT_STEP * theta[j].abs().max(1.0);
            let mut t = theta.to_vec();
            t[j] += h;
            (f(&t) - f0) / h
        })
        .collect();
    let mut var = 0.0;
    for i in 0..n {
        for j in 0..n {
            var += grad[i] * cov[(i, j)] * grad[j];
        }
    }
    (var.is_finite() && var >= 0.0).then(|| var.sqrt())
}

/// The pairs of free parameters whose estimates correlate beyond
/// [`INSEPARABLE_CORRELATION`], as sentences.
pub fn inseparable(free: &[GreyParameter], cov: &DMatrix<f64>) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..free.len() {
        for j in i + 1..free.len() {
            let r = cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).sqrt();
            if r.abs() > INSEPARABLE_CORRELATION {
                out.push(format!(
                    "{} and {} are not separable by these recordings (correlation {r:.3}): only a combination of them is determined",
                    free[i].key(),
                    free[j].key()
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn propagation_of_a_product_adds_relative_variances() {
        // f = exp(a) exp(b), sigma_a = 0.1, sigma_b = 0.2, independent: rel. sigma sqrt(0.05)
        let cov = DMatrix::from_row_slice(2, 2, &[0.01, 0.0, 0.0, 0.04]);
        let s = propagate(|t| (t[0] + t[1]).exp(), &[0.0, 0.0], &cov).unwrap();
        assert!((s - 0.05f64.sqrt()).abs() < 1e-5, "{s}");
    }

    #[test]
    fn correlated_pairs_are_named() {
        use GreyParameter::*;
        let cov = DMatrix::from_row_slice(2, 2, &[1.0, 0.99, 0.99, 1.0]);
        let v = inseparable(&[BulkModulus, TableMass], &cov);
        assert_eq!(v.len(), 1);
        assert!(v[0].contains("actuator.bulk_modulus_pa") && v[0].contains("table.mass_kg"));
        let cov = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.5, 1.0]);
        assert!(inseparable(&[BulkModulus, TableMass], &cov).is_empty());
    }

    #[test]
    fn the_loop_gain_of_the_defaults() {
        let p = Params::trees_lab();
        let c = combinations(&p, &[GreyParameter::DisplacementGain], None);
        assert_eq!(c.len(), 1);
        // 10 * 1 * 0.2 / 0.0911
        assert!((c[0].value - 21.954).abs() < 1e-2, "{}", c[0].value);
    }
}

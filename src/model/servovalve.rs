//! Servovalve spool dynamics (spec section 3, paper eqs. 4.1-4.2).

use crate::params::{Servovalve, ServovalveModel};
use std::f64::consts::PI;

/// Precomputed spool-dynamics coefficients.
#[derive(Debug, Clone, Copy)]
pub struct SpoolDynamics {
    pub model: ServovalveModel,
    pub gain: f64,
    pub tau_s: f64,
    pub omega_rad_s: f64,
    pub damping_ratio: f64,
    /// `1/tau`, `w^2` and `2 xi w`, precomputed for the hot path.
    inv_tau: f64,
    omega_sq: f64,
    two_xi_omega: f64,
}

impl SpoolDynamics {
    pub fn new(p: &Servovalve) -> Self {
        let w = 2.0 * PI * p.natural_frequency_hz;
        SpoolDynamics {
            inv_tau: 1.0 / p.time_constant_s,
            omega_sq: w * w,
            two_xi_omega: 2.0 * p.damping_ratio * w,
            model: p.model,
            gain: p.gain,
            tau_s: p.time_constant_s,
            omega_rad_s: 2.0 * PI * p.natural_frequency_hz,
            damping_ratio: p.damping_ratio,
        }
    }

    /// Spool derivatives `(x_v', x_v'')` for the command `u` and spool state `(x_v, x_v')`.
    /// The `delay` variant has no state: its spool is `Ks u(t - tau)`, kept by the solver.
    #[inline]
    pub fn derivatives(&self, u: f64, xv: f64, xv_dot: f64) -> (f64, f64) {
        match self.model {
            ServovalveModel::Delay => (0.0, 0.0),
            // eq. 4.1: tau x_v' + x_v = Ks u
            ServovalveModel::FirstOrder => ((self.gain * u - xv) * self.inv_tau, 0.0),
            // eq. 4.2: x_v'' + 2 xi w x_v' + w^2 x_v = w^2 Ks u
            ServovalveModel::SecondOrder => (
                xv_dot,
                self.omega_sq * (self.gain * u - xv) - self.two_xi_omega * xv_dot,
            ),
        }
    }
}

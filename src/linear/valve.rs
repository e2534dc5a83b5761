//! The servovalve as a transfer function from command to spool (spec section 3; paper
//! eqs. 4.1-4.2), and its state-space realisation for the closed-loop poles.

use super::PADE_ORDER;
use crate::params::{Params, ServovalveModel};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use std::f64::consts::PI;

/// The servovalve as a transfer function from command to spool (spec section 3).
#[derive(Debug, Clone, Copy)]
pub enum ValveTf {
    Delay {
        gain: f64,
        tau_s: f64,
    },
    FirstOrder {
        gain: f64,
        tau_s: f64,
    },
    SecondOrder {
        gain: f64,
        omega_rad_s: f64,
        damping_ratio: f64,
    },
}

impl ValveTf {
    /// The servovalve of parameter set `p`.
    pub fn new(p: &Params) -> Self {
        let v = &p.servovalve;
        match v.model {
            ServovalveModel::Delay => ValveTf::Delay {
                gain: v.gain,
                tau_s: v.time_constant_s,
            },
            ServovalveModel::FirstOrder => ValveTf::first_order(v.gain, v.time_constant_s),
            ServovalveModel::SecondOrder => {
                ValveTf::second_order(v.gain, v.natural_frequency_hz, v.damping_ratio)
            }
        }
    }

    /// The first-order valve of paper eq. 4.1, `Ks / (1 + s tau)`.
    pub fn first_order(gain: f64, tau_s: f64) -> Self {
        ValveTf::FirstOrder { gain, tau_s }
    }

    /// The second-order valve of paper eq. 4.2, `Ks w^2 / (s^2 + 2 xi w s + w^2)`, with
    /// `w = 2 pi natural_frequency_hz`.
    pub fn second_order(gain: f64, natural_frequency_hz: f64, damping_ratio: f64) -> Self {
        ValveTf::SecondOrder {
            gain,
            omega_rad_s: 2.0 * PI * natural_frequency_hz,
            damping_ratio,
        }
    }

    /// `x_v(s) / u(s)`.
    pub fn response(&self, s: Complex64) -> Complex64 {
        match *self {
            ValveTf::Delay { gain, tau_s } => gain * (-s * tau_s).exp(),
            ValveTf::FirstOrder { gain, tau_s } => gain / (1.0 + s * tau_s),
            ValveTf::SecondOrder {
                gain,
                omega_rad_s: w,
                damping_ratio: xi,
            } => gain * w * w / (s * s + 2.0 * xi * w * s + w * w),
        }
    }

    /// A state-space realisation `(A, B, C, D)`; the delay as a Pade approximant of
    /// order [`PADE_ORDER`] (controllable canonical form).
    pub fn state_space(&self) -> (DMatrix<f64>, DVector<f64>, DVector<f64>, f64) {
        match *self {
            ValveTf::FirstOrder { gain, tau_s } => (
                DMatrix::from_element(1, 1, -1.0 / tau_s),
                DVector::from_element(1, gain / tau_s),
                DVector::from_element(1, 1.0),
                0.0,
            ),
            ValveTf::SecondOrder {
                gain,
                omega_rad_s: w,
                damping_ratio: xi,
            } => (
                DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w * w, -2.0 * xi * w]),
                DVector::from_row_slice(&[0.0, w * w * gain]),
                DVector::from_row_slice(&[1.0, 0.0]),
                0.0,
            ),
            ValveTf::Delay { gain, tau_s } => pade_delay(gain, tau_s, PADE_ORDER),
        }
    }
}

/// `gain exp(-s tau)` as the diagonal Pade approximant of order `n` in `sigma = s tau`
/// (so the companion matrix stays well conditioned): `N(sigma)/D(sigma)` with
/// `D = sum c_k sigma^k`, `N = sum (-1)^k c_k sigma^k`, `c_k = (2n-k)! n! / ((2n)! k! (n-k)!)`.
fn pade_delay(gain: f64, tau_s: f64, n: usize) -> (DMatrix<f64>, DVector<f64>, DVector<f64>, f64) {
    let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
    let c: Vec<f64> = (0..=n)
        .map(|k| fact(2 * n - k) * fact(n) / (fact(2 * n) * fact(k) * fact(n - k)))
        .collect();
    // monic denominator in sigma
    let den: Vec<f64> = c.iter().map(|x| x / c[n]).collect();
    let num: Vec<f64> = (0..=n)
        .map(|k| gain * if k % 2 == 0 { den[k] } else { -den[k] })
        .collect();
    let d = num[n];
    // controllable canonical form in sigma; d/dt = (1/tau) d/dsigma-time
    let mut a = DMatrix::zeros(n, n);
    for i in 0..n - 1 {
        a[(i, i + 1)] = 1.0 / tau_s;
    }
    for k in 0..n {
        a[(n - 1, k)] = -den[k] / tau_s;
    }
    let mut b = DVector::zeros(n);
    b[n - 1] = 1.0 / tau_s;
    let cvec = DVector::from_iterator(n, (0..n).map(|k| num[k] - d * den[k]));
    (a, b, cvec, d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear::jw;

    #[test]
    fn pade_matches_delay_at_low_frequency() {
        let v = ValveTf::Delay {
            gain: 1.0,
            tau_s: 0.0137,
        };
        let (a, b, c, d) = v.state_space();
        for f in [1.0, 10.0, 30.0] {
            let s = jw(f);
            let n = a.nrows();
            let m = DMatrix::from_fn(n, n, |i, j| {
                (if i == j { s } else { Complex64::new(0.0, 0.0) }) - a[(i, j)]
            });
            let x = m.lu().solve(&b.map(|x| Complex64::new(x, 0.0))).unwrap();
            let h: Complex64 = (0..n).map(|i| c[i] * x[i]).sum::<Complex64>() + d;
            // Pade(4,4) error grows like (s tau)^9: 1e-7 at 1 Hz, ~2e-4 at 30 Hz
            let tol = if f <= 10.0 { 1e-5 } else { 1e-3 };
            assert!(
                (h - v.response(s)).norm() < tol,
                "f={f}: {h} vs {}",
                v.response(s)
            );
        }
    }
}

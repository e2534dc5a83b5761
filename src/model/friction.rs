//! Bouc-Wen viscoplastic friction (paper eqs. 4.14-4.15) with the optional Stribeck
//! stick-slip amplitude (spec section 7, `stick_slip`).

use crate::params::{Friction, StickSlip};

#[derive(Debug, Clone, Copy)]
pub struct BoucWen {
    pub force_n: f64,
    pub yield_displacement_m: f64,
    pub shape: f64,
    /// `1/Y`, precomputed.
    pub inv_yield: f64,
    /// `(r_s - 1)` when stick-slip is on, else 0.
    pub static_excess: f64,
    /// `1 / v_s^2` of the Stribeck term.
    pub inv_stribeck_sq: f64,
}

impl BoucWen {
    pub fn new(f: &Friction, s: &StickSlip) -> Self {
        let (static_excess, inv_stribeck_sq) = if s.enabled {
            (s.static_ratio - 1.0, 1.0 / s.stribeck_velocity_m_s.powi(2))
        } else {
            (0.0, 0.0)
        };
        BoucWen {
            force_n: f.force_n,
            yield_displacement_m: f.yield_displacement_m,
            shape: f.shape,
            inv_yield: 1.0 / f.yield_displacement_m,
            static_excess,
            inv_stribeck_sq,
        }
    }

    /// Dissipative force `F_D = F_mu(v) Z` (eq. 4.14; stick-slip amplitude of spec section 7).
    #[inline]
    pub fn force(&self, z: f64, v: f64) -> f64 {
        let amplitude = if self.static_excess != 0.0 {
            self.force_n * (1.0 + self.static_excess * (-(v * v) * self.inv_stribeck_sq).exp())
        } else {
            self.force_n
        };
        amplitude * z
    }

    /// `Z' = (1 - Z^2 (b + (1 - b) sign(Z v))) v / Y` (eq. 4.15).
    #[inline]
    pub fn z_rate(&self, z: f64, v: f64) -> f64 {
        let b = self.shape;
        let sign = if z * v > 0.0 {
            1.0
        } else if z * v < 0.0 {
            -1.0
        } else {
            0.0
        };
        (1.0 - z * z * (b + (1.0 - b) * sign)) * v * self.inv_yield
    }
}

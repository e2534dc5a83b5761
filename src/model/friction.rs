//! Bouc-Wen viscoplastic friction (paper eqs. 4.14-4.15) with the optional Stribeck
//! stick-slip amplitude (spec section 7, `stick_slip`, in [`crate::effects::stick_slip`]).

use crate::effects::stick_slip::Stribeck;
use crate::params::{Friction, StickSlip};

#[derive(Debug, Clone, Copy)]
pub struct BoucWen {
    pub force_n: f64,
    pub yield_displacement_m: f64,
    pub shape: f64,
    /// `1/Y`, precomputed.
    pub inv_yield: f64,
    /// The stick-slip Stribeck term (zero when the effect is off).
    pub stribeck: Stribeck,
    /// Amplitude factors while `Z > 0` and `Z <= 0` (`friction_asymmetry`; 1 when off).
    pub direction: (f64, f64),
}

impl BoucWen {
    pub fn new(f: &Friction, s: &StickSlip) -> Self {
        BoucWen {
            force_n: f.force_n,
            yield_displacement_m: f.yield_displacement_m,
            shape: f.shape,
            inv_yield: 1.0 / f.yield_displacement_m,
            stribeck: s.stribeck(),
            direction: (1.0, 1.0),
        }
    }

    /// With the direction factors of `friction_asymmetry` (spec section 7).
    pub fn with_direction(mut self, a: &crate::params::FrictionAsymmetry) -> Self {
        self.direction = a.factors();
        self
    }

    /// Dissipative force `F_D = F_mu(v) Z` (eq. 4.14; stick-slip amplitude of spec section 7).
    #[inline]
    pub fn force(&self, z: f64, v: f64) -> f64 {
        let side = if z > 0.0 {
            self.direction.0
        } else {
            self.direction.1
        };
        self.stribeck.amplitude(self.force_n, v) * z * side
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

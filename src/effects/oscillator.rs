//! A mass on a spring and damper: the physics shared by the `specimen` and `foundation`
//! effects (spec section 7).

use std::f64::consts::PI;

/// A mass on a spring and damper: `k = m (2 pi f)^2`, `c = 2 zeta m 2 pi f`.
#[derive(Debug, Clone, Copy)]
pub struct Oscillator {
    pub enabled: bool,
    pub mass_kg: f64,
    pub stiffness_n_m: f64,
    pub damping_n_s_m: f64,
}

impl Oscillator {
    pub(crate) fn new(enabled: bool, mass_kg: f64, frequency_hz: f64, damping_ratio: f64) -> Self {
        let w = 2.0 * PI * frequency_hz;
        Oscillator {
            enabled,
            mass_kg,
            stiffness_n_m: mass_kg * w * w,
            damping_n_s_m: 2.0 * damping_ratio * mass_kg * w,
        }
    }

    /// The force its base feels per unit base acceleration at `frequency_hz` (its apparent
    /// mass): `m (k + i c w) / (k - m w^2 + i c w)`, the mass itself at low frequency,
    /// peaking near resonance; zero when disabled.
    pub fn apparent_mass(&self, frequency_hz: f64) -> num_complex::Complex64 {
        if !self.enabled {
            return num_complex::Complex64::new(0.0, 0.0);
        }
        let w = 2.0 * PI * frequency_hz;
        let spring = num_complex::Complex64::new(self.stiffness_n_m, self.damping_n_s_m * w);
        self.mass_kg * spring / (spring - self.mass_kg * w * w)
    }

    /// Spring-damper force on the oscillator's mass at `(x, v)` relative to its base.
    #[inline]
    pub fn restoring_force(&self, x_rel: f64, v_rel: f64) -> f64 {
        -(self.stiffness_n_m * x_rel + self.damping_n_s_m * v_rel)
    }
}

//! Payload: rigid table on a horizontal spring (spec section 5, paper eq. 4.4).

use crate::params::{FreePlay, Table};

#[derive(Debug, Clone, Copy)]
pub struct Payload {
    pub mass_kg: f64,
    /// `1/M`, precomputed: the derivative function multiplies instead of dividing.
    pub inv_mass: f64,
    pub stiffness_n_m: f64,
}

impl Payload {
    pub fn new(t: &Table) -> Self {
        Payload {
            mass_kg: t.mass_kg,
            inv_mass: 1.0 / t.mass_kg,
            stiffness_n_m: t.stiffness_n_m,
        }
    }

    /// With `free_play` on, the rod's mass moves with the piston and the table keeps
    /// `M - m_r` (spec section 7, second part); unchanged when it is off.
    pub fn without_rod(self, f: &FreePlay) -> Self {
        if !f.enabled {
            return self;
        }
        let mass_kg = self.mass_kg - f.rod_mass_kg;
        Payload {
            mass_kg,
            inv_mass: 1.0 / mass_kg,
            ..self
        }
    }

    /// Elastic force `F_E = k_h x` on the stroke relative to the reaction mass.
    #[inline]
    pub fn elastic_force(&self, x_rel: f64) -> f64 {
        self.stiffness_n_m * x_rel
    }

    /// `M a = F_A - F_D - F_E + F_specimen + F_external` (spec section 5).
    #[inline]
    pub fn acceleration(&self, net_force_n: f64) -> f64 {
        net_force_n * self.inv_mass
    }
}

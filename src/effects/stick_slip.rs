//! `stick_slip`: static friction above kinetic, a Stribeck amplitude on the Bouc-Wen
//! friction (spec section 7): `F_mu(v) = F_mu (1 + (r_s - 1) exp(-v^2 / v_s^2))`.

use super::{parameter, switch, Effect, SignatureTests, EVERY};
use crate::campaign::Measured;
use crate::params::Rule::{AtLeastOne, Positive};
use serde::{Deserialize, Serialize};

/// Static friction above kinetic (spec section 7, `stick_slip`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StickSlip {
    pub enabled: bool,
    /// r_s: static over kinetic friction.
    pub static_ratio: f64,
    /// v_s: Stribeck velocity, m/s.
    pub stribeck_velocity_m_s: f64,
}

impl Default for StickSlip {
    fn default() -> Self {
        StickSlip {
            enabled: false,
            static_ratio: 2.0,
            stribeck_velocity_m_s: 0.005,
        }
    }
}

/// The Stribeck term precomputed for the friction model: `(r_s - 1)` and `1 / v_s^2`,
/// both 0 when stick-slip is off.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stribeck {
    pub static_excess: f64,
    pub inv_stribeck_sq: f64,
}

impl StickSlip {
    /// Physics hook: the precomputed Stribeck term.
    pub fn stribeck(&self) -> Stribeck {
        let (static_excess, inv_stribeck_sq) = if self.enabled {
            (
                self.static_ratio - 1.0,
                1.0 / self.stribeck_velocity_m_s.powi(2),
            )
        } else {
            (0.0, 0.0)
        };
        Stribeck {
            static_excess,
            inv_stribeck_sq,
        }
    }
}

impl Stribeck {
    /// Friction amplitude at velocity `v` from the kinetic amplitude `force_n`.
    #[inline]
    pub fn amplitude(&self, force_n: f64, v: f64) -> f64 {
        if self.static_excess != 0.0 {
            force_n * (1.0 + self.static_excess * (-(v * v) * self.inv_stribeck_sq).exp())
        } else {
            force_n
        }
    }
}

pub const EFFECT: Effect = Effect {
    name: "stick_slip",
    switch: switch!(stick_slip, fmu: "stick_slip.enabled", vr: 160,
        "Static friction above kinetic friction (Stribeck)"),
    parameters: &[
        parameter!(stick_slip.static_ratio, fmu: "stick_slip.static_ratio", vr: 161, unit: None,
            rule: AtLeastOne, fit: (1.0, 6.0), "Static to kinetic friction ratio r_s"),
        parameter!(stick_slip.stribeck_velocity_m_s, fmu: "stick_slip.stribeck_velocity",
            vr: 162, unit: Some("m/s"), rule: Positive, fit: (1e-4, 0.05),
            "Stribeck velocity v_s"),
    ],
    unfitted: &[],
    cross_check: None,
    help: "",
    // the friction-dominated sines creep through the Stribeck range twice a cycle, as
    // do the slowest triangles (S1, S2, S4, S5, S7, S8, T1, T3)
    signature_tests: SignatureTests {
        random: &[],
        slow_sines: EVERY,
        slow_triangles: 2,
        fast_sines: 0,
    },
    no_effect: &[("static_ratio", 1.0)],
    signature_channels: &[&[Measured::Force], &[Measured::Acceleration]],
};

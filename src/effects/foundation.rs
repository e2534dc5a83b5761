//! `foundation`: a compliant reaction mass on spring and damper (spec section 7). The
//! actuator, friction and table stiffness push it back ([`Oscillator`]).

use super::oscillator::Oscillator;
use super::{parameter, switch, Effect, RandomRole, SignatureTests};
use crate::campaign::Measured;
use crate::params::Rule::{NonNegative, Positive};
use serde::{Deserialize, Serialize};

/// Compliant reaction mass (spec section 7, `foundation`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Foundation {
    pub enabled: bool,
    pub mass_kg: f64,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
}

impl Default for Foundation {
    fn default() -> Self {
        Foundation {
            enabled: false,
            mass_kg: 1.0e6,
            frequency_hz: 20.0,
            damping_ratio: 0.05,
        }
    }
}

impl Foundation {
    /// Physics hook: the reaction mass on its spring and damper.
    pub fn oscillator(&self) -> Oscillator {
        Oscillator::new(
            self.enabled,
            self.mass_kg,
            self.frequency_hz,
            self.damping_ratio,
        )
    }
}

pub const EFFECT: Effect = Effect {
    name: "foundation",
    switch: switch!(foundation, fmu: "foundation.enabled", vr: 150, "Compliant reaction mass"),
    parameters: &[
        parameter!(foundation.mass_kg, fmu: "foundation.mass", vr: 151, unit: Some("kg"),
            rule: Positive, fit: (1e4, 1e8), "Reaction mass M_f"),
        parameter!(foundation.frequency_hz, fmu: "foundation.frequency", vr: 152,
            unit: Some("Hz"), rule: Positive, fit: (2.0, 100.0),
            "Foundation natural frequency (M_f alone)"),
        parameter!(foundation.damping_ratio, fmu: "foundation.damping_ratio", vr: 153,
            unit: None, rule: NonNegative, fit: (0.002, 0.5), "Foundation damping ratio"),
    ],
    unfitted: &[],
    cross_check: None,
    help: "",
    // the broadest random tests show a stiff foundation's mode, the fastest sine's
    // forces its deflection in the LVDT (R1, R3, S9)
    signature_tests: SignatureTests {
        random: &[RandomRole::Valve, RandomRole::OilColumn],
        slow_sines: 0,
        slow_triangles: 0,
        fast_sines: 1,
    },
    no_effect: &[],
    signature_channels: &[
        &[Measured::Force],
        &[Measured::Acceleration, Measured::Displacement],
    ],
};

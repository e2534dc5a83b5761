//! `specimen`: a flexible SDOF specimen on the table (spec section 7). The model adds its
//! mass-spring-damper ([`Oscillator`]) on top of the table.

use super::oscillator::Oscillator;
use super::{parameter, switch, Effect};
use crate::params::Rule::{NonNegative, Positive};
use serde::{Deserialize, Serialize};

/// Flexible SDOF specimen on the table (spec section 7, `specimen`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Specimen {
    pub enabled: bool,
    pub mass_kg: f64,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
}

impl Default for Specimen {
    fn default() -> Self {
        Specimen {
            enabled: false,
            mass_kg: 10_000.0,
            frequency_hz: 5.0,
            damping_ratio: 0.02,
        }
    }
}

impl Specimen {
    /// Physics hook: the specimen's mass on spring and damper.
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
    name: "specimen",
    switch: switch!(specimen, fmu: "specimen.enabled", vr: 140,
        "Flexible SDOF specimen on the table"),
    parameters: &[
        parameter!(specimen.mass_kg, fmu: "specimen.mass", vr: 141, unit: Some("kg"),
            rule: Positive, fit: (200.0, 2e5), "Specimen mass"),
        parameter!(specimen.frequency_hz, fmu: "specimen.frequency", vr: 142, unit: Some("Hz"),
            rule: Positive, fit: (0.5, 60.0), "Specimen natural frequency"),
        parameter!(specimen.damping_ratio, fmu: "specimen.damping_ratio", vr: 143, unit: None,
            rule: NonNegative, fit: (0.002, 0.5), "Specimen damping ratio"),
    ],
    signature_tests: &["R2", "R3"],
};

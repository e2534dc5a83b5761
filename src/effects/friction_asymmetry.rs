//! `friction_asymmetry`: the friction amplitude depends on the sliding direction (spec
//! section 7, second part): `F_mu 2r/(1+r)` while `Z > 0`, `F_mu 2/(1+r)` while `Z <= 0`,
//! so the mean of the two is kept.

use super::{parameter, switch, Effect, SignatureTests};
use crate::campaign::Measured;
use crate::params::Rule::Positive;
use serde::{Deserialize, Serialize};

/// Direction-dependent friction (spec section 7, `friction_asymmetry`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionAsymmetry {
    pub enabled: bool,
    /// Friction while sliding positively over friction while sliding negatively.
    pub ratio: f64,
}

impl Default for FrictionAsymmetry {
    fn default() -> Self {
        FrictionAsymmetry {
            enabled: false,
            ratio: 1.5,
        }
    }
}

impl FrictionAsymmetry {
    /// Physics hook: the amplitude factors `(Z > 0, Z <= 0)`; `(1, 1)` when off.
    pub fn factors(&self) -> (f64, f64) {
        direction_factors(self.enabled, self.ratio)
    }
}

/// `(2r/(1+r), 2/(1+r))` when on, `(1, 1)` when off: the positive and negative sides of
/// an asymmetry of ratio `r` whose mean is 1.
pub fn direction_factors(enabled: bool, ratio: f64) -> (f64, f64) {
    if enabled {
        (2.0 * ratio / (1.0 + ratio), 2.0 / (1.0 + ratio))
    } else {
        (1.0, 1.0)
    }
}

pub const EFFECT: Effect = Effect {
    name: "friction_asymmetry",
    switch: switch!(friction_asymmetry, fmu: "friction_asymmetry.enabled", vr: 240,
        "Friction that depends on the sliding direction"),
    parameters: &[
        parameter!(friction_asymmetry.ratio, fmu: "friction_asymmetry.ratio", vr: 241,
            unit: None, rule: Positive, fit: (0.2, 5.0),
            "Friction sliding positively over friction sliding negatively"),
    ],
    unfitted: &[],
    cross_check: None,
    help: "",
    // the slowest triangles and sines, where friction is most of the force (T1, T3,
    // S1, S4)
    signature_tests: SignatureTests {
        random: &[],
        slow_sines: 2,
        slow_triangles: 2,
        fast_sines: 0,
    },
    no_effect: &[("ratio", 1.0)],
    signature_channels: &[&[Measured::Force], &[Measured::Acceleration]],
};

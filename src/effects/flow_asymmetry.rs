//! `flow_asymmetry`: the valve's flow gain depends on the spool's sign (spec section 7,
//! second part): `Kq 2r/(1+r)` for a positive spool, `Kq 2/(1+r)` for a negative one
//! (the mean is kept); with the nonlinear actuator it scales the orifice coefficient alike.

use super::friction_asymmetry::direction_factors;
use super::{parameter, switch, Effect, RandomRole, SignatureTests};
use crate::campaign::Measured;
use crate::params::Rule::Positive;
use serde::{Deserialize, Serialize};

/// Direction-dependent valve flow (spec section 7, `flow_asymmetry`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlowAsymmetry {
    pub enabled: bool,
    /// Flow gain for a positive spool over flow gain for a negative one.
    pub ratio: f64,
}

impl Default for FlowAsymmetry {
    fn default() -> Self {
        FlowAsymmetry {
            enabled: false,
            ratio: 1.2,
        }
    }
}

impl FlowAsymmetry {
    /// Physics hook: the flow factors `(positive spool, negative spool)`; `(1, 1)` off.
    pub fn factors(&self) -> (f64, f64) {
        direction_factors(self.enabled, self.ratio)
    }
}

pub const EFFECT: Effect = Effect {
    name: "flow_asymmetry",
    switch: switch!(flow_asymmetry, fmu: "flow_asymmetry.enabled", vr: 250,
        "Valve flow gain that depends on the spool's sign"),
    parameters: &[
        parameter!(flow_asymmetry.ratio, fmu: "flow_asymmetry.ratio", vr: 251,
            unit: None, rule: Positive, fit: (0.2, 5.0),
            "Flow gain for a positive spool over flow gain for a negative spool"),
    ],
    unfitted: &[],
    cross_check: None,
    help: "",
    // the fastest sines and the mass test demand the most flow (S9, S6, R2)
    signature_tests: SignatureTests {
        random: &[RandomRole::Mass],
        slow_sines: 0,
        slow_triangles: 0,
        fast_sines: 2,
    },
    no_effect: &[("ratio", 1.0)],
    signature_channels: &[&[Measured::Displacement], &[Measured::Acceleration]],
};

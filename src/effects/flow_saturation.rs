//! `flow_saturation`: bounded valve/supply flow (spec section 7): each metered flow is
//! clipped to `+-Q_max`.

use super::{parameter, switch, Effect, RandomRole, SignatureTests};
use crate::campaign::Measured;
use crate::params::Rule::Positive;
use serde::{Deserialize, Serialize};

/// Bounded valve/supply flow (spec section 7, `flow_saturation`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlowSaturation {
    pub enabled: bool,
    pub max_flow_m3_s: f64,
}

impl Default for FlowSaturation {
    fn default() -> Self {
        FlowSaturation {
            enabled: false,
            max_flow_m3_s: 0.1,
        }
    }
}

impl FlowSaturation {
    /// Physics hook: `Some(Q_max)` when the effect is on.
    pub fn max_flow(&self) -> Option<f64> {
        self.enabled.then_some(self.max_flow_m3_s)
    }
}

/// The flow `q` clipped to `+-max_flow` when saturation is on.
#[inline]
pub fn saturate(max_flow: Option<f64>, q: f64) -> f64 {
    match max_flow {
        Some(m) => q.clamp(-m, m),
        None => q,
    }
}

pub const EFFECT: Effect = Effect {
    name: "flow_saturation",
    switch: switch!(flow_saturation, fmu: "flow_saturation.enabled", vr: 170,
        "Bounded valve flow"),
    parameters: &[
        parameter!(flow_saturation.max_flow_m3_s, fmu: "flow_saturation.max_flow",
        vr: 171, unit: Some("m3/s"), rule: Positive, fit: (1e-4, 1.0), "Largest flow Q_max"),
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
    no_effect: &[],
    signature_channels: &[&[Measured::Displacement], &[Measured::Acceleration]],
};

//! `valve_deadband`: spool overlap (spec section 7): no flow while `|x_v| <= d`, the
//! opening shifted by `d` outside the band.

use super::{parameter, switch, Effect, RandomRole, SignatureTests};
use crate::campaign::Measured;
use crate::params::Rule::HalfOpenUnit;
use serde::{Deserialize, Serialize};

/// Spool overlap (spec section 7, `valve_deadband`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ValveDeadband {
    pub enabled: bool,
    /// Deadband d as a fraction of full spool.
    pub deadband: f64,
}

impl Default for ValveDeadband {
    fn default() -> Self {
        ValveDeadband {
            enabled: false,
            deadband: 0.02,
        }
    }
}

impl ValveDeadband {
    /// Physics hook: the deadband d, 0 when the effect is off.
    pub fn band(&self) -> f64 {
        if self.enabled {
            self.deadband
        } else {
            0.0
        }
    }
}

/// Spool opening that meters flow: zero inside the deadband, shifted outside it.
#[inline]
pub fn metering_opening(deadband: f64, xv: f64) -> f64 {
    if deadband == 0.0 {
        xv
    } else if xv.abs() <= deadband {
        0.0
    } else {
        xv - deadband.copysign(xv)
    }
}

pub const EFFECT: Effect = Effect {
    name: "valve_deadband",
    switch: switch!(valve_deadband, fmu: "valve_deadband.enabled", vr: 180,
        "Spool overlap (no flow inside the band)"),
    parameters: &[
        parameter!(valve_deadband.deadband, fmu: "valve_deadband.deadband",
        vr: 181, unit: None, rule: HalfOpenUnit, fit: (0.0, 0.2),
        "Deadband d (fraction of full spool)"),
    ],
    unfitted: &[],
    cross_check: None,
    help: "",
    // the mass test's small commands and the slowest reversals sit in the deadband
    // (R2, T1, T3, S1)
    signature_tests: SignatureTests {
        random: &[RandomRole::Mass],
        slow_sines: 1,
        slow_triangles: 2,
        fast_sines: 0,
    },
    no_effect: &[("deadband", 0.0)],
    signature_channels: &[
        &[Measured::Displacement],
        &[Measured::Acceleration],
        &[Measured::Force],
    ],
};

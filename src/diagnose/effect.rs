//! The catalogue effects diagnosis fits (spec section 7): names, parameters, where
//! their signature lives, how they are read from and applied to parameters, fitting bounds.

use crate::params::Params;
use serde::Serialize;

/// Catalogue effects (spec section 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    Specimen,
    Foundation,
    StickSlip,
    FlowSaturation,
    ValveDeadband,
}

pub const EFFECTS: [Effect; 5] = [
    Effect::Specimen,
    Effect::Foundation,
    Effect::StickSlip,
    Effect::FlowSaturation,
    Effect::ValveDeadband,
];

impl Effect {
    pub fn name(self) -> &'static str {
        match self {
            Effect::Specimen => "specimen",
            Effect::Foundation => "foundation",
            Effect::StickSlip => "stick_slip",
            Effect::FlowSaturation => "flow_saturation",
            Effect::ValveDeadband => "valve_deadband",
        }
    }

    /// Parameter names (spec section 7).
    pub fn parameters(self) -> &'static [&'static str] {
        match self {
            Effect::Specimen | Effect::Foundation => &["mass_kg", "frequency_hz", "damping_ratio"],
            Effect::StickSlip => &["static_ratio", "stribeck_velocity_m_s"],
            Effect::FlowSaturation => &["max_flow_m3_s"],
            Effect::ValveDeadband => &["deadband"],
        }
    }

    /// The fitting tests where its signature lives.
    pub(super) fn signature_tests(self) -> &'static [&'static str] {
        match self {
            Effect::Specimen => &["R2", "R3"],
            // the broadest random test shows a stiff foundation's mode, the largest
            // forces its deflection in the LVDT
            Effect::Foundation => &["R1", "R3", "S9"],
            // the slow sines creep through the Stribeck range twice a cycle
            Effect::StickSlip => &["S1", "S2", "S4", "S5", "S7", "S8", "T1", "T3"],
            Effect::FlowSaturation => &["S9", "S6", "R2"],
            Effect::ValveDeadband => &["R2", "T1", "T3", "S1"],
        }
    }

    /// The effect's parameters in `p` (the inverse of [`Effect::apply`]).
    pub(super) fn read(self, p: &Params) -> Vec<f64> {
        match self {
            Effect::Specimen => vec![
                p.specimen.mass_kg,
                p.specimen.frequency_hz,
                p.specimen.damping_ratio,
            ],
            Effect::Foundation => vec![
                p.foundation.mass_kg,
                p.foundation.frequency_hz,
                p.foundation.damping_ratio,
            ],
            Effect::StickSlip => vec![
                p.stick_slip.static_ratio,
                p.stick_slip.stribeck_velocity_m_s,
            ],
            Effect::FlowSaturation => vec![p.flow_saturation.max_flow_m3_s],
            Effect::ValveDeadband => vec![p.valve_deadband.deadband],
        }
    }

    /// Switch the effect on in `p` with its parameters `theta`.
    pub(super) fn apply(self, p: &mut Params, theta: &[f64]) {
        match self {
            Effect::Specimen => {
                p.specimen.enabled = true;
                p.specimen.mass_kg = theta[0];
                p.specimen.frequency_hz = theta[1];
                p.specimen.damping_ratio = theta[2];
            }
            Effect::Foundation => {
                p.foundation.enabled = true;
                p.foundation.mass_kg = theta[0];
                p.foundation.frequency_hz = theta[1];
                p.foundation.damping_ratio = theta[2];
            }
            Effect::StickSlip => {
                p.stick_slip.enabled = true;
                p.stick_slip.static_ratio = theta[0];
                p.stick_slip.stribeck_velocity_m_s = theta[1];
            }
            Effect::FlowSaturation => {
                p.flow_saturation.enabled = true;
                p.flow_saturation.max_flow_m3_s = theta[0];
            }
            Effect::ValveDeadband => {
                p.valve_deadband.enabled = true;
                p.valve_deadband.deadband = theta[0];
            }
        }
    }

    pub(super) fn bounds(self) -> (Vec<f64>, Vec<f64>) {
        match self {
            Effect::Specimen => (vec![200.0, 0.5, 0.002], vec![2e5, 60.0, 0.5]),
            Effect::Foundation => (vec![1e4, 2.0, 0.002], vec![1e8, 100.0, 0.5]),
            Effect::StickSlip => (vec![1.0, 1e-4], vec![6.0, 0.05]),
            Effect::FlowSaturation => (vec![1e-4], vec![1.0]),
            Effect::ValveDeadband => (vec![0.0], vec![0.2]),
        }
    }
}

//! Where the model switches: functions of the state and inputs that cross zero exactly
//! when a non-smooth term changes branch. A variable-step integrator (the FMU's Model
//! Exchange event indicators) stops there instead of stepping over the kink.
//! A switch that does not exist in a configuration reads a constant 1 (never crosses).

use super::{ix, Inputs, Model, SensorNoise, State};
use crate::params::ActuatorModel;

/// Number of switching functions.
pub const SWITCH_COUNT: usize = 10;

/// What each switching function marks, in order (for the FMU's documentation).
pub const SWITCHES: [&str; SWITCH_COUNT] = [
    "table velocity relative to the reaction mass (friction direction, Stribeck |v|)",
    "Bouc-Wen friction variable Z (the sign of Z v in eq. 4.15)",
    "1 - command before the clip (upper clip edge)",
    "command before the clip + 1 (lower clip edge)",
    "metering spool opening (nonlinear actuator: the orifice flows change chambers; flow asymmetry)",
    "1 - |metering spool opening| (nonlinear actuator: spool clip at full opening)",
    "|spool| - deadband (valve deadband edges)",
    "maximum flow - |flow into chamber A| (flow saturation)",
    "maximum flow - |flow out of chamber B| (flow saturation)",
    "contact of actuator rod and table: positive while it pushes (free play)",
];

/// A switch absent from the configuration: never crosses zero.
const ABSENT: f64 = 1.0;

impl Model {
    /// The switching functions at state `s` with inputs `inp` (noise-free feedback).
    pub fn switching_functions(&self, s: &State, inp: &Inputs) -> [f64; SWITCH_COUNT] {
        let alg = self.algebraic(s, inp, &SensorNoise::default(), 0.0);
        let h = &self.hydraulics;
        let xv = alg.spool_position;
        let opening = h.metering_opening(xv);
        let nonlinear = h.model == ActuatorModel::Nonlinear;
        let (qa, qb) = h.valve_flows(xv, s[ix::PA], s[ix::PB]);
        let saturation = |q: f64| h.max_flow.map_or(ABSENT, |m| m - q.abs());
        [
            alg.v_rel,
            s[ix::Z],
            1.0 - alg.command_before_clip,
            alg.command_before_clip + 1.0,
            if nonlinear || h.direction.0 != h.direction.1 {
                opening
            } else {
                ABSENT
            },
            if nonlinear {
                1.0 - opening.abs()
            } else {
                ABSENT
            },
            if h.deadband > 0.0 {
                xv.abs() - h.deadband
            } else {
                ABSENT
            },
            saturation(qa),
            saturation(qb),
            if self.contact.enabled {
                self.contact
                    .pushing(s[ix::XR] - s[ix::X], s[ix::VR] - s[ix::V])
            } else {
                ABSENT
            },
        ]
    }
}

//! The compared channels: their names, the measured and simulated samples of each, and
//! the feedback noise each carries.

use crate::campaign::Record;
use crate::{Outputs, SensorNoise};

/// The compared channels.
pub const CHANNELS: [&str; 5] = [
    "displacement",
    "acceleration",
    "force",
    "spool",
    "valve_command",
];

/// Channel `ch` of [`CHANNELS`] in a record (None when the record lacks it).
pub fn measured(r: &Record, ch: usize) -> Option<&[f64]> {
    match ch {
        0 => r.displacement_m.as_deref(),
        1 => r.acceleration_m_s2.as_deref(),
        2 => r.force_n.as_deref(),
        3 => r.spool_position.as_deref(),
        _ => r.valve_command.as_deref(),
    }
}

/// Channel `ch` of [`CHANNELS`] in simulated readings.
pub fn simulated(o: &Outputs, ch: usize) -> f64 {
    match ch {
        0 => o.displacement_m,
        1 => o.acceleration_m_s2,
        2 => o.actuator_force_n,
        3 => o.spool_position,
        _ => o.valve_command,
    }
}

/// The noise sample of channel `ch` that the feedback saw (none on the spool and command).
pub(super) fn fed_back(n: &SensorNoise, ch: usize) -> f64 {
    match ch {
        0 => n.displacement_m,
        1 => n.acceleration_m_s2,
        2 => n.force_n,
        _ => 0.0,
    }
}

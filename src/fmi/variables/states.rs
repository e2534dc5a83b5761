//! The model's continuous states as FMU variables (read in Co-Simulation, integrated by
//! a Model Exchange importer), each with its derivative.

use super::*;

pub(super) const fn state_row(
    vr: u32,
    name: &'static str,
    role: Role,
    unit: Option<&'static str>,
    description: &'static str,
) -> Variable {
    Variable {
        vr,
        name,
        kind: Kind::Real,
        role,
        unit,
        description,
        key: None,
        enumeration: None,
        feedthrough: &[],
    }
}

/// Value reference of the first state; its derivative's is [`DERIVATIVE_VR`] + index.
pub(super) const STATE_VR: u32 = 200;
pub(super) const DERIVATIVE_VR: u32 = 220;

/// One continuous state of the model as the FMU shows it (Model Exchange integrates
/// them; Co-Simulation lets them be read).
pub(super) struct StateRow {
    pub(super) name: &'static str,
    pub(super) derivative: &'static str,
    pub(super) unit: Option<&'static str>,
    pub(super) derivative_unit: Option<&'static str>,
    pub(super) description: &'static str,
    pub(super) derivative_description: &'static str,
}

/// The model's state vector, in [`crate::model::ix`] order.
pub(super) const STATES: [StateRow; crate::model::NX] = [
    StateRow { name: "state.spool_position", derivative: "der(state.spool_position)",
        unit: None, derivative_unit: Some("1/s"),
        description: "Servovalve spool position (first- and second-order valves)",
        derivative_description: "Spool speed" },
    StateRow { name: "state.spool_velocity", derivative: "der(state.spool_velocity)",
        unit: Some("1/s"), derivative_unit: Some("1/s2"),
        description: "Servovalve spool speed (second-order valve)",
        derivative_description: "Spool acceleration" },
    StateRow { name: "state.pressure_a", derivative: "der(state.pressure_a)",
        unit: Some("Pa"), derivative_unit: Some("Pa/s"),
        description: "Chamber A pressure (nonlinear actuator), or the load pressure P_a - P_b (ideal actuator)",
        derivative_description: "Rate of the first pressure state" },
    StateRow { name: "state.pressure_b", derivative: "der(state.pressure_b)",
        unit: Some("Pa"), derivative_unit: Some("Pa/s"),
        description: "Chamber B pressure (nonlinear actuator; unused by the ideal one)",
        derivative_description: "Rate of the second pressure state" },
    StateRow { name: "state.table_displacement", derivative: "der(state.table_displacement)",
        unit: Some("m"), derivative_unit: Some("m/s"),
        description: "Absolute table displacement",
        derivative_description: "Absolute table velocity" },
    StateRow { name: "state.table_velocity", derivative: "der(state.table_velocity)",
        unit: Some("m/s"), derivative_unit: Some("m/s2"),
        description: "Absolute table velocity",
        derivative_description: "Absolute table acceleration" },
    StateRow { name: "state.friction_z", derivative: "der(state.friction_z)",
        unit: None, derivative_unit: Some("1/s"),
        description: "Bouc-Wen friction variable Z, in [-1, 1]",
        derivative_description: "Rate of the friction variable" },
    StateRow { name: "state.specimen_displacement", derivative: "der(state.specimen_displacement)",
        unit: Some("m"), derivative_unit: Some("m/s"),
        description: "Absolute specimen displacement (specimen effect)",
        derivative_description: "Absolute specimen velocity" },
    StateRow { name: "state.specimen_velocity", derivative: "der(state.specimen_velocity)",
        unit: Some("m/s"), derivative_unit: Some("m/s2"),
        description: "Absolute specimen velocity (specimen effect)",
        derivative_description: "Absolute specimen acceleration" },
    StateRow { name: "state.foundation_displacement", derivative: "der(state.foundation_displacement)",
        unit: Some("m"), derivative_unit: Some("m/s"),
        description: "Reaction-mass displacement (foundation effect)",
        derivative_description: "Reaction-mass velocity" },
    StateRow { name: "state.foundation_velocity", derivative: "der(state.foundation_velocity)",
        unit: Some("m/s"), derivative_unit: Some("m/s2"),
        description: "Reaction-mass velocity (foundation effect)",
        derivative_description: "Reaction-mass acceleration" },
    StateRow { name: "state.specimen_mode2_displacement",
        derivative: "der(state.specimen_mode2_displacement)",
        unit: Some("m"), derivative_unit: Some("m/s"),
        description: "Absolute displacement of specimen mode 2 (specimen effect with several modes)",
        derivative_description: "Absolute velocity of specimen mode 2" },
    StateRow { name: "state.specimen_mode2_velocity",
        derivative: "der(state.specimen_mode2_velocity)",
        unit: Some("m/s"), derivative_unit: Some("m/s2"),
        description: "Absolute velocity of specimen mode 2 (specimen effect with several modes)",
        derivative_description: "Absolute acceleration of specimen mode 2" },
    StateRow { name: "state.specimen_mode3_displacement",
        derivative: "der(state.specimen_mode3_displacement)",
        unit: Some("m"), derivative_unit: Some("m/s"),
        description: "Absolute displacement of specimen mode 3 (specimen effect with several modes)",
        derivative_description: "Absolute velocity of specimen mode 3" },
    StateRow { name: "state.specimen_mode3_velocity",
        derivative: "der(state.specimen_mode3_velocity)",
        unit: Some("m/s"), derivative_unit: Some("m/s2"),
        description: "Absolute velocity of specimen mode 3 (specimen effect with several modes)",
        derivative_description: "Absolute acceleration of specimen mode 3" },
    StateRow { name: "state.rod_displacement", derivative: "der(state.rod_displacement)",
        unit: Some("m"), derivative_unit: Some("m/s"),
        description: "Absolute actuator-rod displacement (free_play effect; the LVDT reads it)",
        derivative_description: "Absolute actuator-rod velocity" },
    StateRow { name: "state.rod_velocity", derivative: "der(state.rod_velocity)",
        unit: Some("m/s"), derivative_unit: Some("m/s2"),
        description: "Absolute actuator-rod velocity (free_play effect)",
        derivative_description: "Absolute actuator-rod acceleration" },
];

//! The table's own rows of the variable table (inputs, outputs, parameters of the
//! controller, servovalve, actuator, table and friction) and the operating limits', with
//! the row-building macros and the structural choices' integer codes.

use super::*;
use crate::params::{ActuatorModel, ServovalveModel};

fn servovalve_code(m: ServovalveModel) -> f64 {
    match m {
        ServovalveModel::Delay => 1.0,
        ServovalveModel::FirstOrder => 2.0,
        ServovalveModel::SecondOrder => 3.0,
    }
}

fn servovalve_of(x: f64) -> Option<ServovalveModel> {
    match x as i64 {
        1 => Some(ServovalveModel::Delay),
        2 => Some(ServovalveModel::FirstOrder),
        3 => Some(ServovalveModel::SecondOrder),
        _ => None,
    }
}

fn actuator_of(x: f64) -> Option<ActuatorModel> {
    match x as i64 {
        1 => Some(ActuatorModel::Ideal),
        2 => Some(ActuatorModel::Nonlinear),
        _ => None,
    }
}

macro_rules! real_param {
    ($vr:expr, $name:expr, $unit:expr, $desc:expr, $($field:ident).+) => {
        Variable {
            vr: $vr,
            name: $name,
            kind: Kind::Real,
            role: Role::Parameter(|p| p.$($field).+, |p, v| p.$($field).+ = v),
            unit: $unit,
            description: $desc,
            key: Some(stringify!($($field).+)),
            enumeration: None,
            feedthrough: &[],
        }
    };
}

macro_rules! output {
    ($vr:expr, $name:expr, $unit:expr, $desc:expr, $field:ident) => {
        output!($vr, $name, $unit, $desc, $field, &[])
    };
    ($vr:expr, $name:expr, $unit:expr, $desc:expr, $field:ident, $feedthrough:expr) => {
        Variable {
            vr: $vr,
            name: $name,
            kind: Kind::Real,
            role: Role::Output(|o| o.$field),
            unit: $unit,
            description: $desc,
            key: None,
            enumeration: None,
            feedthrough: $feedthrough,
        }
    };
}

/// An input row (continuous; interpolated over a step with fmi2SetRealInputDerivatives).
macro_rules! input {
    ($vr:expr, $index:expr, $unit:expr, $desc:expr) => {
        Variable {
            vr: $vr,
            name: INPUTS[$index],
            kind: Kind::Real,
            role: Role::Input($index),
            unit: Some($unit),
            description: $desc,
            key: None,
            enumeration: None,
            feedthrough: &[],
        }
    };
}

/// A structural choice: an Integer on the C side, an Enumeration in the XML.
macro_rules! choice {
    ($vr:expr, $name:expr, $enumeration:expr, $desc:expr, $read:expr, $write:expr) => {
        Variable {
            vr: $vr,
            name: $name,
            kind: Kind::Integer,
            role: Role::Parameter($read, $write),
            unit: None,
            description: $desc,
            key: Some($name),
            enumeration: Some(&$enumeration),
            feedthrough: &[],
        }
    };
}

/// The controller's command reads the three references directly and, through the
/// acceleration feedback `Ka`, the external force; both through the clip to [-1, 1].
const VALVE_COMMAND_FEEDTHROUGH: &[Feedthrough] = &[
    Feedthrough {
        input: 0,
        kind: "dependent",
    },
    Feedthrough {
        input: 1,
        kind: "dependent",
    },
    Feedthrough {
        input: 2,
        kind: "dependent",
    },
    Feedthrough {
        input: 3,
        kind: "dependent",
    },
];

/// The table's acceleration is `(forces + F_ext) / M`: linear in the external force with
/// a factor fixed at initialization.
const ACCELERATION_FEEDTHROUGH: &[Feedthrough] = &[Feedthrough {
    input: 3,
    kind: "fixed",
}];

/// The rows before the effects'.
pub(super) const TABLE_VARIABLES: &[Variable] = &[
    input!(0, 0, "m", "Reference displacement the controller tracks"),
    input!(
        1,
        1,
        "m/s",
        "Reference velocity (time derivative of the reference displacement)"
    ),
    input!(
        2,
        2,
        "m/s2",
        "Reference acceleration (second derivative of the reference displacement)"
    ),
    input!(
        3,
        3,
        "N",
        "Force a co-simulated body (e.g. a specimen) applies to the table"
    ),
    output!(
        10,
        "displacement",
        Some("m"),
        "Table displacement measured by the actuator LVDT (relative to the reaction mass)",
        displacement_m
    ),
    output!(
        11,
        "velocity",
        Some("m/s"),
        "Table velocity relative to the reaction mass",
        velocity_m_s
    ),
    output!(
        12,
        "acceleration",
        Some("m/s2"),
        "Absolute table acceleration",
        acceleration_m_s2,
        ACCELERATION_FEEDTHROUGH
    ),
    output!(
        13,
        "actuator_force",
        Some("N"),
        "Actuator force: piston area times the chamber pressure difference",
        actuator_force_n
    ),
    output!(
        14,
        "valve_command",
        None,
        "Controller command to the servovalve, clipped to [-1, 1]",
        valve_command,
        VALVE_COMMAND_FEEDTHROUGH
    ),
    output!(
        15,
        "spool_position",
        None,
        "Servovalve spool position (fraction of full opening)",
        spool_position
    ),
    output!(
        16,
        "pressure_a",
        Some("Pa"),
        "Pressure in actuator chamber A",
        pressure_a_pa
    ),
    output!(
        17,
        "pressure_b",
        Some("Pa"),
        "Pressure in actuator chamber B",
        pressure_b_pa
    ),
    // controller: three-variable control with delta-P stabilisation
    real_param!(
        100,
        "controller.kp",
        Some("1/m"),
        "Displacement feedback gain Kp (valve command per metre of error)",
        controller.kp
    ),
    real_param!(
        101,
        "controller.kv",
        Some("s/m"),
        "Velocity feedback gain Kv",
        controller.kv
    ),
    real_param!(
        102,
        "controller.ka",
        Some("s2/m"),
        "Acceleration feedback gain Ka",
        controller.ka
    ),
    real_param!(
        103,
        "controller.fv",
        Some("s/m"),
        "Velocity feed-forward gain Fv",
        controller.fv
    ),
    real_param!(
        104,
        "controller.fa",
        Some("s2/m"),
        "Acceleration feed-forward gain Fa",
        controller.fa
    ),
    real_param!(
        105,
        "controller.kdp",
        Some("1/N"),
        "Delta-P stabilisation gain Kdp (valve command per newton of actuator force)",
        controller.kdp
    ),
    choice!(
        110,
        "servovalve.model",
        SERVOVALVE_MODELS,
        "Servovalve dynamics: delay (Co-Simulation only), first_order or second_order",
        |p| servovalve_code(p.servovalve.model),
        |p, v| {
            if let Some(m) = servovalve_of(v) {
                p.servovalve.model = m
            }
        }
    ),
    real_param!(
        111,
        "servovalve.gain",
        None,
        "Spool opening per unit command Ks",
        servovalve.gain
    ),
    real_param!(
        112,
        "servovalve.time_constant",
        Some("s"),
        "Time constant of the first-order valve, or the delay of the delay valve",
        servovalve.time_constant_s
    ),
    real_param!(
        113,
        "servovalve.natural_frequency",
        Some("Hz"),
        "Natural frequency of the second-order valve",
        servovalve.natural_frequency_hz
    ),
    real_param!(
        114,
        "servovalve.damping_ratio",
        None,
        "Damping ratio of the second-order valve",
        servovalve.damping_ratio
    ),
    choice!(
        120,
        "actuator.model",
        ACTUATOR_MODELS,
        "Actuator: ideal (linearised oil column) or nonlinear (two chambers, orifice flow)",
        |p| if p.actuator.model == ActuatorModel::Ideal {
            1.0
        } else {
            2.0
        },
        |p, v| {
            if let Some(m) = actuator_of(v) {
                p.actuator.model = m
            }
        }
    ),
    real_param!(
        121,
        "actuator.piston_area",
        Some("m2"),
        "Effective piston area",
        actuator.piston_area_m2
    ),
    real_param!(
        122,
        "actuator.total_oil_volume",
        Some("m3"),
        "Oil volume of both chambers and their lines",
        actuator.total_oil_volume_m3
    ),
    real_param!(
        123,
        "actuator.leakage",
        Some("m3/(s.Pa)"),
        "Cross-port leakage coefficient (flow per pressure difference)",
        actuator.leakage_m3_s_pa
    ),
    real_param!(
        124,
        "actuator.supply_pressure",
        Some("Pa"),
        "Hydraulic supply pressure",
        actuator.supply_pressure_pa
    ),
    real_param!(
        125,
        "oil_column.bulk_modulus",
        Some("Pa"),
        "Effective bulk modulus of the oil (with hoses and entrained air)",
        actuator.bulk_modulus_pa
    ),
    real_param!(
        126,
        "valve.flow_gain",
        Some("m3/s"),
        "Servovalve flow at full opening",
        actuator.flow_gain_m3_s
    ),
    real_param!(
        130,
        "table.mass",
        Some("kg"),
        "Moving mass of the table and its payload",
        table.mass_kg
    ),
    real_param!(
        131,
        "table.stiffness",
        Some("N/m"),
        "Horizontal stiffness holding the table (bearings, centring springs)",
        table.stiffness_n_m
    ),
    real_param!(
        132,
        "friction.force",
        Some("N"),
        "Sliding friction force of the bearings",
        friction.force_n
    ),
    real_param!(
        133,
        "friction.yield_displacement",
        Some("m"),
        "Pre-sliding displacement before friction is fully developed",
        friction.yield_displacement_m
    ),
    real_param!(
        134,
        "friction.shape",
        None,
        "Shape of the friction loop (Bouc-Wen b, from 0 to just under 1)",
        friction.shape
    ),
];

/// The rows after the effects': the operating limits (fmi2DoStep stops beyond them with
/// fmi2Error).
pub(super) const LIMIT_VARIABLES: &[Variable] = &[
    real_param!(
        190,
        "limits.stroke",
        Some("m"),
        "Actuator stroke: a step whose LVDT displacement passes 1.1 times it is an error",
        limits.stroke_m
    ),
    real_param!(
        191,
        "limits.velocity",
        Some("m/s"),
        "Velocity limit: a step whose table speed passes twice it is an error",
        limits.velocity_m_s
    ),
];

//! The one table of the FMU's variables: value reference, name, type, causality, unit,
//! description, and how each reads/writes the model's parameters or signals.
//! `modelDescription.xml` and the documentation page are generated from it.

use crate::effects::CATALOGUE;
use crate::model::{Inputs, Outputs};
use crate::params::{ActuatorModel, Params, ServovalveModel};

/// FMI type of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Real,
    Integer,
    Boolean,
}

/// What a variable is and where its value lives.
#[derive(Clone, Copy)]
pub enum Role {
    /// Continuous input, index into [`INPUTS`].
    Input(usize),
    /// Continuous output.
    Output(fn(&Outputs) -> f64),
    /// Fixed parameter: read and write the parameter block (Integer and Boolean values
    /// travel as f64 here).
    Parameter(fn(&Params) -> f64, fn(&mut Params, f64)),
    /// Continuous state, index into the model's state vector ([`crate::model::ix`]):
    /// a local variable, set only through fmi2SetContinuousStates (Model Exchange).
    State(usize),
    /// Time derivative of the state with this index.
    Derivative(usize),
}

/// One row of the table.
#[derive(Clone, Copy)]
pub struct Variable {
    pub vr: u32,
    pub name: &'static str,
    pub kind: Kind,
    pub role: Role,
    pub unit: Option<&'static str>,
    pub description: &'static str,
    /// Dotted parameter-file key of a parameter (`table.mass_kg`): its validation rule
    /// gives the FMU's `min`/`max`. `None` for inputs and outputs.
    pub key: Option<&'static str>,
    /// The enumeration of a structural choice (set and read as an Integer).
    pub enumeration: Option<&'static Enumeration>,
    /// The inputs an output depends on directly (within one instant), with FMI 2.0's
    /// `dependenciesKind`; empty when the output depends on the state alone.
    pub feedthrough: &'static [Feedthrough],
}

/// A direct dependency of an output on an input (ModelStructure `dependencies`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Feedthrough {
    /// Index into [`INPUTS`].
    pub input: usize,
    /// `fixed`: linear with a factor fixed after initialization; `dependent`: nonlinear.
    pub kind: &'static str,
}

/// An FMI enumeration type (TypeDefinitions) of a structural parameter.
#[derive(Debug)]
pub struct Enumeration {
    pub name: &'static str,
    pub items: &'static [EnumerationItem],
}

/// One item of an [`Enumeration`]: the parameter file's word and its Integer value.
#[derive(Debug)]
pub struct EnumerationItem {
    pub name: &'static str,
    pub value: i32,
    pub description: &'static str,
}

/// The servovalve models (spec section 3); `delay` is not offered in Model Exchange.
pub static SERVOVALVE_MODELS: Enumeration = Enumeration {
    name: "ServovalveModel",
    items: &[
        EnumerationItem {
            name: "delay",
            value: 1,
            description: "Pure delay of the command (Co-Simulation only)",
        },
        EnumerationItem {
            name: "first_order",
            value: 2,
            description: "First-order lag",
        },
        EnumerationItem {
            name: "second_order",
            value: 3,
            description: "Second-order spool dynamics",
        },
    ],
};

/// The actuator models (spec section 4).
pub static ACTUATOR_MODELS: Enumeration = Enumeration {
    name: "ActuatorModel",
    items: &[
        EnumerationItem {
            name: "ideal",
            value: 1,
            description: "Linearised oil column on the load pressure",
        },
        EnumerationItem {
            name: "nonlinear",
            value: 2,
            description: "Two chambers with the orifice equation",
        },
    ],
};

/// Names of the inputs, in [`Role::Input`] order.
pub const INPUTS: [&str; 4] = [
    "ref_displacement",
    "ref_velocity",
    "ref_acceleration",
    "external_force",
];

/// The model inputs from the four input values.
pub fn inputs_from(u: &[f64; 4]) -> Inputs {
    Inputs {
        reference: crate::model::Reference {
            displacement_m: u[0],
            velocity_m_s: u[1],
            acceleration_m_s2: u[2],
        },
        external_force_n: u[3],
    }
}

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

/// Whether `value` is allowed for a structural (Integer) parameter: one of its
/// enumeration's items.
pub fn integer_allowed(name: &str, value: i32) -> bool {
    match by_name(name).and_then(|v| v.enumeration) {
        Some(e) => e.items.iter().any(|i| i.value == value),
        None => true,
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

/// Every variable of the FMU, in modelDescription order: the table's own, then each
/// catalogue effect's switch and parameters ([`crate::effects::CATALOGUE`]), then the
/// operating limits. Built at compile time from the three parts.
pub static VARIABLES: &[Variable] = &ALL_VARIABLES;

/// Number of FMU rows the catalogue's effects declare (a switch plus its parameters each).
const fn effect_row_count() -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < CATALOGUE.len() {
        n += 1 + CATALOGUE[i].parameters.len() + CATALOGUE[i].unfitted.len();
        i += 1;
    }
    n
}

const ROW_COUNT: usize =
    TABLE_VARIABLES.len() + effect_row_count() + LIMIT_VARIABLES.len() + 2 * STATES.len();

const ALL_VARIABLES: [Variable; ROW_COUNT] = all_variables();

/// The table's rows, then per effect its Boolean switch and its Real parameters, then the
/// limits.
const fn all_variables() -> [Variable; ROW_COUNT] {
    let mut rows = [TABLE_VARIABLES[0]; ROW_COUNT];
    let mut n = 0;
    let mut i = 0;
    while i < TABLE_VARIABLES.len() {
        rows[n] = TABLE_VARIABLES[i];
        n += 1;
        i += 1;
    }
    let mut e = 0;
    while e < CATALOGUE.len() {
        let effect = &CATALOGUE[e];
        let switch = &effect.switch;
        rows[n] = Variable {
            vr: switch.value_reference,
            name: switch.fmu_name,
            kind: Kind::Boolean,
            role: Role::Parameter(switch.read, switch.write),
            unit: None,
            description: switch.description,
            key: Some(switch.dotted_key),
            enumeration: None,
            feedthrough: &[],
        };
        n += 1;
        // the fitted parameters, then the unfitted ones (a const fn cannot chain iterators)
        let mut k = 0;
        while k < effect.parameters.len() + effect.unfitted.len() {
            let q = if k < effect.parameters.len() {
                &effect.parameters[k]
            } else {
                &effect.unfitted[k - effect.parameters.len()]
            };
            rows[n] = Variable {
                vr: q.value_reference,
                name: q.fmu_name,
                kind: Kind::Real,
                role: Role::Parameter(q.read, q.write),
                unit: q.unit,
                description: q.description,
                key: Some(q.dotted_key),
                enumeration: None,
                feedthrough: &[],
            };
            n += 1;
            k += 1;
        }
        e += 1;
    }
    let mut i = 0;
    while i < LIMIT_VARIABLES.len() {
        rows[n] = LIMIT_VARIABLES[i];
        n += 1;
        i += 1;
    }
    let mut i = 0;
    while i < STATES.len() {
        let st = &STATES[i];
        rows[n] = state_row(
            STATE_VR + i as u32,
            st.name,
            Role::State(i),
            st.unit,
            st.description,
        );
        rows[n + STATES.len()] = state_row(
            DERIVATIVE_VR + i as u32,
            st.derivative,
            Role::Derivative(i),
            st.derivative_unit,
            st.derivative_description,
        );
        n += 1;
        i += 1;
    }
    rows
}

const fn state_row(
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
const STATE_VR: u32 = 200;
const DERIVATIVE_VR: u32 = 220;

/// One continuous state of the model as the FMU shows it (Model Exchange integrates
/// them; Co-Simulation lets them be read).
struct StateRow {
    name: &'static str,
    derivative: &'static str,
    unit: Option<&'static str>,
    derivative_unit: Option<&'static str>,
    description: &'static str,
    derivative_description: &'static str,
}

/// The model's state vector, in [`crate::model::ix`] order.
const STATES: [StateRow; crate::model::NX] = [
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
const TABLE_VARIABLES: &[Variable] = &[
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
const LIMIT_VARIABLES: &[Variable] = &[
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

/// The variable with value reference `vr`.
pub fn by_vr(vr: u32) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.vr == vr)
}

/// The variable named `name`.
pub fn by_name(name: &str) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.name == name)
}

/// One unit of the table: its SI base-unit exponents and the display unit labs read it
/// in (`display = factor * value`), for UnitDefinitions and each variable's `displayUnit`.
#[derive(Debug, Clone, Copy)]
pub struct Unit {
    pub name: &'static str,
    /// Exponents of kg, m and s.
    pub base: (i32, i32, i32),
    /// `(name, factor)` of the display unit.
    pub display: Option<(&'static str, f64)>,
}

/// Standard gravity, m/s^2: the `g` display unit of accelerations.
const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// Every unit the variables use.
pub const UNITS: &[Unit] = &[
    Unit {
        name: "m",
        base: (0, 1, 0),
        display: Some(("mm", 1e3)),
    },
    Unit {
        name: "m/s",
        base: (0, 1, -1),
        display: Some(("mm/s", 1e3)),
    },
    Unit {
        name: "m/s2",
        base: (0, 1, -2),
        display: Some(("g", 1.0 / STANDARD_GRAVITY_M_S2)),
    },
    Unit {
        name: "N",
        base: (1, 1, -2),
        display: Some(("kN", 1e-3)),
    },
    Unit {
        name: "Pa",
        base: (1, -1, -2),
        display: Some(("bar", 1e-5)),
    },
    Unit {
        name: "kg",
        base: (1, 0, 0),
        display: Some(("t", 1e-3)),
    },
    Unit {
        name: "N/m",
        base: (1, 0, -2),
        display: Some(("kN/mm", 1e-6)),
    },
    Unit {
        name: "m2",
        base: (0, 2, 0),
        display: Some(("cm2", 1e4)),
    },
    Unit {
        name: "m3",
        base: (0, 3, 0),
        display: Some(("l", 1e3)),
    },
    Unit {
        name: "m3/s",
        base: (0, 3, -1),
        display: Some(("l/min", 6e4)),
    },
    Unit {
        name: "m3/(s.Pa)",
        base: (-1, 4, 1),
        display: None,
    },
    Unit {
        name: "s",
        base: (0, 0, 1),
        display: Some(("ms", 1e3)),
    },
    Unit {
        name: "Hz",
        base: (0, 0, -1),
        display: None,
    },
    Unit {
        name: "1/s",
        base: (0, 0, -1),
        display: None,
    },
    Unit {
        name: "1/s2",
        base: (0, 0, -2),
        display: None,
    },
    Unit {
        name: "Pa/s",
        base: (1, -1, -3),
        display: Some(("bar/s", 1e-5)),
    },
    Unit {
        name: "1/m",
        base: (0, -1, 0),
        display: None,
    },
    Unit {
        name: "s/m",
        base: (0, -1, 1),
        display: None,
    },
    Unit {
        name: "s2/m",
        base: (0, -1, 2),
        display: None,
    },
    Unit {
        name: "1/N",
        base: (-1, -1, 2),
        display: None,
    },
];

/// The unit named `name`.
pub fn unit(name: &str) -> Option<&'static Unit> {
    UNITS.iter().find(|u| u.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_references_and_names_are_unique_and_units_defined() {
        for (i, a) in VARIABLES.iter().enumerate() {
            for b in &VARIABLES[i + 1..] {
                assert_ne!(a.vr, b.vr, "{} and {}", a.name, b.name);
                assert_ne!(a.name, b.name);
            }
            if let Some(u) = a.unit {
                assert!(unit(u).is_some(), "{u}");
            }
        }
    }

    /// Every parameter round-trips through its setter and changes the parameter file.
    #[test]
    fn every_parameter_reads_and_writes_its_block() {
        for v in VARIABLES {
            if let Role::Parameter(get, set) = v.role {
                let mut p = Params::trees_lab();
                let x = get(&p);
                let y = match v.kind {
                    Kind::Real => x * 1.25 + 0.001,
                    Kind::Boolean => 1.0 - x,
                    Kind::Integer => {
                        if x == 1.0 {
                            2.0
                        } else {
                            1.0
                        }
                    }
                };
                set(&mut p, y);
                assert_eq!(get(&p), y, "{}", v.name);
                assert_ne!(
                    p,
                    Params::trees_lab(),
                    "{} did not change the parameters",
                    v.name
                );
            }
        }
    }

    /// Every Real parameter names its parameter-file key, and that key has a validation
    /// rule (the FMU's min/max); every numeric key of the file has its variable.
    #[test]
    fn every_real_parameter_has_its_key_and_rule() {
        let entries = Params::trees_lab().numeric_entries();
        for v in VARIABLES {
            if let (Role::Parameter(get, _), Kind::Real) = (v.role, v.kind) {
                let key = v.key.unwrap_or_else(|| panic!("{} has no key", v.name));
                let (_, value) = entries.iter().find(|(k, _)| *k == key).unwrap();
                assert_eq!(*value, get(&Params::trees_lab()), "{key}");
                assert!(
                    crate::params::fmu_rule_of(key).is_some(),
                    "{key} has no rule"
                );
            }
        }
        for (key, _) in entries {
            assert!(
                VARIABLES.iter().any(|v| v.key == Some(key)),
                "{key} has no variable"
            );
        }
    }

    /// The structural choices accept exactly their enumeration's items.
    #[test]
    fn enumerations_bound_the_structural_choices() {
        assert!(integer_allowed("servovalve.model", 3));
        assert!(!integer_allowed("servovalve.model", 4));
        assert!(integer_allowed("actuator.model", 2));
        assert!(!integer_allowed("actuator.model", 0));
    }
}

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
}

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

/// Whether `value` is allowed for a structural (Integer) parameter.
pub fn integer_allowed(name: &str, value: i32) -> bool {
    match name {
        "servovalve.model" => servovalve_of(value as f64).is_some(),
        "actuator.model" => actuator_of(value as f64).is_some(),
        _ => true,
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
        }
    };
}

macro_rules! output {
    ($vr:expr, $name:expr, $unit:expr, $desc:expr, $field:ident) => {
        Variable {
            vr: $vr,
            name: $name,
            kind: Kind::Real,
            role: Role::Output(|o| o.$field),
            unit: $unit,
            description: $desc,
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
        n += 1 + CATALOGUE[i].parameters.len();
        i += 1;
    }
    n
}

const ROW_COUNT: usize = TABLE_VARIABLES.len() + effect_row_count() + LIMIT_VARIABLES.len();

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
        };
        n += 1;
        let mut k = 0;
        while k < effect.parameters.len() {
            let q = &effect.parameters[k];
            rows[n] = Variable {
                vr: q.value_reference,
                name: q.fmu_name,
                kind: Kind::Real,
                role: Role::Parameter(q.read, q.write),
                unit: q.unit,
                description: q.description,
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
    rows
}

/// The rows before the effects'.
const TABLE_VARIABLES: &[Variable] = &[
    // inputs (continuous; linear interpolation over a step with fmi2SetRealInputDerivatives)
    Variable {
        vr: 0,
        name: "ref_displacement",
        kind: Kind::Real,
        role: Role::Input(0),
        unit: Some("m"),
        description: "Reference displacement r (spec section 2)",
    },
    Variable {
        vr: 1,
        name: "ref_velocity",
        kind: Kind::Real,
        role: Role::Input(1),
        unit: Some("m/s"),
        description: "Reference velocity r'",
    },
    Variable {
        vr: 2,
        name: "ref_acceleration",
        kind: Kind::Real,
        role: Role::Input(2),
        unit: Some("m/s2"),
        description: "Reference acceleration r''",
    },
    Variable {
        vr: 3,
        name: "external_force",
        kind: Kind::Real,
        role: Role::Input(3),
        unit: Some("N"),
        description: "Force applied to the table by a co-simulated body (e.g. a specimen)",
    },
    // outputs
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
        acceleration_m_s2
    ),
    output!(
        13,
        "actuator_force",
        Some("N"),
        "Actuator force A (P_a - P_b)",
        actuator_force_n
    ),
    output!(
        14,
        "valve_command",
        None,
        "Controller command u in [-1, 1]",
        valve_command
    ),
    output!(
        15,
        "spool_position",
        None,
        "Servovalve spool position x_v (fraction of full stroke)",
        spool_position
    ),
    output!(
        16,
        "pressure_a",
        Some("Pa"),
        "Chamber A pressure (ideal actuator: P_s/2 + P_L/2)",
        pressure_a_pa
    ),
    output!(
        17,
        "pressure_b",
        Some("Pa"),
        "Chamber B pressure (ideal actuator: P_s/2 - P_L/2)",
        pressure_b_pa
    ),
    // controller (spec section 2)
    real_param!(
        100,
        "controller.kp",
        Some("1/m"),
        "Displacement feedback gain Kp",
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
        "Velocity feed-forward Fv",
        controller.fv
    ),
    real_param!(
        104,
        "controller.fa",
        Some("s2/m"),
        "Acceleration feed-forward Fa",
        controller.fa
    ),
    real_param!(
        105,
        "controller.kdp",
        Some("1/N"),
        "Delta-P (force) stabilisation Kdp",
        controller.kdp
    ),
    // servovalve (spec section 3)
    Variable {
        vr: 110,
        name: "servovalve.model",
        kind: Kind::Integer,
        role: Role::Parameter(
            |p| servovalve_code(p.servovalve.model),
            |p, v| {
                if let Some(m) = servovalve_of(v) {
                    p.servovalve.model = m
                }
            },
        ),
        unit: None,
        description: "Servovalve model: 1 = delay, 2 = first_order, 3 = second_order",
    },
    real_param!(
        111,
        "servovalve.gain",
        None,
        "Spool gain Ks",
        servovalve.gain
    ),
    real_param!(
        112,
        "servovalve.time_constant",
        Some("s"),
        "Time constant (first order) or delay (delay model) tau",
        servovalve.time_constant_s
    ),
    real_param!(
        113,
        "servovalve.natural_frequency",
        Some("Hz"),
        "Natural frequency f_v (second order)",
        servovalve.natural_frequency_hz
    ),
    real_param!(
        114,
        "servovalve.damping_ratio",
        None,
        "Damping ratio xi (second order)",
        servovalve.damping_ratio
    ),
    // actuator and oil column (spec section 4)
    Variable {
        vr: 120,
        name: "actuator.model",
        kind: Kind::Integer,
        role: Role::Parameter(
            |p| {
                if p.actuator.model == ActuatorModel::Ideal {
                    1.0
                } else {
                    2.0
                }
            },
            |p, v| {
                if let Some(m) = actuator_of(v) {
                    p.actuator.model = m
                }
            },
        ),
        unit: None,
        description: "Actuator model: 1 = ideal, 2 = nonlinear",
    },
    real_param!(
        121,
        "actuator.piston_area",
        Some("m2"),
        "Piston area A",
        actuator.piston_area_m2
    ),
    real_param!(
        122,
        "actuator.total_oil_volume",
        Some("m3"),
        "Total oil volume V_t",
        actuator.total_oil_volume_m3
    ),
    real_param!(
        123,
        "actuator.leakage",
        Some("m3/(s.Pa)"),
        "Cross-port leakage C_l",
        actuator.leakage_m3_s_pa
    ),
    real_param!(
        124,
        "actuator.supply_pressure",
        Some("Pa"),
        "Supply pressure P_s",
        actuator.supply_pressure_pa
    ),
    real_param!(
        125,
        "oil_column.bulk_modulus",
        Some("Pa"),
        "Effective bulk modulus beta",
        actuator.bulk_modulus_pa
    ),
    real_param!(
        126,
        "valve.flow_gain",
        Some("m3/s"),
        "Valve flow gain Kq per unit spool",
        actuator.flow_gain_m3_s
    ),
    // payload and friction (spec section 5)
    real_param!(
        130,
        "table.mass",
        Some("kg"),
        "Rigid table mass M",
        table.mass_kg
    ),
    real_param!(
        131,
        "table.stiffness",
        Some("N/m"),
        "Horizontal stiffness k_h",
        table.stiffness_n_m
    ),
    real_param!(
        132,
        "friction.force",
        Some("N"),
        "Bouc-Wen friction amplitude F_mu",
        friction.force_n
    ),
    real_param!(
        133,
        "friction.yield_displacement",
        Some("m"),
        "Bouc-Wen yield displacement Y",
        friction.yield_displacement_m
    ),
    real_param!(
        134,
        "friction.shape",
        None,
        "Bouc-Wen shape constant b in [0, 1)",
        friction.shape
    ),
];

/// The rows after the effects'.
const LIMIT_VARIABLES: &[Variable] = &[
    // operating limits (spec section 8): fmi2DoStep stops beyond them with fmi2Error
    real_param!(
        190,
        "limits.stroke",
        Some("m"),
        "Stroke: a step whose LVDT displacement passes 1.1 times it is an error",
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

/// SI base-unit exponents (kg, m, s) of every unit the table uses, for UnitDefinitions.
pub fn unit_exponents(unit: &str) -> Option<(i32, i32, i32)> {
    Some(match unit {
        "m" => (0, 1, 0),
        "m/s" => (0, 1, -1),
        "m/s2" => (0, 1, -2),
        "N" => (1, 1, -2),
        "Pa" => (1, -1, -2),
        "kg" => (1, 0, 0),
        "N/m" => (1, 0, -2),
        "m2" => (0, 2, 0),
        "m3" => (0, 3, 0),
        "m3/s" => (0, 3, -1),
        "m3/(s.Pa)" => (-1, 4, 1),
        "s" => (0, 0, 1),
        "Hz" => (0, 0, -1),
        "1/m" => (0, -1, 0),
        "s/m" => (0, -1, 1),
        "s2/m" => (0, -1, 2),
        "1/N" => (-1, -1, 2),
        _ => return None,
    })
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
                assert!(unit_exponents(u).is_some(), "{u}");
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
}

//! The one table of the FMU's variables: value reference, name, type, causality, unit,
//! description, and how each reads/writes the model's parameters or signals.
//! `modelDescription.xml` and the documentation page are generated from it.
//!
//! Here: the row types, the enumerations and the assembled table; `table.rs`: the table's
//! own rows and the limits; `states.rs`: the model's states; `units.rs`: the units.

mod states;
mod table;
mod units;

pub use units::{unit, Unit, UNITS};

use states::{state_row, DERIVATIVE_VR, STATES, STATE_VR};
use table::{LIMIT_VARIABLES, TABLE_VARIABLES};

use crate::effects::CATALOGUE;
use crate::model::{Inputs, Outputs};
use crate::params::Params;

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

/// Whether `value` is allowed for a structural (Integer) parameter: one of its
/// enumeration's items.
pub fn integer_allowed(name: &str, value: i32) -> bool {
    match by_name(name).and_then(|v| v.enumeration) {
        Some(e) => e.items.iter().any(|i| i.value == value),
        None => true,
    }
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

/// The variable with value reference `vr`.
pub fn by_vr(vr: u32) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.vr == vr)
}

/// The variable named `name`.
pub fn by_name(name: &str) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.name == name)
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

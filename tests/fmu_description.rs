//! The committed modelDescription/modelDescription.xml is what the variable table
//! generates (one source of truth): this test fails when they drift apart.
//! Regenerate with `shaketable fmu description > modelDescription/modelDescription.xml`.

use shaketable::fmi::model_description::model_description_xml;
use shaketable::fmi::variables::{Role, VARIABLES};
use shaketable::Params;

#[test]
fn committed_model_description_matches_the_variable_table() {
    let committed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/modelDescription/modelDescription.xml"
    ))
    .expect("modelDescription/modelDescription.xml");
    let generated = model_description_xml(&Params::trees_lab());
    assert!(
        committed == generated,
        "modelDescription/modelDescription.xml drifted from src/fmi/variables.rs; regenerate it with \
         `shaketable fmu description > modelDescription/modelDescription.xml`"
    );
}

/// Every required name of the FMU issue is in the table with its causality.
#[test]
fn required_variables_exist() {
    let has =
        |name: &str, f: fn(&Role) -> bool| VARIABLES.iter().any(|v| v.name == name && f(&v.role));
    for n in [
        "ref_displacement",
        "ref_velocity",
        "ref_acceleration",
        "external_force",
    ] {
        assert!(has(n, |r| matches!(r, Role::Input(_))), "{n}");
    }
    for n in [
        "displacement",
        "velocity",
        "acceleration",
        "actuator_force",
        "valve_command",
        "spool_position",
        "pressure_a",
        "pressure_b",
    ] {
        assert!(has(n, |r| matches!(r, Role::Output(_))), "{n}");
    }
    for n in [
        "table.mass",
        "table.stiffness",
        "oil_column.bulk_modulus",
        "actuator.piston_area",
        "actuator.total_oil_volume",
        "actuator.leakage",
        "valve.flow_gain",
        "servovalve.gain",
        "servovalve.time_constant",
        "servovalve.natural_frequency",
        "servovalve.damping_ratio",
        "controller.kp",
        "controller.kdp",
        "friction.force",
        "friction.yield_displacement",
        "friction.shape",
        "specimen.enabled",
        "specimen.mass",
        "servovalve.model",
        "actuator.model",
    ] {
        assert!(has(n, |r| matches!(r, Role::Parameter(..))), "{n}");
    }
}

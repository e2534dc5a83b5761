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

/// The catalogue's second part in the FMU (spec section 7): the specimen's modes 2 and 3,
/// free play, their states, and the free-play contact's event indicator.
#[test]
fn specimen_modes_and_free_play_are_variables() {
    let has = |name: &str| VARIABLES.iter().any(|v| v.name == name);
    for n in [
        "specimen.mass",
        "specimen.mode2.mass",
        "specimen.mode2.frequency",
        "specimen.mode2.damping_ratio",
        "specimen.mode3.mass",
        "specimen.mode3.frequency",
        "specimen.mode3.damping_ratio",
        "free_play.enabled",
        "free_play.gap",
        "free_play.rod_mass",
        "free_play.contact_stiffness",
        "free_play.contact_damping_ratio",
        "state.specimen_mode2_displacement",
        "state.specimen_mode3_velocity",
        "state.rod_displacement",
        "der(state.rod_velocity)",
    ] {
        assert!(has(n), "{n}");
    }
    let xml = model_description_xml(&Params::trees_lab());
    assert!(xml.contains("numberOfEventIndicators=\"10\""));
}

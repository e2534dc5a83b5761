//! `modelDescription.xml` and the documentation page, generated from the variable table
//! ([`super::variables::VARIABLES`]) with the start values of a parameter set.

use super::variables::{unit_exponents, Kind, Role, VARIABLES};
use crate::model::Model;
use crate::params::Params;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;
use std::io::Cursor;

/// The model identifier: the shared library is `binaries/linux64/ShakeTable.so`.
pub const MODEL_IDENTIFIER: &str = "ShakeTable";
/// The GUID the binary checks in fmi2Instantiate. It names the variable table's version,
/// not the start values (a lab's parameter file is baked in as resources/parameters.toml).
pub const GUID: &str = "{5e1d7a3c-9b7f-4d2e-8a61-2c0f4b7d9e13}";

fn fmt_real(x: f64) -> String {
    let mut b = ryu::Buffer::new();
    b.format(x).to_string()
}

/// The start value of every variable for parameters `p` (inputs 0, outputs at rest).
pub fn start_value(v: &super::variables::Variable, p: &Params) -> String {
    match v.role {
        Role::Input(_) => "0".into(),
        Role::Output(f) => {
            let m = Model::new(p);
            let o = m.outputs(
                &m.rest_state(),
                &Default::default(),
                &Default::default(),
                0.0,
            );
            fmt_real(f(&o))
        }
        Role::Parameter(get, _) => match v.kind {
            Kind::Real => fmt_real(get(p)),
            Kind::Integer => format!("{}", get(p) as i64),
            Kind::Boolean => (if get(p) != 0.0 { "true" } else { "false" }).into(),
        },
    }
}

/// The XML for parameters `p` (their values become the parameters' start values).
pub fn model_description_xml(p: &Params) -> String {
    let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    let mut put = |e: Event| {
        // writing into a Vec cannot fail
        let _ = w.write_event(e);
    };
    put(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)));
    let mut root = BytesStart::new("fmiModelDescription");
    root.push_attribute(("fmiVersion", "2.0"));
    root.push_attribute(("modelName", MODEL_IDENTIFIER));
    root.push_attribute(("guid", GUID));
    root.push_attribute((
        "description",
        "Servo-hydraulic uni-axial shake table (EUCENTRE TREES Lab): TVC controller, servovalve, actuator and oil column, payload with Bouc-Wen friction, and the effects of spec section 7",
    ));
    root.push_attribute((
        "generationTool",
        concat!("shaketable ", env!("CARGO_PKG_VERSION")),
    ));
    root.push_attribute(("variableNamingConvention", "flat"));
    root.push_attribute(("numberOfEventIndicators", "0"));
    put(Event::Start(root));
    let mut cs = BytesStart::new("CoSimulation");
    for (k, v) in [
        ("modelIdentifier", MODEL_IDENTIFIER),
        ("canHandleVariableCommunicationStepSize", "true"),
        ("canInterpolateInputs", "true"),
        ("maxOutputDerivativeOrder", "0"),
        ("canRunAsynchronuously", "false"),
        ("canBeInstantiatedOnlyOncePerProcess", "false"),
        ("canNotUseMemoryManagementFunctions", "true"),
        ("canGetAndSetFMUstate", "true"),
        ("canSerializeFMUstate", "true"),
        ("providesDirectionalDerivative", "false"),
    ] {
        cs.push_attribute((k, v));
    }
    put(Event::Empty(cs));
    // units
    let mut units: Vec<&str> = VARIABLES.iter().filter_map(|v| v.unit).collect();
    units.sort();
    units.dedup();
    put(Event::Start(BytesStart::new("UnitDefinitions")));
    for u in &units {
        let mut e = BytesStart::new("Unit");
        e.push_attribute(("name", *u));
        put(Event::Start(e));
        let (kg, m, s) = unit_exponents(u).unwrap_or((0, 0, 0));
        let mut b = BytesStart::new("BaseUnit");
        for (k, x) in [("kg", kg), ("m", m), ("s", s)] {
            if x != 0 {
                b.push_attribute((k, x.to_string().as_str()));
            }
        }
        put(Event::Empty(b));
        put(Event::End(BytesEnd::new("Unit")));
    }
    put(Event::End(BytesEnd::new("UnitDefinitions")));
    let mut de = BytesStart::new("DefaultExperiment");
    de.push_attribute(("startTime", "0"));
    de.push_attribute(("stopTime", "10"));
    de.push_attribute(("stepSize", "0.001953125"));
    put(Event::Empty(de));
    put(Event::Start(BytesStart::new("ModelVariables")));
    for v in VARIABLES {
        let mut e = BytesStart::new("ScalarVariable");
        e.push_attribute(("name", v.name));
        e.push_attribute(("valueReference", v.vr.to_string().as_str()));
        e.push_attribute(("description", v.description));
        let (causality, variability, initial) = match v.role {
            Role::Input(_) => ("input", "continuous", None),
            Role::Output(_) => ("output", "continuous", Some("calculated")),
            Role::Parameter(..) => ("parameter", "fixed", Some("exact")),
        };
        e.push_attribute(("causality", causality));
        e.push_attribute(("variability", variability));
        if let Some(i) = initial {
            e.push_attribute(("initial", i));
        }
        put(Event::Start(e));
        let tag = match v.kind {
            Kind::Real => "Real",
            Kind::Integer => "Integer",
            Kind::Boolean => "Boolean",
        };
        let mut t = BytesStart::new(tag);
        if let Some(u) = v.unit {
            t.push_attribute(("unit", u));
        }
        if !matches!(v.role, Role::Output(_)) {
            t.push_attribute(("start", start_value(v, p).as_str()));
        }
        put(Event::Empty(t));
        put(Event::End(BytesEnd::new("ScalarVariable")));
    }
    put(Event::End(BytesEnd::new("ModelVariables")));
    put(Event::Start(BytesStart::new("ModelStructure")));
    for section in ["Outputs", "InitialUnknowns"] {
        put(Event::Start(BytesStart::new(section)));
        for (i, v) in VARIABLES.iter().enumerate() {
            if matches!(v.role, Role::Output(_)) {
                let mut u = BytesStart::new("Unknown");
                u.push_attribute(("index", (i + 1).to_string().as_str()));
                put(Event::Empty(u));
            }
        }
        put(Event::End(BytesEnd::new(section)));
    }
    put(Event::End(BytesEnd::new("ModelStructure")));
    put(Event::End(BytesEnd::new("fmiModelDescription")));
    String::from_utf8(w.into_inner().into_inner()).unwrap_or_default() + "\n"
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// `documentation/index.html`: the variable table.
pub fn documentation_html(p: &Params) -> String {
    let mut h = String::from(
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>ShakeTable FMU</title>\
         <style>body{font-family:sans-serif}td,th{border:1px solid #ccc;padding:2px 6px}\
         table{border-collapse:collapse}</style></head><body><h1>ShakeTable: FMI 2.0 Co-Simulation FMU</h1>\
         <p>Servo-hydraulic uni-axial shake table (EUCENTRE TREES Lab). Inputs are interpolated \
         linearly over a step when fmi2SetRealInputDerivatives gives slopes; the FMU sub-steps \
         internally (RK4, at most 1/3072 s), so any communication step works. Parameters are \
         fixed: set them before fmi2ExitInitializationMode.</p><table><tr><th>vr</th><th>name</th>\
         <th>causality</th><th>type</th><th>unit</th><th>start</th><th>description</th></tr>",
    );
    for v in VARIABLES {
        let causality = match v.role {
            Role::Input(_) => "input",
            Role::Output(_) => "output",
            Role::Parameter(..) => "parameter",
        };
        h.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            v.vr,
            v.name,
            causality,
            v.kind,
            v.unit.unwrap_or(""),
            if matches!(v.role, Role::Output(_)) { String::new() } else { start_value(v, p) },
            escape(v.description)
        ));
    }
    h.push_str("</table></body></html>\n");
    h
}

//! The FMI 3.0 Co-Simulation `modelDescription.xml` (ShakeTable3.fmu), from the same
//! variable table as the FMI 2.0 one: the inputs, outputs and parameters with their
//! units, display units, bounds and enumerations. The model's states are internal to
//! Co-Simulation and are not listed (FMI 2.0 lists them for its Model Exchange).

use crate::fmi::model_description::{
    header_attributes, kind_of_variable, real_attributes, start_value, token_of, unit_definitions,
    Xml, GUID_PLACEHOLDER, MODEL_IDENTIFIER, MODEL_SUMMARY,
};
use crate::fmi::variables::{Kind, Role, Variable, INPUTS, VARIABLES};
use crate::params::Params;
use quick_xml::events::{BytesDecl, Event};
use quick_xml::Writer;
use std::io::Cursor;

/// Value reference of the independent variable `time` (FMI 3.0 requires one): above
/// every value reference of the table.
pub const TIME_VR: u32 = 1000;

/// The variables the FMI 3.0 description lists: every row but the model's states.
pub fn listed(v: &Variable) -> bool {
    match v.role {
        Role::Input(_) | Role::Output(_) | Role::Parameter(..) => true,
        Role::State(_) | Role::Derivative(_) => false,
    }
}

/// The instantiation token for parameters `p`: a UUID v5 of the description's text (no
/// date), so it changes with the start values; fmi3InstantiateCoSimulation recomputes it.
pub fn instantiation_token(p: &Params) -> String {
    token_of(&description_xml(p, GUID_PLACEHOLDER, None))
}

/// The XML for parameters `p`, with `generationDateAndTime` when given.
pub fn model_description_xml(p: &Params, generated_at: Option<&str>) -> String {
    description_xml(p, &instantiation_token(p), generated_at)
}

fn description_xml(p: &Params, token: &str, generated_at: Option<&str>) -> String {
    let mut x = Xml(Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2));
    x.put(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)));
    let mut root = vec![
        ("fmiVersion", "3.0"),
        ("modelName", MODEL_IDENTIFIER),
        ("instantiationToken", token),
        ("description", MODEL_SUMMARY),
    ];
    root.extend(header_attributes(generated_at));
    x.start("fmiModelDescription", &root);
    x.empty(
        "CoSimulation",
        &[
            ("modelIdentifier", MODEL_IDENTIFIER),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canGetAndSetFMUState", "true"),
            ("canSerializeFMUState", "true"),
            ("providesIntermediateUpdate", "false"),
            ("hasEventMode", "false"),
            ("canReturnEarlyAfterIntermediateUpdate", "false"),
            ("maxOutputDerivativeOrder", "0"),
        ],
    );
    unit_definitions(&mut x);
    type_definitions(&mut x);
    x.empty(
        "DefaultExperiment",
        &[
            ("startTime", "0"),
            ("stopTime", "10"),
            ("stepSize", "0.001953125"),
        ],
    );
    x.start("ModelVariables", &[]);
    let time_vr = TIME_VR.to_string();
    x.empty(
        "Float64",
        &[
            ("name", "time"),
            ("valueReference", &time_vr),
            ("causality", "independent"),
            ("variability", "continuous"),
            ("description", "Simulation time"),
            ("unit", "s"),
        ],
    );
    for v in VARIABLES.iter().filter(|v| listed(v)) {
        variable(&mut x, v, p);
    }
    x.end("ModelVariables");
    model_structure(&mut x);
    x.end("fmiModelDescription");
    String::from_utf8(x.0.into_inner().into_inner()).unwrap_or_default() + "\n"
}

/// FMI 3.0 enumeration types of the structural choices.
fn type_definitions(x: &mut Xml) {
    x.start("TypeDefinitions", &[]);
    for e in VARIABLES.iter().filter_map(|v| v.enumeration) {
        x.start("EnumerationType", &[("name", e.name)]);
        for item in e.items {
            let value = item.value.to_string();
            x.empty(
                "Item",
                &[
                    ("name", item.name),
                    ("value", &value),
                    ("description", item.description),
                ],
            );
        }
        x.end("EnumerationType");
    }
    x.end("TypeDefinitions");
}

fn variable(x: &mut Xml, v: &Variable, p: &Params) {
    let vr = v.vr.to_string();
    let (causality, variability, initial) = kind_of_variable(v);
    let mut a: Vec<(&str, String)> = vec![
        ("name", v.name.into()),
        ("valueReference", vr),
        ("description", v.description.into()),
        ("causality", causality.into()),
        ("variability", variability.into()),
    ];
    a.extend(initial.map(|i| ("initial", i.to_string())));
    let tag = match (v.kind, v.enumeration) {
        (Kind::Integer, Some(e)) => {
            a.push(("declaredType", e.name.into()));
            "Enumeration"
        }
        (Kind::Integer, None) => "Int32",
        (Kind::Real, _) => "Float64",
        (Kind::Boolean, _) => "Boolean",
    };
    a.extend(real_attributes(v));
    if matches!(v.role, Role::Input(_) | Role::Parameter(..)) {
        a.push(("start", start_value(v, p)));
    }
    let attributes: Vec<(&str, &str)> = a.iter().map(|(k, s)| (*k, s.as_str())).collect();
    x.empty(tag, &attributes);
}

/// Outputs with their direct dependencies on the inputs (value references, FMI 3.0);
/// the outputs as initial unknowns.
fn model_structure(x: &mut Xml) {
    x.start("ModelStructure", &[]);
    for v in VARIABLES
        .iter()
        .filter(|v| matches!(v.role, Role::Output(_)))
    {
        let vr = v.vr.to_string();
        let input_vr = |i: usize| {
            VARIABLES
                .iter()
                .find(|w| w.name == INPUTS[i])
                .map_or(0, |w| w.vr)
        };
        let deps: Vec<String> = v
            .feedthrough
            .iter()
            .map(|f| input_vr(f.input).to_string())
            .collect();
        let kinds: Vec<&str> = v.feedthrough.iter().map(|f| f.kind).collect();
        let (deps, kinds) = (deps.join(" "), kinds.join(" "));
        let mut a = vec![
            ("valueReference", vr.as_str()),
            ("dependencies", deps.as_str()),
        ];
        if !kinds.is_empty() {
            a.push(("dependenciesKind", kinds.as_str()));
        }
        x.empty("Output", &a);
    }
    for v in VARIABLES
        .iter()
        .filter(|v| matches!(v.role, Role::Output(_)))
    {
        x.empty("InitialUnknown", &[("valueReference", &v.vr.to_string())]);
    }
    x.end("ModelStructure");
}

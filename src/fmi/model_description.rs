//! `modelDescription.xml` and the documentation page, generated from the variable table
//! ([`super::variables::VARIABLES`]) with the start values of a parameter set.

use super::model_exchange::EVENT_INDICATOR_COUNT;
use super::structure::output_state_dependencies;
use super::variables::{unit, Kind, Role, Variable, INPUTS, UNITS, VARIABLES};
use crate::model::Model;
use crate::params::{fmu_rule_of, Params};
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;
use std::io::Cursor;

/// The model identifier: the shared library is `binaries/linux64/ShakeTable.so`.
pub const MODEL_IDENTIFIER: &str = "ShakeTable";

/// The GUID's stand-in while the text the GUID is computed from is written.
pub(super) const GUID_PLACEHOLDER: &str = "{00000000-0000-0000-0000-000000000000}";

/// Namespace of the GUIDs (UUID v5): fixed, so equal descriptions give equal GUIDs.
pub(super) const GUID_NAMESPACE: uuid::Uuid =
    uuid::Uuid::from_u128(0x5e1d7a3c_9b7f_4d2e_8a61_2c0f4b7d9e13);

/// The header attributes that say who made the FMU and under which terms.
pub(super) const AUTHOR: &str = "shaketable developers";
pub(super) const COPYRIGHT: &str = "Copyright (c) 2026 the shaketable developers";
pub(super) const LICENSE: &str = env!("CARGO_PKG_LICENSE");

pub(super) fn fmt_real(x: f64) -> String {
    let mut b = ryu::Buffer::new();
    b.format(x).to_string()
}

/// The start value of every variable for parameters `p` (inputs 0, outputs at rest).
pub fn start_value(v: &Variable, p: &Params) -> String {
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
        Role::State(k) => fmt_real(Model::new(p).rest_state()[k]),
        Role::Derivative(_) => "0".into(),
    }
}

/// Whether the variable declares a start value (calculated ones may not, FMI 2.0 2.2.7).
pub fn declares_start(v: &Variable) -> bool {
    matches!(v.role, Role::Input(_) | Role::Parameter(..))
}

/// A UUID v5 of a description's text, in braces: the GUID (FMI 2.0) or the
/// instantiation token (FMI 3.0).
pub(super) fn token_of(text: &str) -> String {
    format!(
        "{{{}}}",
        uuid::Uuid::new_v5(&GUID_NAMESPACE, text.as_bytes()).hyphenated()
    )
}

/// The header attributes both FMI versions share (after the version and the token).
pub(super) fn header_attributes(generated_at: Option<&str>) -> Vec<(&'static str, &str)> {
    let mut a = vec![
        ("author", AUTHOR),
        ("version", env!("CARGO_PKG_VERSION")),
        ("copyright", COPYRIGHT),
        ("license", LICENSE),
        (
            "generationTool",
            concat!("shaketable ", env!("CARGO_PKG_VERSION")),
        ),
    ];
    if let Some(date) = generated_at {
        a.push(("generationDateAndTime", date));
    }
    a.push(("variableNamingConvention", "structured"));
    a
}

/// The model's description in both FMI versions.
pub(super) const MODEL_SUMMARY: &str =
    "Servo-hydraulic uni-axial shake table (EUCENTRE TREES Lab model): three-variable \
     controller, servovalve, actuator and oil column, table with bearing friction, and \
     optional specimen, foundation, stick-slip, flow saturation and valve deadband";

/// The GUID of the description for parameters `p`: a UUID v5 of its text (without the
/// generation date), so it changes with the start values, the variables and the version,
/// and the binary recomputes it from the parameters it starts from (fmi2Instantiate).
pub fn guid(p: &Params) -> String {
    token_of(&description_xml(p, GUID_PLACEHOLDER, None))
}

/// The XML for parameters `p` (their values become the parameters' start values), without
/// a generation date (the committed copy: reproducible).
pub fn model_description_xml(p: &Params) -> String {
    description_xml(p, &guid(p), None)
}

/// The XML with `generationDateAndTime` (ISO 8601, e.g. `2026-11-24T18:00:00Z`), as
/// scripts/build_fmu.sh packages it.
pub fn model_description_xml_at(p: &Params, generated_at: &str) -> String {
    description_xml(p, &guid(p), Some(generated_at))
}

/// Writes XML events into a buffer (writing into a `Vec` cannot fail).
pub(super) struct Xml(pub(super) Writer<Cursor<Vec<u8>>>);

impl Xml {
    pub(super) fn put(&mut self, e: Event) {
        let _ = self.0.write_event(e);
    }
    pub(super) fn start(&mut self, tag: &str, attributes: &[(&str, &str)]) {
        let mut e = BytesStart::new(tag);
        e.extend_attributes(attributes.iter().copied());
        self.put(Event::Start(e));
    }
    pub(super) fn empty(&mut self, tag: &str, attributes: &[(&str, &str)]) {
        let mut e = BytesStart::new(tag);
        e.extend_attributes(attributes.iter().copied());
        self.put(Event::Empty(e));
    }
    pub(super) fn end(&mut self, tag: &str) {
        self.put(Event::End(BytesEnd::new(tag)));
    }
}

fn description_xml(p: &Params, guid: &str, generated_at: Option<&str>) -> String {
    let mut x = Xml(Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2));
    x.put(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)));
    let mut root = vec![
        ("fmiVersion", "2.0"),
        ("modelName", MODEL_IDENTIFIER),
        ("guid", guid),
        ("description", MODEL_SUMMARY),
    ];
    root.extend(header_attributes(generated_at));
    let indicators = EVENT_INDICATOR_COUNT.to_string();
    root.push(("numberOfEventIndicators", &indicators));
    x.start("fmiModelDescription", &root);
    model_exchange(&mut x);
    co_simulation(&mut x);
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
    for v in VARIABLES {
        scalar_variable(&mut x, v, p);
    }
    x.end("ModelVariables");
    model_structure(&mut x);
    x.end("fmiModelDescription");
    String::from_utf8(x.0.into_inner().into_inner()).unwrap_or_default() + "\n"
}

fn model_exchange(x: &mut Xml) {
    x.empty(
        "ModelExchange",
        &[
            ("modelIdentifier", MODEL_IDENTIFIER),
            ("completedIntegratorStepNotNeeded", "false"),
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("providesDirectionalDerivative", "false"),
        ],
    );
}

fn co_simulation(x: &mut Xml) {
    x.empty(
        "CoSimulation",
        &[
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
        ],
    );
}

/// The units the variables use, with the display units labs read them in.
pub(super) fn unit_definitions(x: &mut Xml) {
    x.start("UnitDefinitions", &[]);
    for u in UNITS
        .iter()
        .filter(|u| VARIABLES.iter().any(|v| v.unit == Some(u.name)))
    {
        x.start("Unit", &[("name", u.name)]);
        let (kg, m, s) = u.base;
        let exponents: Vec<(&str, String)> = [("kg", kg), ("m", m), ("s", s)]
            .into_iter()
            .filter(|&(_, e)| e != 0)
            .map(|(k, e)| (k, e.to_string()))
            .collect();
        let attributes: Vec<(&str, &str)> =
            exponents.iter().map(|(k, e)| (*k, e.as_str())).collect();
        x.empty("BaseUnit", &attributes);
        if let Some((name, factor)) = u.display {
            x.empty(
                "DisplayUnit",
                &[("name", name), ("factor", &fmt_real(factor))],
            );
        }
        x.end("Unit");
    }
    x.end("UnitDefinitions");
}

/// The enumerations of the structural choices.
fn type_definitions(x: &mut Xml) {
    x.start("TypeDefinitions", &[]);
    for e in VARIABLES.iter().filter_map(|v| v.enumeration) {
        x.start("SimpleType", &[("name", e.name)]);
        x.start("Enumeration", &[]);
        for item in e.items {
            x.empty(
                "Item",
                &[
                    ("name", item.name),
                    ("value", &item.value.to_string()),
                    ("description", item.description),
                ],
            );
        }
        x.end("Enumeration");
        x.end("SimpleType");
    }
    x.end("TypeDefinitions");
}

/// Causality, variability and `initial` of a variable (the same in FMI 2.0 and 3.0).
pub(super) fn kind_of_variable(v: &Variable) -> (&'static str, &'static str, Option<&'static str>) {
    match v.role {
        Role::Input(_) => ("input", "continuous", None),
        Role::Output(_) => ("output", "continuous", Some("calculated")),
        Role::Parameter(..) => ("parameter", "fixed", Some("exact")),
        Role::State(_) | Role::Derivative(_) => ("local", "continuous", Some("calculated")),
    }
}

/// The unit, display unit and bounds of a Real variable (from the validation rules).
pub(super) fn real_attributes(v: &Variable) -> Vec<(&'static str, String)> {
    let mut t: Vec<(&'static str, String)> = Vec::new();
    if let Some(u) = v.unit {
        t.push(("unit", u.into()));
        if let Some((display, _)) = unit(u).and_then(|u| u.display) {
            t.push(("displayUnit", display.into()));
        }
    }
    if v.kind == Kind::Real {
        let (min, max) = v
            .key
            .and_then(fmu_rule_of)
            .map(|r| r.bounds())
            .unwrap_or_default();
        t.extend(min.map(|m| ("min", fmt_real(m))));
        t.extend(max.map(|m| ("max", fmt_real(m))));
    }
    t
}

fn scalar_variable(x: &mut Xml, v: &Variable, p: &Params) {
    let vr = v.vr.to_string();
    let (causality, variability, initial) = kind_of_variable(v);
    let mut attributes = vec![
        ("name", v.name),
        ("valueReference", vr.as_str()),
        ("description", v.description),
        ("causality", causality),
        ("variability", variability),
    ];
    if let Some(i) = initial {
        attributes.push(("initial", i));
    }
    x.start("ScalarVariable", &attributes);
    let mut t: Vec<(&str, String)> = Vec::new();
    let tag = match (v.kind, v.enumeration) {
        (Kind::Integer, Some(e)) => {
            t.push(("declaredType", e.name.into()));
            "Enumeration"
        }
        (Kind::Real, _) => "Real",
        (Kind::Integer, None) => "Integer",
        (Kind::Boolean, _) => "Boolean",
    };
    t.extend(real_attributes(v));
    if let Role::Derivative(k) = v.role {
        t.push(("derivative", state_index(k).to_string()));
    }
    if declares_start(v) {
        t.push(("start", start_value(v, p)));
    }
    let attributes: Vec<(&str, &str)> = t.iter().map(|(k, s)| (*k, s.as_str())).collect();
    x.empty(tag, &attributes);
    x.end("ScalarVariable");
}

/// The 1-based index of the variable in ModelVariables.
fn index_of(name: &str) -> usize {
    VARIABLES
        .iter()
        .position(|v| v.name == name)
        .map_or(0, |i| i + 1)
}

/// The 1-based index of the variable of state `k`.
fn state_index(k: usize) -> usize {
    VARIABLES
        .iter()
        .position(|v| matches!(v.role, Role::State(j) if j == k))
        .map_or(0, |i| i + 1)
}

/// Outputs with their exact direct dependencies on the inputs and the states they read;
/// the state derivatives; InitialUnknowns (outputs, states and derivatives, calculated
/// from every parameter at rest).
fn model_structure(x: &mut Xml) {
    x.start("ModelStructure", &[]);
    x.start("Outputs", &[]);
    for (i, v) in VARIABLES.iter().enumerate() {
        if let Role::Output(read) = v.role {
            let mut known: Vec<(usize, &str)> = v
                .feedthrough
                .iter()
                .map(|f| (index_of(INPUTS[f.input]), f.kind))
                .collect();
            // a state enters an output through the model's nonlinear algebra
            known.extend(
                output_state_dependencies(read)
                    .into_iter()
                    .map(|k| (state_index(k), "dependent")),
            );
            known.sort_unstable();
            let deps: Vec<String> = known.iter().map(|(i, _)| i.to_string()).collect();
            let kinds: Vec<&str> = known.iter().map(|(_, k)| *k).collect();
            let (deps, kinds) = (deps.join(" "), kinds.join(" "));
            let index = (i + 1).to_string();
            let mut attributes = vec![("index", index.as_str()), ("dependencies", deps.as_str())];
            if !kinds.is_empty() {
                attributes.push(("dependenciesKind", kinds.as_str()));
            }
            x.empty("Unknown", &attributes);
        }
    }
    x.end("Outputs");
    x.start("Derivatives", &[]);
    for (i, v) in VARIABLES.iter().enumerate() {
        if matches!(v.role, Role::Derivative(_)) {
            x.empty("Unknown", &[("index", &(i + 1).to_string())]);
        }
    }
    x.end("Derivatives");
    x.start("InitialUnknowns", &[]);
    for (i, v) in VARIABLES.iter().enumerate() {
        if matches!(
            v.role,
            Role::Output(_) | Role::State(_) | Role::Derivative(_)
        ) {
            x.empty("Unknown", &[("index", &(i + 1).to_string())]);
        }
    }
    x.end("InitialUnknowns");
    x.end("ModelStructure");
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
         table{border-collapse:collapse}</style></head><body><h1>ShakeTable: FMI 2.0 FMU \
         (Co-Simulation and Model Exchange)</h1>\
         <p>Servo-hydraulic uni-axial shake table (EUCENTRE TREES Lab). <b>Co-Simulation</b>: \
         inputs are interpolated linearly over a step when fmi2SetRealInputDerivatives gives \
         slopes; the FMU sub-steps internally (RK4, at most 1/3072 s), so any communication \
         step works. <b>Model Exchange</b>: the importer integrates the eleven states \
         (<code>state.*</code>, derivatives <code>der(state.*)</code>); the delay servovalve \
         (servovalve.model = delay) is Co-Simulation only and is refused at \
         fmi2ExitInitializationMode. Parameters are fixed: set them before \
         fmi2ExitInitializationMode.</p>",
    );
    h.push_str("<h2>Event indicators (Model Exchange)</h2><ol start=\"0\">");
    for s in crate::model::switching::SWITCHES {
        h.push_str(&format!("<li>{}</li>", escape(s)));
    }
    h.push_str(
        "</ol><h2>Variables</h2><table><tr><th>vr</th><th>name</th><th>causality</th>\
         <th>type</th><th>unit</th><th>start</th><th>description</th></tr>",
    );
    for v in VARIABLES {
        let causality = match v.role {
            Role::Input(_) => "input",
            Role::Output(_) => "output",
            Role::Parameter(..) => "parameter",
            Role::State(_) | Role::Derivative(_) => "local",
        };
        h.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            v.vr,
            v.name,
            causality,
            v.kind,
            v.unit.unwrap_or(""),
            if declares_start(v) { start_value(v, p) } else { String::new() },
            escape(v.description)
        ));
    }
    h.push_str("</table></body></html>\n");
    h
}

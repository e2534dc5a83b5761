//! "Adding an effect touches one place": every catalogue parameter reaches the parameter
//! file, validation, the FMU variables and `--effect` parsing from its one declaration.

use super::*;
use crate::fmi::variables::{by_vr, Kind, VARIABLES};

fn all_parameters() -> impl Iterator<Item = (&'static Effect, &'static Parameter)> {
    CATALOGUE
        .iter()
        .flat_map(|e| e.parameters.iter().map(move |q| (e, q)))
}

#[test]
fn names_keys_and_value_references_are_unique() {
    let names: Vec<&str> = CATALOGUE.iter().map(|e| e.name).collect();
    assert_eq!(
        names,
        [
            "specimen",
            "foundation",
            "stick_slip",
            "flow_saturation",
            "valve_deadband",
            "friction_asymmetry",
            "flow_asymmetry"
        ]
    );
    let mut vrs: Vec<u32> = CATALOGUE.iter().map(|e| e.switch.value_reference).collect();
    let mut keys: Vec<&str> = Vec::new();
    let mut fmu: Vec<&str> = CATALOGUE.iter().map(|e| e.switch.fmu_name).collect();
    for (e, q) in all_parameters() {
        assert_eq!(q.dotted_key, format!("{}.{}", e.name, q.key));
        assert!(
            q.fmu_name.starts_with(&format!("{}.", e.name)),
            "{}",
            q.fmu_name
        );
        vrs.push(q.value_reference);
        keys.push(q.dotted_key);
        fmu.push(q.fmu_name);
    }
    for list in [&keys, &fmu] {
        let mut sorted = list.to_vec();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), list.len(), "{list:?}");
    }
    let n = vrs.len();
    vrs.sort();
    vrs.dedup();
    assert_eq!(vrs.len(), n);
}

#[test]
fn every_parameter_appears_once_in_the_toml() {
    let text = Params::trees_lab().to_toml_string();
    let table: toml::Table = toml::from_str(&text).unwrap();
    for e in &CATALOGUE {
        let block = table[e.name].as_table().unwrap();
        // the switch plus each declared parameter, nothing else
        assert_eq!(block.len(), e.parameters.len() + 1, "{}", e.name);
        assert!(block.contains_key("enabled"));
        for q in e.parameters {
            assert_eq!(
                block[q.key].as_float(),
                Some((q.read)(&Params::trees_lab()))
            );
        }
    }
    let entries = Params::trees_lab().numeric_entries();
    for (_, q) in all_parameters() {
        assert_eq!(
            entries.iter().filter(|(k, _)| *k == q.dotted_key).count(),
            1
        );
    }
}

#[test]
fn every_parameter_appears_once_in_the_fmu_variables() {
    for e in &CATALOGUE {
        let v = by_vr(e.switch.value_reference).unwrap();
        assert_eq!((v.name, v.kind), (e.switch.fmu_name, Kind::Boolean));
        for q in e.parameters {
            let v = by_vr(q.value_reference).unwrap();
            assert_eq!((v.name, v.kind, v.unit), (q.fmu_name, Kind::Real, q.unit));
            assert_eq!(VARIABLES.iter().filter(|w| w.name == q.fmu_name).count(), 1);
        }
    }
}

#[test]
fn every_parameter_is_set_by_effect_syntax_and_validated() {
    for (e, q) in all_parameters() {
        let mut p = Params::trees_lab();
        let value = (q.read)(&p) * 1.25 + 0.001;
        p.apply_effect_spec(&format!("{}:{}={value}", e.name, q.key))
            .unwrap();
        assert!(e.is_enabled(&p));
        assert_eq!(e.read(&p, q.key), Some(value));
        // a value breaking the rule names the dotted key
        let err = Params::trees_lab()
            .apply_effect_spec(&format!("{}:{}=-5", e.name, q.key))
            .unwrap_err();
        assert!(err.contains(q.dotted_key), "{err}");
    }
    assert!(Params::trees_lab()
        .apply_effect_spec("specimen:enabled=1")
        .is_err());
}

#[test]
fn fit_bounds_are_the_diagnosis_ranges() {
    let p = Params::trees_lab();
    let specimen = by_name("specimen").unwrap().fit_bounds(&p);
    assert_eq!(
        specimen,
        [
            FitRange {
                lower: 200.0,
                upper: 2e5
            },
            FitRange {
                lower: 0.5,
                upper: 60.0
            },
            FitRange {
                lower: 0.002,
                upper: 0.5
            },
        ]
    );
    for e in &CATALOGUE {
        for r in e.fit_bounds(&p) {
            assert!(r.lower < r.upper, "{}", e.name);
        }
        let mut q = p;
        assert!(e.apply(&mut q, e.parameters[0].key, 0.125));
        assert_eq!(e.read(&q, e.parameters[0].key), Some(0.125));
        assert!(!e.apply(&mut q, "nonsense", 1.0));
    }
}

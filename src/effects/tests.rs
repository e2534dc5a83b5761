//! "Adding an effect touches one place": every catalogue parameter reaches the parameter
//! file, validation, the FMU variables and `--effect` parsing from its one declaration.

use super::*;
use crate::fmi::variables::{by_vr, Kind, VARIABLES};

fn all_parameters() -> impl Iterator<Item = (&'static Effect, &'static Parameter)> {
    CATALOGUE
        .iter()
        .flat_map(|e| e.all_parameters().map(move |q| (e, q)))
}

/// A parameter of a higher specimen mode (`modeN.key`): written in the `modes` list.
fn is_mode_key(q: &Parameter) -> bool {
    q.key.contains('.')
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
            "flow_asymmetry",
            "free_play"
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
        // the switch plus each declared parameter, nothing else (absent specimen modes are
        // not written)
        let written = e.all_parameters().filter(|q| !is_mode_key(q)).count();
        assert_eq!(block.len(), written + 1, "{}", e.name);
        assert!(block.contains_key("enabled"));
        for q in e.all_parameters().filter(|q| !is_mode_key(q)) {
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
        // a higher specimen mode exists with a mass (and mode 3 with mode 2)
        let modes = if is_mode_key(q) {
            "mode2.mass_kg=3000,mode3.mass_kg=1000,"
        } else {
            ""
        };
        p.apply_effect_spec(&format!("{}:{modes}{}={value}", e.name, q.key))
            .unwrap();
        assert!(e.is_enabled(&p));
        assert_eq!(e.read(&p, q.key), Some(value));
        // a value breaking the rule names the dotted key
        let err = Params::trees_lab()
            .apply_effect_spec(&format!("{}:{modes}{}=-5", e.name, q.key))
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

/// Issue 17 part 6: on a 6-t table the mass ranges shrink with the table, the
/// frequencies keep theirs, and a flow range follows the valve's flow gain.
#[test]
fn fit_bounds_scale_with_the_table() {
    let big = Params::trees_lab();
    let mut small = big;
    small.table.mass_kg = 6_000.0;
    small.actuator.flow_gain_m3_s *= 0.25;
    let k = 6_000.0 / big.table.mass_kg;
    let specimen = by_name("specimen").unwrap();
    let (a, b) = (specimen.fit_bounds(&big), specimen.fit_bounds(&small));
    assert!((b[0].upper / a[0].upper - k).abs() < 1e-12);
    assert_eq!(a[1], b[1]);
    let flow = by_name("flow_saturation").unwrap();
    let (a, b) = (flow.fit_bounds(&big), flow.fit_bounds(&small));
    assert!((b[0].upper / a[0].upper - 0.25).abs() < 1e-12);
}

#[test]
fn specimen_modes_reach_the_parameter_file_and_come_back() {
    let mut p = Params::trees_lab();
    p.apply_effect_spec(
        "specimen:mass_kg=15000,frequency_hz=6,damping_ratio=0.03,\
         mode2.mass_kg=4000,mode2.frequency_hz=17,mode3.mass_kg=1500,mode3.frequency_hz=31",
    )
    .unwrap();
    assert_eq!(p.specimen.modes().len(), 3);
    let text = p.to_toml_string();
    assert!(text.contains("[[specimen.modes]]"), "{text}");
    let back = Params::from_toml_str(&text, "t.toml").unwrap();
    assert_eq!(back, p);
    // one mode: no list, the block as it always was
    let one = Params::trees_lab().to_toml_string();
    assert!(!one.contains("modes"), "{one}");
    let block = "[specimen]\nenabled = true\nmass_kg = 10000.0\nfrequency_hz = 5.0\n\
                 damping_ratio = 0.02\n\n[foundation]";
    let mut q = Params::trees_lab();
    q.specimen.enabled = true;
    assert!(q.to_toml_string().contains(block));
}

#[test]
fn specimen_modes_are_checked_with_their_keys() {
    let bad = |text: &str| {
        Params::from_toml_str(text, "t.toml")
            .unwrap_err()
            .to_string()
    };
    let list = |entries: &str| format!("[specimen]\nenabled = true\nmodes = [{entries}]\n");
    let m = |mass: f64, f: f64| {
        format!("{{ mass_kg = {mass:?}, frequency_hz = {f:?}, damping_ratio = 0.02 }}")
    };
    // the list alone gives mode 1
    let p =
        Params::from_toml_str(&list(&[m(9000.0, 4.0), m(3000.0, 11.0)].join(", ")), "t").unwrap();
    assert_eq!(
        (p.specimen.mass_kg, p.specimen.mode2.frequency_hz),
        (9000.0, 11.0)
    );
    let four = [m(1.0, 1.0), m(1.0, 2.0), m(1.0, 3.0), m(1.0, 4.0)].join(", ");
    assert!(bad(&list(&four)).contains("at most 3") || bad(&list(&four)).contains("1 to 3"));
    let e = bad(&list(&[m(9000.0, 4.0), m(0.0, 11.0)].join(", ")));
    assert!(
        e.contains("specimen.mode2.mass_kg") && e.contains("> 0"),
        "{e}"
    );
    let e = bad(&list(&[m(9000.0, 4.0), m(3000.0, -1.0)].join(", ")));
    assert!(
        e.contains("specimen.mode2.frequency_hz") && e.contains("> 0"),
        "{e}"
    );
    let e = bad(&format!("{}mass_kg = 8000.0\n", list(&m(9000.0, 4.0))));
    assert!(
        e.contains("specimen.mass_kg") && e.contains("first mode"),
        "{e}"
    );
    let e = bad("[specimen]\nenabled = true\n[specimen.mode2]\nmass_kg = 1.0\n");
    assert!(e.contains("mode2"), "{e}");
    // --effect: a mode needs its mass, mode 3 needs mode 2
    let mut p = Params::trees_lab();
    let e = p
        .apply_effect_spec("specimen:mode2.frequency_hz=12")
        .unwrap_err();
    assert!(e.contains("specimen.mode2.mass_kg"), "{e}");
    let e = p
        .apply_effect_spec("specimen:mode3.mass_kg=100")
        .unwrap_err();
    assert!(
        e.contains("specimen.mode3.mass_kg") && e.contains("mode2"),
        "{e}"
    );
    let e = p
        .apply_effect_spec("specimen:mode2.mass_kg=100,mode2.damping_ratio=-1")
        .unwrap_err();
    assert!(
        e.contains("specimen.mode2.damping_ratio") && e.contains(">= 0"),
        "{e}"
    );
}

#[test]
fn free_play_is_validated_with_its_keys() {
    let mut p = Params::trees_lab();
    p.apply_effect_spec("free_play:gap_m=0.001,rod_mass_kg=900")
        .unwrap();
    assert_eq!((p.free_play.gap_m, p.free_play.rod_mass_kg), (0.001, 900.0));
    for (spec, key, rule) in [
        ("free_play:gap_m=-0.001", "free_play.gap_m", ">= 0"),
        ("free_play:rod_mass_kg=0", "free_play.rod_mass_kg", "> 0"),
        (
            "free_play:rod_mass_kg=41258",
            "free_play.rod_mass_kg",
            "table.mass_kg",
        ),
        (
            "free_play:contact_stiffness_n_m=0",
            "free_play.contact_stiffness_n_m",
            "> 0",
        ),
        (
            "free_play:contact_damping_ratio=-0.1",
            "free_play.contact_damping_ratio",
            ">= 0",
        ),
    ] {
        let e = Params::trees_lab().apply_effect_spec(spec).unwrap_err();
        assert!(e.contains(key) && e.contains(rule), "{spec}: {e}");
    }
    // the help names the new keys and the modes' syntax
    let help = effect_syntax_help();
    assert!(
        help.contains("free_play: gap_m (m, default 0.0002)"),
        "{help}"
    );
    assert!(help.contains("mode2.mass_kg (kg, default 0)"), "{help}");
    assert!(help.contains("mode 3 needs mode 2"), "{help}");
}

//! Two effects on the paper's whole campaign (90-s random tests), diagnosed as a user
//! would: the cause accepted first was fitted on a model that lacked the second, and the
//! full-length records resolve a hair of its bend (a deadband 0.26 % narrow left the slow
//! tests' displacement at twice the floor). Every polish refits the causes accepted
//! before with the new one; without that, such a pair came out `explained: false` with
//! the specimen's damping 6 % low. The hidden-effect suite's campaigns are 30 s long,
//! where this bend hides in the noise.

use std::process::Command;

/// The deadband (fitted on every slow test's reversals) within this share: the records
/// set it to a few hundredths of a percent once the specimen is in the model; 1 % is
/// four times the bend the refit removes.
const DEADBAND_TOLERANCE: f64 = 0.01;
/// The specimen's frequency within this share: its resonance in a 90-s random test is
/// read to a few hundredths of a percent.
const FREQUENCY_TOLERANCE: f64 = 0.005;
/// Its damping within this share: the bend left it 6 % low; the random tests' noise
/// leaves about 1 %.
const DAMPING_TOLERANCE: f64 = 0.03;
/// Its mass within this share (the hidden-effect suite's tolerance is 15 %).
const MASS_TOLERANCE: f64 = 0.02;

/// A 25-t specimen at 6.5 Hz (3 % damping) with a valve deadband of 0.8 % of the
/// spool's stroke, neither the one the behaviour was found on (seed 803).
const SPECIMEN: (f64, f64, f64) = (25e3, 6.5, 0.03);
const DEADBAND: f64 = 0.008;

#[test]
fn a_cause_found_first_is_refitted_with_the_second() {
    let (mass_kg, frequency_hz, damping) = SPECIMEN;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    let bin = env!("CARGO_BIN_EXE_shaketable");
    let specimen =
        format!("specimen:mass_kg={mass_kg},frequency_hz={frequency_hz},damping_ratio={damping}");
    let deadband = format!("valve_deadband:deadband={DEADBAND}");
    let o = Command::new(bin)
        .args(["campaign", "synth", "--quiet", "--seed", "806"])
        .args(["--effect", &specimen, "--effect", &deadband])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = tmp.path().join("diagnosis.json");
    let o = Command::new(bin)
        .args(["diagnose", "--quiet", "--json"])
        .arg(&json)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let causes = v["causes"].as_array().unwrap();
    let named = |effect: &str| {
        causes
            .iter()
            .find(|c| c["effect"] == effect)
            .unwrap_or_else(|| panic!("{effect} not named: {v:#}"))
    };
    assert_eq!(causes.len(), 2, "{v:#}");
    let off = |c: &serde_json::Value, key: &str, truth: f64| {
        c["parameters"][key].as_f64().unwrap() / truth - 1.0
    };
    let d = named("valve_deadband");
    let s = named("specimen");
    let errors = [
        (off(d, "deadband", DEADBAND), DEADBAND_TOLERANCE),
        (off(s, "frequency_hz", frequency_hz), FREQUENCY_TOLERANCE),
        (off(s, "damping_ratio", damping), DAMPING_TOLERANCE),
        (off(s, "mass_kg", mass_kg), MASS_TOLERANCE),
    ];
    for (error, tolerance) in errors {
        assert!(error.abs() < tolerance, "{errors:?}: {v:#}");
    }
    assert_eq!(v["explained"], true, "{v:#}");
}

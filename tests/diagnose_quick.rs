//! The quick diagnosis of the development loop (issue 15): short seeded campaigns (the
//! paper's three random tests, 20 s of band-limited motion each) diagnosed with
//! `shaketable diagnose --quick` as a user would, in seconds each: a specimen is named and
//! fitted on two noise seeds, and clean data gives `none`. A change to the
//! selection rules that breaks either shows here before the hidden-effect suite runs.

use std::path::Path;
use std::process::Command;

/// A quick fit's frequency must land within the hidden-effect suite's 5 %: three
/// iterations from the apparent mass's peak, which is read to a quarter hertz.
const FREQUENCY_TOLERANCE: f64 = 0.05;
/// Its mass within 20 %: the quick baseline's mass, refined three iterations, still holds
/// part of the specimen's (the full diagnosis's 15 % allows for the same).
const MASS_TOLERANCE: f64 = 0.20;

/// Synthesise the short campaign with `effects` (`--effect` specs) and `seed` into `dir`.
fn synthesise(dir: &Path, effects: &[String], seed: u64) {
    let mut args: Vec<String> = [
        "campaign",
        "synth",
        "--quiet",
        "--tests",
        "R1,R2,R3",
        "--random-duration",
        "20",
        "--seed",
    ]
    .map(String::from)
    .to_vec();
    args.push(seed.to_string());
    for e in effects {
        args.extend(["--effect".to_string(), e.clone()]);
    }
    args.push(dir.to_str().unwrap().into());
    let o = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(&args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `shaketable diagnose --quick` on `dir`: its JSON.
fn quick_diagnosis(dir: &Path) -> serde_json::Value {
    let json = dir.join("diagnosis.json");
    let o = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["diagnose", "--quiet", "--quick", "--json"])
        .arg(&json)
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("quick diagnosis"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    assert_eq!(v["effort"], "quick");
    v
}

/// A 15-t specimen at 5 Hz with 5 % damping: a building model in the middle of the
/// catalogue's range. One fixed case keeps this loop to seconds; the seeded draws over the
/// whole range are the hidden-effect suite's (`tests/diagnose_hidden.rs`), run with the
/// full diagnosis: a short campaign of the random tests alone gives the closed-loop
/// baseline, on which a 23-t specimen at 3.2 Hz takes minutes even quick.
const SPECIMEN: (f64, f64, f64) = (15e3, 5.0, 0.05);

#[test]
fn quick_diagnosis_names_and_fits_a_specimen() {
    let (mass_kg, frequency_hz, damping) = SPECIMEN;
    for seed in [31, 32] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("campaign");
        let spec = format!(
            "specimen:mass_kg={mass_kg},frequency_hz={frequency_hz},damping_ratio={damping}"
        );
        synthesise(&dir, std::slice::from_ref(&spec), seed);
        let v = quick_diagnosis(&dir);
        assert_eq!(v["causes"][0]["effect"], "specimen", "{spec}: {v:#}");
        let p = &v["causes"][0]["parameters"];
        let f = p["frequency_hz"].as_f64().unwrap();
        let m = p["mass_kg"].as_f64().unwrap();
        assert!(
            (f / frequency_hz - 1.0).abs() < FREQUENCY_TOLERANCE,
            "{spec}: frequency {f}"
        );
        assert!(
            (m / mass_kg - 1.0).abs() < MASS_TOLERANCE,
            "{spec}: mass {m}"
        );
        assert!(
            v["gain"].as_f64().unwrap() > 1.25,
            "{spec}: gain {}",
            v["gain"]
        );
        // measured against simulated on the report quarters: the specimen's resonance
        // moves the acceleration, and the extended model follows it where the table
        // alone does not (seed 31: 75-87 % -> 93-98 %; the oil-column test R3, whose
        // motion lies mostly above the specimen, gains least: 7 points)
        let acc: Vec<(f64, f64)> = v["fits"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["channel"] == "acceleration_m_s2")
            .map(|f| {
                let pct = |k: &str| f[k].as_f64().unwrap();
                (pct("baseline_fit_percent"), pct("extended_fit_percent"))
            })
            .collect();
        assert_eq!(acc.len(), 3, "{spec}: {}", v["fits"]);
        for (base, ext) in acc {
            assert!(
                ext > base + FIT_GAIN_POINTS && ext > EXTENDED_FIT_PERCENT,
                "{spec}: {}",
                v["fits"]
            );
        }
    }
}

/// Points of acceleration fit % the extended model must gain over the baseline on every
/// random test: the specimen's resonance leaves the table alone 7-22 points short (a
/// model gaining less than half of that has not found it).
const FIT_GAIN_POINTS: f64 = 3.0;
/// Acceleration fit % the extended model must reach on every random test: 93-98 % on seed
/// 31 where the noise allows 94-99.8 %; a specimen fitted to within the suite's
/// tolerances stays above 90 %.
const EXTENDED_FIT_PERCENT: f64 = 90.0;

#[test]
fn quick_diagnosis_of_clean_data_is_none() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    synthesise(&dir, &[], 33);
    let v = quick_diagnosis(&dir);
    assert_eq!(v["cause"], "none", "{v:#}");
    assert_eq!(v["causes"].as_array().unwrap().len(), 0);
}

//! `shaketable identify` as a lab runs it: on the files, with missing tests and a missing
//! spool channel, and on bad input.

use shaketable::campaign::format::{read_campaign, write_campaign};
use std::path::Path;
use std::process::Command;

fn shaketable(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(args)
        .output()
        .expect("run shaketable")
}

fn synth(dir: &Path, extra: &[&str]) {
    let mut args = vec![
        "campaign",
        "synth",
        "--quiet",
        "--seed",
        "3",
        "--random-duration",
        "40",
    ];
    args.extend_from_slice(extra);
    args.push(dir.to_str().unwrap());
    let o = shaketable(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn identify_writes_json_params_and_report_that_simulate_accepts() {
    let tmp = tempfile::tempdir().unwrap();
    let c = tmp.path().join("c");
    synth(&c, &[]);
    let json = tmp.path().join("id.json");
    let toml = tmp.path().join("id.toml");
    let report = tmp.path().join("report");
    let o = shaketable(&[
        "identify",
        c.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--params-out",
        toml.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for (block, key) in [
        ("servovalve", "gain"),
        ("servovalve", "time_constant_s"),
        ("servovalve", "natural_frequency_hz"),
        ("servovalve", "damping_ratio"),
        ("table", "mass_kg"),
        ("table", "mass_random_kg"),
        ("table", "mass_periodic_kg"),
        ("table", "stiffness_n_m"),
        ("oil_column", "frequency_hz"),
        ("oil_column", "damping_ratio"),
        ("oil_column", "bulk_modulus_pa"),
        ("friction", "force_n"),
        ("friction", "yield_displacement_m"),
        ("friction", "shape"),
        ("validation", "table_tf_error"),
        ("validation", "peak_hz"),
    ] {
        assert!(
            v[block][key].is_f64(),
            "{block}.{key} is {:?}",
            v[block][key]
        );
    }
    assert!((v["table"]["mass_kg"].as_f64().unwrap() / 41258.0 - 1.0).abs() < 0.02);
    // a table that moves as one body: no carried mode, no warning
    assert!(v["table"]["carried"].is_null(), "{}", v["table"]);
    assert_eq!(v["warnings"].as_array().map(Vec::len), Some(0));
    assert!(
        v["uncertainty"]["oil_column"]["frequency_hz"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    for f in [
        "index.html",
        "README.md",
        "servovalve.png",
        "mass_random.png",
        "oil_column.png",
        "triangles.png",
        "mass_periodic.png",
        "friction.png",
        "validation.png",
    ] {
        assert!(report.join(f).exists(), "{f} missing");
    }
    // the identified file runs in the simulator
    let sim = tmp.path().join("sim.csv");
    let o = shaketable(&[
        "simulate",
        "--params",
        toml.to_str().unwrap(),
        "--reference",
        c.join("R2.csv").to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(shaketable::Params::from_file(&toml).is_ok());
}

#[test]
fn missing_tests_and_spool_are_named_not_failed() {
    let tmp = tempfile::tempdir().unwrap();
    let c = tmp.path().join("c");
    synth(&c, &["--tests", "R2,R3,S3,T1"]);
    // drop the spool channel
    let mut camp = read_campaign(&c).unwrap();
    for r in &mut camp.records {
        r.spool_position = None;
    }
    let d = tmp.path().join("nospool");
    write_campaign(&camp, &d).unwrap();
    let json = tmp.path().join("id.json");
    let o = shaketable(&[
        "identify",
        d.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("no valve test"), "{out}");
    assert!(out.contains("R3 has no spool_position channel"), "{out}");
    assert!(out.contains("no slow sine test"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["servovalve"]["natural_frequency_hz"].is_null());
    assert!(v["oil_column"]["frequency_hz"].is_null());
    // what the data allows is still identified
    assert!((v["table"]["mass_kg"].as_f64().unwrap() / 41258.0 - 1.0).abs() < 0.02);
    // a table that moves as one body: no carried mode, no warning
    assert!(v["table"]["carried"].is_null(), "{}", v["table"]);
    assert_eq!(v["warnings"].as_array().map(Vec::len), Some(0));
    assert!(v["table"]["stiffness_n_m"].as_f64().unwrap().abs() < 2e4);
}

#[test]
fn bad_campaign_file_names_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let c = tmp.path().join("c");
    synth(&c, &["--tests", "R2"]);
    let csv = c.join("R2.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[5] = lines[5].replacen(',', ",abc,", 1);
    std::fs::write(&csv, lines.join("\n") + "\n").unwrap();
    let o = shaketable(&["identify", c.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("R2.csv") && err.contains("line 6"), "{err}");
}

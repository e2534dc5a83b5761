//! `shaketable frf` as a user runs it: files written, figures printed and consistent with
//! the library, bad input reported with the file and key.

use std::process::Command;

fn shaketable(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(args)
        .output()
        .expect("run shaketable")
}

#[test]
fn frf_writes_csv_png_and_figures() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frf");
    let params = dir.path().join("first.toml");
    std::fs::write(&params, "[servovalve]\nmodel = \"first_order\"\n").unwrap();
    let o = shaketable(&[
        "frf",
        "--params",
        params.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("servovalve first_order"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("figures.json")).unwrap()).unwrap();
    let peak = json["table_tf"]["peak_hz"].as_f64().unwrap();
    let mut p = shaketable::Params::trees_lab();
    p.servovalve.model = shaketable::params::ServovalveModel::FirstOrder;
    let lib = shaketable::linear::Linearisation::new(&p)
        .table_tf_figures()
        .unwrap();
    assert_eq!(peak, lib.peak_hz);
    assert!(stdout.contains(&format!("{:.3} Hz", lib.peak_hz)));
    // the CSV: header plus 1000 rows, the gain peaks near the printed peak
    let mut r = csv::Reader::from_path(out.join("frf.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 1000);
    let best = rows
        .iter()
        .map(|r| (r[0].parse::<f64>().unwrap(), r[1].parse::<f64>().unwrap()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!((best.0 - peak).abs() < 0.1, "CSV peak {} vs {peak}", best.0);
    let png = std::fs::read(out.join("bode.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn frf_reports_bad_parameter_file_with_key() {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("bad.toml");
    std::fs::write(&params, "[table]\nmass_kg = -5.0\n").unwrap();
    let o = shaketable(&["frf", "--params", params.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml") && err.contains("table.mass_kg"),
        "{err}"
    );
}

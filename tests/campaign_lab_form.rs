//! A laboratory's recordings read in place (campaign-format.md, "Recordings as
//! laboratories make them"): a synthesised campaign rewritten the way a data-acquisition
//! program exports it (a preamble, a header on line 7, `;` separators, a date column, an
//! event column that only the first row fills, millimetres, kilonewtons with the
//! opposite sign, g, no time column, one reference channel) reads back as the same
//! campaign through `[read]` and `[columns]`, and identifies the same table.

use shaketable::campaign::format::{read_campaign, write_campaign};
use shaketable::campaign::synth::{synthesise, SynthOptions};
use shaketable::campaign::{Campaign, Control, Record};
use shaketable::identify::{fit_mass, fit_servovalve, identify};
use shaketable::params::ServovalveModel;
use shaketable::Params;
use std::fmt::Write as _;
use std::path::Path;

const G: f64 = 9.80665;

fn small_campaign() -> Campaign {
    let opts = SynthOptions {
        seed: 5,
        random_duration_s: 12.0,
        ..SynthOptions::default()
    };
    synthesise(&Params::trees_lab(), &opts, None)
}

/// `r` as the DAQ exports it; `force_sign` is the lab's sign convention.
fn lab_text(r: &Record, control: Control, force_sign: f64) -> String {
    let mut s = String::from(
        "Header Size:  7\nVersion:  2\nSampling Interval:  0.001953125\nSampling Rate:  512\n",
    );
    let _ = writeln!(s, "Sample Count:  {}\nDevice Serial Number:  0", r.len());
    let reference = match control {
        Control::Displacement => "Ref_mm",
        Control::Acceleration => "Ref_g",
    };
    let _ = writeln!(
        s,
        "Sample Number; Date/Time; LVDT; Load; Accel; {reference}; Valve; Spool; Events"
    );
    for k in 0..r.len() {
        let reference = match control {
            Control::Displacement => r.ref_displacement_m[k] * 1000.0,
            Control::Acceleration => r.ref_acceleration_m_s2[k] / G,
        };
        let _ = write!(
            s,
            "{}; 06/29/2022 04:05:36.674 PM; {:e}; {:e}; {:e}; {:e}; {:e}; {:e}",
            k + 1,
            r.displacement_m.as_deref().unwrap()[k] * 1000.0,
            force_sign * r.force_n.as_deref().unwrap()[k] / 1000.0,
            r.acceleration_m_s2.as_deref().unwrap()[k] / G,
            reference,
            r.valve_command.as_deref().unwrap()[k],
            r.spool_position.as_ref().unwrap()[k],
        );
        s.push_str(if k == 0 { "; DAQ Start\n" } else { "\n" });
    }
    s
}

const LAB_TOML: &str = r#"
[read]
delimiter = ";"
header_line = 7

[columns]
displacement_m = { column = "LVDT", scale = 0.001 }
force_n = { column = "Load", scale = -1000.0 }
acceleration_m_s2 = { column = "Accel", scale = 9.80665 }
ref_displacement_m = { column = "Ref_mm", scale = 0.001 }
valve_command = "Valve"
spool_position = "Spool"
"#;

/// The campaign written in the lab's form into `dir`: campaign.toml from the original
/// with `[read]`/`[columns]`, files `.txt`; test R3 records force with the project's
/// sign and says so in its own `columns` override.
fn write_lab_campaign(c: &Campaign, dir: &Path) {
    write_campaign(c, dir).unwrap();
    let mut toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    for (spec, r) in c.info.tests.iter().zip(&c.records) {
        std::fs::remove_file(dir.join(&spec.file)).unwrap();
        let sign = if spec.name == "R3" { 1.0 } else { -1.0 };
        let txt = format!("{}.txt", spec.name);
        std::fs::write(dir.join(&txt), lab_text(r, spec.control, sign)).unwrap();
        toml = toml.replace(
            &format!("file = \"{}\"", spec.file),
            &format!("file = \"{txt}\""),
        );
    }
    // acceleration-controlled tests recorded their reference in g, not in mm
    let accel_ref = "ref_displacement_m = false, ref_acceleration_m_s2 = { column = \"Ref_g\", scale = 9.80665 }";
    toml = toml.replace(
        "name = \"R2\"\n",
        &format!("name = \"R2\"\ncolumns = {{ {accel_ref} }}\n"),
    );
    toml = toml.replace(
        "name = \"R3\"\n",
        &format!("name = \"R3\"\ncolumns = {{ {accel_ref}, force_n = {{ scale = 1000.0 }} }}\n"),
    );
    toml.push_str(LAB_TOML);
    std::fs::write(dir.join("campaign.toml"), toml).unwrap();
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// RMS of `a - b` over RMS of `b`.
fn rel_rms(a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    rms(&d) / rms(b).max(1e-300)
}

#[test]
fn a_lab_export_reads_back_as_the_campaign_it_came_from() {
    let c = small_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lab");
    write_lab_campaign(&c, &dir);
    let lab = read_campaign(&dir).unwrap();
    assert_eq!(lab.records.len(), c.records.len());
    for ((spec, a), b) in c.info.tests.iter().zip(&lab.records).zip(&c.records) {
        let n = &spec.name;
        assert_eq!(a.len(), b.len(), "{n}");
        for k in 0..a.len() {
            assert!((a.time_s[k] - b.time_s[k]).abs() < 1e-9, "{n} time {k}");
        }
        // scaled channels: the text keeps 17 digits, the scale costs an ulp or two
        for (what, x, y) in [
            ("displacement", &a.displacement_m, &b.displacement_m),
            ("force", &a.force_n, &b.force_n),
            ("acceleration", &a.acceleration_m_s2, &b.acceleration_m_s2),
        ] {
            let (x, y) = (x.as_deref().unwrap(), y.as_deref().unwrap());
            assert!(rel_rms(x, y) < 1e-12, "{n} {what}: {}", rel_rms(x, y));
        }
        assert_eq!(a.valve_command, b.valve_command, "{n}");
        // the derivatives computed from a recorded displacement reference match the
        // synthesised exact ones (band-limited, at rest at both ends); integrals of a
        // recorded acceleration reference are fixed up to their lowest frequencies only
        // (no record tells a displacement's drift), so the displacement is looser
        let (x, v, acc) = (
            rel_rms(&a.ref_displacement_m, &b.ref_displacement_m),
            rel_rms(&a.ref_velocity_m_s, &b.ref_velocity_m_s),
            rel_rms(&a.ref_acceleration_m_s2, &b.ref_acceleration_m_s2),
        );
        let shown = format!("{n}: reference x {x:.2e}, v {v:.2e}, a {acc:.2e}");
        match spec.control {
            Control::Displacement => assert!(x < 1e-12 && v < 1e-5 && acc < 1e-3, "{shown}"),
            Control::Acceleration => assert!(acc < 1e-12 && v < 2e-2 && x < 0.3, "{shown}"),
        }
        eprintln!("{shown}");
        // Sample Number is kept; the date and the event note are text and dropped
        let extras: Vec<&str> = a.extra.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(extras, ["Sample Number"], "{n}");
    }
}

#[test]
fn a_lab_export_identifies_the_same_table() {
    let c = small_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lab");
    write_lab_campaign(&c, &dir);
    let lab = read_campaign(&dir).unwrap();
    let (a, b) = (identify(&lab), identify(&c));
    let (ma, mb) = (a.mass_kg.unwrap(), b.mass_kg.unwrap());
    assert!((ma / mb - 1.0).abs() < 2e-3, "mass {ma} vs {mb}");
    let (ka, kb) = (
        a.params.actuator.bulk_modulus_pa,
        b.params.actuator.bulk_modulus_pa,
    );
    assert!((ka / kb - 1.0).abs() < 2e-2, "bulk modulus {ka} vs {kb}");
}

/// A one-test lab campaign (R1's first 200 samples) with `toml_extra` appended to its
/// campaign.toml and `edit` applied to its text; the error of reading it.
fn lab_error(toml_extra: &str, edit: impl Fn(String) -> String) -> String {
    let mut c = small_campaign();
    c.info.tests.truncate(1);
    c.records.truncate(1);
    let r = &mut c.records[0];
    let keep = 200;
    for ch in [
        &mut r.time_s,
        &mut r.ref_displacement_m,
        &mut r.ref_velocity_m_s,
        &mut r.ref_acceleration_m_s2,
        r.valve_command.as_mut().unwrap(),
        r.displacement_m.as_mut().unwrap(),
        r.acceleration_m_s2.as_mut().unwrap(),
        r.force_n.as_mut().unwrap(),
    ] {
        ch.truncate(keep);
    }
    r.spool_position.as_mut().unwrap().truncate(keep);
    r.extra.clear();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lab");
    write_lab_campaign(&c, &dir);
    let txt = dir.join("R1.txt");
    let text = std::fs::read_to_string(&txt).unwrap();
    std::fs::write(&txt, edit(text)).unwrap();
    let toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    std::fs::write(dir.join("campaign.toml"), toml + toml_extra).unwrap();
    match read_campaign(&dir) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn lab_form_mistakes_are_named() {
    let same = |t: String| t;
    assert_eq!(lab_error("", same), "", "the unedited campaign reads");
    let e = lab_error("", |t| t.replace("; Load;", "; Force;"));
    assert!(
        e.contains("column `Load` (mapped to `force_n`) not found") && e.contains("Force"),
        "{e}"
    );
    assert!(e.contains("R1.txt: line 7"), "{e}");
    // an event note holding the delimiter is the rest of that text column (real DAQs
    // write "DAQ Pause, DAQ Stop")...
    let e = lab_error("", |t| {
        t.replacen("; DAQ Start", "; DAQ Pause; DAQ Stop", 1)
    });
    assert_eq!(
        e, "",
        "a note with the delimiter in the last, text column reads"
    );
    // ... but a surplus cell after a numeric last column is a ragged row
    let e = lab_error("", |t| {
        t.replacen("; Spool; Events", "; Spool", 1)
            .replacen("; DAQ Start", "", 1)
            .replacen(" PM; ", " PM; 1; ", 2)
    });
    assert!(
        e.contains("ragged row: 9 cells but the header (line 7) has 8"),
        "{e}"
    );
    // a text cell in a used column names its line; in an unused one it is no error
    let e = lab_error("", |t| {
        let mut lines: Vec<String> = t.lines().map(str::to_string).collect();
        lines[20] = lines[20].replacen("; 06/29", "; n/a; 06/29", 1);
        lines[20] = lines[20].replacen("; n/a; 06/29/2022 04:05:36.674 PM", "; 06/29/2022; n/a", 1);
        lines.join("\n") + "\n"
    });
    assert!(
        e.contains("line 21: channel `LVDT`: `n/a` is not a number (mapped to `displacement_m`)"),
        "{e}"
    );
    let e = lab_error("", |t| t.replace("06/29/2022", "yesterday"));
    assert_eq!(e, "", "a date column nobody maps may hold anything");
}

#[test]
fn lab_form_keys_are_checked() {
    // the appended keys go into the last table of the file, `[columns]`
    let toml_with = |extra: &str| lab_error(extra, |t| t);
    let e = toml_with("pressure_a_pa = { column = \"Valve\", scale = 0.0 }\n");
    assert!(
        e.contains("columns.pressure_a_pa.scale") && e.contains("scale of 0"),
        "{e}"
    );
    let e = toml_with("pressure_a_pa = { column = \"Spool\", scal = 2.0 }\n");
    assert!(
        e.contains("columns.pressure_a_pa.scal") && e.contains("unknown key"),
        "{e}"
    );
    let e = toml_with("pressure_a_pa = { column = \"Valve\", offset = nan }\n");
    assert!(e.contains("not a finite number"), "{e}");
    // a further channel mapped from a column is kept under the channel's name
    assert_eq!(
        toml_with("pressure_a_pa = { column = \"Valve\", scale = 2.0 }\n"),
        ""
    );
    let e = toml_with("[read]\nheader_lines = 7\n");
    assert!(e.contains("not valid TOML"), "a second [read] table: {e}");
}

#[test]
fn read_keys_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let c = small_campaign();
    write_lab_campaign(&c, dir.path());
    let toml = std::fs::read_to_string(dir.path().join("campaign.toml")).unwrap();
    for (from, to, expect) in [
        ("header_line = 7", "header_lines = 7", "read.header_lines"),
        ("header_line = 7", "header_line = -1", "read.header_line"),
        (
            "delimiter = \";\"",
            "delimiter = \"semicolon\"",
            "not a delimiter",
        ),
        ("delimiter = \";\"", "delimiter = \",\"", "not found"),
    ] {
        std::fs::write(dir.path().join("campaign.toml"), toml.replace(from, to)).unwrap();
        let e = read_campaign(dir.path()).unwrap_err().to_string();
        assert!(e.contains(expect), "{to}: {e}");
    }
}

/// The lab's export with a decimal comma (a European locale's spreadsheet or DAQ
/// software: `1,25e-3` between `;`) reads back as the same campaign with `[read] decimal =
/// ","`, `campaign init` finds the comma, and a comma that would also separate cells is
/// refused by name.
#[test]
fn a_decimal_comma_export_reads_back_and_is_sniffed() {
    let c = small_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lab");
    write_lab_campaign(&c, &dir);
    for spec in &c.info.tests {
        let path = dir.join(format!("{}.txt", spec.name));
        let text = std::fs::read_to_string(&path).unwrap();
        let (head, rows) = text.split_at(text.find("Sample Number;").unwrap());
        std::fs::write(&path, format!("{head}{}", rows.replace('.', ","))).unwrap();
    }
    let toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    let with_comma = toml.replace("header_line = 7", "header_line = 7\ndecimal = \",\"");
    std::fs::write(dir.join("campaign.toml"), &with_comma).unwrap();
    let lab = read_campaign(&dir).unwrap();
    for ((spec, a), b) in c.info.tests.iter().zip(&lab.records).zip(&c.records) {
        for (x, y) in [
            (&a.displacement_m, &b.displacement_m),
            (&a.force_n, &b.force_n),
            (&a.acceleration_m_s2, &b.acceleration_m_s2),
        ] {
            let (x, y) = (x.as_deref().unwrap(), y.as_deref().unwrap());
            assert!(rel_rms(x, y) < 1e-12, "{}: {}", spec.name, rel_rms(x, y));
        }
    }
    // without the key the comma is named as what it is not: a number
    std::fs::write(dir.join("campaign.toml"), &toml).unwrap();
    let e = read_campaign(&dir).unwrap_err().to_string();
    assert!(e.contains("is not a number"), "{e}");
    let both = with_comma.replace("delimiter = \";\"", "delimiter = \",\"");
    std::fs::write(dir.join("campaign.toml"), both).unwrap();
    let e = read_campaign(&dir).unwrap_err().to_string();
    assert!(e.contains("could not be told"), "{e}");
    std::fs::remove_file(dir.join("campaign.toml")).unwrap();
    let o = shaketable(&["campaign", "init", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: toml::Table =
        toml::from_str(&std::fs::read_to_string(dir.join("campaign.toml")).unwrap()).unwrap();
    assert_eq!(v["read"]["delimiter"].as_str(), Some(";"));
    assert_eq!(v["read"]["decimal"].as_str(), Some(","));
}

/// `campaign init` on a lab export describes every file (columns, sample values, the
/// rate from the preamble) in a campaign.toml that is valid TOML, and never overwrites.
#[test]
fn campaign_init_describes_a_lab_export_and_never_overwrites() {
    let c = small_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lab");
    write_lab_campaign(&c, &dir);
    std::fs::remove_file(dir.join("campaign.toml")).unwrap();
    std::fs::write(dir.join("notes.md"), "# what we did on Tuesday\n").unwrap();
    let bin = env!("CARGO_BIN_EXE_shaketable");
    let run = || {
        std::process::Command::new(bin)
            .args(["campaign", "init", dir.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let o = run();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    let v: toml::Table = toml::from_str(&text).unwrap();
    assert_eq!(v["sample_rate_hz"].as_float(), Some(512.0));
    assert_eq!(v["read"]["delimiter"].as_str(), Some(";"));
    assert_eq!(v["read"]["header_line"].as_integer(), Some(7));
    assert_eq!(v["test"].as_array().unwrap().len(), c.records.len());
    assert!(text.contains("\"LVDT\": "), "{text}");
    assert!(text.contains("# skipped notes.md"), "{text}");
    let o = run();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("never overwrites"));
    assert_eq!(
        std::fs::read_to_string(dir.join("campaign.toml")).unwrap(),
        text
    );
}

fn shaketable(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(args)
        .output()
        .unwrap()
}

fn column(csv: &Path, name: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let j = lines
        .next()
        .unwrap()
        .split(',')
        .position(|h| h == name)
        .unwrap();
    lines
        .map(|l| l.split(',').nth(j).unwrap().parse().unwrap())
        .collect()
}

/// `simulate --campaign DIR --test NAME`: in the project's form it is the same run as
/// `--reference DIR/R1.csv` byte for byte; in a laboratory's form (a recorded
/// displacement reference only, in mm) it simulates the same motion.
#[test]
fn simulate_one_test_of_a_campaign() {
    let c = small_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let (own, lab) = (tmp.path().join("own"), tmp.path().join("lab"));
    write_campaign(&c, &own).unwrap();
    write_lab_campaign(&c, &lab);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let out = |n: &str| tmp.path().join(n);
    for (args, file) in [
        (
            vec![
                "--campaign".to_string(),
                s(&own),
                "--test".into(),
                "S3".into(),
            ],
            "by_test.csv",
        ),
        (
            vec!["--reference".to_string(), s(&own.join("S3.csv"))],
            "by_file.csv",
        ),
        (
            vec![
                "--campaign".to_string(),
                s(&lab),
                "--test".into(),
                "S3".into(),
            ],
            "lab.csv",
        ),
    ] {
        let mut all = vec!["simulate".to_string(), "--out".into(), s(&out(file))];
        all.extend(args);
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        let o = shaketable(&refs);
        assert!(
            o.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let (a, b) = (
        std::fs::read(out("by_test.csv")).unwrap(),
        std::fs::read(out("by_file.csv")).unwrap(),
    );
    assert!(a == b, "--test and --reference differ");
    let (x_lab, x_own) = (
        column(&out("lab.csv"), "displacement_m"),
        column(&out("by_file.csv"), "displacement_m"),
    );
    assert!(
        rel_rms(&x_lab, &x_own) < 1e-4,
        "{}",
        rel_rms(&x_lab, &x_own)
    );
    let o = shaketable(&[
        "simulate",
        "--campaign",
        &s(&own),
        "--test",
        "W9",
        "--out",
        &s(&out("x.csv")),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("no such test") && e.contains("R1, R2"),
        "{e}"
    );
}

/// A MATLAB level-5 file (uncompressed, little-endian) of double row vectors: written by
/// hand here so the test needs no MATLAB or Python.
fn mat_file(vars: &[(&str, Vec<f64>)]) -> Vec<u8> {
    let mut out = vec![b' '; 116];
    out[..19].copy_from_slice(b"MATLAB 5.0 MAT-file");
    out.extend_from_slice(&[0u8; 8]);
    out.extend_from_slice(&0x0100u16.to_le_bytes());
    out.extend_from_slice(b"IM");
    let element = |ty: u32, data: &[u8]| {
        let mut e = Vec::new();
        e.extend_from_slice(&ty.to_le_bytes());
        e.extend_from_slice(&(data.len() as u32).to_le_bytes());
        e.extend_from_slice(data);
        while e.len() % 8 != 0 {
            e.push(0);
        }
        e
    };
    for (name, x) in vars {
        let mut body = Vec::new();
        body.extend(element(6, &[6u8, 0, 0, 0, 0, 0, 0, 0])); // miUINT32 flags: mxDOUBLE
        let dims: Vec<u8> = [1i32, x.len() as i32]
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect();
        body.extend(element(5, &dims)); // miINT32 dimensions 1 x n
        body.extend(element(1, name.as_bytes())); // miINT8 name
        let data: Vec<u8> = x.iter().flat_map(|v| v.to_le_bytes()).collect();
        body.extend(element(9, &data)); // miDOUBLE
        out.extend(element(14, &body)); // miMATRIX
    }
    out
}

/// A test recorded in a MATLAB file (lab variable names, mm and kN) reads back through
/// `[columns]` as the record it came from; a mapped variable the file lacks is named.
#[test]
fn a_matlab_recording_reads_back_through_the_mapping() {
    let mut c = small_campaign();
    c.info.tests.truncate(1); // R1, displacement control
    c.records.truncate(1);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("mat");
    write_campaign(&c, &dir).unwrap();
    let r = &c.records[0];
    let scaled = |x: &[f64], k: f64| x.iter().map(|v| v * k).collect::<Vec<f64>>();
    let vars = [
        (
            "lvdt_mm",
            scaled(r.displacement_m.as_deref().unwrap(), 1000.0),
        ),
        ("load_kN", scaled(r.force_n.as_deref().unwrap(), 1e-3)),
        ("acc", r.acceleration_m_s2.clone().unwrap()),
        ("ref_mm", scaled(&r.ref_displacement_m, 1000.0)),
        ("u", r.valve_command.clone().unwrap()),
    ];
    std::fs::remove_file(dir.join("R1.csv")).unwrap();
    std::fs::write(dir.join("R1.mat"), mat_file(&vars)).unwrap();
    let toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    let toml = toml.replace("file = \"R1.csv\"", "file = \"R1.mat\"")
        + "\n[columns]\ndisplacement_m = { column = \"lvdt_mm\", scale = 0.001 }\n\
           force_n = { column = \"load_kN\", scale = 1000.0 }\n\
           acceleration_m_s2 = \"acc\"\nref_displacement_m = { column = \"ref_mm\", scale = 0.001 }\n\
           valve_command = \"u\"\n";
    std::fs::write(dir.join("campaign.toml"), &toml).unwrap();
    let got = read_campaign(&dir).unwrap();
    let a = &got.records[0];
    let both = |x: &Option<Vec<f64>>, y: &Option<Vec<f64>>| {
        rel_rms(x.as_deref().unwrap(), y.as_deref().unwrap())
    };
    assert!(both(&a.displacement_m, &r.displacement_m) < 1e-12);
    assert!(both(&a.force_n, &r.force_n) < 1e-12);
    assert_eq!(a.valve_command, r.valve_command);
    assert!(rel_rms(&a.ref_velocity_m_s, &r.ref_velocity_m_s) < 1e-5);
    assert!((a.time_s[100] - r.time_s[100]).abs() < 1e-12);
    std::fs::write(
        dir.join("campaign.toml"),
        toml.replace("\"acc\"", "\"accel\""),
    )
    .unwrap();
    let e = read_campaign(&dir).unwrap_err().to_string();
    assert!(
        e.contains("R1.mat") && e.contains("`accel`") && e.contains("lvdt_mm"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------
// tests at their own sample rates (campaign-format.md, "campaign.toml additions":
// `sample_rate_hz` is the default for every test; a test may set its own)
// ---------------------------------------------------------------------------------------

/// Rates of the two-rate campaign: the valve test R1 at 1 kHz, the mass test R2 at the
/// synthesiser's 512 Hz, and a campaign default that neither uses (so that a consumer
/// reading the campaign's rate instead of the test's gets every test wrong).
const R1_HZ: f64 = 1000.0;
const R2_HZ: f64 = 512.0;
const DEFAULT_HZ: f64 = 2048.0;

/// R1 and R2 of the paper's program synthesised by the project's simulator, each at its
/// own rate, 30 s of random data (enough for the valve and mass accuracies of
/// tests/identify_accuracy.rs); returns the truth too.
fn two_rate_campaign() -> (Campaign, Params) {
    use shaketable::campaign::synth::{selected_program, synthesise_program};
    let opts = SynthOptions {
        seed: 7,
        random_duration_s: 30.0,
        tests: Some(vec!["R1".into(), "R2".into()]),
        ..SynthOptions::default()
    };
    let mut program = selected_program(&opts);
    for (_, spec) in &mut program {
        spec.sample_rate_hz = Some(if spec.name == "R1" { R1_HZ } else { R2_HZ });
    }
    let truth = Params::trees_lab();
    let mut c = synthesise_program(&truth, &program, &opts, None).unwrap();
    c.info.sample_rate_hz = DEFAULT_HZ;
    (c, truth)
}

/// Seconds between the first two samples of `csv`'s time column.
fn first_step_s(csv: &Path) -> f64 {
    let t = column(csv, "time_s");
    t[1] - t[0]
}

#[test]
fn tests_at_their_own_rates_read_check_identify_and_simulate() {
    let (c, truth) = two_rate_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rates");
    write_campaign(&c, &dir).unwrap();
    let toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    assert!(toml.contains("sample_rate_hz = 1000.0"), "{toml}");
    // read: each time column checked against its test's rate
    let got = read_campaign(&dir).unwrap();
    assert_eq!(got.info.sample_rate_hz, DEFAULT_HZ);
    for (spec, want) in got.info.tests.iter().zip([R1_HZ, R2_HZ]) {
        assert_eq!(got.sample_rate_for(spec), want, "{}", spec.name);
    }
    assert_eq!(got.records, c.records);
    // campaign check passes and says which test runs at which rate
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let o = shaketable(&["campaign", "check", &s(&dir)]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains("R1 at 1000 Hz, R2 at 512 Hz"), "{out}");
    // identification: the valve from R1 at 1 kHz, the mass from R2 at 512 Hz
    let id = identify(&got);
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    let second_order = truth.servovalve.model == ServovalveModel::SecondOrder;
    let valve_err = |v: &shaketable::identify::ServovalveFit| match second_order {
        true => rel(
            v.natural_frequency_hz,
            truth.servovalve.natural_frequency_hz,
        ),
        false => rel(v.time_constant_s, truth.servovalve.time_constant_s),
    };
    // the tolerances of tests/identify_accuracy.rs (the valve's 3 % on f_v, 10 % on tau)
    let valve_tol = if second_order { 0.03 } else { 0.10 };
    let v = id.servovalve.as_ref().expect("servovalve identified");
    assert!(valve_err(v) < valve_tol, "valve error {}", valve_err(v));
    // what this checks: R1 read at the campaign's default rate would be far off
    let (_, r1) = got.test("R1").unwrap();
    let wrong = fit_servovalve("R1", r1, DEFAULT_HZ).map_or(f64::INFINITY, |v| valve_err(&v));
    assert!(
        wrong > valve_tol,
        "R1 at the default rate: valve error {wrong}"
    );
    let m = id.mass_random.as_ref().expect("mass identified").mass_kg;
    assert!(rel(m, truth.table.mass_kg) < 0.02, "mass {m}");
    let (_, r2) = got.test("R2").unwrap();
    let wrong = fit_mass("R2", r2, DEFAULT_HZ).map_or(f64::INFINITY, |m| m.mass_kg);
    assert!(
        rel(wrong, truth.table.mass_kg) > 0.02,
        "R2 at the default rate: {wrong}"
    );
    eprintln!(
        "valve error {:.2} %, mass error {:.2} %",
        100.0 * valve_err(v),
        100.0 * rel(m, truth.table.mass_kg)
    );
    // simulate one test: written at that test's rate
    for (name, fs) in [("R1", R1_HZ), ("R2", R2_HZ)] {
        let csv = tmp.path().join(format!("{name}_sim.csv"));
        let o = shaketable(&[
            "simulate",
            "--campaign",
            &s(&dir),
            "--test",
            name,
            "--out",
            &s(&csv),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!((first_step_s(&csv) * fs - 1.0).abs() < 1e-9, "{name}");
        let (_, rec) = got.test(name).unwrap();
        assert_eq!(column(&csv, "time_s").len(), rec.len(), "{name}");
    }
}

/// In a laboratory's form without a time column, each test's time comes from its own rate.
#[test]
fn a_lab_export_at_two_rates_takes_each_tests_time_from_its_rate() {
    let (c, _) = two_rate_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lab");
    write_lab_campaign(&c, &dir);
    let lab = read_campaign(&dir).unwrap();
    for ((spec, a), b) in c.info.tests.iter().zip(&lab.records).zip(&c.records) {
        assert_eq!(a.len(), b.len(), "{}", spec.name);
        let last = a.len() - 1;
        assert!(
            (a.time_s[last] - b.time_s[last]).abs() < 1e-9,
            "{}",
            spec.name
        );
    }
}

/// A bad per-test rate is an error naming campaign.toml's line, the test and the key; a
/// rate the test's time column disagrees with names the record's line and where the rate
/// was given.
#[test]
fn a_bad_per_test_rate_is_named() {
    let (c, _) = two_rate_campaign();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rates");
    write_campaign(&c, &dir).unwrap();
    let toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    let line = toml
        .lines()
        .position(|l| l == "sample_rate_hz = 1000.0")
        .unwrap()
        + 1;
    for (bad, why) in [
        ("0.0", "must be a finite number > 0"),
        ("-512.0", "must be a finite number > 0"),
        ("nan", "must be finite"),
        ("\"fast\"", "expected a number"),
    ] {
        let text = toml.replace(
            "sample_rate_hz = 1000.0",
            &format!("sample_rate_hz = {bad}"),
        );
        std::fs::write(dir.join("campaign.toml"), text).unwrap();
        let e = read_campaign(&dir).unwrap_err().to_string();
        for want in [
            "campaign.toml: ",
            &format!("line {line}: "),
            "test `R1`",
            "key `sample_rate_hz`",
            why,
        ] {
            assert!(e.contains(want), "{bad}: no `{want}` in {e}");
        }
    }
    // 1 % off the time column's 1 kHz: a rate mismatch, named in both files
    let text = toml.replace("sample_rate_hz = 1000.0", "sample_rate_hz = 1010.0");
    std::fs::write(dir.join("campaign.toml"), text).unwrap();
    let e = read_campaign(&dir).unwrap_err().to_string();
    for want in [
        "R1.csv: line 3: sample rate disagrees",
        "1000 Hz",
        &format!("campaign.toml line {line} (test `R1`, key `sample_rate_hz`) says 1010 Hz"),
    ] {
        assert!(e.contains(want), "no `{want}` in {e}");
    }
}

/// The spool refinement pools tests (diagnosis' output-error valve): each record is
/// simulated at its own rate, so a start 30 % off comes back to the truth; read at one
/// rate, the pooled fit is off.
#[test]
fn the_spool_refinement_pools_tests_each_at_its_rate() {
    use shaketable::identify::spool::refine_servovalve;
    let (c, truth) = two_rate_campaign();
    let second_order = truth.servovalve.model == ServovalveModel::SecondOrder;
    let mut start = truth.servovalve;
    start.time_constant_s *= 1.3;
    start.natural_frequency_hz /= 1.3;
    let err = |v: &shaketable::params::Servovalve| match second_order {
        true => (v.natural_frequency_hz / truth.servovalve.natural_frequency_hz - 1.0).abs(),
        false => (v.time_constant_s / truth.servovalve.time_constant_s - 1.0).abs(),
    };
    let at = |rate: &dyn Fn(usize) -> f64| -> f64 {
        let rated: Vec<_> = (0..c.records.len())
            .map(|i| (&c.records[i], rate(i)))
            .collect();
        refine_servovalve(&start, &rated, |n| 0..n).map_or(f64::INFINITY, |v| err(&v))
    };
    let own = at(&|i| c.sample_rate_of(i));
    // the tolerance of tests/identify_accuracy.rs on the valve (3 % on f_v, 10 % on tau)
    let tol = if second_order { 0.03 } else { 0.10 };
    assert!(own < tol, "each at its own rate: valve error {own}");
    let one = at(&|_| c.info.sample_rate_hz);
    eprintln!("valve error: each at its own rate {own:.2e}, all at one rate {one:.2e}");
    assert!(
        one > tol,
        "every test at the campaign's rate: valve error {one}"
    );
}

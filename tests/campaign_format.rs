//! The campaign format (campaign-format.md): round trip, and every bad-input rule gives
//! an error naming the file and the line (and, for campaign.toml, the key and the test);
//! never a panic.

use proptest::prelude::*;
use shaketable::campaign::format::{
    read_campaign, read_record, read_record_str, read_reference, write_campaign, write_record,
    CampaignError,
};
use shaketable::campaign::provenance::Source;
use shaketable::campaign::{
    Campaign, CampaignInfo, Control, ControllerOverride, Geometry, Record, TestKind, TestSpec,
};
use shaketable::Params;
use std::path::{Path, PathBuf};

const FS: f64 = 512.0;
const HEADER: &str = "time_s,ref_displacement_m,ref_velocity_m_s,ref_acceleration_m_s2,valve_command,spool_position,displacement_m,acceleration_m_s2,force_n";

/// A valid CSV body: `n` rows at 512 Hz.
fn rows(n: usize) -> Vec<String> {
    (0..n)
        .map(|k| {
            let t = k as f64 / FS;
            format!(
                "{t},{},{},{},{},{},{},{},{}",
                1e-3 * (k as f64).sin(),
                0.01 * k as f64,
                -0.5,
                0.0125,
                0.02,
                1e-3 * (k as f64).cos(),
                0.1,
                1234.5
            )
        })
        .collect()
}

fn csv(lines: &[String]) -> String {
    let mut s = lines.join("\n");
    s.push('\n');
    s
}

fn valid_lines() -> Vec<String> {
    let mut l = vec![HEADER.to_string()];
    l.extend(rows(6));
    l
}

/// Assert an error names `file` and `line N`, and mentions every `words`.
fn assert_names(e: &CampaignError, file: &Path, line: usize, words: &[&str]) {
    let msg = e.to_string();
    let f = file.display().to_string();
    assert!(msg.contains(&f), "message does not name {f}: {msg}");
    assert!(
        msg.contains(&format!("line {line}:")),
        "message does not name line {line}: {msg}"
    );
    assert_eq!(e.line(), Some(line), "{msg}");
    for w in words {
        assert!(msg.contains(w), "message does not mention `{w}`: {msg}");
    }
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Write `lines` as a CSV and read it; it must fail at `line` mentioning `words`.
fn csv_fails(lines: &[String], line: usize, words: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "R1.csv", &csv(lines));
    let e = read_record(&p, FS).expect_err("bad record accepted");
    assert_names(&e, &p, line, words);
}

#[test]
fn a_valid_record_reads() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "R1.csv", &csv(&valid_lines()));
    let r = read_record(&p, FS).unwrap();
    assert_eq!(r.len(), 6);
    assert_eq!(r.time_s[1], 1.0 / 512.0);
    assert_eq!(r.force_n, Some(vec![1234.5; 6]));
    assert!(r.spool_position.is_some());
    assert!(r.extra.is_empty());
    // a spreadsheet's byte-order mark and CRLF line ends are fine
    let text = format!("\u{feff}{}", csv(&valid_lines()).replace('\n', "\r\n"));
    let p2 = write(dir.path(), "R2.csv", &text);
    assert_eq!(read_record(&p2, FS).unwrap(), r);
}

#[test]
fn ragged_rows() {
    let mut l = valid_lines();
    l[3] = l[3].rsplit_once(',').unwrap().0.to_string(); // one cell short
    csv_fails(&l, 4, &["ragged row", "8 cells", "9 channels"]);
    let mut l = valid_lines();
    l[5].push_str(",7.0"); // one cell too many
    csv_fails(&l, 6, &["ragged row", "10 cells"]);
}

#[test]
fn non_numeric_and_empty_cells() {
    let mut l = valid_lines();
    l[2] = l[2].replacen(",0.0125,", ",abc,", 1);
    csv_fails(&l, 3, &["`abc` is not a number", "valve_command"]);
    let mut l = valid_lines();
    l[4] = l[4].replacen(",1234.5", ",", 1);
    csv_fails(&l, 5, &["empty cell", "force_n"]);
}

#[test]
fn nan_and_infinity() {
    for bad in ["NaN", "nan", "inf", "-inf", "infinity", "1e999"] {
        let mut l = valid_lines();
        l[3] = l[3].replacen(",0.1,", &format!(",{bad},"), 1);
        csv_fails(&l, 4, &["not finite", "acceleration_m_s2"]);
    }
}

#[test]
fn time_not_increasing() {
    let mut l = valid_lines();
    // row 4 (line 5) repeats the time of row 3
    let t3 = 2.0 / FS;
    l[4] = l[4].replacen(&format!("{}", 3.0 / FS), &format!("{t3}"), 1);
    csv_fails(&l, 5, &["not increasing"]);
    let mut l = valid_lines();
    l[6] = l[6].replacen(&format!("{}", 5.0 / FS), "0.001", 1);
    csv_fails(&l, 7, &["not increasing"]);
}

#[test]
fn non_uniform_time() {
    // a missing sample: line 5 jumps by two steps, the others are uniform
    let mut l = vec![HEADER.to_string()];
    let mut r = rows(40);
    r.remove(3);
    l.extend(r);
    csv_fails(&l, 5, &["non-uniform time"]);
}

#[test]
fn sample_rate_disagrees_with_time() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "R1.csv", &csv(&valid_lines()));
    let e = read_record(&p, 500.0).expect_err("500 Hz accepted for 512 Hz data");
    assert_names(&e, &p, 3, &["sample rate disagrees", "512", "500"]);
}

#[test]
fn missing_required_channel() {
    let mut l = valid_lines();
    l.insert(0, "# recorded by the MTS controller".to_string());
    l.insert(1, "".to_string());
    l[2] = l[2].replace(",force_n", ",load_n");
    csv_fails(&l, 3, &["missing required channel", "`force_n`"]);
}

#[test]
fn empty_records() {
    csv_fails(&[HEADER.to_string()], 1, &["empty record"]);
    csv_fails(
        &["# only a comment".to_string(), "".to_string()],
        1,
        &["empty record"],
    );
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "E.csv", "");
    let e = read_record(&p, FS).unwrap_err();
    assert_names(&e, &p, 1, &["empty record"]);
}

#[test]
fn duplicate_channel() {
    let mut l = valid_lines();
    l[0] = l[0].replace("valve_command", "force_n");
    csv_fails(&l, 1, &["`force_n` appears twice"]);
}

#[test]
fn comment_lines_are_skipped_but_counted() {
    let mut l = valid_lines();
    l.insert(0, "# TREES Lab, 2009".to_string());
    l.insert(3, "# operator note".to_string());
    l.insert(4, "   ".to_string());
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "R1.csv", &csv(&l));
    let r = read_record(&p, FS).unwrap();
    assert_eq!(r.len(), 6);
    // the bad cell is on physical line 8 (comments and the blank line count)
    l[7] = l[7].replacen(",0.0125,", ",x,", 1);
    csv_fails(&l, 8, &["`x` is not a number"]);
}

#[test]
fn missing_spool_and_extra_channels() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("time_s,ref_displacement_m,ref_velocity_m_s,ref_acceleration_m_s2,valve_command,displacement_m,acceleration_m_s2,force_n,velocity_m_s,oil_temperature_c\r\n");
    for k in 0..5 {
        text.push_str(&format!("{},0,0,0,0,0,0,0,{},40.5\r\n", k as f64 / FS, k));
    }
    let p = write(dir.path(), "R1.csv", &text);
    let r = read_record(&p, FS).unwrap();
    assert!(r.spool_position.is_none());
    assert_eq!(r.extra.len(), 2);
    assert_eq!(r.extra[0].0, "velocity_m_s");
    assert_eq!(r.extra[0].1, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
    assert_eq!(r.extra[1], ("oil_temperature_c".to_string(), vec![40.5; 5]));
}

#[test]
fn reference_only_files_for_simulate() {
    let dir = tempfile::tempdir().unwrap();
    let mut text =
        String::from("time_s,ref_displacement_m,ref_velocity_m_s,ref_acceleration_m_s2\n");
    for k in 0..10 {
        text.push_str(&format!("{},{},0,0\n", k as f64 / 256.0, k));
    }
    let p = write(dir.path(), "ref.csv", &text);
    let r = read_reference(&p, None).unwrap();
    assert_eq!(r.sample_rate_hz, 256.0);
    assert_eq!(r.ref_displacement_m[9], 9.0);
    let e = read_reference(&p, Some(512.0)).unwrap_err();
    assert_names(&e, &p, 3, &["sample rate disagrees"]);
    // a record (not only a reference) needs the measured channels
    let e = read_record(&p, 256.0).unwrap_err();
    assert_names(&e, &p, 1, &["valve_command", "force_n"]);
}

// ---------------------------------------------------------------------------------------
// campaign.toml and whole campaigns
// ---------------------------------------------------------------------------------------

const TOML: &str = r#"name = "TREES Lab bare table, 2009 characterisation"
sample_rate_hz = 512.0
operator = "kept and ignored"

[geometry]
piston_area_m2 = 0.0911
total_oil_volume_m3 = 0.12101
supply_pressure_pa = 28.0e6
flow_gain_m3_s = 0.2

[controller]
kp = 10.0
kv = 0.0
ka = 0.0
fv = 0.4555
fa = 0.0
kdp = 3.293e-8

[lab]
city = "Pavia"

[[test]]
name = "R1"
file = "R1.csv"
kind = "random"
control = "displacement"
rms = 0.005
band_hz = [0.0, 125.0]
controller = { fv = 0.0 }
notes = "kept and ignored"

[[test]]
name = "S3"
file = "S3.csv"
kind = "sine"
control = "displacement"
frequency_hz = 0.5
amplitude_m = 0.05
"#;

/// A campaign directory with campaign.toml = `toml` and two valid records.
fn campaign_dir(toml: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "campaign.toml", toml);
    write(dir.path(), "R1.csv", &csv(&valid_lines()));
    write(dir.path(), "S3.csv", &csv(&valid_lines()));
    dir
}

/// Read a campaign whose campaign.toml is `toml`; expect an error naming campaign.toml,
/// `line`, and mentioning `words` (key, test, ...).
fn toml_fails(toml: &str, line: Option<usize>, words: &[&str]) -> String {
    let dir = campaign_dir(toml);
    let e = read_campaign(dir.path()).expect_err("bad campaign.toml accepted");
    let msg = e.to_string();
    let file = dir.path().join("campaign.toml").display().to_string();
    assert!(msg.contains(&file), "message does not name {file}: {msg}");
    assert_eq!(e.line(), line, "{msg}");
    if let Some(l) = line {
        assert!(msg.contains(&format!("line {l}:")), "no line {l}: {msg}");
    }
    for w in words {
        assert!(msg.contains(w), "message does not mention `{w}`: {msg}");
    }
    msg
}

/// Line (1-based) of the first occurrence of `needle` in `text` at or after line `from`.
fn line_of(text: &str, needle: &str, from: usize) -> usize {
    text.lines()
        .enumerate()
        .skip(from.saturating_sub(1))
        .find(|(_, l)| l.contains(needle))
        .map(|(i, _)| i + 1)
        .unwrap()
}

#[test]
fn a_valid_campaign_reads_with_unknown_keys_ignored() {
    let dir = campaign_dir(TOML);
    let c = read_campaign(dir.path()).unwrap();
    assert_eq!(c.info.name, "TREES Lab bare table, 2009 characterisation");
    assert_eq!(c.info.sample_rate_hz, 512.0);
    assert_eq!(c.info.geometry.supply_pressure_pa, Some(28.0e6));
    assert_eq!(c.info.controller.kdp, Some(3.293e-8));
    assert_eq!(c.info.tests.len(), 2);
    let (r1, rec) = c.test("R1").unwrap();
    assert_eq!(r1.kind, TestKind::Random);
    assert_eq!(r1.band_hz, Some([0.0, 125.0]));
    assert_eq!(c.controller_for(r1).unwrap().fv, 0.0);
    assert_eq!(c.controller_for(r1).unwrap().kp, 10.0);
    assert_eq!(rec.len(), 6);
    let (s3, _) = c.test("S3").unwrap();
    assert_eq!((s3.frequency_hz, s3.amplitude_m), (Some(0.5), Some(0.05)));
}

#[test]
fn missing_required_keys_name_file_key_and_test() {
    // a test without `control`: the line of its [[test]] header
    let t = TOML.replacen(
        "control = \"displacement\"\nfrequency_hz",
        "frequency_hz",
        1,
    );
    let l = line_of(&t, "[[test]]", line_of(&t, "name = \"R1\"", 1));
    toml_fails(&t, Some(l), &["test `S3`", "key `control`", "missing"]);
    // a test without `file`
    let t = TOML.replacen("file = \"R1.csv\"\n", "", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "[[test]]", 1)),
        &["test `R1`", "key `file`", "missing"],
    );
    // a test without a name
    let t = TOML.replacen("name = \"S3\"\n", "", 1);
    let l = line_of(&t, "[[test]]", line_of(&t, "name = \"R1\"", 1));
    toml_fails(
        &t,
        Some(l),
        &["test `#2 (unnamed)`", "key `name`", "missing"],
    );
    // top level: no line to point at, but file and key
    let t = TOML.replacen("sample_rate_hz = 512.0\n", "", 1);
    toml_fails(&t, None, &["key `sample_rate_hz`", "missing"]);
}

/// campaign-format.md: every `[geometry]` and `[controller]` key is optional; one not
/// given is unknown (not a default), and simulating a test needs its gains.
#[test]
fn missing_geometry_and_gains_are_unknown_not_defaults() {
    let t = TOML.replacen("flow_gain_m3_s = 0.2\n", "", 1);
    let c = read_campaign(campaign_dir(&t).path()).unwrap();
    assert_eq!(c.info.geometry.flow_gain_m3_s, None);
    assert_eq!(c.info.geometry.piston_area_m2, Some(0.0911));
    let mut p = Params::trees_lab();
    p.actuator.flow_gain_m3_s = 1.5;
    assert_eq!(
        c.info.geometry.apply_to(&mut p),
        vec!["actuator.flow_gain_m3_s"]
    );
    assert_eq!(
        p.actuator.flow_gain_m3_s, 1.5,
        "an unknown key leaves the value alone"
    );
    let t = TOML.replacen("kdp = 3.293e-8\n", "", 1);
    let c = read_campaign(campaign_dir(&t).path()).unwrap();
    let (r1, _) = c.test("R1").unwrap();
    let e = c.controller_for(r1).unwrap_err();
    assert_eq!(e.gains, vec!["kdp"]);
    assert!(
        e.to_string().contains("kdp") && e.to_string().contains("R1"),
        "{e}"
    );
    assert!(c.gains_known().is_err());
    // a test's own override completes the gains for that test
    let t2 = t.replacen(
        "controller = { fv = 0.0 }",
        "controller = { fv = 0.0, kdp = 1e-8 }",
        1,
    );
    let c = read_campaign(campaign_dir(&t2).path()).unwrap();
    assert_eq!(c.controller_for(c.test("R1").unwrap().0).unwrap().kdp, 1e-8);
    assert!(c.controller_for(c.test("S3").unwrap().0).is_err());
    // no [geometry] at all
    let t = TOML.replacen("[geometry]", "[geometry_old]", 1);
    let c = read_campaign(campaign_dir(&t).path()).unwrap();
    assert_eq!(c.info.geometry, Geometry::default());
}

#[test]
fn unknown_kind_and_control() {
    let t = TOML.replacen("kind = \"sine\"", "kind = \"sweep\"", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "sweep", 1)),
        &["test `S3`", "key `kind`", "unknown kind `sweep`"],
    );
    let t = TOML.replacen("control = \"displacement\"", "control = \"force\"", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "\"force\"", 1)),
        &["test `R1`", "key `control`", "unknown control `force`"],
    );
}

#[test]
fn random_needs_rms_and_band() {
    let t = TOML.replacen("rms = 0.005\n", "", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "[[test]]", 1)),
        &["test `R1`", "key `rms`", "missing"],
    );
    let t = TOML.replacen("band_hz = [0.0, 125.0]\n", "", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "[[test]]", 1)),
        &["test `R1`", "key `band_hz`", "missing"],
    );
    let t = TOML.replacen("band_hz = [0.0, 125.0]", "band_hz = [0.0, 300.0]", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "band_hz", 1)),
        &["test `R1`", "key `band_hz`", "Nyquist"],
    );
    let t = TOML.replacen("band_hz = [0.0, 125.0]", "band_hz = [50.0, 5.0]", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "band_hz", 1)),
        &["key `band_hz`", "low < high"],
    );
    let t = TOML.replacen("rms = 0.005", "rms = \"high\"", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "rms =", 1)),
        &["test `R1`", "key `rms`", "expected a number"],
    );
    let t = TOML.replacen("rms = 0.005", "rms = -0.005", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "rms =", 1)),
        &["test `R1`", "key `rms`", "> 0"],
    );
}

#[test]
fn sine_needs_frequency_and_amplitude() {
    let s3 = line_of(TOML, "name = \"S3\"", 1) - 1;
    let t = TOML.replacen("frequency_hz = 0.5\n", "", 1);
    toml_fails(
        &t,
        Some(s3),
        &["test `S3`", "key `frequency_hz`", "missing"],
    );
    let t = TOML.replacen("amplitude_m = 0.05\n", "", 1);
    toml_fails(&t, Some(s3), &["test `S3`", "key `amplitude_m`", "missing"]);
    let t = TOML
        .replacen("kind = \"sine\"", "kind = \"triangle\"", 1)
        .replacen("amplitude_m = 0.05\n", "", 1);
    toml_fails(
        &t,
        Some(s3),
        &["test `S3`", "key `amplitude_m`", "triangle"],
    );
}

#[test]
fn duplicate_test_names() {
    let t = TOML.replacen("name = \"S3\"", "name = \"R1\"", 1);
    let first = line_of(&t, "[[test]]", 1);
    let second = line_of(&t, "[[test]]", first + 1);
    let msg = toml_fails(&t, Some(second), &["test `R1`", "duplicate test name"]);
    assert!(msg.contains(&format!("line {first}")), "{msg}");
    // two tests on one file
    let t = TOML.replacen("file = \"S3.csv\"", "file = \"R1.csv\"", 1);
    toml_fails(
        &t,
        Some(line_of(
            &t,
            "file = \"R1.csv\"",
            line_of(&t, "name = \"S3\"", 1),
        )),
        &["test `S3`", "key `file`", "already the file of test `R1`"],
    );
}

#[test]
fn unknown_controller_gain_is_an_error() {
    let t = TOML.replacen("controller = { fv = 0.0 }", "controller = { Fv = 0.0 }", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "Fv", 1)),
        &[
            "test `R1`",
            "key `controller.Fv`",
            "unknown controller gain",
        ],
    );
    let t = TOML.replacen("kdp = 3.293e-8", "kdp = 3.293e-8\nkd = 1.0", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "kd =", 1)),
        &["key `controller.kd`", "unknown controller gain"],
    );
}

#[test]
fn toml_syntax_and_type_errors() {
    let t = TOML.replacen("rms = 0.005", "rms = = 0.005", 1);
    toml_fails(&t, Some(line_of(&t, "rms =", 1)), &["not valid TOML"]);
    let t = TOML.replacen("sample_rate_hz = 512.0", "sample_rate_hz = \"fast\"", 1);
    toml_fails(&t, Some(2), &["key `sample_rate_hz`", "expected a number"]);
    let t = TOML.replacen("piston_area_m2 = 0.0911", "piston_area_m2 = 0.0", 1);
    toml_fails(
        &t,
        Some(line_of(&t, "piston_area_m2", 1)),
        &["key `geometry.piston_area_m2`", "> 0"],
    );
}

#[test]
fn missing_record_file_names_campaign_toml_line() {
    let dir = campaign_dir(TOML);
    std::fs::remove_file(dir.path().join("S3.csv")).unwrap();
    let e = read_campaign(dir.path()).unwrap_err();
    let toml = dir.path().join("campaign.toml");
    assert_names(
        &e,
        &toml,
        line_of(TOML, "file = \"S3.csv\"", 1),
        &["test `S3`", "key `file`", "S3.csv", "cannot read"],
    );
    // and a missing campaign.toml names itself
    let empty = tempfile::tempdir().unwrap();
    let e = read_campaign(empty.path()).unwrap_err();
    assert!(e.to_string().contains("campaign.toml"), "{e}");
}

#[test]
fn bad_record_in_a_campaign_names_the_record_and_line() {
    let dir = campaign_dir(TOML);
    let mut l = valid_lines();
    l[2] = l[2].replacen(",0.02,", ",--,", 1);
    let p = write(dir.path(), "S3.csv", &csv(&l));
    let e = read_campaign(dir.path()).unwrap_err();
    assert_names(&e, &p, 3, &["spool_position"]);
    // the campaign's sample rate is checked against every record's time column
    let t = TOML.replacen("sample_rate_hz = 512.0", "sample_rate_hz = 1024.0", 1);
    let dir = campaign_dir(&t);
    let e = read_campaign(dir.path()).unwrap_err();
    assert_names(
        &e,
        &dir.path().join("R1.csv"),
        3,
        &["sample rate disagrees", "1024", "campaign.toml"],
    );
}

// ---------------------------------------------------------------------------------------
// Round trip
// ---------------------------------------------------------------------------------------

fn awkward_values(n: usize, salt: f64) -> Vec<f64> {
    let special = [
        0.0,
        -0.0,
        0.1 + 0.2,
        1.0 / 3.0,
        -2.5e-300,
        5e-324,
        f64::MAX,
        f64::MIN_POSITIVE,
        1e16,
        123456789.12345679,
        -1e-5,
    ];
    (0..n)
        .map(|k| {
            if k < special.len() {
                special[k]
            } else {
                (k as f64 * salt).sin() * 10f64.powi((k % 13) as i32 - 6)
            }
        })
        .collect()
}

fn sample_campaign() -> Campaign {
    let p = Params::trees_lab();
    let n = 300;
    let time: Vec<f64> = (0..n).map(|k| k as f64 / FS).collect();
    let rec = |salt: f64, spool: bool, extra: bool| Record {
        time_s: time.clone(),
        ref_displacement_m: awkward_values(n, salt),
        ref_velocity_m_s: awkward_values(n, salt + 0.1),
        ref_acceleration_m_s2: awkward_values(n, salt + 0.2),
        valve_command: Some(awkward_values(n, salt + 0.3)),
        spool_position: spool.then(|| awkward_values(n, salt + 0.4)),
        displacement_m: Some(awkward_values(n, salt + 0.5)),
        acceleration_m_s2: Some(awkward_values(n, salt + 0.6)),
        force_n: Some(awkward_values(n, salt + 0.7)),
        extra: if extra {
            vec![
                ("velocity_m_s".to_string(), awkward_values(n, salt + 0.8)),
                ("pressure_a_pa".to_string(), awkward_values(n, salt + 0.9)),
            ]
        } else {
            vec![]
        },
    };
    let spec =
        |name: &str, kind, control| TestSpec::new(name, format!("{name}.csv"), kind, control);
    let mut r1 = spec("R1", TestKind::Random, Control::Displacement);
    r1.rms = Some(0.005);
    r1.band_hz = Some([0.0, 125.0]);
    r1.controller.fv = Some(0.0);
    r1.controller.kdp = Some(1.0 / 3.0);
    let mut r2 = spec("R2", TestKind::Random, Control::Acceleration);
    r2.rms = Some(0.981);
    r2.band_hz = Some([0.5, 50.0]);
    let mut t1 = spec("T1", TestKind::Triangle, Control::Displacement);
    t1.frequency_hz = Some(0.05);
    t1.amplitude_m = Some(0.05);
    Campaign {
        dir: PathBuf::new(),
        sources: Default::default(),
        info: CampaignInfo {
            name: "round \"trip\" \\ test".to_string(),
            sample_rate_hz: FS,
            geometry: Geometry::from_params(&p),
            controller: ControllerOverride::known(&p.controller),
            tests: vec![r1, r2, t1],
        },
        records: vec![
            rec(1.0, true, true),
            rec(2.0, false, false),
            rec(3.0, true, false),
        ],
    }
}

#[test]
fn round_trip_is_bit_exact() {
    let c = sample_campaign();
    let dir = tempfile::tempdir().unwrap();
    write_campaign(&c, dir.path()).unwrap();
    let back = read_campaign(dir.path()).unwrap();
    assert_eq!(back.info, c.info);
    assert_eq!(back.records.len(), c.records.len());
    // the project's own form: every channel read from the column of its name
    let r1 = &back.sources["R1"];
    assert_eq!(r1.of("force_n"), Some(&Source::same_column("force_n")));
    assert_eq!(r1.channels.len(), back.records[0].channels().len());
    for (a, b) in back.records.iter().zip(&c.records) {
        // bit for bit, including -0.0 and subnormals
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&a.ref_displacement_m), bits(&b.ref_displacement_m));
        assert_eq!(
            bits(a.force_n.as_deref().unwrap()),
            bits(b.force_n.as_deref().unwrap())
        );
        assert_eq!(a, b);
    }
    // writing again gives the same bytes
    let dir2 = tempfile::tempdir().unwrap();
    write_campaign(&back, dir2.path()).unwrap();
    for f in ["campaign.toml", "R1.csv", "R2.csv", "T1.csv"] {
        assert_eq!(
            std::fs::read(dir.path().join(f)).unwrap(),
            std::fs::read(dir2.path().join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn writing_refuses_what_could_not_be_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = sample_campaign();
    c.records[1].force_n.as_mut().unwrap()[7] = f64::NAN;
    let e = write_campaign(&c, dir.path()).unwrap_err();
    assert!(
        e.to_string().contains("R2.csv") && e.to_string().contains("force_n"),
        "{e}"
    );
    let mut c = sample_campaign();
    c.records[0].valve_command.as_mut().unwrap().pop();
    let e = write_record(&c.records[0], &dir.path().join("x.csv")).unwrap_err();
    assert!(e.to_string().contains("valve_command"), "{e}");
    let e = write_record(&Record::default(), &dir.path().join("y.csv")).unwrap_err();
    assert!(e.to_string().contains("empty record"), "{e}");
}

// ---------------------------------------------------------------------------------------
// No panics on arbitrary input
// ---------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Mangled CSV text: an error or a record, never a panic; an error always names a line.
    #[test]
    fn mangled_csv_never_panics(
        cut in 0usize..2000,
        insert in "[0-9a-zA-Z,#.\\-\n\r \"]{0,20}",
        at in 0usize..2000,
    ) {
        let text = csv(&valid_lines());
        let mut s: String = text.chars().take(cut.min(text.len())).collect();
        let pos = at.min(s.len());
        s.insert_str(pos, &insert);
        match read_record_str(&s, "fuzz.csv", FS, "sample_rate_hz") {
            Ok(r) => prop_assert!(!r.is_empty()),
            Err(e) => {
                prop_assert!(e.line().is_some(), "{}", e);
                prop_assert!(e.to_string().starts_with("fuzz.csv: line "), "{}", e);
            }
        }
    }

    /// Mangled campaign.toml: an error or a campaign description, never a panic.
    #[test]
    fn mangled_toml_never_panics(
        cut in 0usize..1200,
        insert in "[0-9a-z=\\[\\]{}\",.\n #]{0,16}",
        at in 0usize..1200,
    ) {
        let mut s: String = TOML.chars().take(cut.min(TOML.len())).collect();
        let pos = at.min(s.len());
        s.insert_str(pos, &insert);
        let r = shaketable::campaign::format::parse_campaign_toml(&s, "campaign.toml", "x");
        if let Err(e) = r {
            prop_assert!(e.to_string().starts_with("campaign.toml: "), "{}", e);
        }
    }
}

//! Reading campaigns safely (issue 14, items 2, 9 and 12): only regular files inside the
//! campaign folder are read, nothing blocks or reads without limit, physical values are
//! bounded, paths are normalised, and line endings, encodings and sample rates are
//! reported precisely. Every check that could hang runs under a timeout.

use shaketable::campaign::format::{read_campaign, read_record, CampaignError};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

const FS: f64 = 512.0;
const HEADER: &str = "time_s,ref_displacement_m,ref_velocity_m_s,ref_acceleration_m_s2,valve_command,displacement_m,acceleration_m_s2,force_n";

/// A valid CSV of `n` rows whose clock runs at `fs` Hz.
fn csv_at(n: usize, fs: f64) -> String {
    let mut s = format!("{HEADER}\n");
    for k in 0..n {
        let t = k as f64 / fs;
        s.push_str(&format!(
            "{t},{},0,0,0.01,0.001,0.1,1000\n",
            1e-3 * (k as f64).sin()
        ));
    }
    s
}

fn toml_with(r2_file: &str) -> String {
    format!(
        r#"name = "reading"
sample_rate_hz = 512.0

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

[[test]]
name = "R1"
file = "R1.csv"
kind = "random"
control = "displacement"
rms = 0.005
band_hz = [0.0, 125.0]

[[test]]
name = "S3"
file = "{r2_file}"
kind = "sine"
control = "displacement"
frequency_hz = 0.5
amplitude_m = 0.05
"#
    )
}

/// A campaign folder whose second test reads `s3_file`; R1.csv is valid.
fn campaign(s3_file: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("campaign.toml"), toml_with(s3_file)).unwrap();
    std::fs::write(dir.path().join("R1.csv"), csv_at(8, FS)).unwrap();
    dir
}

/// `read_campaign` in a thread: the test fails (instead of hanging) after 20 s.
fn read_bounded(dir: &Path) -> Result<(), String> {
    let (tx, rx) = mpsc::channel();
    let d = dir.to_path_buf();
    std::thread::spawn(move || {
        let _ = tx.send(read_campaign(&d).map(|_| ()).map_err(|e| e.to_string()));
    });
    rx.recv_timeout(Duration::from_secs(20))
        .expect("campaign check did not finish within 20 s (blocked or reading without limit)")
}

fn refused(dir: &Path, words: &[&str]) -> String {
    let msg = read_bounded(dir).expect_err("campaign accepted");
    for w in words {
        assert!(msg.contains(w), "message does not mention `{w}`: {msg}");
    }
    msg
}

fn mkfifo(p: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

// --- item 2: only regular files, bounded --------------------------------------------------

#[test]
fn a_fifo_is_refused_without_blocking() {
    let dir = campaign("S3.csv");
    mkfifo(&dir.path().join("S3.csv"));
    refused(
        dir.path(),
        &["test `S3`", "S3.csv", "not a regular file", "FIFO"],
    );
    // campaign.toml itself as a FIFO
    let dir = campaign("S3.csv");
    std::fs::write(dir.path().join("S3.csv"), csv_at(8, FS)).unwrap();
    std::fs::remove_file(dir.path().join("campaign.toml")).unwrap();
    mkfifo(&dir.path().join("campaign.toml"));
    refused(dir.path(), &["campaign.toml", "not a regular file"]);
}

#[test]
fn a_fifo_record_read_alone_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("ref.csv");
    mkfifo(&p);
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(read_record(&p, FS).map(|_| ()).map_err(|e| e.to_string()));
    });
    let msg = rx
        .recv_timeout(Duration::from_secs(20))
        .expect("blocked on a FIFO")
        .unwrap_err();
    assert!(msg.contains("not a regular file"), "{msg}");
}

#[test]
fn a_directory_and_a_socket_are_refused() {
    let dir = campaign("S3.csv");
    std::fs::create_dir(dir.path().join("S3.csv")).unwrap();
    refused(
        dir.path(),
        &["test `S3`", "directory", "not a regular file"],
    );
    let dir = campaign("S3.csv");
    let _l = std::os::unix::net::UnixListener::bind(dir.path().join("S3.csv")).unwrap();
    refused(dir.path(), &["test `S3`", "socket", "not a regular file"]);
}

#[test]
fn dev_zero_is_refused() {
    // named directly, and through a symlink inside the folder
    let dir = campaign("/dev/zero");
    refused(dir.path(), &["test `S3`", "/dev/zero"]);
    let dir = campaign("S3.csv");
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("S3.csv")).unwrap();
    refused(dir.path(), &["test `S3`", "S3.csv"]);
}

#[test]
fn a_record_too_large_is_refused_before_reading() {
    use shaketable::campaign::format::MAX_RECORD_BYTES;
    let dir = campaign("S3.csv");
    // sparse: no disk used, and reading it would take gigabytes of memory
    let f = std::fs::File::create(dir.path().join("S3.csv")).unwrap();
    f.set_len(MAX_RECORD_BYTES + 1).unwrap();
    refused(
        dir.path(),
        &["test `S3`", "S3.csv", "bytes", "largest plausible record"],
    );
}

#[test]
fn a_campaign_toml_too_large_is_refused() {
    use shaketable::campaign::format::MAX_TOML_BYTES;
    let dir = campaign("S3.csv");
    let f = std::fs::OpenOptions::new()
        .append(true)
        .open(dir.path().join("campaign.toml"))
        .unwrap();
    f.set_len(MAX_TOML_BYTES + 1).unwrap();
    refused(dir.path(), &["campaign.toml", "bytes"]);
}

// --- items 2 and 12: inside the campaign folder only ----------------------------------------

#[test]
fn a_file_outside_the_folder_is_refused_before_opening() {
    for path in ["../../../../etc/passwd", "/etc/passwd", "sub/../../x.csv"] {
        let dir = campaign(path);
        let msg = refused(
            dir.path(),
            &["test `S3`", path, "outside the campaign folder"],
        );
        assert!(
            !msg.contains("root:"),
            "the file's content is quoted: {msg}"
        );
    }
}

#[test]
fn a_symlink_resolving_outside_is_refused_inside_is_read() {
    let outside = tempfile::tempdir().unwrap();
    std::fs::write(outside.path().join("S3.csv"), csv_at(8, FS)).unwrap();
    let dir = campaign("S3.csv");
    std::os::unix::fs::symlink(outside.path().join("S3.csv"), dir.path().join("S3.csv")).unwrap();
    refused(
        dir.path(),
        &["test `S3`", "S3.csv", "outside the campaign folder"],
    );
    // a symlink to a file inside the folder is fine
    let dir = campaign("S3.csv");
    std::fs::create_dir(dir.path().join("data")).unwrap();
    std::fs::write(dir.path().join("data/s3.csv"), csv_at(8, FS)).unwrap();
    std::os::unix::fs::symlink("data/s3.csv", dir.path().join("S3.csv")).unwrap();
    read_bounded(dir.path()).unwrap();
}

// --- item 9: one file per test, after normalisation -----------------------------------------

#[test]
fn one_file_per_test_after_normalising_paths() {
    for alias in ["./R1.csv", "sub/../R1.csv", ".//R1.csv"] {
        let dir = campaign(alias);
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        refused(dir.path(), &["test `S3`", "key `file`", "R1"]);
    }
    // a symlink or a hard link to R1.csv is R1.csv
    let dir = campaign("S3.csv");
    std::os::unix::fs::symlink("R1.csv", dir.path().join("S3.csv")).unwrap();
    refused(dir.path(), &["test `S3`", "same file", "R1"]);
    let dir = campaign("S3.csv");
    std::fs::hard_link(dir.path().join("R1.csv"), dir.path().join("S3.csv")).unwrap();
    refused(dir.path(), &["test `S3`", "same file", "R1"]);
    // a test cannot read campaign.toml
    let dir = campaign("./campaign.toml");
    refused(dir.path(), &["test `S3`", "campaign.toml"]);
}

// --- item 9: physical bounds on campaign.toml values ------------------------------------------

fn bounded_value_refused(from: &str, to: &str, key: &str) {
    let dir = campaign("S3.csv");
    std::fs::write(dir.path().join("S3.csv"), csv_at(8, FS)).unwrap();
    let text = toml_with("S3.csv");
    assert!(text.contains(from), "{from}");
    std::fs::write(dir.path().join("campaign.toml"), text.replacen(from, to, 1)).unwrap();
    let msg = refused(dir.path(), &[key]);
    assert!(
        msg.contains("line ") && msg.contains("campaign.toml"),
        "{to}: {msg}"
    );
}

#[test]
fn geometry_outside_physical_bounds_is_refused() {
    for (from, key) in [
        ("piston_area_m2 = 0.0911", "geometry.piston_area_m2"),
        (
            "total_oil_volume_m3 = 0.12101",
            "geometry.total_oil_volume_m3",
        ),
        ("supply_pressure_pa = 28.0e6", "geometry.supply_pressure_pa"),
        ("flow_gain_m3_s = 0.2", "geometry.flow_gain_m3_s"),
    ] {
        let name = from.split(" = ").next().unwrap();
        for v in ["1e-300", "1e300"] {
            bounded_value_refused(from, &format!("{name} = {v}"), key);
        }
    }
    for v in ["1e-300", "1e300"] {
        bounded_value_refused(
            "sample_rate_hz = 512.0",
            &format!("sample_rate_hz = {v}"),
            "sample_rate_hz",
        );
    }
}

#[test]
fn controller_gains_outside_bounds_are_refused() {
    bounded_value_refused("kp = 10.0", "kp = 1e300", "controller.kp");
    bounded_value_refused("kdp = 3.293e-8", "kdp = -1e300", "controller.kdp");
    bounded_value_refused(
        "amplitude_m = 0.05",
        "amplitude_m = 0.05\ncontroller = { fv = 1e300 }",
        "controller.fv",
    );
}

#[test]
fn test_levels_outside_bounds_are_refused() {
    for (from, to, key) in [
        ("rms = 0.005", "rms = 1e300", "rms"),
        ("rms = 0.005", "rms = 1e-300", "rms"),
        ("frequency_hz = 0.5", "frequency_hz = 1e300", "frequency_hz"),
        (
            "frequency_hz = 0.5",
            "frequency_hz = 1e-300",
            "frequency_hz",
        ),
        ("frequency_hz = 0.5", "frequency_hz = 300.0", "frequency_hz"),
        ("amplitude_m = 0.05", "amplitude_m = 1e300", "amplitude_m"),
        ("amplitude_m = 0.05", "amplitude_m = 1e-300", "amplitude_m"),
        (
            "band_hz = [0.0, 125.0]",
            "band_hz = [1e-300, 125.0]",
            "band_hz",
        ),
    ] {
        bounded_value_refused(from, to, key);
    }
}

// --- item 12: line endings, encodings, sample rates ------------------------------------------

fn record_in(dir: &Path, name: &str, text: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn cr_only_line_endings_read_like_lf() {
    let dir = tempfile::tempdir().unwrap();
    let lf = record_in(dir.path(), "lf.csv", csv_at(20, FS).as_bytes());
    let cr = record_in(
        dir.path(),
        "cr.csv",
        csv_at(20, FS).replace('\n', "\r").as_bytes(),
    );
    let crlf = record_in(
        dir.path(),
        "crlf.csv",
        csv_at(20, FS).replace('\n', "\r\n").as_bytes(),
    );
    let want = read_record(&lf, FS).unwrap();
    assert_eq!(read_record(&cr, FS).unwrap(), want);
    assert_eq!(read_record(&crlf, FS).unwrap(), want);
    // an error in a CR-only file names its line
    let bad = csv_at(20, FS)
        .replacen(",1000\n", ",x\n", 4)
        .replace('\n', "\r");
    let p = record_in(dir.path(), "bad.csv", bad.as_bytes());
    let e = read_record(&p, FS).unwrap_err();
    assert_eq!(e.line(), Some(2), "{e}");
    // a CR-only campaign.toml reads too
    let d = campaign("S3.csv");
    std::fs::write(d.path().join("S3.csv"), csv_at(8, FS)).unwrap();
    std::fs::write(
        d.path().join("campaign.toml"),
        toml_with("S3.csv").replace('\n', "\r"),
    )
    .unwrap();
    read_bounded(d.path()).unwrap();
}

#[test]
fn a_non_utf8_byte_names_its_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = csv_at(8, FS).into_bytes();
    // line 5, inside the third cell
    let start: usize = csv_at(8, FS).split('\n').take(4).map(|l| l.len() + 1).sum();
    let third = start
        + csv_at(8, FS)
            .split('\n')
            .nth(4)
            .unwrap()
            .match_indices(',')
            .nth(1)
            .unwrap()
            .0
        + 1;
    bytes[third] = 0xFF;
    let p = record_in(dir.path(), "latin.csv", &bytes);
    let e = read_record(&p, FS).unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.line(), Some(5), "{msg}");
    for w in ["latin.csv", "UTF-8", "0xFF", "column"] {
        assert!(msg.contains(w), "no `{w}`: {msg}");
    }
    // in campaign.toml too
    let d = campaign("S3.csv");
    std::fs::write(d.path().join("S3.csv"), csv_at(8, FS)).unwrap();
    let mut t = toml_with("S3.csv").into_bytes();
    let i = t.iter().position(|&b| b == b'r').unwrap(); // in `name = "reading"` (line 1)
    t[i] = 0xE9;
    std::fs::write(d.path().join("campaign.toml"), &t).unwrap();
    let e = read_campaign(d.path()).unwrap_err();
    assert_eq!(e.line(), Some(1), "{e}");
    assert!(e.to_string().contains("UTF-8"), "{e}");
}

fn read_at(fs_clock: f64, n: usize) -> Result<(), CampaignError> {
    let dir = tempfile::tempdir().unwrap();
    let p = record_in(dir.path(), "R1.csv", csv_at(n, fs_clock).as_bytes());
    read_record(&p, FS).map(|_| ())
}

#[test]
fn a_small_rate_mismatch_is_within_tolerance_not_jitter() {
    // 0.04 % off over 4000 samples drifts 1.6 steps: within the 0.1 % rate tolerance
    read_at(FS * 1.0004, 4000).unwrap();
    read_at(FS * 0.9996, 4000).unwrap();
    // 0.3 % off is a rate mismatch, named as such with both rates
    let e = read_at(FS * 1.003, 4000).unwrap_err().to_string();
    assert!(e.contains("sample rate disagrees"), "{e}");
    assert!(e.contains("513.5") && e.contains("512 Hz"), "{e}");
    // 0.15 % off too, however the steps fall
    let e = read_at(FS * 0.9985, 20000).unwrap_err().to_string();
    assert!(e.contains("sample rate disagrees"), "{e}");
}

#[test]
fn jitter_and_gaps_are_still_non_uniform_time() {
    let dir = tempfile::tempdir().unwrap();
    // a 0.04 %-off clock with one sample 5 % of a step late
    let mut lines: Vec<String> = csv_at(3000, FS * 1.0004)
        .lines()
        .map(String::from)
        .collect();
    let t: f64 = lines[2001].split(',').next().unwrap().parse().unwrap();
    lines[2001] = lines[2001].replacen(&format!("{t}"), &format!("{}", t + 0.05 / FS), 1);
    let p = record_in(dir.path(), "j.csv", (lines.join("\n") + "\n").as_bytes());
    let e = read_record(&p, FS).unwrap_err();
    assert_eq!(e.line(), Some(2002), "{e}");
    assert!(e.to_string().contains("non-uniform time"), "{e}");
    // and a missing sample
    let mut lines: Vec<String> = csv_at(3000, FS * 1.0004)
        .lines()
        .map(String::from)
        .collect();
    lines.remove(1500);
    let p = record_in(dir.path(), "g.csv", (lines.join("\n") + "\n").as_bytes());
    let e = read_record(&p, FS).unwrap_err();
    assert_eq!(e.line(), Some(1501), "{e}");
    assert!(e.to_string().contains("non-uniform time"), "{e}");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

    /// Any constant clock offset: within 0.09 % it reads, beyond 0.11 % it is named a rate
    /// mismatch (never "non-uniform time"), whatever the record length.
    #[test]
    fn a_constant_rate_offset_is_never_jitter(
        offset in -0.004f64..0.004,
        n in 20usize..6000,
    ) {
        let r = read_at(FS * (1.0 + offset), n);
        if offset.abs() < 0.0009 {
            proptest::prop_assert!(r.is_ok(), "{offset}: {:?}", r.err().map(|e| e.to_string()));
        } else if offset.abs() > 0.0011 {
            let e = r.unwrap_err().to_string();
            proptest::prop_assert!(e.contains("sample rate disagrees"), "{offset}: {e}");
        }
    }
}

//! `shaketable record import|check` as a lab runs them (issue 19, part 1): El Centro 1940
//! (tests/data/records, dt 0.01 s) made a 0.3 g table target, read back from a PEER AT2
//! file, checked against the envelope, and the check's demands compared with a
//! simulation of the table following the target.

use shaketable::model::Model;
use shaketable::motion::envelope::check_target;
use shaketable::motion::prepare::Target;
use shaketable::motion::target_file::read_target;
use shaketable::solver::{simulate_run, DEFAULT_MAX_SUBSTEP_S};
use shaketable::Params;
use std::path::{Path, PathBuf};
use std::process::Command;

const ELCENTRO: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/records/elcentro_1940_ns_g.txt"
);
const G: f64 = 9.80665;

fn shaketable(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(args)
        .output()
        .expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("shaketable-record-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn import_elcentro(dir: &Path, extra: &[&str]) -> PathBuf {
    let out = dir.join("target.csv");
    let mut args = vec!["record", "import", ELCENTRO, "--units", "g", "--dt", "0.01"];
    args.extend_from_slice(&["--scale-pga", "0.3g", "--out", out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    let (ok, stdout, stderr) = shaketable(&args);
    assert!(ok, "{stdout}{stderr}");
    out
}

/// El Centro's values as its file writes them, one a line.
fn elcentro_values() -> Vec<String> {
    std::fs::read_to_string(ELCENTRO)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.trim().to_string())
        .collect()
}

fn peak(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

#[test]
fn elcentro_becomes_a_target_at_rest_with_the_pga_asked() {
    let dir = tmp("import");
    let t = read_target(&import_elcentro(&dir, &[])).unwrap();
    assert_eq!(t.rate_hz.round(), 1024.0);
    assert!((peak(&t.acceleration_m_s2) - 0.3 * G).abs() < 1e-6 * G);
    // 39.95 s of record and 3 s at rest at each end
    assert!((t.duration_s() - 45.95).abs() < 0.01, "{}", t.duration_s());
    // the peak stays where the record has it (about 2.1 s into the record)
    let k = t
        .acceleration_m_s2
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .unwrap()
        .0;
    assert!(
        (k as f64 / t.rate_hz - 3.0 - 2.15).abs() < 0.1,
        "peak at {}",
        k as f64 / t.rate_hz
    );
    // integrated from rest, the table ends where it started, at rest
    let n = t.acceleration_m_s2.len();
    assert!(t.velocity_m_s[n - 1].abs() < 1e-3 * peak(&t.velocity_m_s));
    assert!(t.displacement_m[n - 1].abs() < 1e-2 * peak(&t.displacement_m));
    assert!(peak(&t.displacement_m) < 0.4 && peak(&t.displacement_m) > 0.03);
    // never overwritten without --force
    let again = dir.join("target.csv");
    let (ok, _, stderr) = shaketable(&[
        "record",
        "import",
        ELCENTRO,
        "--units",
        "g",
        "--dt",
        "0.01",
        "--out",
        again.to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("--force"), "{stderr}");
}

#[test]
fn a_peer_at2_file_reads_as_the_same_record() {
    let dir = tmp("at2");
    let values: Vec<String> = elcentro_values()
        .iter()
        .map(|v| format!("{v:>15}"))
        .collect();
    let mut at2 = format!(
        "PEER NGA STRONG MOTION DATABASE RECORD\nImperial Valley, 5/19/1940, El Centro, 180\n\
         ACCELERATION TIME SERIES IN UNITS OF G\nNPTS= {:>6}, DT=   .0100 SEC\n",
        values.len()
    );
    for row in values.chunks(5) {
        at2.push_str(&row.concat());
        at2.push('\n');
    }
    let file = dir.join("ELCENTRO.AT2");
    std::fs::write(&file, at2).unwrap();
    let out = dir.join("from-at2.csv");
    let (ok, stdout, stderr) = shaketable(&[
        "record",
        "import",
        file.to_str().unwrap(),
        "--scale-pga",
        "0.3g",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains("PEER NGA AT2"), "{stdout}");
    let from_text = std::fs::read(import_elcentro(&dir, &[])).unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), from_text);
    // a unit that contradicts the header is refused with the line
    let (ok, _, stderr) = shaketable(&[
        "record",
        "import",
        file.to_str().unwrap(),
        "--units",
        "m/s2",
        "--out",
        dir.join("x.csv").to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("ELCENTRO.AT2:3:"), "{stderr}");
}

/// El Centro as a European DAQ or spreadsheet exports it, rows of time and acceleration
/// with decimal commas (`0,01;-0,00602871`), reads as the same record; and as one column
/// when told.
#[test]
fn a_decimal_comma_export_reads_as_the_same_record() {
    let dir = tmp("comma");
    let values: Vec<String> = elcentro_values()
        .iter()
        .map(|v| v.replace('.', ","))
        .collect();
    let rows: Vec<String> = values
        .iter()
        .enumerate()
        .map(|(k, v)| {
            format!(
                "{};{v}",
                format!("{:.2}", k as f64 * 0.01).replace('.', ",")
            )
        })
        .collect();
    let two = dir.join("elcentro_de.csv");
    std::fs::write(&two, rows.join("\n")).unwrap();
    let one = dir.join("elcentro_de_one.txt");
    std::fs::write(&one, values.join("\n")).unwrap();
    let from_text = csv_numbers(&import_elcentro(&dir, &[]));
    for (file, extra) in [
        (&two, vec![]),
        (&one, vec!["--decimal-comma", "--dt", "0.01"]),
    ] {
        let out = dir.join("from-comma.csv");
        let mut args = vec!["record", "import", file.to_str().unwrap(), "--units", "g"];
        args.extend(extra.iter().copied());
        args.extend([
            "--scale-pga",
            "0.3g",
            "--force",
            "--out",
            out.to_str().unwrap(),
        ]);
        let (ok, stdout, stderr) = shaketable(&args);
        assert!(ok, "{stdout}{stderr}");
        assert!(stdout.contains("decimal commas"), "{stdout}");
        // the same target: to the last digit from one column and the same step; from the
        // time column to rounding (its least-squares step is 0.010000000000000002 s, which
        // cost the taper a sample when its length was truncated: 0.16 % of the peak
        // displacement)
        let got = csv_numbers(&out);
        assert_eq!(got.len(), from_text.len(), "{}", file.display());
        let peaks: Vec<f64> = (0..4)
            .map(|c| {
                from_text
                    .iter()
                    .skip(c)
                    .step_by(4)
                    .fold(0.0, |m, v| v.abs().max(m))
            })
            .collect();
        let worst = (0..got.len())
            .map(|k| (got[k] - from_text[k]).abs() / peaks[k % 4])
            .fold(0.0, f64::max);
        let tolerance = if extra.is_empty() { 1e-9 } else { 0.0 };
        assert!(
            worst <= tolerance,
            "{}: {worst} of the peak",
            file.display()
        );
    }
}

/// Every number of a CSV file after its header line.
fn csv_numbers(path: &Path) -> Vec<f64> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .flat_map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().unwrap())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Parameters with a 60-t specimen at 5 Hz (El Centro's band) on the table.
fn with_specimen(dir: &Path) -> PathBuf {
    let params = dir.join("specimen.toml");
    let (_, defaults, _) = shaketable(&["params", "--defaults"]);
    let with = defaults.replace(
        "[specimen]\nenabled = false\nmass_kg = 10000.0",
        "[specimen]\nenabled = true\nmass_kg = 60000.0",
    );
    assert_ne!(
        with, defaults,
        "the defaults name [specimen] enabled = false, mass_kg = 10000.0"
    );
    std::fs::write(&params, with).unwrap();
    params
}

/// The check's force and valve demands are the simulator's: play the target through the
/// model with a specimen, then check the motion the simulated table made; its peak force
/// and spool opening must be the simulated ones.
#[test]
fn the_check_demands_are_what_the_simulated_table_needed() {
    let dir = tmp("check");
    let target = import_elcentro(&dir, &[]);
    let params = with_specimen(&dir);
    let p = Params::from_file(&params).unwrap();
    let t = read_target(&target).unwrap();
    let inputs = t.inputs();
    let run = simulate_run(
        &Model::new(&p),
        &inputs,
        t.rate_hz,
        None,
        DEFAULT_MAX_SUBSTEP_S,
    );
    assert!(run.stop.is_none());
    let series =
        |f: fn(&shaketable::model::Outputs) -> f64| run.outputs.iter().map(f).collect::<Vec<_>>();
    let made = Target {
        rate_hz: t.rate_hz,
        acceleration_m_s2: series(|o| o.acceleration_m_s2),
        velocity_m_s: series(|o| o.velocity_m_s),
        displacement_m: series(|o| o.displacement_m),
    };
    let c = check_target(&p, &made);
    let sim_force = peak(&series(|o| o.actuator_force_n));
    let sim_spool = peak(&series(|o| o.spool_position));
    assert!(
        (c.peak_force_n - sim_force).abs() < 0.03 * sim_force,
        "force: check {}, simulated {sim_force}",
        c.peak_force_n
    );
    let opening = c.demands[2].peak;
    assert!(
        (opening - sim_spool).abs() < 0.05 * sim_spool,
        "spool: check {opening}, simulated {sim_spool}"
    );
    assert!((c.demands[0].peak - peak(&made.displacement_m)).abs() < 1e-12);
}

#[test]
fn the_check_reports_the_envelope_and_sees_a_specimen() {
    let dir = tmp("verdict");
    let target = import_elcentro(&dir, &[]);
    let json = dir.join("c.json");
    let (ok, stdout, stderr) = shaketable(&[
        "record",
        "check",
        target.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}{stderr}");
    assert!(
        stdout.contains("inside the envelope") && stdout.contains("bare table"),
        "{stdout}"
    );
    let bare: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let bare_force = bare["peak_force_n"].as_f64().unwrap();
    // 41 t at 0.3 g plus the friction
    let p = Params::trees_lab();
    let expected = p.table.mass_kg * 0.3 * G + p.friction.force_n;
    assert!(
        (bare_force - expected).abs() < 0.05 * expected,
        "{bare_force} {expected}"
    );
    let params = with_specimen(&dir);
    let (_, stdout, stderr) = shaketable(&[
        "record",
        "check",
        target.to_str().unwrap(),
        "--params",
        params.to_str().unwrap(),
    ]);
    assert!(stdout.contains("with the specimen"), "{stdout}{stderr}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("peak actuator force"))
        .unwrap();
    let force: f64 = line.split_whitespace().nth(3).unwrap().parse().unwrap();
    // a 60-t specimen more than doubles the force of a 41-t table
    assert!(force > 2.0 * bare_force, "{stdout}");
    // with a 5-cm stroke the same target leaves the envelope, named by its demand
    let tight = dir.join("tight.toml");
    let text = std::fs::read_to_string(&params)
        .unwrap()
        .replace("stroke_m = 0.5", "stroke_m = 0.05");
    std::fs::write(&tight, text).unwrap();
    let (ok, stdout, stderr) = shaketable(&[
        "record",
        "check",
        target.to_str().unwrap(),
        "--params",
        tight.to_str().unwrap(),
    ]);
    assert!(!ok, "{stdout}");
    assert!(
        stdout.contains("OUTSIDE") && stderr.contains("leaves the table's envelope: stroke"),
        "{stdout}{stderr}"
    );
}

#[test]
fn hostile_inputs_are_refused_with_the_file_or_the_option() {
    let dir = tmp("hostile");
    let out = dir.join("t.csv");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "record",
                "import",
                "/dev/zero",
                "--units",
                "g",
                "--dt",
                "0.01",
                "--out",
                o,
            ],
            "not a regular file",
        ),
        (
            vec![
                "record",
                "import",
                ELCENTRO,
                "--units",
                "g",
                "--dt",
                "0.01",
                "--rate-hz",
                "1e12",
                "--out",
                o,
            ],
            "--rate-hz",
        ),
        (
            vec![
                "record", "import", ELCENTRO, "--units", "g", "--dt", "10", "--out", o,
            ],
            "time step",
        ),
        (
            vec![
                "record",
                "import",
                ELCENTRO,
                "--units",
                "g",
                "--dt",
                "0.01",
                "--scale-pga",
                "0.3",
                "--out",
                o,
            ],
            "give a unit",
        ),
        (
            vec![
                "record",
                "import",
                ELCENTRO,
                "--units",
                "g",
                "--dt",
                "0.01",
                "--scale-pga",
                "NaNg",
                "--out",
                o,
            ],
            "--scale-pga",
        ),
        (
            vec![
                "record", "import", ELCENTRO, "--units", "furlong", "--dt", "0.01", "--out", o,
            ],
            "--units",
        ),
        (
            vec![
                "record",
                "import",
                ELCENTRO,
                "--units",
                "g",
                "--dt",
                "0.01",
                "--scale-pga",
                "5g",
                "--out",
                o,
            ],
            "scale it down",
        ),
        (
            vec![
                "record", "import", ELCENTRO, "--units", "g", "--dt", "0.01", "--out", ELCENTRO,
                "--force",
            ],
            "input",
        ),
        (vec!["record", "check", ELCENTRO], "time_s"),
    ];
    for (args, want) in cases {
        let (ok, stdout, stderr) = shaketable(&args);
        assert!(!ok, "{args:?} passed: {stdout}");
        assert!(stderr.contains(want), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // a NaN in the record names its line
    let bad = dir.join("bad.txt");
    std::fs::write(&bad, "0 0.1\n0.01 NaN\n0.02 0.3\n").unwrap();
    let (ok, _, stderr) = shaketable(&[
        "record",
        "import",
        bad.to_str().unwrap(),
        "--units",
        "g",
        "--out",
        o,
    ]);
    assert!(!ok && stderr.contains("bad.txt:2:"), "{stderr}");
    assert!(!out.exists());
}

/// The lab's loop on the command line: import, offline drive, the lab plays it
/// (`simulate` on a table with a specimen the model lacks), one online iteration.
#[test]
fn drive_offline_then_online_on_the_command_line() {
    let dir = tmp("drive");
    let target = import_elcentro(&dir, &["--rate-hz", "512"]);
    let t = target.to_str().unwrap();
    let d0 = dir.join("d0");
    let (ok, stdout, stderr) = shaketable(&["drive", "--target", t, "--out", d0.to_str().unwrap()]);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains("naive drive"), "{stdout}");
    let m0: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d0.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(m0["iteration"], 0);
    assert_eq!(m0["basis"], "predicted");
    assert!(m0["rms_error"].as_f64().unwrap() < 0.5 * m0["naive"]["rms_error"].as_f64().unwrap());
    // the lab plays d0 on its table (a 60-t specimen the model does not know)
    let lab = with_specimen(&dir);
    let run0 = dir.join("run0.csv");
    let drive = d0.join("drive.csv");
    let (ok, _, stderr) = shaketable(&[
        "simulate",
        "--reference",
        drive.to_str().unwrap(),
        "--params",
        lab.to_str().unwrap(),
        "--out",
        run0.to_str().unwrap(),
        "--no-campaign",
    ]);
    assert!(ok, "{stderr}");
    let d1 = dir.join("d1");
    let args = [
        "drive",
        "--target",
        t,
        "--previous",
        d0.to_str().unwrap(),
        "--measured",
        run0.to_str().unwrap(),
        "--out",
        d1.to_str().unwrap(),
    ];
    let (ok, stdout, stderr) = shaketable(&args);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains("shifted by 0.0 ms"), "{stdout}");
    let m1: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d1.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(m1["iteration"], 1);
    assert_eq!(m1["basis"], "measured");
    assert_eq!(m1["transfer_pairs"], 1);
    // the same again replaces the folder drive made; a folder of the user's is kept
    let (ok, _, stderr) = shaketable(&args);
    assert!(ok, "{stderr}");
    let mine = dir.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let (ok, _, stderr) = shaketable(&["drive", "--target", t, "--out", mine.to_str().unwrap()]);
    assert!(!ok && stderr.contains("--force"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(mine.join("notes.txt")).unwrap(),
        "keep"
    );
    // --previous without --measured, and a previous folder of another target, are refused
    let (ok, _, stderr) = shaketable(&[
        "drive",
        "--target",
        t,
        "--previous",
        d0.to_str().unwrap(),
        "--out",
        dir.join("x").to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("--measured"), "{stderr}");
    let other = import_elcentro(&tmp("drive-other"), &["--rate-hz", "256"]);
    let (ok, _, stderr) = shaketable(&[
        "drive",
        "--target",
        other.to_str().unwrap(),
        "--previous",
        d0.to_str().unwrap(),
        "--measured",
        run0.to_str().unwrap(),
        "--out",
        dir.join("y").to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("--previous must come from this target"),
        "{stderr}"
    );
}

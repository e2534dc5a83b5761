//! Physics no catalogue row describes (issue 17): the diagnosis must say `explained: false`
//! and locate the residual, never name a catalogue effect as its cause. Each case is a
//! seeded synthetic campaign (the hidden suite's 30-s records) whose recordings are then
//! altered as a laboratory's might be (mains hum on the load cell, an accelerometer whose
//! calibration is off), or whose table feels a force no row describes (a drag). A
//! sensor's error is named as the sensor's (`sensor_findings`), physics and disturbances
//! are not.

#[path = "common/unknown_physics.rs"]
mod unknown_physics;

use std::path::Path;
use std::process::Command;

/// Mains frequency of the hum, Hz, and its amplitude, N: five times the force channel's
/// default noise RMS (200 N) in one line of the spectrum.
const HUM_HZ: f64 = 50.0;
const HUM_N: f64 = 1000.0;

/// The accelerometer's calibration error: it reads 8 % high, within what a wrong
/// sensitivity or a wrong g in a lab's conversion gives.
const ACCELEROMETER_GAIN: f64 = 1.08;

/// How much larger the drag's residual must be while the table moves fast than while it
/// moves slowly: the drag grows as the speed squared, so on a sine its RMS above half the
/// largest speed is about six times that below (0.6 against 0.1 of its peak); half of
/// that leaves room for the noise and for what the refined baseline absorbs.
const DRAG_FAST_OVER_SLOW: f64 = 3.0;

/// The drag case's seed (921 and 924 were both checked by hand: 13.6 / 1.7 and 13.0 / 1.7
/// on S9's force).
const DRAG_SEED: u64 = 924;

fn synthesise(dir: &Path, seed: u64) {
    let o = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["campaign", "synth", "--quiet", "--random-duration", "30"])
        .args(["--seed", &seed.to_string()])
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Rewrite column `name` of every test's CSV in `dir` with `f(time_s, value)`.
fn alter(dir: &Path, name: &str, f: impl Fn(f64, f64) -> f64) {
    rewrite_column(dir, name, |times, values| {
        times.iter().zip(values).map(|(&t, &x)| f(t, x)).collect()
    });
}

/// Rewrite column `name` of every test's CSV in `dir` with `f(times, values)`, a whole
/// column at a time (a filter's state starts afresh in each test).
fn rewrite_column(dir: &Path, name: &str, f: impl Fn(&[f64], &[f64]) -> Vec<f64>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "csv") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let rows: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        let (t, j) = (
            rows[0].iter().position(|c| c == "time_s").unwrap(),
            rows[0].iter().position(|c| c == name).unwrap(),
        );
        let times: Vec<f64> = rows[1..].iter().map(|r| r[t].parse().unwrap()).collect();
        let values: Vec<f64> = rows[1..].iter().map(|r| r[j].parse().unwrap()).collect();
        let new = f(&times, &values);
        let mut out = vec![rows[0].join(",")];
        for (r, v) in rows[1..].iter().zip(new) {
            let mut r = r.clone();
            r[j] = format!("{v:e}");
            out.push(r.join(","));
        }
        std::fs::write(&path, out.join("\n") + "\n").unwrap();
    }
}

fn diagnose(dir: &Path) -> serde_json::Value {
    let json = dir.with_extension("json");
    let o = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["diagnose", "--quiet", "--json"])
        .arg(&json)
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

/// Share of the listed unexplained cells that must lie on the altered channel: the
/// baseline's refinement bends to follow the altered channel and leaves a few cells of
/// the others a little off (an 8 % accelerometer left one force and one displacement cell
/// of twelve at 2-4 noise RMS).
const ON_CHANNEL_SHARE: f64 = 0.75;

/// No cause, `explained: false`, and the cells it lists (worst first) on `channel`: the
/// worst one and most of them. Returns those on `channel`.
fn unexplained_on(v: &serde_json::Value, channel: &str) -> Vec<serde_json::Value> {
    assert_eq!(v["cause"], "none", "{v:#}");
    assert_eq!(v["explained"], false, "{v:#}");
    let cells = v["unexplained"].as_array().unwrap().clone();
    assert!(!cells.is_empty(), "{v:#}");
    assert_eq!(cells[0]["channel"], channel, "{cells:#?}");
    let on: Vec<serde_json::Value> = cells
        .iter()
        .filter(|c| c["channel"] == channel)
        .cloned()
        .collect();
    assert!(
        on.len() as f64 >= ON_CHANNEL_SHARE * cells.len() as f64,
        "{cells:#?}"
    );
    on
}

#[test]
fn mains_hum_on_the_load_cell_is_unexplained_and_located_at_its_frequency() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    synthesise(&dir, 902);
    alter(&dir, "force_n", |t, f| {
        f + HUM_N * (std::f64::consts::TAU * HUM_HZ * t).sin()
    });
    let v = diagnose(&dir);
    // a hum is neither a sensor's scale nor its delay
    no_sensor_finding_on(&v, "force");
    let cells = unexplained_on(&v, "force");
    for c in cells {
        let band: Vec<f64> = serde_json::from_value(c["band_hz"].clone()).unwrap();
        assert!(band[0] <= HUM_HZ && HUM_HZ < band[1], "{c:#}");
    }
}

#[test]
fn a_miscalibrated_accelerometer_is_unexplained_and_located_on_its_channel() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    synthesise(&dir, 901);
    alter(&dir, "acceleration_m_s2", |_, a| ACCELEROMETER_GAIN * a);
    let v = diagnose(&dir);
    let cells = unexplained_on(&v, "acceleration");
    // the error is proportional to the motion: larger where the displacement is
    let worst = &cells[0]["depends_on"]["large_displacement"];
    assert!(
        worst["when"].as_f64().unwrap() > worst["otherwise"].as_f64().unwrap(),
        "{:#}",
        cells[0]
    );
    // and one factor reads it off: the channel is named with the calibration's factor
    let found = v["sensor_findings"].as_array().unwrap();
    let acc: Vec<_> = found
        .iter()
        .filter(|f| f["channel"] == "acceleration")
        .collect();
    eprintln!("sensor findings: {found:#?}");
    assert_eq!(acc.len(), 1, "{found:#?}");
    assert_eq!(acc[0]["kind"], "scale", "{found:#?}");
    let factor = acc[0]["value"].as_f64().unwrap();
    assert!(
        (factor - ACCELEROMETER_GAIN).abs() < FACTOR_TOLERANCE,
        "{found:#?}"
    );
    // the recordings alone say the same: the accelerometer against the LVDT's `x''`
    let k = &v["kinematics"];
    let ratio = k["ratio"].as_f64().unwrap();
    assert!(
        (ratio - ACCELEROMETER_GAIN).abs() < KINEMATIC_TOLERANCE,
        "{k:#}"
    );
    assert!(k["finding"].is_string(), "{k:#}");
}

/// How close the data-only check's ratio must come: it reads the sensors against each
/// other on the coherent bins, where the noise biases it by well under 0.1 % (1.0800 on
/// seed 901; 0.9500 to 1.0309 for errors of 0.95 to 1/0.97 on other seeds).
const KINEMATIC_TOLERANCE: f64 = 0.003;

/// An accelerometer that lags the LVDT by 2 ms (an anti-alias filter's group delay, an
/// acquisition skew) is read off the recordings alone by `campaign check`, within a
/// twentieth of a millisecond (other seeds, rates and tables: 0.999 to 5.003 ms for 1 to
/// 5 ms); the same campaign untouched agrees.
#[test]
fn a_late_accelerometer_is_named_by_the_recordings_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    synthesise(&dir, 941);
    let agree = campaign_check(&dir);
    assert!(agree.contains("they agree"), "{agree}");
    delay(&dir, "acceleration_m_s2", ACCELEROMETER_LAG_S);
    let text = campaign_check(&dir);
    let lag_ms: f64 = text
        .split("accelerometer lag ")
        .nth(1)
        .and_then(|t| t.split(" ms").next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!((lag_ms - 1e3 * ACCELEROMETER_LAG_S).abs() < 0.05, "{text}");
    assert!(text.contains("sensor: the accelerometer runs"), "{text}");
}

const ACCELEROMETER_LAG_S: f64 = 0.002;

fn campaign_check(dir: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["campaign", "check"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Delay column `name` of every test's CSV in `dir` by `delay_s` (linear interpolation
/// between samples; the first samples hold the first value).
fn delay(dir: &Path, name: &str, delay_s: f64) {
    rewrite_column(dir, name, |times, values| {
        let dt = times[1] - times[0];
        let at = |x: f64| {
            let k = (x / dt).floor().max(0.0) as usize;
            let w = (x / dt - k as f64).clamp(0.0, 1.0);
            let next = values[(k + 1).min(values.len() - 1)];
            values[k.min(values.len() - 1)] * (1.0 - w) + next * w
        };
        (times.iter())
            .map(|t| at((t - times[0] - delay_s).max(0.0)))
            .collect()
    });
}

/// Pass column `name` of every test's CSV in `dir` through a first-order high-pass of
/// corner `corner_hz` (`s / (s + wc)`, bilinear), as an AC-coupled accelerometer reads:
/// `(K + wc) y[n] = K (x[n] - x[n-1]) + (K - wc) y[n-1]`, `K = 2 / dt`, from rest.
fn high_pass(dir: &Path, name: &str, corner_hz: f64) {
    rewrite_column(dir, name, |times, values| {
        let (k, wc) = (
            2.0 / (times[1] - times[0]),
            2.0 * std::f64::consts::PI * corner_hz,
        );
        let mut y = vec![0.0; values.len()];
        for n in 1..values.len() {
            y[n] = (k * (values[n] - values[n - 1]) + (k - wc) * y[n - 1]) / (k + wc);
        }
        y
    });
}

/// An AC-coupled accelerometer (a piezoelectric sensor's charge amplifier; corner 0.5 Hz)
/// is read off the recordings alone by `campaign check`: its corner within 3 % (0.501
/// and 0.499 Hz on seeds 31 and 32 by hand, one with a 10-t specimen; no corner read on
/// 22 campaigns of every catalogue effect, 6- and 41-t tables), where one gain and one
/// delay read no test of it. Untouched, the same campaign agrees. `identify`'s JSON
/// carries the same check (`kinematics`).
#[test]
fn an_ac_coupled_accelerometer_is_named_by_the_recordings_alone() {
    const CORNER_HZ: f64 = 0.5;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    synthesise(&dir, 942);
    let agree = campaign_check(&dir);
    assert!(agree.contains("they agree"), "{agree}");
    high_pass(&dir, "acceleration_m_s2", CORNER_HZ);
    let text = campaign_check(&dir);
    let corner_hz: f64 = text
        .split("through a first-order high-pass at ")
        .nth(1)
        .and_then(|t| t.split(" Hz").next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!((corner_hz / CORNER_HZ - 1.0).abs() < 0.03, "{text}");
    // identify's JSON carries the same check: what a script reading it sees
    let json = tmp.path().join("identified.json");
    let o = Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["identify", "--json"])
        .args([&json, &dir])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let k = &v["kinematics"];
    let read = k["high_pass_hz"]
        .as_f64()
        .unwrap_or_else(|| panic!("{k:#}"));
    assert!((read - corner_hz).abs() < 5e-4, "{k:#}");
    assert!(
        k["finding"].as_str().unwrap().contains("AC-coupled"),
        "{k:#}"
    );
}

/// How close the sensor finding's factor must come to the accelerometer's error: the
/// refined baseline takes a little of it into the table's parameters (seed 901: 1.079
/// for 1.08, the random tests' cells 1.061 to 1.070).
const FACTOR_TOLERANCE: f64 = 0.01;

/// No sensor finding on `channel`: the residual there is the table's physics (or a
/// disturbance), which no one scale or delay of the channel removes.
fn no_sensor_finding_on(v: &serde_json::Value, channel: &str) {
    let found = v["sensor_findings"].as_array().unwrap();
    assert!(found.iter().all(|f| f["channel"] != channel), "{found:#?}");
    // nor does the data-only check find the motion sensors at odds
    assert!(
        v["kinematics"]["finding"].is_null(),
        "{:#}",
        v["kinematics"]
    );
}

#[test]
fn a_drag_on_the_table_is_unexplained_and_located_where_it_moves_fast() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    let opts = shaketable::campaign::synth::SynthOptions {
        seed: DRAG_SEED,
        random_duration_s: 30.0,
        ..Default::default()
    };
    let table = shaketable::Params::trees_lab();
    unknown_physics::synthesise_with_body(&table, "quadratic_damping", 1.0, &opts, &dir);
    let v = diagnose(&dir);
    assert_eq!(v["cause"], "none", "{v:#}");
    assert_eq!(v["explained"], false, "{v:#}");
    no_sensor_finding_on(&v, "force");
    let worst = &v["unexplained"][0];
    assert_eq!(worst["channel"], "force", "{worst:#}");
    let fast = &worst["depends_on"]["fast_motion"];
    assert!(
        fast["when"].as_f64().unwrap() > DRAG_FAST_OVER_SLOW * fast["otherwise"].as_f64().unwrap(),
        "{worst:#}"
    );
}

//! Mistakes in reading a laboratory's recordings that must be named, not read silently
//! (campaign-format.md, "Recordings as laboratories make them", "Bad input in this form"):
//! a file read at the wrong delimiter, a misspelled channel key, and a campaign whose time
//! base is a time column rather than `sample_rate_hz`.

use shaketable::campaign::format::read_campaign;
use std::f64::consts::PI;
use std::path::Path;

/// Samples of the hand-made lab export: 2 s at 1 kHz.
const SAMPLES: usize = 2000;
const RATE_HZ: f64 = 1000.0;

/// A lab export separated by `;`: time in ms, the reference and the LVDT in mm, the
/// accelerometer in g (a 1-Hz sine of 10 mm).
fn lab_text() -> String {
    let mut s = String::from("Time_ms;REF_mm;LVDT_mm;ACC_g\n");
    for k in 0..SAMPLES {
        let t = k as f64 / RATE_HZ;
        let x = 10.0 * (2.0 * PI * t).sin();
        let a = -(2.0 * PI).powi(2) * x / 1000.0 / 9.80665;
        s.push_str(&format!("{};{x};{};{a}\n", 1000.0 * t, 0.99 * x));
    }
    s
}

/// The `[columns]` of the lab export, without a time column.
const COLUMNS: &str = "[columns]\nref_displacement_m = { column = \"REF_mm\", scale = 0.001 }\n\
    displacement_m = { column = \"LVDT_mm\", scale = 0.001 }\n\
    acceleration_m_s2 = { column = \"ACC_g\", scale = 9.80665 }\n";

const TEST: &str =
    "\n[[test]]\nname = \"sine\"\nfile = \"sine.txt\"\nkind = \"record\"\ncontrol = \"displacement\"\n";

/// A campaign folder `dir` holding the lab export and `toml` as campaign.toml.
fn write(dir: &Path, toml: &str) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("sine.txt"), lab_text()).unwrap();
    std::fs::write(dir.join("campaign.toml"), toml).unwrap();
}

fn read_error(toml: &str) -> String {
    let tmp = tempfile::tempdir().unwrap();
    write(tmp.path(), toml);
    match read_campaign(tmp.path()) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_header_read_as_one_column_suggests_its_delimiter() {
    let with = |read: &str| format!("sample_rate_hz = 1000.0\n{read}{COLUMNS}{TEST}");
    assert_eq!(read_error(&with("[read]\ndelimiter = \";\"\n")), "");
    let e = read_error(&with(""));
    assert!(
        e.contains("column `ACC_g` (mapped to `acceleration_m_s2`) not found")
            && e.contains("the columns are: Time_ms;REF_mm;LVDT_mm;ACC_g"),
        "{e}"
    );
    assert!(
        e.contains("the file seems to use \";\" as its delimiter; set `[read] delimiter = \";\"`"),
        "{e}"
    );
    // a header split into several columns is a plain missing column: no hint
    let e = read_error(&with("[read]\ndelimiter = \";\"\n").replace("LVDT_mm\"", "LVDT\""));
    assert!(
        e.contains("column `LVDT` (mapped to") && !e.contains("seems to use"),
        "{e}"
    );
}

/// The time column of the lab export, in ms.
const TIME_MS: &str = "time_s = { column = \"Time_ms\", scale = 0.001 }\n";

#[test]
fn a_mapped_time_column_is_a_time_base_without_sample_rate_hz() {
    let read = "[read]\ndelimiter = \";\"\n";
    let tmp = tempfile::tempdir().unwrap();
    write(tmp.path(), &format!("{read}{COLUMNS}{TIME_MS}{TEST}"));
    let c = read_campaign(tmp.path()).unwrap();
    assert_eq!(c.info.sample_rate_hz, RATE_HZ);
    assert_eq!(c.sample_rate_for(&c.info.tests[0]), RATE_HZ);
    assert_eq!(c.records[0].len(), SAMPLES);
    assert!((c.records[0].time_s[1] - 1e-3).abs() < 1e-15);
    let info = shaketable::campaign::format::read_campaign_info(tmp.path()).unwrap();
    assert_eq!(info.sample_rate_for(&info.tests[0]), RATE_HZ);
    // per test: the test maps its own time column
    let per_test = format!(
        "{read}{COLUMNS}{}columns = {{ {} }}\n",
        TEST,
        TIME_MS.trim()
    );
    write(tmp.path(), &per_test);
    let c = read_campaign(tmp.path()).unwrap();
    assert_eq!(c.sample_rate_for(&c.info.tests[0]), RATE_HZ);
    // neither a rate nor a time column: the missing key, the test and the way out
    let e = read_error(&format!("{read}{COLUMNS}{TEST}"));
    assert!(
        e.contains("test `sine`: key `sample_rate_hz`: required key is missing")
            && e.contains("`time_s`"),
        "{e}"
    );
    // the project's own form still needs its rate
    let e = read_error(TEST);
    assert!(
        e.contains("key `sample_rate_hz`: required key is missing"),
        "{e}"
    );
}

#[test]
fn a_rate_from_the_time_column_is_checked_like_a_given_one() {
    let toml = |test_extra: &str| {
        format!("[read]\ndelimiter = \";\"\n{COLUMNS}{TIME_MS}{TEST}{test_extra}")
    };
    let tmp = tempfile::tempdir().unwrap();
    write(tmp.path(), &toml(""));
    // a sample 0.3 ms late is non-uniform time, named at its line
    let text = lab_text().replacen("\n100;", "\n100.3;", 1);
    std::fs::write(tmp.path().join("sine.txt"), text).unwrap();
    let e = read_campaign(tmp.path()).unwrap_err().to_string();
    assert!(e.contains("sine.txt: line 102: non-uniform time"), "{e}");
    // a frequency above the Nyquist frequency of the time column's rate
    let sine = toml("").replace("kind = \"record\"", "kind = \"sine\"");
    let e = read_error(&(sine.clone() + "frequency_hz = 600.0\namplitude_m = 0.01\n"));
    assert!(
        e.contains("test `sine`: key `frequency_hz`: 600 Hz is above the Nyquist frequency 500 Hz of the test's time column"),
        "{e}"
    );
    assert_eq!(
        read_error(&(sine + "frequency_hz = 1.0\namplitude_m = 0.01\n")),
        ""
    );
    // a given rate still has to agree with the time column
    let e = read_error(&format!("sample_rate_hz = 1024.0\n{}", toml("")));
    assert!(e.contains("sample rate disagrees"), "{e}");
}

#[test]
fn a_misspelled_channel_is_named_with_the_channel_it_probably_means() {
    use shaketable::campaign::channel_names::NameOrigin;
    let read = "sample_rate_hz = 1000.0\n[read]\ndelimiter = \";\"\n";
    let typo = COLUMNS.replace("\ndisplacement_m =", "\ndisplacment_m =");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("typo");
    write(&dir, &format!("{read}{typo}{TEST}"));
    let c = read_campaign(&dir).unwrap();
    assert!(
        c.records[0].displacement_m.is_none(),
        "kept as a further channel"
    );
    let misses = c.near_misses();
    assert_eq!(misses.len(), 1, "{misses:?}");
    let m = &misses[0];
    assert_eq!(
        (m.name.as_str(), m.channel, m.edits, m.tests.as_slice()),
        (
            "displacment_m",
            "displacement_m",
            1,
            ["sine".to_string()].as_slice()
        )
    );
    assert_eq!(
        m.origin,
        NameOrigin::ColumnsKey {
            column: "LVDT_mm".into()
        }
    );
    // `campaign check` says so instead of "every rule holds" alone
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["campaign", "check", dir.to_str().unwrap()])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("warning: [columns] key `displacment_m` (column `LVDT_mm`) is no channel name but is 1 edit from `displacement_m`, which test `sine` does not read"),
        "{out}"
    );
    assert!(
        out.contains("every rule of the format holds, but 1 channel name looks misspelled"),
        "{out}"
    );
    // a file column kept under a misspelled project name is named too
    let mapped = COLUMNS.replace(
        "displacement_m = { column = \"LVDT_mm\", scale = 0.001 }\n",
        "",
    );
    write(&dir, &format!("{read}{mapped}{TEST}"));
    let text = lab_text().replacen("LVDT_mm", "Displacement_m", 1);
    std::fs::write(dir.join("sine.txt"), text).unwrap();
    let misses = read_campaign(&dir).unwrap().near_misses();
    assert_eq!(misses.len(), 1, "{misses:?}");
    assert_eq!(
        (misses[0].edits, &misses[0].origin),
        (0, &NameOrigin::FileColumn)
    );
    // a lab's own further channels are no misspelling, nor one beside the channel it resembles
    let own = format!(
        "{read}{COLUMNS}pressure_a_pa = \"LVDT_mm\"\ndisplacement_mm = \"LVDT_mm\"\n{TEST}"
    );
    write(&dir, &own);
    let c = read_campaign(&dir).unwrap();
    assert_eq!(
        c.records[0].extra.len(),
        3,
        "Time_ms, pressure_a_pa, displacement_mm"
    );
    assert!(c.near_misses().is_empty(), "{:?}", c.near_misses());
}

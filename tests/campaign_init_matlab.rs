//! `campaign init` on MATLAB files (campaign-format.md, "Finding out what a file holds"):
//! the skeleton lists every variable, matrix column and dSPACE signal with its `column`,
//! guesses the rate from a dSPACE time vector, names every skipped file with the reason,
//! and, filled in, reads as a campaign whose time base is the recording's time vector.

use shaketable::campaign::format::read_campaign;
use std::path::Path;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/matlab")
        .join(name)
}

fn init(dir: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(["campaign", "init", dir.to_str().unwrap()])
        .output()
        .unwrap()
}

#[test]
fn init_lists_matlab_variables_and_dspace_signals() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for f in ["dspace.mat", "plain.mat", "v73.mat"] {
        std::fs::copy(fixture(f), dir.join(f)).unwrap();
    }
    let o = init(dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("skipped v73.mat: MATLAB v7.3 (HDF5) MAT-files are not supported"),
        "{out}"
    );
    let text = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    let v: toml::Table = toml::from_str(&text).unwrap();
    assert_eq!(v["sample_rate_hz"].as_float(), Some(1000.0), "{text}");
    assert!(v.get("read").is_none(), "no text file, no [read]: {text}");
    let tests = v["test"].as_array().unwrap();
    let files: Vec<&str> = tests.iter().map(|t| t["file"].as_str().unwrap()).collect();
    assert_eq!(files, ["dspace.mat", "plain.mat"]);
    for want in [
        "#   \"Agf\" (200 samples, dSPACE signal \"Model Root/Plant/Agf\", m/s^2, time `rec.X.Data`): 0, 0.5, 1",
        "#   \"Model Root/Controller/Xgf\" (",
        "#   \"rec.X.Data\" (200 samples, the time of dSPACE recording `rec`): 0, 0.001, 0.002",
        "#   \"data:3\" (50 samples, a column of `data`, 50x3 numeric array): 300.25, 301.25, 302.25",
        "#   \"accel\" (100 samples): 0, ",
        "#   \"label\" (not a signal: text \"Xgf table displacement\")",
        "# columns = { time_s = \"rec.X.Data\", ",
        "# skipped v73.mat: MATLAB v7.3",
    ] {
        assert!(text.contains(want), "{want}\n{text}");
    }

    // filled in as the skeleton says: the dSPACE time vector is the time base
    let filled = "name = \"dspace\"\n[[test]]\nname = \"dspace\"\nfile = \"dspace.mat\"\n\
        kind = \"record\"\ncontrol = \"displacement\"\ncolumns = { time_s = \"rec.X.Data\", \
        ref_displacement_m = { column = \"Model Root/Controller/Xgf\", scale = 0.001 }, \
        displacement_m = \"Model Root/Plant/Xgf\", acceleration_m_s2 = \"Agf\" }\n";
    std::fs::write(dir.join("campaign.toml"), filled).unwrap();
    let c = read_campaign(dir).unwrap();
    assert_eq!(c.sample_rate_for(&c.info.tests[0]), 1000.0);
    assert_eq!(c.records[0].len(), 200);
    assert_eq!(c.records[0].acceleration_m_s2.as_ref().unwrap()[2], 1.0);
}

#[test]
fn init_says_why_each_file_was_skipped_when_none_is_described() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::copy(fixture("v73.mat"), dir.join("v73.mat")).unwrap();
    std::fs::copy(fixture("v4.mat"), dir.join("old.mat")).unwrap();
    std::fs::write(dir.join("notes.txt"), "nothing but words here\n").unwrap();
    let o = init(dir);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    for want in [
        "(3 skipped)",
        "skipped notes.txt: no rows of numbers found",
        "skipped old.mat: level 4 MAT files are not supported",
        "skipped v73.mat: MATLAB v7.3 (HDF5)",
    ] {
        assert!(e.contains(want), "{want}\n{e}");
    }
    assert!(!dir.join("campaign.toml").exists());
}

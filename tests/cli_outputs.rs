//! Issue 14, items 3, 11 and 12 (outputs): no command loses a file, bounds on the options
//! that size memory, each OS error said once, and user text escaped in the reports.

use std::fs;
use std::path::Path;
use std::process::Command;

fn shaketable(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_shaketable"))
        .args(args)
        .output()
        .expect("run shaketable")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small synthetic campaign (R1, R2; 24 s of table time).
fn synth(dir: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "campaign",
        "synth",
        "--quiet",
        "--tests",
        "R1,R2",
        "--random-duration",
        "10",
    ];
    args.extend_from_slice(extra);
    args.push(s(dir));
    shaketable(&args)
}

fn synth_ok(dir: &Path) {
    let o = synth(dir, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}

fn refused(o: &std::process::Output, words: &[&str]) {
    assert!(!o.status.success(), "should have been refused");
    let e = stderr(o);
    for w in words {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
}

#[test]
fn simulate_never_replaces_its_reference() {
    let t = tempfile::tempdir().unwrap();
    let c = t.path().join("c");
    synth_ok(&c);
    let r1 = c.join("R1.csv");
    let before = fs::read(&r1).unwrap();
    for force in [false, true] {
        let mut args = vec!["simulate", "--reference", s(&r1), "--out", s(&r1)];
        if force {
            args.push("--force");
        }
        refused(&shaketable(&args), &["R1.csv", "input"]);
        assert_eq!(
            fs::read(&r1).unwrap(),
            before,
            "the measured R1 was replaced"
        );
    }
    // another record of the campaign is an input too (campaign.toml next to the CSV)
    let r2 = c.join("R2.csv");
    let o = shaketable(&[
        "simulate",
        "--reference",
        s(&r1),
        "--out",
        s(&r2),
        "--force",
    ]);
    refused(&o, &["R2.csv", "input"]);
    // a new file is written; writing it again needs --force
    let out = t.path().join("sim.csv");
    let o = shaketable(&["simulate", "--reference", s(&r1), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = shaketable(&["simulate", "--reference", s(&r1), "--out", s(&out)]);
    refused(&o, &["sim.csv", "--force"]);
    let o = shaketable(&[
        "simulate",
        "--reference",
        s(&r1),
        "--out",
        s(&out),
        "--force",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn identify_and_diagnose_never_overwrite_inputs_or_existing_files() {
    let t = tempfile::tempdir().unwrap();
    let c = t.path().join("c");
    synth_ok(&c);
    let toml = c.join("campaign.toml");
    let before = fs::read(&toml).unwrap();
    for cmd in ["identify", "diagnose"] {
        for opt in ["--json", "--params-out"] {
            for target in [&toml, &c.join("R1.csv")] {
                let o = shaketable(&[cmd, s(&c), opt, s(target), "--force"]);
                refused(&o, &["input", s(target)]);
            }
        }
        // the campaign folder as a report folder: it holds the inputs
        let o = shaketable(&[cmd, s(&c), "--report", s(&c), "--force"]);
        refused(&o, &["holds an input"]);
    }
    assert_eq!(fs::read(&toml).unwrap(), before);
    // an existing file that is not an input needs --force, checked before the work
    let mine = t.path().join("notes.json");
    fs::write(&mine, "mine").unwrap();
    let start = std::time::Instant::now();
    let o = shaketable(&["diagnose", s(&c), "--quiet", "--json", s(&mine)]);
    refused(&o, &["notes.json", "--force"]);
    assert!(
        start.elapsed().as_secs_f64() < 5.0,
        "refused only after the diagnosis"
    );
    assert_eq!(fs::read_to_string(&mine).unwrap(), "mine");
    let o = shaketable(&[
        "identify",
        s(&c),
        "--json",
        s(&mine),
        "--params-out",
        s(&mine),
    ]);
    refused(&o, &["given twice"]);
    let o = shaketable(&["identify", s(&c), "--json", s(&mine), "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(fs::read_to_string(&mine).unwrap().starts_with('{'));
}

#[test]
fn report_folders_of_others_need_force_and_errors_name_the_path() {
    let t = tempfile::tempdir().unwrap();
    let c = t.path().join("c");
    synth_ok(&c);
    let r = t.path().join("r");
    fs::create_dir(&r).unwrap();
    fs::write(r.join("thesis.tex"), "mine").unwrap();
    let o = shaketable(&["identify", s(&c), "--report", s(&r)]);
    refused(&o, &[s(&r), "--force"]);
    // our own report (with the JSON inside it) is replaced without --force
    let mine = t.path().join("ours");
    fs::create_dir(&mine).unwrap();
    let json = mine.join("id.json");
    for _ in 0..2 {
        let o = shaketable(&["identify", s(&c), "--json", s(&json), "--report", s(&mine)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(json.exists() && mine.join("index.html").exists());
    }
    // with --force into someone else's folder, the user's file stays
    let o = shaketable(&["identify", s(&c), "--report", s(&r), "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(fs::read_to_string(r.join("thesis.tex")).unwrap(), "mine");
    assert!(r.join("index.html").exists());
    // a report under a regular file: the error names the path
    let file = t.path().join("plain");
    fs::write(&file, "x").unwrap();
    let bad = file.join("report");
    let o = shaketable(&["identify", s(&c), "--report", s(&bad)]);
    refused(&o, &[s(&bad)]);
}

#[test]
fn synth_never_touches_a_users_files_nor_writes_through_symlinks() {
    let t = tempfile::tempdir().unwrap();
    let outside = t.path().join("outside.txt");
    fs::write(&outside, "precious").unwrap();
    let d = t.path().join("d");
    fs::create_dir(&d).unwrap();
    fs::write(d.join("R2.csv"), "my own R2").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&outside, d.join("R1.csv")).unwrap();
    refused(&synth(&d, &[]), &[s(&d), "--force"]);
    assert_eq!(fs::read_to_string(d.join("R2.csv")).unwrap(), "my own R2");
    // even with --force, never through the symlink
    let o = synth(&d, &["--force"]);
    assert!(!o.status.success());
    assert_eq!(fs::read_to_string(&outside).unwrap(), "precious");
    assert_eq!(fs::read_to_string(d.join("R2.csv")).unwrap(), "my own R2");
    // a symlink as the output folder itself
    #[cfg(unix)]
    {
        let target = t.path().join("elsewhere");
        fs::create_dir(&target).unwrap();
        let link = t.path().join("link");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        refused(&synth(&link, &["--force"]), &["symbolic link"]);
        assert_eq!(fs::read_dir(&target).unwrap().count(), 0);
    }
    // nothing left behind by the refused runs
    let names: Vec<String> = fs::read_dir(t.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.contains("partial")), "{names:?}");
}

#[test]
fn synth_replaces_its_own_campaign_whole() {
    let t = tempfile::tempdir().unwrap();
    let c = t.path().join("c");
    synth_ok(&c);
    let o = shaketable(&[
        "campaign",
        "synth",
        "--quiet",
        "--tests",
        "R1",
        "--random-duration",
        "10",
        s(&c),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(c.join("R1.csv").exists());
    assert!(
        !c.join("R2.csv").exists(),
        "a stale record of the old campaign"
    );
    let o = shaketable(&["campaign", "check", s(&c)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // a measured campaign (no marker) is not replaced without --force
    fs::remove_file(c.join(".shaketable-output")).unwrap();
    refused(&synth(&c, &[]), &["--force"]);
    assert_eq!(fs::read_dir(&c).unwrap().count(), 4);
}

#[test]
fn options_that_size_memory_are_bounded() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("x");
    let cases: Vec<(Vec<&str>, [&str; 3])> = vec![
        (
            vec!["campaign", "synth", "--random-duration", "1e9", s(&out)],
            ["--random-duration", "1000000000", "3600"],
        ),
        (
            vec!["campaign", "synth", "--max-substep", "1e-12", s(&out)],
            ["--max-substep", "0.000000000001", "0.00001"],
        ),
        (
            vec!["frf", "--points", "4000000000"],
            ["--points", "4000000000", "100000"],
        ),
        (
            vec!["bench", "--seconds", "1e9"],
            ["--seconds", "1000000000", "3600"],
        ),
        (
            vec!["bench", "--repeats", "1000000"],
            ["--repeats", "1000000", "100"],
        ),
    ];
    for (args, words) in &cases {
        let start = std::time::Instant::now();
        refused(&shaketable(args), words);
        assert!(start.elapsed().as_secs_f64() < 5.0, "{args:?}");
    }
    let c = t.path().join("c");
    synth_ok(&c);
    let r1 = c.join("R1.csv");
    let sim = t.path().join("sim.csv");
    for (opt, value, limit) in [
        ("--sample-rate", "1e9", "100000"),
        ("--max-substep", "1e-12", "0.00001"),
    ] {
        let o = shaketable(&[
            "simulate",
            "--reference",
            s(&r1),
            "--out",
            s(&sim),
            opt,
            value,
        ]);
        refused(&o, &[opt, limit]);
    }
    assert!(!out.exists() && !sim.exists());
}

#[test]
fn each_os_error_is_said_once() {
    let t = tempfile::tempdir().unwrap();
    let missing = t.path().join("missing");
    let sim = t.path().join("sim.csv");
    for args in [
        vec!["campaign", "check", s(&missing)],
        vec!["identify", s(&missing)],
        vec!["frf", "--params", s(&missing)],
        vec!["simulate", "--reference", s(&missing), "--out", s(&sim)],
    ] {
        let o = shaketable(&args);
        let e = stderr(&o);
        assert!(!o.status.success());
        assert_eq!(e.matches("os error 2").count(), 1, "{e}");
    }
}

#[test]
fn campaign_name_is_escaped_in_the_report() {
    let t = tempfile::tempdir().unwrap();
    let c = t.path().join("c");
    // the whole program (diagnose refuses a campaign that lacks a part of the baseline),
    // with short random tests
    let o = shaketable(&[
        "campaign",
        "synth",
        "--quiet",
        "--random-duration",
        "30",
        s(&c),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let toml = c.join("campaign.toml");
    let text = fs::read_to_string(&toml).unwrap();
    let evil = "<img src=x onerror=alert(1)>";
    let first = text.lines().find(|l| l.starts_with("name = ")).unwrap();
    let text = text.replacen(first, &format!("name = \"{evil}\""), 1);
    assert!(text.contains(evil));
    fs::write(&toml, text).unwrap();
    // the quick diagnosis writes the same report (and keeps CI inside its time)
    for cmd in [&["identify"][..], &["diagnose", "--quick"][..]] {
        let r = t.path().join(cmd[0]);
        let o = shaketable(&[cmd, &[s(&c), "--report", s(&r)]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let html = fs::read_to_string(r.join("index.html")).unwrap();
        assert!(!html.contains(evil), "live markup in the {cmd:?} report");
        assert!(
            html.contains("&lt;img src=x onerror=alert(1)&gt;"),
            "{cmd:?}"
        );
    }
}

/// Item 5 (second half): `simulate` shows its progress on a terminal, and nothing when
/// stderr is a file or a pipe.
#[test]
fn simulate_shows_progress_only_on_a_terminal() {
    let t = tempfile::tempdir().unwrap();
    let c = t.path().join("c");
    synth_ok(&c);
    let r1 = c.join("R1.csv");
    let out = t.path().join("a.csv");
    let o = shaketable(&["simulate", "--reference", s(&r1), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("simulating"), "{}", stderr(&o));
    // on a pseudo-terminal (util-linux `script`), when available
    let cmd = format!(
        "{} simulate --reference {} --out {}",
        env!("CARGO_BIN_EXE_shaketable"),
        s(&r1),
        s(&t.path().join("b.csv"))
    );
    let Ok(o) = Command::new("script")
        .args(["-qec", &cmd, "/dev/null"])
        .output()
    else {
        eprintln!("no `script`: the terminal half is skipped");
        return;
    };
    assert!(o.status.success(), "{}", stderr(&o));
    let all = String::from_utf8_lossy(&o.stdout);
    assert!(all.contains("simulating"), "{all}");
}

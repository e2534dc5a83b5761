//! Unit tests of the safe-write rules.

use super::*;
use std::fs;

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn existing_file_needs_force_and_an_input_is_never_replaced() {
    let d = tmp();
    let p = d.path().join("a.json");
    fs::write(&p, "old").unwrap();
    let none = Inputs::new();
    assert!(matches!(
        write_file(&p, b"new", false, &none),
        Err(OutputError::Exists { .. })
    ));
    assert_eq!(fs::read_to_string(&p).unwrap(), "old");
    write_file(&p, b"new", true, &none).unwrap();
    assert_eq!(fs::read_to_string(&p).unwrap(), "new");
    let mut inputs = Inputs::new();
    // the same file under another name (a hard link) is still the input
    let alias = d.path().join("alias.json");
    fs::hard_link(&p, &alias).unwrap();
    inputs.add(&p);
    assert!(matches!(
        write_file(&alias, b"x", true, &inputs),
        Err(OutputError::IsInput { .. })
    ));
    assert_eq!(fs::read_to_string(&p).unwrap(), "new");
}

#[cfg(unix)]
#[test]
fn symlinks_are_never_written_through() {
    let outside = tmp();
    let victim = outside.path().join("victim.txt");
    fs::write(&victim, "precious").unwrap();
    let d = tmp();
    let link = d.path().join("out.csv");
    std::os::unix::fs::symlink(&victim, &link).unwrap();
    for force in [false, true] {
        assert!(matches!(
            write_file(&link, b"x", force, &Inputs::new()),
            Err(OutputError::Symlink { .. })
        ));
    }
    assert!(atomic_write(&link, b"x").is_err());
    let dirlink = d.path().join("report");
    std::os::unix::fs::symlink(outside.path(), &dirlink).unwrap();
    assert!(matches!(
        plan_dir(&dirlink, "test", true, &Inputs::new()),
        Err(OutputError::Symlink { .. })
    ));
    assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
}

#[test]
fn atomic_write_leaves_no_temporary_file() {
    let d = tmp();
    let p = d.path().join("x.txt");
    atomic_write(&p, b"one").unwrap();
    atomic_write(&p, b"two").unwrap();
    assert_eq!(fs::read_to_string(&p).unwrap(), "two");
    assert_eq!(fs::read_dir(d.path()).unwrap().count(), 1);
}

fn stage_and_commit(plan: &DirPlan, files: &[(&str, &str)]) {
    let s = plan.stage().unwrap();
    for (n, c) in files {
        fs::write(s.path().join(n), c).unwrap();
    }
    s.commit().unwrap();
}

#[test]
fn own_folder_is_replaced_whole_a_foreign_one_needs_force() {
    let d = tmp();
    let out = d.path().join("out");
    let plan = plan_dir(&out, "test", false, &Inputs::new()).unwrap();
    stage_and_commit(&plan, &[("a.csv", "1"), ("b.csv", "1")]);
    // ours: replaced as a whole (b.csv goes)
    let plan = plan_dir(&out, "test", false, &Inputs::new()).unwrap();
    stage_and_commit(&plan, &[("a.csv", "2")]);
    assert_eq!(fs::read_to_string(out.join("a.csv")).unwrap(), "2");
    assert!(!out.join("b.csv").exists());
    // a user's file in it: no longer ours
    fs::write(out.join("notes.txt"), "mine").unwrap();
    assert!(matches!(
        plan_dir(&out, "test", false, &Inputs::new()),
        Err(OutputError::ForeignDir { .. })
    ));
    // another command's folder is not ours either
    fs::remove_file(out.join("notes.txt")).unwrap();
    assert!(plan_dir(&out, "other", false, &Inputs::new()).is_err());
    // --force into a foreign folder: files added, the user's kept
    fs::write(out.join("notes.txt"), "mine").unwrap();
    let plan = plan_dir(&out, "test", true, &Inputs::new()).unwrap();
    stage_and_commit(&plan, &[("a.csv", "3")]);
    assert_eq!(fs::read_to_string(out.join("a.csv")).unwrap(), "3");
    assert_eq!(fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
    assert_eq!(
        fs::read_dir(d.path()).unwrap().count(),
        1,
        "no temporary left"
    );
}

#[test]
fn folder_holding_an_input_is_refused_even_with_force() {
    let d = tmp();
    let input = d.path().join("campaign.toml");
    fs::write(&input, "x").unwrap();
    let mut inputs = Inputs::new();
    inputs.add(&input);
    assert!(matches!(
        plan_dir(d.path(), "test", true, &inputs),
        Err(OutputError::HoldsInput { .. })
    ));
}

#[test]
fn a_dropped_staging_leaves_nothing() {
    let d = tmp();
    let out = d.path().join("out");
    let plan = plan_dir(&out, "test", false, &Inputs::new()).unwrap();
    let s = plan.stage().unwrap();
    fs::write(s.path().join("half.csv"), "1").unwrap();
    drop(s);
    assert_eq!(fs::read_dir(d.path()).unwrap().count(), 0);
}

#[test]
fn the_same_output_twice_is_refused() {
    let a = Path::new("x/out.json");
    assert!(check_distinct(&[a, Path::new("x/../x/out.json"), a]).is_err());
    assert!(check_distinct(&[a, Path::new("y.json")]).is_ok());
}

#[cfg(unix)]
#[test]
fn write_via_temp_keeps_the_extension_and_refuses_symlinks() {
    let d = tmp();
    let p = d.path().join("fig.png");
    write_via_temp(
        &p,
        |t| {
            assert_eq!(t.extension().unwrap(), "png");
            fs::write(t, "png").map_err(|e| e.to_string())
        },
        |e| e.to_string(),
    )
    .unwrap();
    assert_eq!(fs::read_to_string(&p).unwrap(), "png");
    let victim = d.path().join("victim");
    fs::write(&victim, "keep").unwrap();
    let link = d.path().join("link.png");
    std::os::unix::fs::symlink(&victim, &link).unwrap();
    let r = write_via_temp(
        &link,
        |t| fs::write(t, "x").map_err(|e| e.to_string()),
        |e| e.to_string(),
    );
    assert!(r.is_err());
    assert_eq!(fs::read_to_string(&victim).unwrap(), "keep");
    // a failing writer leaves nothing behind
    let q = d.path().join("bad.png");
    assert!(write_via_temp(&q, |_| Err("no".to_string()), |e| e.to_string()).is_err());
    assert_eq!(fs::read_dir(d.path()).unwrap().count(), 3);
}

#[test]
fn a_dot_target_is_its_real_folder() {
    let d = tmp();
    let out = d.path().join("out");
    fs::create_dir(&out).unwrap();
    let plan = plan_dir(&out.join("."), "test", false, &Inputs::new()).unwrap();
    stage_and_commit(&plan, &[("a.csv", "1")]);
    assert_eq!(fs::read_to_string(out.join("a.csv")).unwrap(), "1");
    assert!(out.join(MARKER_FILE).exists());
    assert_eq!(fs::read_dir(d.path()).unwrap().count(), 1);
    // and it is ours now
    let plan = plan_dir(&out, "test", false, &Inputs::new()).unwrap();
    stage_and_commit(&plan, &[("b.csv", "2")]);
    assert!(!out.join("a.csv").exists());
}
